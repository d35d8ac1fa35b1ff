"""
One PlanSequence request against one snapshot: the ROS-level checks, then the core.

This is the service's logic without the ROS graph: the node calls it with a
snapshot of its subscriptions and parameters, ``punctured-planner plan`` calls
it offline with a parameter file. The checks here are only the ROS-level ones,
in the priority order of the error codes (the smallest code wins):

1. NO_CONFIGURATIONS, 2. NO_ROBOT_STATE, 3. REQUEST_OVER_LIMITS (from list
lengths, before any conversion or allocation), 4. INVALID_REQUEST,
5. ROBOT_COUNT_MISMATCH, 6. NON_FINITE_VALUE, 7. FRAME_MISMATCH, 8. OFF_PLANE;
then the core's own checks (9 OBSTACLES_DEGENERATE, 10 ROBOTS_COINCIDE,
11 ROBOT_ON_OBSTACLE, 12 CLEARANCE_BELOW_REQUIRED). The finiteness check runs
here, before the frame and plane checks, because its code comes first and in
planar mode the core never sees z.
"""

from collections import OrderedDict
from dataclasses import dataclass
import math
import re
import threading
import time
from typing import Any

import numpy as np

from . import conversions
from .core import (ErrorCode, first_out_of_range, MAX_COORDINATE, plan as core_plan,
                   PlanningError, SCHEDULES, Workspace)
from .core.plan import Plan
from .parameters import MAX_SAMPLES_PER_LEG, Settings

# Largest |z - plane_z| accepted in planar mode (m).
PLANE_TOLERANCE = 1e-9
# builtin_interfaces/Time holds int32 seconds: no stamp may reach 2^31 s.
_LAST_STAMP_NS = (2 ** 31 - 1) * 1000000000
_AXES = 'xyz'


def format_stamp(ns: int) -> str:
    """Return integer nanoseconds as exact seconds, 'S.NNNNNNNNN' (no float rounding)."""
    seconds, nanoseconds = divmod(int(ns), 1000000000)
    return '%d.%09d' % (seconds, nanoseconds)


@dataclass(frozen=True, eq=False)
class ObstacleSet:
    """The obstacles of a snapshot: (r, 3) points, their frame and where they came from."""

    points: np.ndarray
    frame_id: str = ''
    source: str = 'parameter'
    stamp_ns: int = 0

    @property
    def origin(self) -> str:
        """Return where the set came from, as messages say it: 'the parameter', 'topic /x'."""
        return 'the parameter' if self.source == 'parameter' else 'topic ' + self.source

    def describe(self) -> str:
        """Return a short text for the log: count, source and stamp."""
        if self.source == 'parameter':
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

    def describe(self) -> str:
        """Return a short text for the log: robots, source and stamp."""
        return '%d robots from %s (stamp %s)' % (
            len(self.positions), self.source, format_stamp(self.stamp_ns))


@dataclass(frozen=True)
class Snapshot:
    """Everything one request is planned against, taken at once under the node's lock."""

    settings: Settings
    obstacles: ObstacleSet
    state: RobotState | None = None
    state_problem: str = 'no robot state received yet (topic robot_states)'

    def describe(self) -> str:
        """Return the log line of the snapshot."""
        state = self.state.describe() if self.state is not None else 'no robot state'
        return '%s; %s' % (self.obstacles.describe(), state)


@dataclass
class Outcome:
    """The answer to one request: the filled response and, on success, the plan."""

    response: Any
    plan: Plan | None = None
    paths: list | None = None
    names: list[str] | None = None
    start_ns: int = 0
    max_speed: float = 0.0
    exception: BaseException | None = None
    dropped: list[int] | None = None  # request configurations that repeated the state
    plan_id: int = 0  # the id the node published the plan under (0: not published)

    @property
    def ok(self) -> bool:
        """Return whether the request was planned (error_code NONE)."""
        return self.response.error_code == ErrorCode.NONE


@dataclass(frozen=True, eq=False)
class Gathered:
    """A request's inputs from list lengths and options alone (step 1, nothing converted)."""

    configurations: list
    state: RobotState | None
    counts: list[int]
    max_speed: float
    samples_per_leg: int

    def label(self, m: int) -> str:
        """
        Return how every message names configuration m (0-based, the state first).

        With use_current_state, configuration 0 is the state (named with its
        source) and configuration m is the request's configurations[m - 1].
        """
        if self.state is None:
            return 'configuration %d' % m
        if m == 0:
            return 'configuration 0 (the current robot state from %s)' % self.state.source
        return 'configuration %d (request configurations[%d])' % (m, m - 1)


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


