"""
What plan_executor keeps between callbacks: the plans it heard, and the robots' state.

ROS-free apart from the ExecutePlan result codes: :class:`PlanStore` keeps the
last published plans and answers a goal's plan id with a :class:`Lookup`;
:func:`fleet_state` turns the robots' last odometry into one control step's
input (:class:`FleetState`).
"""

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
from punctured_planner_interfaces.action import ExecutePlan

from .snapshot import RobotOdometry
from ..execution import Bodies
from ..execution import Reference

Result = ExecutePlan.Result
# Plans kept for goals that name an older one.
PLAN_HISTORY = 16


@dataclass(frozen=True)
class KnownPlan:
    """A plan heard on ``plan``, ready to execute."""

    plan_id: int
    names: tuple
    frame_id: str
    reference: Reference
    bodies: Bodies
    min_gap: float
    tolerance: float


@dataclass(frozen=True)
class Lookup:
    """A goal's plan: the plan (None if there is none), the result code and why."""

    plan: KnownPlan | None
    code: int
    message: str = ''

    @property
    def runnable(self) -> KnownPlan | None:
        """Return the plan a goal can run (code NONE), else None."""
        return self.plan if self.code == Result.NONE else None


class PlanStore:
    """The last PLAN_HISTORY plans by id, oldest first."""

    def __init__(self) -> None:
        """Start with no plan."""
        self._plans: OrderedDict[int, KnownPlan] = OrderedDict()

    def add(self, plan: KnownPlan) -> None:
        """Keep a plan (a plan id heard again replaces the old one and becomes the latest)."""
        self._plans.pop(plan.plan_id, None)
        self._plans[plan.plan_id] = plan
        while len(self._plans) > PLAN_HISTORY:
            self._plans.popitem(last=False)

    def lookup(self, plan_id: int, topic: str) -> Lookup:
        """Return the plan a goal names (0: the latest) with NONE, NO_PLAN or UNSAFE_PLAN."""
        if not self._plans:
            return Lookup(None, Result.NO_PLAN, 'no plan received yet on %s' % topic)
        if plan_id == 0:
            plan = next(reversed(self._plans.values()))
        elif plan_id in self._plans:
            plan = self._plans[plan_id]
        else:
            return Lookup(None, Result.NO_PLAN, 'plan %d is not there (known plans: %s)' % (
                plan_id, ', '.join(str(i) for i in self._plans)))
        if not plan.tolerance > 0:
            return Lookup(plan, Result.UNSAFE_PLAN, (
                'plan %d has min_gap %.6g m, tracking tolerance %.6g m: its bodies touch '
                'even when executed exactly' % (plan.plan_id, plan.min_gap, plan.tolerance)))
        return Lookup(plan, Result.NONE)


@dataclass(frozen=True, eq=False)
class FleetState:
    """
    The robots of a plan at one control step.

    positions (k, 3) and orientations (k, 4) (a stale robot keeps the plan's
    start and the identity), the stale robots' names and (k,) mask, the (k,)
    ages of the odometry by arrival (s; 0 for a stale robot) and
    ``wrong_frame``: why some odometry is in another frame than the plan's
    ('' when none is).
    """

    positions: np.ndarray
    orientations: np.ndarray
    stale: tuple
    stale_mask: np.ndarray
    ages: np.ndarray
    wrong_frame: str = ''


def fleet_state(plan: KnownPlan, odometry: dict[str, RobotOdometry], now_ns: int,
                timeout_sec: float) -> FleetState:
    """Return the state of plan's robots from their last odometry (stale after timeout_sec)."""
    k = len(plan.names)
    positions = plan.reference.position(0.0).copy()
    orientations = np.tile([0.0, 0.0, 0.0, 1.0], (k, 1))
    stale = []
    wrong_frame = ''
    ages = np.zeros(k)
    for i, name in enumerate(plan.names):
        entry = odometry.get(name)
        if entry is None or now_ns - entry.received_ns > timeout_sec * 1e9:
            stale.append(name)
            continue
        if entry.frame_id and entry.frame_id != plan.frame_id:
            wrong_frame = ('odometry of %s is in frame %r, the plan in %r'
                           % (name, entry.frame_id, plan.frame_id))
            break
        positions[i] = entry.position
        orientations[i] = entry.orientation
        ages[i] = (now_ns - entry.received_ns) * 1e-9
    mask = np.array([name in stale for name in plan.names])
    return FleetState(positions, orientations, tuple(stale), mask, ages, wrong_frame)
