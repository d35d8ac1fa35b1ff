"""
Every conversion between ROS messages and the core's numpy arrays, in one place.

The node, the ``punctured-planner`` command and the MCAP writer all use these
functions, so a plan looks the same on a topic, in a service response and in
a recording; the nodes fill every message they publish with the builders
here. The RViz markers are in :mod:`punctured_planner.ros.markers`, the list
of published messages in :mod:`punctured_planner.ros.publications`.

Conventions:

* Inputs are 3-D points (x, y, z). In planar mode (dimension 2) the core sees
  (x, y) and outputs get z = plane_z back.
* Paths: one nav_msgs/Path per robot; every breakpoint of the plan is a pose
  (linear interpolation between consecutive poses is exactly the certified
  motion), with ``samples_per_leg`` extra poses evenly spaced inside every
  leg, and no pose twice: the end of a leg in which no robot moves is left
  out (the core's Plan.sample), so stamps strictly increase. All robots'
  paths share the same stamps: start + the time parameterisation at
  max_speed (each leg lasts long enough that its fastest robot moves at
  max_speed) and, when set, the planner's max_acceleration (the speed
  profile of doc/design.md section 8; the Plan message carries both).
* Orientation rule: at waypoint C_m a robot has the orientation of its input
  pose in C_m; between C_m and C_{m+1} it holds the orientation of C_m (the
  last waypoint passed). A zero-length or non-finite input quaternion counts
  as the identity; others are normalised.
* Messages built in bulk are *filled in place*: rosidl's generated classes keep
  field f in slot ``_f`` (beside ``_check_fields``), and their constructor
  builds a default for every nested message first; for the k x M poses of a
  plan that churn was most of the time spent building the response. So those
  builders create the object bare and set its slots, with values that already
  have the field types (floats, messages); test_conversions compares the
  results with constructed messages.
"""

from collections.abc import Iterable
from collections.abc import Sequence
from dataclasses import dataclass
import math

from builtin_interfaces.msg import Duration
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point
from geometry_msgs.msg import Pose
from geometry_msgs.msg import PoseArray
from geometry_msgs.msg import PoseStamped
from geometry_msgs.msg import Quaternion
from geometry_msgs.msg import Twist
from geometry_msgs.msg import Vector3
from nav_msgs.msg import Odometry
from nav_msgs.msg import Path
import numpy as np
import numpy.typing as npt
from punctured_planner_interfaces.msg import Plan
from punctured_planner_interfaces.srv import PlanSequence
from std_msgs.msg import Header
from std_msgs.msg import UInt32

from .cdr import Paths
from .cdr import PathValues
from .goals import InvalidPlan
from .goals import KnownPlan
from .parameters import ros_names
from .settings import PlannerSettings
from .snapshot import Outcome
from .snapshot import RobotOdometry
from .. import core
from ..core.limits import first_non_finite
from ..core.timing import tracking_tolerance
from ..execution import Bodies
from ..execution import Reference

IDENTITY = (0.0, 0.0, 0.0, 1.0)


# ---------------------------------------------------------------- messages -> arrays

def pose_array_positions(msg: PoseArray) -> np.ndarray:
    """Return the positions of a geometry_msgs/PoseArray as a (k, 3) float array."""
    return np.array([(p.position.x, p.position.y, p.position.z) for p in msg.poses],
                    dtype=float).reshape(-1, 3)


def pose_array_poses(msg: PoseArray) -> tuple[np.ndarray, np.ndarray]:
    """Return (positions (k, 3), orientations (k, 4): x, y, z, w) of a PoseArray."""
    return pose_arrays_poses([msg])


def pose_arrays_poses(messages: Iterable[PoseArray]) -> tuple[np.ndarray, np.ndarray]:
    """
    Return (positions (N, 3), orientations (N, 4)) of the poses of PoseArrays, in their order.

    Every request's poses come through here, all its configurations in one array
    (one conversion, not one per configuration); the fields are read from their
    slots (``_x`` for x, as the messages filled in place have them: module
    docstring), half the time of their properties.
    """
    rows = []
    for msg in messages:
        for p in msg.poses:
            position, orientation = p._position, p._orientation
            rows.append((position._x, position._y, position._z,
                         orientation._x, orientation._y, orientation._z, orientation._w))
    values = np.array(rows, dtype=float).reshape(-1, 7)
    return values[:, :3], values[:, 3:]