def _point(point):
    return '(%s)' % ', '.join('%.6g' % v for v in np.asarray(point, dtype=float).tolist())


def _check_poses(settings, robot_count, breakpoints, samples):
    """REQUEST_OVER_LIMITS when robot_count paths through breakpoints would pass max_poses."""
    poses = robot_count * ((breakpoints - 1) * (samples + 1) + 1)
    if poses > settings.max_poses:
        _fail(ErrorCode.REQUEST_OVER_LIMITS, 'the answer would hold %d poses (%d robots x '
              '%d poses), more than max_poses %d' % (poses, robot_count,
                                                     poses // max(robot_count, 1),
                                                     settings.max_poses))


def _fail(code, message, configuration=None, robots=(), obstacle=None):
    raise PlanningError(code, message, configuration=configuration, robots=robots,
                        obstacle=obstacle)


class PlanSequenceHandler:
    """
    Answers PlanSequence requests; keeps the last few Workspaces (one per obstacle set).

    :meth:`handle` runs named steps that return values, as nav2's computePlan:
    gather (lengths and options), check (conversions and the ROS-level checks),
    plan (the core) and answer (paths and response). Every PlanningError they
    raise becomes the response's error code in one place, :meth:`handle`.
    """

    def __init__(self, cache_size: int = 4) -> None:
        """Create an empty workspace cache."""
        self._cache: OrderedDict = OrderedDict()
        self._cache_size = cache_size
        self._lock = threading.Lock()

    def workspace(self, settings: Settings, obstacles: np.ndarray) -> Workspace:
        """
        Return the Workspace for planar/3-D obstacles (r, d) and the settings (cached).

        The frame is fixed per obstacle set and options, so equal obstacle sets
        give the same Workspace object (and the same domains). Raises PlanningError.
        """
        obstacles = np.ascontiguousarray(obstacles, dtype=float)
        key = (obstacles.shape, obstacles.tobytes(), settings.dimension, settings.core_variant,
               settings.lane_spacing, settings.min_spacing, settings.required_clearance,
               settings.robot_radius, settings.obstacle_radius)
        with self._lock:
            found = self._cache.get(key)
            if found is not None:
                self._cache.move_to_end(key)
                return found
        workspace = Workspace(obstacles, dimension=settings.dimension,
                              lane_spacing=settings.lane_spacing,
                              variant=settings.core_variant, min_spacing=settings.min_spacing,
                              required_clearance=settings.required_clearance,
                              robot_radius=settings.robot_radius,
                              obstacle_radius=settings.obstacle_radii(len(obstacles)))
        with self._lock:
            self._cache[key] = workspace
            while len(self._cache) > self._cache_size:
                self._cache.popitem(last=False)
        return workspace

    def handle(self, request: Any, response: Any, snapshot: Snapshot,
               now_ns: int) -> Outcome:
        """
        Answer ``request`` against ``snapshot``; return an Outcome (never raises).

        now_ns is the request time; the paths start at now_ns + planning time.
        Unexpected exceptions become error_code UNKNOWN with their message (and
        are kept in Outcome.exception for the log).
        """
        started = time.perf_counter()
        gathered = checked = None
        try:
            gathered = self._gather(request, snapshot, now_ns)
            checked = self._check(gathered, snapshot)
            the_plan = self._plan(checked, snapshot)
            return self._answer(response, gathered, checked, the_plan, snapshot.settings,
                                now_ns, started)
        except PlanningError as error:
            message = self._message(error, gathered, checked, snapshot.obstacles)
            conversions.fill_error(response, error.code, message,
                                   time.perf_counter() - started, error.clearance, error.gap)
            return Outcome(response=response)
        except Exception as error:  # any bug becomes UNKNOWN, the node serves on
            conversions.fill_error(response, ErrorCode.UNKNOWN,
                                   'internal error: %s: %s' % (type(error).__name__, error),
                                   time.perf_counter() - started)
            return Outcome(response=response, exception=error)

    def check_obstacles(self, settings: Settings, obstacles: ObstacleSet) -> None:
        """
        Raise PlanningError if an obstacle set cannot be planned in, naming the obstacle.

        The node calls this when a set arrives, so a bad set is refused at once
        and the previous good set stays; requests run the same checks again.
        """
        _check_non_finite(None, obstacles, None)
        _check_frames(settings, None, (), obstacles, None)
        _check_plane(settings, None, obstacles, None)
        _check_range(settings, (), obstacles, None)
        try:
            self.workspace(settings, conversions.leading_coordinates(obstacles.points,
                                                                     settings.dimension))
        except PlanningError as error:
            raise PlanningError(error.code, _name_obstacles(str(error.args[0]), obstacles),
                                obstacle=error.obstacle) from None

    def _message(self, error, gathered, checked, obstacles):
        """Return a PlanningError's message, with the culprits named the one way."""
        message = str(error.args[0]) if error.args else error.code.name
        if error.code < ErrorCode.OBSTACLES_DEGENERATE or gathered is None:
            return message
        # The core's own checks number the planned configurations and name
        # obstacles by index: say which configuration and which obstacle.
        planned = checked.planned if checked is not None else list(
            range(len(gathered.counts)))
        message = re.sub(r'\bconfiguration (\d+)',
                         lambda found: gathered.label(planned[int(found.group(1))]), message)
        message = re.sub(r'C_(\d+)', lambda found: 'C_%d' % (
            planned[int(found.group(1)) - 1] + 1), message)
        return _name_obstacles(message, obstacles)

    def _gather(self, request, snapshot, now_ns):
        """Step 1: the inputs from list lengths and options; codes 1-4 that need no values."""
        settings = snapshot.settings
        configurations = list(request.configurations)
        use_state = bool(request.use_current_state)
        state = snapshot.state if use_state else None
        n = len(configurations) + (1 if use_state else 0)
        if n < 2:
            _fail(ErrorCode.NO_CONFIGURATIONS,
                  'need at least 2 configurations in total, got %d (%d in the request%s)'
                  % (n, len(configurations), ' + the current state' if use_state else ''))
        if use_state and state is None:
            _fail(ErrorCode.NO_ROBOT_STATE,
                  'use_current_state is set but ' + snapshot.state_problem)
        if state is not None and settings.max_state_age > 0:
            age = (int(now_ns) - state.received_ns) * 1e-9
            if age > settings.max_state_age:
                _fail(ErrorCode.NO_ROBOT_STATE, 'use_current_state is set but the robot state '
                      'from %s is %.3f s old (received at %s, stamp %s), more than '
                      'max_state_age %g s' % (state.source, age, format_stamp(state.received_ns),
                                              format_stamp(state.stamp_ns),
                                              settings.max_state_age))
        counts = ([len(state.positions)] if state is not None else []) + [
            len(c.poses) for c in configurations]
        samples = (request.samples_per_leg if request.samples_per_leg >= 0
                   else settings.samples_per_leg)
        self._check_limits(settings, n, counts, samples)
        max_speed = request.max_speed
        if not math.isfinite(max_speed):
            _fail(ErrorCode.INVALID_REQUEST, 'max_speed must be finite, got %r' % max_speed)
        gathered = Gathered(configurations, state, counts,
                            max_speed if max_speed > 0 else settings.max_speed, samples)
        for m, count in enumerate(counts):
            if count == 0:
                _fail(ErrorCode.INVALID_REQUEST, '%s has no robots' % gathered.label(m),
                      configuration=m)
        return gathered

    def _check(self, gathered, snapshot):
        """Step 2: convert the poses; the range, count, finiteness, frame and plane checks."""
        settings = snapshot.settings
        state = gathered.state
        arrays = ([state.positions] if state is not None else []) + [
            conversions.pose_array_positions(c) for c in gathered.configurations]
        _check_range(settings, arrays, snapshot.obstacles, gathered.label)
        _check_counts(settings, gathered)
        positions = np.stack(arrays)
        orientations = np.stack(
            ([state.orientations] if state is not None else [])
            + [conversions.pose_array_orientations(c) for c in gathered.configurations])
        frames = ([state.frame_id] if state is not None else []) + [
            c.header.frame_id for c in gathered.configurations]
        label, obstacles = gathered.label, snapshot.obstacles
        _check_non_finite(positions, obstacles, label)
        _check_frames(settings, positions, frames, obstacles, label)
        _check_plane(settings, positions, obstacles, label)
        planned = list(range(len(positions)))
        if state is not None:
            planned = _without_repeats(settings, positions, gathered)
        dropped = [m - 1 for m in range(1, len(positions)) if m not in planned]
        return Checked(positions[planned], orientations[planned], planned, dropped)

    def _plan(self, checked, snapshot):
        """Step 3: the core's certified plan of the planned coordinates."""
        d = snapshot.settings.dimension
        workspace = self.workspace(snapshot.settings,
                                   conversions.leading_coordinates(snapshot.obstacles.points, d))
        return core_plan(workspace, conversions.leading_coordinates(checked.positions, d),
                         refine=snapshot.settings.refine)

    def _answer(self, response, gathered, checked, the_plan, settings, now_ns, started):
        """Step 4: stamps, paths and the filled response; return the Outcome."""
        planning_time = time.perf_counter() - started
        start_ns = int(now_ns) + int(round(planning_time * 1e9))
        max_speed = gathered.max_speed
        # The plan's own breakpoints: the refinement's knots add to any schedule's.
        _check_poses(settings, gathered.counts[0], len(the_plan.times), gathered.samples_per_leg)
        self._check_duration(the_plan, max_speed, start_ns)
        samples = the_plan.sample(gathered.samples_per_leg, max_speed)
        paths = conversions.plan_to_paths(samples, checked.orientations, settings.frame_id,
                                          start_ns, settings.plane_z)
        conversions.fill_response(response, the_plan, paths, planning_time, max_speed,
                                  samples.waypoints, checked.dropped)
        return Outcome(response=response, plan=the_plan, paths=paths,
                       names=conversions.robot_names(settings.robot_names, gathered.counts[0]),
                       start_ns=start_ns, max_speed=max_speed, dropped=checked.dropped)

    @staticmethod
    def _check_limits(settings, n, counts, samples):
        """REQUEST_OVER_LIMITS from lengths alone, before anything is converted."""
        if n > settings.max_configurations:
            _fail(ErrorCode.REQUEST_OVER_LIMITS, '%d configurations, more than '
                  'max_configurations %d' % (n, settings.max_configurations))
        k = max(counts)
        if k > settings.max_robots:
            m = counts.index(k)
            _fail(ErrorCode.REQUEST_OVER_LIMITS, 'configuration %d has %d robots, more than '
                  'max_robots %d' % (m, k, settings.max_robots), configuration=m)
        if samples > MAX_SAMPLES_PER_LEG:
            _fail(ErrorCode.REQUEST_OVER_LIMITS, 'samples_per_leg %d is more than %d'
                  % (samples, MAX_SAMPLES_PER_LEG))
        schedule = SCHEDULES.get(settings.core_variant)
        # The construction's breakpoints, fewer than the refined plan's: an early refusal
        # before planning; the answer's own count is checked once planned ('discs' has
        # no fixed legs, so only then).
        if schedule is not None:
            _check_poses(settings, k, schedule.breakpoint_count(n), samples)

    @staticmethod
    def _check_duration(the_plan, max_speed, start_ns):
        """
        INVALID_REQUEST when the motion's stamps do not fit builtin_interfaces/Time.

        Time and Duration carry int32 seconds: the last stamp must come before
        2038-01-19 and the duration must stay below 2^31 s. Known only once the
        plan's length is, so checked after planning.
        """
        with np.errstate(over='ignore', divide='ignore', invalid='ignore'):
            duration = the_plan.duration(max_speed)
        if not (math.isfinite(duration) and start_ns + duration * 1e9 < _LAST_STAMP_NS):
            _fail(ErrorCode.INVALID_REQUEST, 'the motion would last %.6g s at max_speed %.6g '
                  'm/s: its stamps would pass the largest builtin_interfaces/Time '
                  '(2038-01-19T03:14:07Z); raise max_speed' % (duration, max_speed))


