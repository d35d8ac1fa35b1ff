"""
The ROS-level checks of a PlanSequence request, in the priority order of the error codes.

1. NO_CONFIGURATIONS, 2. NO_ROBOT_STATE, 3. REQUEST_OVER_LIMITS (from list
lengths, before any conversion or allocation), 4. INVALID_REQUEST,
5. ROBOT_COUNT_MISMATCH, 6. NON_FINITE_VALUE, 7. FRAME_MISMATCH, 8. OFF_PLANE;
the core's own checks come after (9-13), and two of the answer's, once
planned: REQUEST_OVER_LIMITS for the plan's own pose count and INVALID_REQUEST
for stamps past 2038 (check_poses, check_duration). The finiteness check runs here,
before the frame and plane checks, because its code comes first and in
planar mode the core never sees z. Each raises a PlanningError with its
culprits as data; :mod:`punctured_planner.ros.wording` names them.
"""

import bisect
from dataclasses import dataclass
import itertools
import math
from typing import Any
from typing import Callable

import numpy as np

from . import conversions
from .settings import MAX_SAMPLES_PER_LEG
from .settings import MAX_SPEED
from .settings import PlannerSettings
from .snapshot import format_stamp
from .snapshot import in_other_frame
from .snapshot import ObstacleSet
from .snapshot import RobotState
from .snapshot import Snapshot
from ..core import ErrorCode
from ..core import first_out_of_range
from ..core import MAX_COORDINATE
from ..core import PlanningError
from ..core.errors import axis_name
from ..core.errors import literal
from ..core.limits import first_non_finite

# Largest |z - plane_z| accepted in planar mode (m).
PLANE_TOLERANCE = 1e-9
# builtin_interfaces/Time holds int32 seconds: no stamp may reach 2^31 s.
_LAST_STAMP_NS = (2 ** 31 - 1) * 1000000000


@dataclass(frozen=True, eq=False)
class Gathered:
    """A request's inputs from list lengths and options alone (step 1, nothing converted)."""

    configurations: list
    state: RobotState | None
    counts: list[int]
    max_speed: float
    samples_per_leg: int

    def label(self, m: int) -> str:
        """Return how every message names configuration m (configuration_label)."""
        return configuration_label(self.state, m)


def configuration_label(state: RobotState | None, m: int) -> str:
    """
    Return how every message names configuration m (0-based, the state first).

    With use_current_state (state given), configuration 0 is the state (named
    with its source) and configuration m is the request's configurations[m - 1].
    """
    if state is None:
        return 'configuration %d' % m
    if m == 0:
        return 'configuration 0 (the current robot state from %s)' % state.source
    return 'configuration %d (request configurations[%d])' % (m, m - 1)


def requested_state(request: Any, snapshot: Snapshot) -> RobotState | None:
    """Return the robot state a request plans from: with use_current_state, the snapshot's."""
    return snapshot.state if request.use_current_state else None


@dataclass(frozen=True, eq=False)
class Checked:
    """
    The converted, checked inputs (step 2).

    positions (n, k, 3) and orientations (n, k, 4) of the configurations that
    are planned; ``planned[i]`` is the configuration number (as labelled) of
    the i-th of them, and ``dropped`` the request indices left out because
    they repeat the current state (doc/design.md section 12).
    """

    positions: np.ndarray
    orientations: np.ndarray
    planned: list[int]
    dropped: list[int]


def fail(code: ErrorCode, message: str, **culprits: Any) -> None:
    """Raise a PlanningError whose message is free text (no slots) and the culprits."""
    raise PlanningError(code, literal(message), **culprits)


def gather(request: Any, snapshot: Snapshot, now_ns: int) -> Gathered:
    """Step 1: the inputs from list lengths and options; codes 1-4 that need no values."""
    settings = snapshot.settings
    configurations = list(request.configurations)
    use_state = bool(request.use_current_state)
    state = requested_state(request, snapshot)
    n = len(configurations) + (1 if use_state else 0)
    if n < 2:
        fail(ErrorCode.NO_CONFIGURATIONS,
             'need at least 2 configurations in total, got %d (%d in the request%s)'
             % (n, len(configurations), ' + the current state' if use_state else ''))
    if use_state and state is None:
        fail(ErrorCode.NO_ROBOT_STATE, 'use_current_state is set but ' + snapshot.state_problem)
    if state is not None:
        _check_state_age(settings, state, now_ns)
    counts = ([len(state.positions)] if state is not None else []) + [
        len(c.poses) for c in configurations]
    samples = (request.samples_per_leg if request.samples_per_leg >= 0
               else settings.samples_per_leg)
    _check_limits(settings, n, counts, samples)
    max_speed = request.max_speed
    if not (math.isfinite(max_speed) and max_speed <= MAX_SPEED):
        fail(ErrorCode.INVALID_REQUEST, 'max_speed must be finite and at most %g m/s (the '
             "max_speed parameter's range), got %r" % (MAX_SPEED, max_speed))
    for m, count in enumerate(counts):
        if count == 0:
            raise PlanningError(ErrorCode.INVALID_REQUEST, '{configuration} has no robots',
                                configuration=m)
    return Gathered(configurations, state, counts,
                    max_speed if max_speed > 0 else settings.max_speed, samples)