@dataclass(frozen=True)
class PoseValues:
    """A pose as arrays: position (3,) and orientation (4,) quaternion x, y, z, w."""

    position: np.ndarray
    orientation: np.ndarray


def odometry_pose(msg: Odometry) -> PoseValues:
    """Return the pose of a nav_msgs/Odometry message."""
    pose = msg.pose.pose
    return PoseValues(
        np.array([pose.position.x, pose.position.y, pose.position.z], dtype=float),
        np.array([pose.orientation.x, pose.orientation.y, pose.orientation.z,
                  pose.orientation.w], dtype=float))


def robot_odometry(msg: Odometry, received_ns: int) -> RobotOdometry:
    """Return the RobotOdometry of a nav_msgs/Odometry message that arrived at received_ns."""
    pose = odometry_pose(msg)
    linear = msg.twist.twist.linear
    speed = math.hypot(linear.x, linear.y, linear.z)
    # a twist that is not finite says nothing: as none reported (its pose still counts)
    return RobotOdometry(pose.position, pose.orientation, msg.header.frame_id,
                         stamp_to_ns(msg.header.stamp), int(received_ns),
                         speed if math.isfinite(speed) else 0.0)


def obstacles_from_parameter(values: npt.ArrayLike) -> np.ndarray:
    """Return the obstacles parameter (flat x, y, z per obstacle) as an (r, 3) array."""
    return np.asarray(values, dtype=float).reshape(-1, 3)


def obstacles_from_pose_array(msg: PoseArray) -> np.ndarray:
    """Return the obstacles of a PoseArray (positions; orientations ignored) as (r, 3)."""
    return pose_array_positions(msg)


def stamp_to_ns(stamp: Time) -> int:
    """Return a builtin_interfaces/Time as integer nanoseconds."""
    return int(stamp.sec) * 1000000000 + int(stamp.nanosec)


def leading_coordinates(points: npt.ArrayLike, dimension: int) -> np.ndarray:
    """Return the first ``dimension`` coordinates of (..., 3) points: the core's input."""
    return np.ascontiguousarray(np.asarray(points, dtype=float)[..., :dimension])


def to_xyz(points: npt.ArrayLike, plane_z: float = 0.0) -> np.ndarray:
    """Return (..., d) points as (..., 3): z = plane_z for d = 2 (d must be 2 or 3)."""
    points = np.asarray(points, dtype=float)
    if points.shape[-1] == 3:
        return points
    xyz = np.empty(points.shape[:-1] + (3,))
    xyz[..., :2], xyz[..., 2] = points, plane_z
    return xyz


# Norms between these come from squares that neither overflow nor lose precision below
# the smallest normal float.
_SMALLEST_SAFE_NORM, _LARGEST_SAFE_NORM = 1e-150, 1e150


def normalized_quaternions(quaternions: npt.ArrayLike) -> np.ndarray:
    """Return (..., 4) quaternions normalised; zero-length or non-finite ones -> identity."""
    quaternions = np.asarray(quaternions, dtype=float)
    with np.errstate(invalid='ignore', over='ignore', under='ignore'):
        # np.linalg.norm's own sum of squares, without its Python wrapper (a request's
        # orientations are a few dozen values): a unit quaternion comes back bit for bit.
        norms = np.sqrt(np.add.reduce(quaternions * quaternions, axis=-1, keepdims=True))
        # A finite one whose squares overflow (1e200) or underflow (1e-170) is scaled by
        # its largest component first, not taken for a non-finite or zero one.
        extreme = ~((norms > _SMALLEST_SAFE_NORM) & (norms < _LARGEST_SAFE_NORM))
        if extreme.any():  # rare: a received plan's 2 M poses took 0.31 s, not 0.11 s
            largest = np.abs(quaternions).max(axis=-1, keepdims=True)
            scale = np.where(extreme & (largest > 0) & np.isfinite(largest), largest, 1.0)
            quaternions = quaternions / scale
            norms = np.where(extreme, np.sqrt(np.add.reduce(
                quaternions * quaternions, axis=-1, keepdims=True)), norms)
        good = np.isfinite(norms) & (norms > 0)
        result = np.where(good, quaternions / np.where(good, norms, 1.0), IDENTITY)
    return result


# ---------------------------------------------------------------- time