def _name_obstacles(message, obstacles):
    """Return message with each 'obstacle(s) j' named with its position and source."""
    def name(found):
        numbers = re.findall(r'\d+', found.group('which'))
        return ' and '.join(obstacles.name(int(j)) for j in numbers)
    return re.sub(r'\b(?P<which>obstacles? \d+(?: and \d+)?)(?: at \[[^\]]*\])?', name,
                  message)


def _check_range(settings, arrays, obstacles, label):
    """
    INVALID_REQUEST for a finite coordinate beyond the core's range (+-1e15).

    The core checks this too, but only after codes 5-8; here it keeps the
    documented priority. Only the d coordinates the core plans in count (in
    planar mode z has its own check, OFF_PLANE); non-finite values are
    NON_FINITE_VALUE.
    """
    d = settings.dimension
    for m, points in enumerate(arrays):
        far = first_out_of_range(points[:, :d])
        if far is not None:
            robot, axis = far
            _fail(ErrorCode.INVALID_REQUEST, '%s, robot %d: %s = %.6g is beyond the '
                  'supported range +-%.0e' % (label(m), robot, _AXES[axis],
                                              float(points[far]), MAX_COORDINATE),
                  configuration=m, robots=[robot])
    far = first_out_of_range(obstacles.points[:, :d])
    if far is not None:
        j, axis = far
        _fail(ErrorCode.INVALID_REQUEST, 'obstacle %d (from %s): %s = %.6g is beyond the '
              'supported range +-%.0e' % (j, obstacles.origin, _AXES[axis],
                                          float(obstacles.points[far]), MAX_COORDINATE),
              obstacle=j)