def _check_state_age(settings: PlannerSettings, state: RobotState, now_ns: int) -> None:
    """
    NO_ROBOT_STATE when the state is older than max_state_age (0: no limit).

    A state from odometry is as old as its oldest robot's: the robots too old are named.
    """
    age = (int(now_ns) - state.received_ns) * 1e-9
    if settings.max_state_age > 0 and age > settings.max_state_age:
        ages = [(name, (int(now_ns) - arrival) * 1e-9)
                for name, arrival in zip(state.robots, state.arrivals_ns)]
        old = ' and '.join('%s (%.3f s old)' % (name, robot_age) for name, robot_age in ages
                           if robot_age > settings.max_state_age)
        fail(ErrorCode.NO_ROBOT_STATE, 'use_current_state is set but the robot state from %s '
             'is %.3f s old (received at %s, stamp %s), more than max_state_age %g s%s'
             % (state.source, age, format_stamp(state.received_ns),
                format_stamp(state.stamp_ns), settings.max_state_age,
                ': the odometry of ' + old if old else ''))


def _check_limits(settings: PlannerSettings, n: int, counts: list[int], samples: int) -> None:
    """
    REQUEST_OVER_LIMITS from lengths alone, before anything is converted.

    Not max_poses: an answer's pose count is known only once planned (check_poses),
    as legs in which no robot moves add none, and with use_current_state leading
    configurations that repeat the state are dropped (_check_fewest_poses bounds it
    once converted).
    """
    if n > settings.max_configurations:
        fail(ErrorCode.REQUEST_OVER_LIMITS, '%d configurations, more than '
             'max_configurations %d' % (n, settings.max_configurations))
    k = max(counts)
    if k > settings.max_robots:
        m = counts.index(k)
        raise PlanningError(ErrorCode.REQUEST_OVER_LIMITS, '{configuration} has %d robots, '
                            'more than max_robots %d' % (k, settings.max_robots),
                            configuration=m)
    if samples > MAX_SAMPLES_PER_LEG:
        fail(ErrorCode.REQUEST_OVER_LIMITS, 'samples_per_leg %d is more than %d'
             % (samples, MAX_SAMPLES_PER_LEG))


def check_poses(settings: PlannerSettings, robot_count: int, breakpoints: int,
                samples: int) -> None:
    """REQUEST_OVER_LIMITS when robot_count paths through breakpoints would pass max_poses."""
    poses = robot_count * ((breakpoints - 1) * (samples + 1) + 1)
    if poses > settings.max_poses:
        fail(ErrorCode.REQUEST_OVER_LIMITS, 'the answer would hold %d poses (%d robots x '
             '%d poses), more than max_poses %d' % (poses, robot_count,
                                                    poses // max(robot_count, 1),
                                                    settings.max_poses))


def check_duration(duration: float, at_speed_alone: Callable[[], float], max_speed: float,
                   max_acceleration: float, start_ns: int) -> None:
    """
    INVALID_REQUEST when the motion's stamps do not fit builtin_interfaces/Time.

    Time and Duration carry int32 seconds: the last stamp must come before
    2038-01-19 and the duration must stay below 2^31 s. Known only once the
    plan's length is, so checked after planning. The message names the limit to
    raise: max_acceleration where the motion at max_speed alone (at_speed_alone(),
    computed for a refusal only) would fit.
    """
    def fits(seconds: float) -> bool:
        return math.isfinite(seconds) and start_ns + seconds * 1e9 < _LAST_STAMP_NS

    if fits(duration):
        return
    if max_acceleration > 0 and fits(at_speed_alone()):
        limits, culprit = ('max_speed %.6g m/s and max_acceleration %.6g m/s^2'
                           % (max_speed, max_acceleration), 'max_acceleration')
    else:
        limits, culprit = 'max_speed %.6g m/s' % max_speed, 'max_speed'
    fail(ErrorCode.INVALID_REQUEST, 'the motion would last %.6g s at %s: its stamps would '
         'pass the largest builtin_interfaces/Time (2038-01-19T03:14:07Z); raise %s'
         % (duration, limits, culprit))