def time_from_ns(ns: int) -> Time:
    """
    Return builtin_interfaces/Time for integer nanoseconds (>= 0).

    Filled in place (module docstring): every stamp of every path is one
    (Time's constructor costs five times as much).
    """
    stamp = object.__new__(Time)
    stamp._sec, stamp._nanosec = divmod(int(ns), 1000000000)
    stamp._check_fields = False
    return stamp


def duration_from_seconds(seconds: float) -> Duration:
    """
    Return builtin_interfaces/Duration for a finite number of seconds (rounded to ns).

    Filled in place, as :func:`time_from_ns`: two of them in every response.
    """
    duration = object.__new__(Duration)
    duration._sec, duration._nanosec = divmod(int(round(float(seconds) * 1e9)), 1000000000)
    duration._check_fields = False
    return duration


def duration_to_seconds(duration: Duration) -> float:
    """Return a builtin_interfaces/Duration as seconds (from its integer nanoseconds)."""
    return stamp_to_ns(duration) * 1e-9


# ---------------------------------------------------------------- arrays -> messages

def robot_names(configured_names: Iterable[str], robot_count: int) -> list[str]:
    """Return the robots' names: the configured ones, or robot_0..robot_{k-1}."""
    if configured_names:
        return list(configured_names)
    return ['robot_%d' % i for i in range(robot_count)]


def stamps_ns(start_ns: int, seconds: npt.ArrayLike) -> np.ndarray:
    """
    Return (M,) integer stamps start_ns + seconds, strictly increasing.

    Seconds round to the nearest nanosecond; where two would round to the
    same one (a leg shorter than a nanosecond of motion), the later is put
    1 ns after the earlier.
    """
    offsets = np.rint(np.asarray(seconds) * 1e9).astype(np.int64)
    steps = np.arange(offsets.size, dtype=np.int64)
    return int(start_ns) + np.maximum.accumulate(offsets - steps) + steps


def plan_to_paths(samples: core.Samples, orientations: npt.ArrayLike, frame_id: str,
                  start_ns: int, plane_z: float = 0.0) -> Paths:
    """
    Return one nav_msgs/Path per robot for a plan's Samples (see the module docstring).

    orientations (n, k, 4) are the input orientations at the waypoints; start_ns
    the stamp of the first pose. samples is ``plan.sample(samples_per_leg,
    max_speed, max_acceleration)``: no pose twice, C_m exactly at
    ``samples.waypoints[m]``.
    Built once, for the response and the topics alike: a :class:`Paths` of the
    messages (all paths share one Header object per stamp, and one as their own
    header, so their stamps are identical by construction, and each robot one
    Quaternion per waypoint; each message is filled in place (module
    docstring), its slots set one by one: a keyword loop per pose cost as much
    as the rest) and the same values
    serialised with numpy on first use.
    """
    xyz = to_xyz(samples.positions, plane_z).transpose(1, 0, 2)
    quaternions = normalized_quaternions(orientations).transpose(1, 0, 2)
    stamps = stamps_ns(start_ns, samples.values)
    waypoint = samples.last_waypoint()
    headers = [header(frame_id, stamp) for stamp in stamps.tolist()]
    path_header = header(frame_id, start_ns)
    held_at = waypoint.tolist()
    new = object.__new__
    paths = []
    for robot_xyz, robot_quaternions in zip(xyz.tolist(), quaternions.tolist()):
        held = []
        for qx, qy, qz, qw in robot_quaternions:
            quaternion = new(Quaternion)
            quaternion._x, quaternion._y, quaternion._z, quaternion._w = qx, qy, qz, qw
            quaternion._check_fields = False
            held.append(quaternion)
        poses = []
        for pose_header, (x, y, z), m in zip(headers, robot_xyz, held_at):
            point = new(Point)
            point._x, point._y, point._z, point._check_fields = x, y, z, False
            pose = new(Pose)
            pose._position, pose._orientation = point, held[m]
            pose._check_fields = False
            stamped = new(PoseStamped)
            stamped._header, stamped._pose, stamped._check_fields = pose_header, pose, False
            poses.append(stamped)
        path = new(Path)
        path._header, path._poses, path._check_fields = path_header, poses, False
        paths.append(path)
    return Paths(paths, PathValues(frame_id, start_ns, stamps, xyz, quaternions, waypoint))