def _check_counts(settings, gathered):
    """
    ROBOT_COUNT_MISMATCH, blaming the configuration that differs from the reference.

    The reference is the node's robot_count (or robot_names) when set, else
    configuration 0: so a state message with the wrong count is the one named.
    """
    counts, label = gathered.counts, gathered.label
    expected = settings.expected_robot_count
    if expected:
        what = ('the %d robot_names' % expected if settings.robot_names
                else 'robot_count %d' % expected)
        for m, count in enumerate(counts):
            if count != expected:
                _fail(ErrorCode.ROBOT_COUNT_MISMATCH, '%s has %d robots but the node is '
                      'configured for %s' % (label(m), count, what), configuration=m)
    for m, count in enumerate(counts):
        if count != counts[0]:
            _fail(ErrorCode.ROBOT_COUNT_MISMATCH, '%s has %d robots, %s has %d'
                  % (label(m), count, label(0), counts[0]), configuration=m)


def _check_non_finite(positions, obstacles, label):
    """NON_FINITE_VALUE: the robots' coordinates (when given), then the obstacles'."""
    bad = conversions.first_non_finite(positions) if positions is not None else None
    if bad is not None:
        m, robot, axis = bad
        _fail(ErrorCode.NON_FINITE_VALUE, '%s, robot %d: %s is %r'
              % (label(m), robot, _AXES[axis], float(positions[bad])),
              configuration=m, robots=[robot])
    bad = conversions.first_non_finite(obstacles.points)
    if bad is not None:
        _fail(ErrorCode.NON_FINITE_VALUE, 'obstacle %d (from %s): %s is %r'
              % (bad[0], obstacles.origin, _AXES[bad[1]], float(obstacles.points[bad])),
              obstacle=bad[0])