def check(gathered: Gathered, snapshot: Snapshot) -> Checked:
    """Step 2: convert the poses; the range, count, finiteness, frame and plane checks."""
    settings, obstacles, state = snapshot.settings, snapshot.obstacles, gathered.state
    # Every configuration's poses in one (N, 3) and one (N, 4) array, the state's first.
    positions, orientations = conversions.pose_arrays_poses(gathered.configurations)
    if state is not None:
        positions = np.concatenate([state.positions, positions])
        orientations = np.concatenate([state.orientations, orientations])
    _check_range(settings, positions, gathered.counts)
    check_obstacle_range(settings, obstacles)
    _check_counts(settings, gathered)
    n = len(gathered.counts)  # each of them with counts[0] robots, as just checked
    positions, orientations = positions.reshape(n, -1, 3), orientations.reshape(n, -1, 4)
    frames = ([state.frame_id] if state is not None else []) + [
        c.header.frame_id for c in gathered.configurations]
    _check_non_finite(positions)
    check_obstacle_values(obstacles)
    _check_frames(settings, frames, state)
    check_obstacle_frame(settings, obstacles)
    _check_plane(settings, positions)
    check_obstacle_plane(settings, obstacles)
    planned = list(range(len(positions)))
    if state is not None:
        planned = _without_repeats(settings, positions, state)
    dropped = [m - 1 for m in range(1, len(positions)) if m not in planned]
    if dropped:
        positions, orientations = positions[planned], orientations[planned]
    _check_fewest_poses(settings, positions, gathered.samples_per_leg)
    return Checked(positions, orientations, planned, dropped)


def _check_fewest_poses(settings: PlannerSettings, positions: np.ndarray,
                        samples: int) -> None:
    """
    REQUEST_OVER_LIMITS before planning when no answer through positions fits max_poses.

    A segment between two configurations that differ has a leg in which some robot
    moves, so the answer has at least one breakpoint more for it (a leg in which none
    moves adds none): a bound no answer stays under, unlike the variants' fixed legs,
    which refused answers that fit. The exact count is checked once planned.
    """
    moved = int(np.any(np.diff(positions, axis=0) != 0, axis=(1, 2)).sum())
    check_poses(settings, positions.shape[1], moved + 1, samples)


def _check_range(settings: PlannerSettings, points: np.ndarray, counts: list[int]) -> None:
    """
    INVALID_REQUEST for a finite coordinate beyond the core's range (+-1e15).

    points (N, 3) are every configuration's robots in order, counts[m] of them
    in configuration m. The core checks this too, but only after codes 5-8;
    here it keeps the documented priority. Only the d coordinates the core
    plans in count (in planar mode z has its own check, OFF_PLANE); non-finite
    values are NON_FINITE_VALUE.
    """
    far = first_out_of_range(points[:, :settings.dimension])
    if far is None:
        return
    row, axis = far
    ends = list(itertools.accumulate(counts))
    m = bisect.bisect_right(ends, row)  # the first offender's configuration, then its robot
    robot = row - (ends[m - 1] if m else 0)
    raise PlanningError(
        ErrorCode.INVALID_REQUEST, '{configuration}, {robot}: %s = %.6g is beyond '
        'the supported range +-%.0e' % (axis_name(axis), float(points[far]), MAX_COORDINATE),
        configuration=m, robots=[robot], coordinate=axis)


def check_obstacle_range(settings: PlannerSettings, obstacles: ObstacleSet) -> None:
    """INVALID_REQUEST for an obstacle coordinate beyond the core's range."""
    far = first_out_of_range(obstacles.points[:, :settings.dimension])
    if far is not None:
        j, axis = far
        value = float(obstacles.points[far])
        raise PlanningError(ErrorCode.INVALID_REQUEST, '{obstacle}: %s = %.6g is beyond the '
                            'supported range +-%.0e' % (axis_name(axis), value, MAX_COORDINATE),
                            obstacle=j, coordinate=axis)


def _check_counts(settings: PlannerSettings, gathered: Gathered) -> None:
    """
    ROBOT_COUNT_MISMATCH, blaming the configuration that differs from the reference.

    The reference is the node's robot_count (or robot_names) when set, else
    configuration 0: so a state message with the wrong count is the one named.
    """
    counts = gathered.counts
    expected = settings.expected_robot_count
    if expected:
        what = ('the %d robot_names' % expected if settings.robot_names
                else 'robot_count %d' % expected)
        for m, count in enumerate(counts):
            if count != expected:
                raise PlanningError(ErrorCode.ROBOT_COUNT_MISMATCH, '{configuration} has %d '
                                    'robots but the node is configured for %s' % (count, what),
                                    configuration=m)
    for m, count in enumerate(counts):
        if count != counts[0]:
            raise PlanningError(ErrorCode.ROBOT_COUNT_MISMATCH, '{configuration} has %d '
                                'robots, %s has %d' % (count, literal(gathered.label(0)),
                                                       counts[0]), configuration=m)