def header(frame_id: str, stamp_ns: int) -> Header:
    """
    Return a std_msgs/Header in frame_id (a str) at integer nanoseconds.

    Filled in place (as :func:`time_from_ns`): Header's constructor would first
    build a default Time only to replace it, for every stamp of every path.
    """
    message = object.__new__(Header)
    message._frame_id, message._stamp = frame_id, time_from_ns(stamp_ns)
    message._check_fields = False
    return message


def point_list(xyz: npt.ArrayLike) -> list[Point]:
    """
    Return geometry_msgs/Points of (N, 3) values, each filled in place (module docstring).

    The markers draw every breakpoint of every robot: Point's constructor, with
    its keyword handling and checks, cost most of their building.
    """
    new = object.__new__
    result = []
    for x, y, z in np.asarray(xyz, dtype=float).tolist():
        point = new(Point)
        point._x, point._y, point._z, point._check_fields = x, y, z, False
        result.append(point)
    return result


def pose(position: npt.ArrayLike, orientation: npt.ArrayLike = IDENTITY) -> Pose:
    """Return a geometry_msgs/Pose at position (3,) with orientation (x, y, z, w)."""
    x, y, z = np.asarray(position, dtype=float).tolist()
    qx, qy, qz, qw = np.asarray(orientation, dtype=float).tolist()
    return Pose(position=Point(x=x, y=y, z=z), orientation=Quaternion(x=qx, y=qy, z=qz, w=qw))


def pose_stamped(stamp_header: Header, position: npt.ArrayLike,
                 orientation: npt.ArrayLike = IDENTITY) -> PoseStamped:
    """Return a geometry_msgs/PoseStamped with a shared Header."""
    return PoseStamped(header=stamp_header, pose=pose(position, orientation))


def vector3(values: npt.ArrayLike) -> Vector3:
    """Return a geometry_msgs/Vector3 of a (3,) array."""
    x, y, z = np.asarray(values, dtype=float).tolist()
    return Vector3(x=x, y=y, z=z)


def twist(linear: npt.ArrayLike = (0.0, 0.0, 0.0), yaw_rate: float = 0.0) -> Twist:
    """Return a geometry_msgs/Twist of linear velocity (3,) and angular z: zero by default."""
    return Twist(linear=vector3(linear), angular=Vector3(z=float(yaw_rate)))


def odometry(stamp_header: Header, child_frame_id: str, position: npt.ArrayLike,
             velocity: npt.ArrayLike, orientation: npt.ArrayLike = IDENTITY,
             yaw_rate: float = 0.0) -> Odometry:
    """Return a nav_msgs/Odometry: pose position (3,), orientation; twist velocity (3,), yaw."""
    message = Odometry(header=stamp_header, child_frame_id=child_frame_id)
    message.pose.pose = pose(position, orientation)
    message.twist.twist = twist(velocity, yaw_rate)
    return message


def domain_index_message(plan: core.Plan) -> UInt32:
    """Return the std_msgs/UInt32 domain index of a plan."""
    return UInt32(data=int(plan.domain_index))


def empty_path(frame_id: str, stamp_ns: int) -> Path:
    """Return a nav_msgs/Path with no poses: 'no current plan' for a robot."""
    return Path(header=header(frame_id, stamp_ns))


# ---------------------------------------------------------------- the response

def fill_response(response: PlanSequence.Response, plan: core.Plan, paths: Sequence[Path],
                  planning_time: float, duration: float, waypoints: npt.ArrayLike,
                  dropped: Iterable[int] = ()) -> PlanSequence.Response:
    """Fill every field of a PlanSequence response from a successful plan lasting duration s."""
    response.error_code = 0
    response.error_msg = ''
    response.domain_index = int(plan.domain_index)
    response.domain_count = int(plan.domain_count)
    response.sequential_complexity = int(plan.sequential_complexity or 0)
    response.optimal = bool(plan.optimal)
    response.projection_counts = [int(c) for c in np.asarray(plan.projection_counts).tolist()]
    response.min_clearance = float(plan.min_clearance)
    response.min_gap = float(plan.min_gap)
    response.planning_time = duration_from_seconds(planning_time)
    response.duration = duration_from_seconds(duration)
    response.paths = paths
    response.waypoint_indices = [int(i) for i in np.asarray(waypoints).tolist()]
    response.dropped_configurations = [int(m) for m in dropped]
    response.tracking_tolerance = plan.tracking_tolerance
    return response


