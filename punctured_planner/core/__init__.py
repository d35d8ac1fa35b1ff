"""
ROS-free math core: the sequential planner of Ipanaque Zapata & González, numpy only.

One module per idea of the paper: ``space`` (the space and its frame),
``strata`` (cp and eps), ``deformations`` (D, S, phi), ``sections`` (Gamma,
lanes and the composition of Remark 2.3), ``plan`` (the plan as breakpoints),
``certificate`` (exact clearance), ``timing`` (time parameterisation),
``complexity`` (domains and TC_n), ``validation`` and ``errors``.
"""

from .certificate import Clearance
from .errors import ErrorCode, PlanningError
from .plan import Plan, plan
from .sections import PAPER_LEGS, SPREAD_LEGS
from .space import Frame, Workspace
from .validation import MAX_COORDINATE

__all__ = ['Clearance', 'ErrorCode', 'Frame', 'MAX_COORDINATE', 'PAPER_LEGS', 'Plan',
           'PlanningError', 'SPREAD_LEGS', 'Workspace', 'plan']