def _check_frames(settings, positions, frames, obstacles, label):
    """FRAME_MISMATCH: the configurations' frames (when given), then the obstacles'."""
    for m, frame_id in enumerate(frames):
        if frame_id and frame_id != settings.frame_id:
            _fail(ErrorCode.FRAME_MISMATCH, "%s is in frame '%s', the planning frame is "
                  "'%s'" % (label(m), frame_id, settings.frame_id), configuration=m)
    if obstacles.frame_id and obstacles.frame_id != settings.frame_id:
        _fail(ErrorCode.FRAME_MISMATCH, "the obstacles (from %s) are in frame '%s', the "
              "planning frame is '%s'" % (obstacles.origin, obstacles.frame_id,
                                          settings.frame_id))


def _check_plane(settings, positions, obstacles, label):
    """OFF_PLANE in planar mode: the robots (when given), then the obstacles."""
    if settings.dimension != 2:
        return
    if positions is not None:
        off = np.abs(positions[..., 2] - settings.plane_z) > PLANE_TOLERANCE
        if off.any():
            m, robot = (int(i) for i in np.argwhere(off)[0])
            _fail(ErrorCode.OFF_PLANE, '%s, robot %d: z = %r but plane_z is %r (dimension 2)'
                  % (label(m), robot, float(positions[m, robot, 2]), settings.plane_z),
                  configuration=m, robots=[robot])
    off = np.abs(obstacles.points[:, 2] - settings.plane_z) > PLANE_TOLERANCE
    if off.any():
        j = int(np.argmax(off))
        _fail(ErrorCode.OFF_PLANE, 'obstacle %d (from %s): z = %r but plane_z is %r '
              '(dimension 2)' % (j, obstacles.origin, float(obstacles.points[j, 2]),
                                 settings.plane_z), obstacle=j)


def _without_repeats(settings, positions, gathered):
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
        _fail(ErrorCode.NO_CONFIGURATIONS, 'every request configuration repeats the current '
              'robot state from %s within repeat_tolerance %g m: the robots are already '
              'there, nothing to plan' % (gathered.state.source, settings.repeat_tolerance))
    return [0] + list(range(first + 1, len(positions)))