def fill_error(response: PlanSequence.Response, code: int, message: str,
               planning_time: float = 0.0, clearance: core.Clearance | None = None,
               gap: core.Clearance | None = None) -> PlanSequence.Response:
    """
    Fill a PlanSequence response for a refused request (no plan, no paths).

    Every plan field is reset, so a failure after a partial fill leaves nothing
    behind; a refused plan's certificates (clearance, gap) still report what it had.
    """
    response.error_code = int(code)
    response.error_msg = str(message)
    response.domain_index = response.domain_count = response.sequential_complexity = 0
    response.optimal = False
    response.projection_counts = []
    response.min_clearance = float(clearance.distance) if clearance is not None else 0.0
    response.min_gap = float(gap.distance) if gap is not None else 0.0
    response.planning_time = duration_from_seconds(planning_time)
    response.duration = Duration()
    response.paths = []
    response.waypoint_indices = []
    response.dropped_configurations = []
    response.plan_id = 0
    response.tracking_tolerance = 0.0
    return response


# ---------------------------------------------------------------- the plan for execution

def plan_message(outcome: Outcome, settings: PlannerSettings) -> Plan:
    """
    Return the punctured_planner_interfaces/Plan of a successful Outcome (topic ``plan``).

    The bodies are the workspace's (robot radius, obstacles and their radii); the
    tracking tolerance is the plan's, as in the response (Plan.tracking_tolerance:
    min_gap and the walls' gap; the walls are not in the message, their gap is in
    the tolerance).
    """
    planned = outcome.planned()
    plan = planned.plan
    workspace = plan.workspace
    obstacles = [Point(x=x, y=y, z=z) for x, y, z in
                 to_xyz(workspace.obstacles, settings.plane_z).reshape(-1, 3).tolist()]
    return Plan(plan_id=int(outcome.plan_id), robot_names=list(planned.names),
                paths=list(planned.paths), max_speed=float(outcome.max_speed),
                max_acceleration=float(outcome.max_acceleration),
                robot_radius=float(workspace.robot_radius), obstacles=obstacles,
                obstacle_radii=np.asarray(workspace.obstacle_radii, dtype=float).tolist(),
                min_gap=float(plan.min_gap),
                tracking_tolerance=float(plan.tracking_tolerance))


@dataclass(frozen=True)
class PathPoses:
    """A Path's poses as arrays: stamps ns (M,), positions (M, 3), orientations (M, 4)."""

    stamps: np.ndarray
    positions: np.ndarray
    orientations: np.ndarray


def path_arrays(path: Path) -> PathPoses:
    """Return the stamps, positions and orientations of a Path's poses."""
    rows = [(stamp_to_ns(p.header.stamp), p.pose.position.x, p.pose.position.y,
             p.pose.position.z, p.pose.orientation.x, p.pose.orientation.y,
             p.pose.orientation.z, p.pose.orientation.w) for p in path.poses]
    stamps = np.array([row[0] for row in rows], dtype=np.int64)
    values = np.array([row[1:] for row in rows], dtype=float).reshape(-1, 7)
    return PathPoses(stamps, values[:, :3], values[:, 3:])


