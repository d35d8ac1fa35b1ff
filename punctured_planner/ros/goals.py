"""
What plan_executor keeps between callbacks: the plans it heard, and the robots' state.

ROS-free apart from the ExecutePlan result codes: :class:`PlanStore` keeps the
last published plans (and why the messages that were no plan were ignored) and
answers a goal's plan id with a :class:`Lookup`;
:func:`fleet_state` turns the robots' last odometry into one control step's
input (:class:`FleetState`).
"""

from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
from punctured_planner_interfaces.action import ExecutePlan

from .snapshot import in_other_frame
from .snapshot import RobotOdometry
from ..execution import Bodies
from ..execution import Reference

Result = ExecutePlan.Result
# Plans kept for goals that name an older one.
PLAN_HISTORY = 16


class InvalidPlan(ValueError):
    """
    A Plan message that is no plan, with its culprits: the plan id and the field at fault.

    field is the Plan message's field ('paths', 'robot_names', 'tracking_tolerance',
    ...), robot the robot whose path is at fault and pose the index of the pose, where
    they are; the message says why, naming them.
    """

    def __init__(self, plan_id: int, field: str, reason: str, robot: str | None = None,
                 pose: int | None = None) -> None:
        """Keep the culprits; the message is 'plan <id>' and the reason."""
        self.plan_id = plan_id
        self.field = field
        self.robot = robot
        self.pose = pose
        super().__init__('plan %d%s' % (plan_id, reason))


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
    """
    The last PLAN_HISTORY plans by id, oldest first, and the last ignored plan messages.

    A message on ``plan`` that is not a plan is ignored, and its id remembered with the
    reason: a goal naming it, or naming the latest plan (0) while it is the latest heard,
    ends NO_PLAN with that reason at once, never running an older plan in its place.
    A planner numbers its plans 1, 2, ... from its start, so a plan whose id is below
    the latest heard is a restarted planner's: every id heard before is forgotten, and
    a goal for the new planner's plan 2 waits for it instead of running the old
    planner's plan 2. (Not an ignored message, nor id 0: no planner's numbering.) Until
    the new planner's first plan arrives, a goal for its plan 1 (or 0) still finds the
    old one; plan_executor then runs it only with every robot at its start.
    """

    def __init__(self) -> None:
        """Start with no plan."""
        self._plans: OrderedDict[int, KnownPlan] = OrderedDict()
        self._ignored: OrderedDict[int, str] = OrderedDict()  # plan id: why
        self._latest: int | None = None  # the id last heard, a plan or not

    def add(self, plan: KnownPlan) -> None:
        """Keep a plan (a plan id heard again replaces the old one and becomes the latest)."""
        if 0 < plan.plan_id < (self._latest or 0):  # a restarted planner: forget the old ids
            self._plans.clear()
            self._ignored.clear()
        _keep(self._plans, plan.plan_id, plan)
        self._ignored.pop(plan.plan_id, None)
        self._latest = plan.plan_id

    def ignore(self, plan_id: int, reason: str) -> None:
        """Note a message that is not a plan: its id is no plan now, and the latest heard."""
        _keep(self._ignored, plan_id, reason)
        self._plans.pop(plan_id, None)
        self._latest = plan_id

    def _named(self, plan_id: int) -> int | None:
        """Return the id a goal's plan_id names: itself, or for 0 the latest heard (None)."""
        return self._latest if plan_id == 0 else plan_id

    def heard(self, plan_id: int) -> bool:
        """Return whether a message named plan_id (0: any) is kept, a plan or an ignored one."""
        named = self._named(plan_id)
        return named in self._plans or named in self._ignored

    def lookup(self, plan_id: int, topic: str) -> Lookup:
        """Return the plan a goal names (0: the latest) with NONE, NO_PLAN or UNSAFE_PLAN."""
        named = self._named(plan_id)
        if named is None:
            return Lookup(None, Result.NO_PLAN, 'no plan received yet on %s' % topic)
        if named in self._ignored:
            return Lookup(None, Result.NO_PLAN, '%splan %d on %s was ignored: %s' % (
                'the latest, ' if plan_id == 0 else '', named, topic, self._ignored[named]))
        if named not in self._plans:
            return Lookup(None, Result.NO_PLAN, 'plan %d is not there (known plans: %s)' % (
                named, ', '.join(str(i) for i in self._plans)))
        plan = self._plans[named]
        if not plan.tolerance > 0:
            return Lookup(plan, Result.UNSAFE_PLAN, (
                'plan %d has min_gap %.6g m, tracking tolerance %.6g m: its bodies touch '
                '(each other, a pillar or a wall) even when executed exactly'
                % (plan.plan_id, plan.min_gap, plan.tolerance)))
        return Lookup(plan, Result.NONE)


def _keep(history: OrderedDict, plan_id: int, value: object) -> None:
    """Make plan_id the newest entry of history, dropping the oldest beyond PLAN_HISTORY."""
    history.pop(plan_id, None)
    history[plan_id] = value
    while len(history) > PLAN_HISTORY:
        history.popitem(last=False)


@dataclass(frozen=True)
class WrongFrame:
    """A robot whose odometry is in a frame other than its plan's: the robot, both frames."""

    robot: str
    frame_id: str
    plan_frame_id: str

    def describe(self) -> str:
        """Return the reason, naming the robot and both frames."""
        return ('odometry of %s is in frame %r, the plan in %r'
                % (self.robot, self.frame_id, self.plan_frame_id))


@dataclass(frozen=True, eq=False)
class FleetState:
    """
    The robots of a plan at one control step.

    positions (k, 3) and orientations (k, 4) (a stale robot keeps the plan's
    start and its last orientation heard, else the identity), the stale robots'
    names and (k,) mask, the (k,) ages of the odometry by arrival (s; 0 for a
    stale robot), the (k,) speeds its twists report (m/s; 0 for a stale robot) and
    ``wrong_frame``: the first robot whose odometry is in another frame than
    the plan's (None when none is).
    """

    positions: np.ndarray
    orientations: np.ndarray
    stale: tuple
    stale_mask: np.ndarray
    ages: np.ndarray
    speeds: np.ndarray
    wrong_frame: WrongFrame | None = None


def fleet_state(plan: KnownPlan, odometry: dict[str, RobotOdometry], now_ns: int,
                timeout_sec: float) -> FleetState:
    """Return the state of plan's robots from their last odometry (stale after timeout_sec)."""
    k = len(plan.names)
    positions = plan.reference.position(0.0).copy()
    orientations = np.tile([0.0, 0.0, 0.0, 1.0], (k, 1))
    stale = []
    wrong_frame = None
    ages, speeds = np.zeros(k), np.zeros(k)
    for i, name in enumerate(plan.names):
        entry = odometry.get(name)
        if entry is None or now_ns - entry.received_ns > timeout_sec * 1e9:
            stale.append(name)
            if entry is not None:  # its last heading: a stale robot is still commanded
                orientations[i] = entry.orientation
            continue
        if in_other_frame(entry.frame_id, plan.frame_id):
            wrong_frame = WrongFrame(name, entry.frame_id, plan.frame_id)
            break
        positions[i] = entry.position
        orientations[i] = entry.orientation
        ages[i] = (now_ns - entry.received_ns) * 1e-9
        speeds[i] = entry.speed
    mask = np.array([name in stale for name in plan.names])
    return FleetState(positions, orientations, tuple(stale), mask, ages, speeds, wrong_frame)