def _check_non_finite(positions: np.ndarray) -> None:
    """NON_FINITE_VALUE in the robots' coordinates."""
    bad = first_non_finite(positions)
    if bad is not None:
        m, robot, axis = bad
        raise PlanningError(ErrorCode.NON_FINITE_VALUE, '{configuration}, {robot}: %s is %r'
                            % (axis_name(axis), float(positions[bad])),
                            configuration=m, robots=[robot], coordinate=axis)


def check_obstacle_values(obstacles: ObstacleSet) -> None:
    """NON_FINITE_VALUE in the obstacles' coordinates."""
    bad = first_non_finite(obstacles.points)
    if bad is not None:
        raise PlanningError(ErrorCode.NON_FINITE_VALUE, '{obstacle}: %s is %r'
                            % (axis_name(bad[1]), float(obstacles.points[bad])),
                            obstacle=bad[0], coordinate=bad[1])


def _check_frames(settings: PlannerSettings, frames: list[str],
                  state: RobotState | None) -> None:
    """
    FRAME_MISMATCH: a configuration in a frame other than the planning frame.

    A state from odometry (configuration 0) names the robots whose odometry is in another.
    """
    for m, frame_id in enumerate(frames):
        if in_other_frame(frame_id, settings.frame_id):
            whose = [] if m or state is None else [
                name for name, frame in zip(state.robots, state.frames)
                if in_other_frame(frame, settings.frame_id)]
            raise PlanningError(ErrorCode.FRAME_MISMATCH, "{configuration} is in frame '%s'%s, "
                                "the planning frame is '%s'"
                                % (literal(frame_id),
                                   literal(' (the odometry of %s)' % ', '.join(whose))
                                   if whose else '', literal(settings.frame_id)),
                                configuration=m)


def check_obstacle_frame(settings: PlannerSettings, obstacles: ObstacleSet) -> None:
    """FRAME_MISMATCH: obstacles in a frame other than the planning frame."""
    if in_other_frame(obstacles.frame_id, settings.frame_id):
        fail(ErrorCode.FRAME_MISMATCH, "the obstacles (from %s) are in frame '%s', the "
             "planning frame is '%s'" % (obstacles.origin, obstacles.frame_id,
                                         settings.frame_id))


def _check_plane(settings: PlannerSettings, positions: np.ndarray) -> None:
    """OFF_PLANE in planar mode: a robot off the plane z = plane_z."""
    if settings.dimension != 2:
        return
    off = np.abs(positions[..., 2] - settings.plane_z) > PLANE_TOLERANCE
    if off.any():
        m, robot = (int(i) for i in np.argwhere(off)[0])
        raise PlanningError(ErrorCode.OFF_PLANE, '{configuration}, {robot}: z = %r but '
                            'plane_z is %r (dimension 2)' % (float(positions[m, robot, 2]),
                                                             settings.plane_z),
                            configuration=m, robots=[robot], coordinate=2)


def check_obstacle_plane(settings: PlannerSettings, obstacles: ObstacleSet) -> None:
    """OFF_PLANE in planar mode: an obstacle off the plane z = plane_z."""
    if settings.dimension != 2:
        return
    off = np.abs(obstacles.points[:, 2] - settings.plane_z) > PLANE_TOLERANCE
    if off.any():
        j = int(np.argmax(off))
        raise PlanningError(ErrorCode.OFF_PLANE, '{obstacle}: z = %r but plane_z is %r '
                            '(dimension 2)' % (float(obstacles.points[j, 2]), settings.plane_z),
                            obstacle=j, coordinate=2)


def _without_repeats(settings: PlannerSettings, positions: np.ndarray,
                     state: RobotState) -> list[int]:
    """
    Return the configuration numbers to plan: the state, then the request without repeats.

    Leading request configurations that repeat the current state are left out
    (doc/design.md section 12).

    A request configuration repeats the state when every robot is within
    repeat_tolerance of its current position (in the planned coordinates).
    Raise NO_CONFIGURATIONS when the whole request repeats the state.
    """
    d = settings.dimension
    planar = positions[..., :d]
    distances = np.linalg.norm(planar[1:] - planar[0], axis=2).max(axis=1)
    repeats = distances <= settings.repeat_tolerance
    first = int(np.argmin(repeats)) if not repeats.all() else len(repeats)
    if first == len(repeats):
        fail(ErrorCode.NO_CONFIGURATIONS, 'every request configuration repeats the current '
             'robot state from %s within repeat_tolerance %g m: the robots are already '
             'there, nothing to plan' % (state.source, settings.repeat_tolerance))
    return [0] + list(range(first + 1, len(positions)))