def plan_reference(msg: Plan) -> Reference:
    """
    Return the execution.Reference of a Plan message (seconds from its first stamp).

    Raises InvalidPlan, naming the plan and the robot, unless the message is a
    plan: one path per robot, the robots' names unique ROS names (each names
    its topics), every pose (position and orientation) finite, one frame and one
    clock (the same stamps on every path, at least two, strictly increasing) and numbers
    a plan can have (plan_numbers).
    """
    plan_id = int(msg.plan_id)
    plan_numbers(msg)
    if len(msg.robot_names) != len(msg.paths):
        raise InvalidPlan(plan_id, 'paths', ' has %d robot_names and %d paths, one per robot'
                          % (len(msg.robot_names), len(msg.paths)))
    try:
        ros_names('robot_names', tuple(msg.robot_names))
    except ValueError as error:  # worded 'robot_names ...'
        raise InvalidPlan(plan_id, 'robot_names', ': %s' % error) from None
    arrays = [path_arrays(path) for path in msg.paths]
    stamps = [a.stamps for a in arrays]
    if not stamps or stamps[0].size < 2:
        count = stamps[0].size if stamps else 0
        raise InvalidPlan(plan_id, 'paths', ' has %s per path, a motion at least 2'
                          % core.errors.counted(count, 'pose'))
    frame = msg.paths[0].header.frame_id
    for name, message, path in zip(msg.robot_names, msg.paths, arrays):
        if message.header.frame_id != frame:
            raise InvalidPlan(plan_id, 'paths', ': the path of %s is in frame %r, that of %s '
                              'in %r: one frame for all' % (name, message.header.frame_id,
                                                            msg.robot_names[0], frame),
                              robot=name)
        if not np.array_equal(path.stamps, stamps[0]):
            raise InvalidPlan(plan_id, 'paths', ': the path of %s does not have the stamps '
                              'of %s' % (name, msg.robot_names[0]), robot=name)
        bad = first_non_finite(np.hstack([path.positions, path.orientations]))
        if bad is not None:
            raise InvalidPlan(plan_id, 'paths', ': the path of %s has a non-finite pose '
                              '(pose %d)' % (name, bad[0]), robot=name, pose=bad[0])
    back = np.flatnonzero(np.diff(stamps[0]) <= 0)
    if back.size:
        raise InvalidPlan(plan_id, 'paths', ': its stamps do not increase at pose %d of %d'
                          % (back[0] + 1, stamps[0].size), pose=int(back[0] + 1))
    seconds = (stamps[0] - stamps[0][0]) * 1e-9
    positions = np.stack([a.positions for a in arrays], axis=1)
    orientations = normalized_quaternions(np.stack([a.orientations for a in arrays], axis=1))
    return Reference.timed(seconds, positions, orientations, float(msg.max_speed),
                           float(msg.max_acceleration), float(msg.tracking_tolerance))


def plan_numbers(msg: Plan) -> None:
    """
    Raise InvalidPlan, naming the field, unless a Plan's numbers are ones a plan has.

    max_speed finite and > 0, max_acceleration and robot_radius finite and >= 0,
    min_gap a number, and tracking_tolerance at most min_gap / 2 (a larger one
    let robots touch while the clock ran on; NaN or inf limits gave NaN references).
    """
    speed, acceleration = float(msg.max_speed), float(msg.max_acceleration)
    radius, gap, tolerance = (float(msg.robot_radius), float(msg.min_gap),
                              float(msg.tracking_tolerance))
    for name, value, low, strict in (('max_speed', speed, 0.0, True),
                                     ('max_acceleration', acceleration, 0.0, False),
                                     ('robot_radius', radius, 0.0, False)):
        if not (np.isfinite(value) and (value > low if strict else value >= low)):
            raise InvalidPlan(int(msg.plan_id), name, ': %s is %r, not a finite number %s 0'
                              % (name, value, '>' if strict else '>='))
    if np.isnan(gap):
        raise InvalidPlan(int(msg.plan_id), 'min_gap', ': min_gap is not a number')
    if not tolerance <= tracking_tolerance(gap, np.inf):
        raise InvalidPlan(int(msg.plan_id), 'tracking_tolerance',
                          ': tracking_tolerance %r is more than min_gap / 2 (min_gap %r)'
                          % (tolerance, gap))


def plan_bodies(msg: Plan) -> Bodies:
    """
    Return the execution.Bodies of a Plan message (robot radius, obstacles and radii).

    Raises InvalidPlan unless there is one radius per obstacle.
    """
    obstacles = np.array([(p.x, p.y, p.z) for p in msg.obstacles], dtype=float).reshape(-1, 3)
    radii = np.asarray(msg.obstacle_radii, dtype=float).reshape(-1)
    if radii.size != len(obstacles):
        raise InvalidPlan(int(msg.plan_id), 'obstacle_radii',
                          ' has %d obstacle_radii for %d obstacles, one per obstacle'
                          % (radii.size, len(obstacles)))
    return Bodies(float(msg.robot_radius), obstacles, radii)


def known_plan(msg: Plan) -> KnownPlan:
    """Return the KnownPlan of a Plan message; raise InvalidPlan for a message that is none."""
    reference = plan_reference(msg)
    return KnownPlan(int(msg.plan_id), tuple(msg.robot_names), msg.paths[0].header.frame_id,
                     reference, plan_bodies(msg), float(msg.min_gap),
                     float(msg.tracking_tolerance))
