"""
ROS-free math core: the sequential planner of Ipanaque Zapata & González, on numpy and scipy.

One module per idea of the paper: ``space`` (the space), ``frame`` (its frame),
``strata`` (cp and eps), ``deformations`` (D, S, phi), ``sections`` (Gamma,
lanes, the composition of Remark 2.3 and the variant table), ``plan`` (the
plan as breakpoints), ``certificate`` (exact clearance), ``timing`` (time
parameterisation), ``complexity`` (domains and TC_n), ``pairs`` (index arrays
of point pairs), ``discs`` (the construction for disc robots among pillars),
``refine`` (the refinement of every construction's motion), ``walls`` (workspace
bounds), ``limits`` (the supported ranges), ``validation`` and ``errors``.
The design, with the proofs, is doc/design.md.
"""

from .certificate import Clearance
from .errors import ErrorCode, PlanningError
from .frame import Frame
from .limits import first_out_of_range, MAX_COORDINATE
from .plan import Plan, plan, Samples
from .sections import Schedule, SCHEDULES, VARIANTS
from .space import Workspace

__all__ = ['Clearance', 'ErrorCode', 'first_out_of_range', 'Frame', 'MAX_COORDINATE', 'Plan',
           'PlanningError', 'Samples', 'Schedule', 'SCHEDULES', 'VARIANTS', 'Workspace', 'plan']
