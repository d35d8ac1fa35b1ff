"""
The inputs a node keeps and one request is planned against: obstacles, robot state, odometry.

ROS-free records of what came in on topics and parameters (:class:`ObstacleSet`,
:class:`RobotState`, :class:`RobotOdometry`), the :class:`Snapshot` of them one
request is planned against, and the :class:`Outcome` of a request.
"""

from dataclasses import dataclass
from typing import Any

import numpy as np

from .cdr import Paths
from .settings import PlannerSettings
from .topics import ODOM
from .topics import robot_topic
from ..core import ErrorCode
from ..core import Plan


def format_stamp(ns: int) -> str:
    """Return integer nanoseconds as exact seconds, 'S.NNNNNNNNN' (no float rounding)."""
    seconds, nanoseconds = divmod(int(ns), 1000000000)
    return '%d.%09d' % (seconds, nanoseconds)


# ObstacleSet.source of the obstacles parameter's set (else the topic's name).
PARAMETER = 'parameter'


def in_other_frame(frame_id: str, planning_frame: str) -> bool:
    """
    Return whether an input's frame_id names a frame other than the planning frame.

    An empty frame_id is the planning frame: there is no TF lookup, so an input in
    another frame is refused, never transformed.
    """
    return bool(frame_id) and frame_id != planning_frame


def missing_state(missing: list[str] | tuple = ()) -> str:
    """Return why a snapshot has no robot state: nothing on robot_states, nor from missing."""
    odometry = (', or odometry from %s' % ', '.join(robot_topic(n, ODOM) for n in missing)
                if missing else '')
    return 'no robot state received yet (topic robot_states%s)' % odometry


@dataclass(frozen=True, eq=False)
class ObstacleSet:
    """The obstacles of a snapshot: (r, 3) points, their frame and where they came from."""

    points: np.ndarray
    frame_id: str = ''
    source: str = PARAMETER
    stamp_ns: int = 0

    @property
    def from_parameter(self) -> bool:
        """Return whether the set is the obstacles parameter's (else a topic's)."""
        return self.source == PARAMETER

    @property
    def origin(self) -> str:
        """Return where the set came from, as messages say it: 'the parameter', 'topic /x'."""
        return 'the parameter' if self.from_parameter else 'topic ' + self.source

    def describe(self) -> str:
        """Return a short text for the log: count, source and stamp."""
        if self.from_parameter:
            return '%d obstacles from the parameter (set at %s)' % (
                len(self.points), format_stamp(self.stamp_ns))
        return '%d obstacles from topic %s (stamp %s)' % (
            len(self.points), self.source, format_stamp(self.stamp_ns))

    def name(self, j: int) -> str:
        """Return how messages name obstacle j: index, position and source."""
        return 'obstacle %d at %s (from %s)' % (j, _point(self.points[j]), self.origin)


@dataclass(frozen=True, eq=False)
class RobotState:
    """The current robot state: positions (k, 3), orientations (k, 4), frame, stamp, source."""

    positions: np.ndarray
    orientations: np.ndarray
    frame_id: str = ''
    stamp_ns: int = 0
    source: str = 'robot_states'
    received_ns: int = 0  # node clock when it arrived (the oldest robot's, for odometry)
    # From odometry (robot_names): whose each position is, and its frame and arrival, so a
    # refusal names the robot at fault (empty from robot_states)
    robots: tuple[str, ...] = ()
    frames: tuple[str, ...] = ()
    arrivals_ns: tuple[int, ...] = ()

    def describe(self) -> str:
        """Return a short text for the log: robots, source and stamp."""
        return '%d robots from %s (stamp %s)' % (
            len(self.positions), self.source, format_stamp(self.stamp_ns))


@dataclass(frozen=True)
class Snapshot:
    """Everything one request is planned against, taken at once under the node's lock."""

    settings: PlannerSettings
    obstacles: ObstacleSet
    state: RobotState | None = None
    state_problem: str = missing_state()

    def describe(self) -> str:
        """Return the log line of the snapshot."""
        state = self.state.describe() if self.state is not None else 'no robot state'
        return '%s; %s' % (self.obstacles.describe(), state)


@dataclass(frozen=True, eq=False)
class Planned:
    """What a planned request made: the core's plan, the robots' Paths and their names."""

    plan: Plan
    paths: Paths
    names: list[str]


@dataclass
class Outcome:
    """The answer to one request: the filled response and, on success, the plan."""

    response: Any
    plan: Plan | None = None
    paths: Paths | None = None
    names: list[str] | None = None
    start_ns: int = 0
    max_speed: float = 0.0
    max_acceleration: float = 0.0  # the stamps' acceleration limit (0: unlimited)
    exception: BaseException | None = None
    plan_id: int = 0  # the id the node published the plan under (0: not published)

    @property
    def ok(self) -> bool:
        """Return whether the request was planned (error_code NONE)."""
        return self.response.error_code == ErrorCode.NONE

    def planned(self) -> Planned:
        """Return what a planned request made; ValueError for one that was not planned."""
        if self.plan is None or self.paths is None or self.names is None:
            raise ValueError('the request was not planned (error_code %d): no plan to publish'
                             % self.response.error_code)
        return Planned(self.plan, self.paths, self.names)


@dataclass(frozen=True, eq=False)
class RobotOdometry:
    """
    The last odometry of one robot: pose, frame, stamp and arrival time (node clock).

    speed: its twist's linear speed (m/s, in any frame; 0 where the twist is not finite).
    """

    position: np.ndarray
    orientation: np.ndarray
    frame_id: str
    stamp_ns: int
    received_ns: int
    speed: float

    def problem(self) -> str:
        """Return why the pose is no pose to track ('' when it is one)."""
        if not np.isfinite(self.position).all():
            return 'its position %s is not finite' % _point(self.position)
        if not (np.isfinite(self.orientation).all() and self.orientation.any()):
            return 'its orientation %s is no rotation' % _point(self.orientation)
        return ''


def take_snapshot(settings: PlannerSettings, obstacles: ObstacleSet,
                  robot_states: RobotState | None,
                  odometry: dict[str, RobotOdometry]) -> Snapshot:
    """
    Return the Snapshot of the node's inputs; its robot state the newer of two sources.

    The sources are the last ``robot_states`` message and, when robot_names is
    set, every named robot's last odometry (complete once each has reported;
    as old as its oldest message; its frame the first that differs from the
    planning frame, so the frame check names it).
    """
    candidates = [robot_states] if robot_states is not None else []
    names = settings.robot_names
    missing = [name for name in names if name not in odometry]
    if names and not missing:
        entries = [odometry[name] for name in names]
        frames = [e.frame_id for e in entries]
        frame = next((f for f in frames if in_other_frame(f, settings.frame_id)), frames[0])
        candidates.append(RobotState(
            np.stack([e.position for e in entries]),
            np.stack([e.orientation for e in entries]), frame,
            min(e.stamp_ns for e in entries), 'odometry of %s' % ', '.join(names),
            min(e.received_ns for e in entries), tuple(names), tuple(frames),
            tuple(e.received_ns for e in entries)))
    if candidates:
        return Snapshot(settings, obstacles,
                        max(candidates, key=lambda state: state.received_ns), '')
    return Snapshot(settings, obstacles, None, missing_state(missing))


def _point(point):
    return '(%s)' % ', '.join('%.6g' % v for v in np.asarray(point, dtype=float).tolist())
