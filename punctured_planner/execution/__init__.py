"""
Executing a plan in lockstep, ROS-free: the shared plan clock and the tracking law.

A plan is collision-free only when every robot is at its reference at the same
instant (doc/design.md section 13). ``tolerance`` gives the rate of the
shared clock for the robots' deviations (the tracking tolerance, how far each may
stray while the bodies still cannot touch, is the core's: core.timing), ``reference`` the robots'
reference positions and velocities at a plan time, ``bodies`` the surface gaps
of disc robots and obstacles, and ``execution`` one control step: advance the
shared clock as far as the robots' errors allow, then track the reference with
feed-forward and saturated feedback; ``unicycle`` is the tracking law of
differential-drive robots (a point ahead of the centre, turns in place, the
clock's caps before corners), ``hold`` when a goal may start and when a hold
of the clock ends it. The ``plan_executor`` node is a thin adapter around
:class:`Execution` and ``hold``; the simulated fleet (``sim``) uses
``bodies`` for its true gap.
"""

from .bodies import Bodies, Gap
from .execution import DRIVES, Execution, ExecutionSettings, Step
from .reference import Reference
from .tolerance import clock_rate

__all__ = ['Bodies', 'DRIVES', 'Execution', 'ExecutionSettings', 'Gap', 'Reference', 'Step',
           'clock_rate']
