"""
Every conversion between ROS messages and the core's numpy arrays, in one place.

The node, the ``punctured-planner`` command and the MCAP writer all use these
functions, so a plan looks the same on a topic, in a service response and in
a recording.

Conventions:

* Inputs are 3-D points (x, y, z). In planar mode (dimension 2) the core sees
  (x, y) and outputs get z = plane_z back.
* Paths: one nav_msgs/Path per robot; every breakpoint of the plan is a pose
  (linear interpolation between consecutive poses is exactly the certified
  motion), with ``samples_per_leg`` extra poses evenly spaced inside every
  leg. All robots' paths share the same stamps: start + the time
  parameterisation at max_speed (each leg lasts long enough that its fastest
  robot moves at max_speed).
* Orientation rule: at waypoint C_m a robot has the orientation of its input
  pose in C_m; between C_m and C_{m+1} it holds the orientation of C_m (the
  last waypoint passed). A zero-length or non-finite input quaternion counts
  as the identity; others are normalised.
"""

from builtin_interfaces.msg import Duration
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Point
from geometry_msgs.msg import PoseStamped
from geometry_msgs.msg import Vector3
from nav_msgs.msg import Path
import numpy as np
from std_msgs.msg import ColorRGBA
from std_msgs.msg import Header
from std_msgs.msg import UInt32
from visualization_msgs.msg import Marker
from visualization_msgs.msg import MarkerArray

IDENTITY = (0.0, 0.0, 0.0, 1.0)
# Colours of the robots in the markers (RGB, matplotlib's tab10).
PALETTE = (
    (0.122, 0.467, 0.706), (1.000, 0.498, 0.055), (0.173, 0.627, 0.173),
    (0.839, 0.153, 0.157), (0.580, 0.404, 0.741), (0.549, 0.337, 0.294),
    (0.890, 0.467, 0.761), (0.498, 0.498, 0.498), (0.737, 0.741, 0.133),
    (0.090, 0.745, 0.812),
)


# ---------------------------------------------------------------- messages -> arrays

def pose_array_positions(msg):
    """Return the positions of a geometry_msgs/PoseArray as a (k, 3) float array."""
    return np.array([(p.position.x, p.position.y, p.position.z) for p in msg.poses],
                    dtype=float).reshape(-1, 3)


def pose_array_orientations(msg):
    """Return the orientations of a PoseArray as a (k, 4) array of (x, y, z, w)."""
    return np.array([(p.orientation.x, p.orientation.y, p.orientation.z, p.orientation.w)
                     for p in msg.poses], dtype=float).reshape(-1, 4)


def configurations_to_arrays(pose_arrays):
    """Return (positions (n, k, 3), orientations (n, k, 4)) of equally long PoseArrays."""
    positions = np.stack([pose_array_positions(msg) for msg in pose_arrays])
    orientations = np.stack([pose_array_orientations(msg) for msg in pose_arrays])
    return positions, orientations


def odometry_pose(msg):
    """Return (position (3,), orientation (4,)) of a nav_msgs/Odometry message."""
    pose = msg.pose.pose
    return (np.array([pose.position.x, pose.position.y, pose.position.z], dtype=float),
            np.array([pose.orientation.x, pose.orientation.y, pose.orientation.z,
                      pose.orientation.w], dtype=float))


def obstacles_from_parameter(values):
    """Return the obstacles parameter (flat x, y, z per obstacle) as an (r, 3) array."""
    return np.asarray(values, dtype=float).reshape(-1, 3)


def obstacles_from_pose_array(msg):
    """Return the obstacles of a PoseArray (positions; orientations ignored) as (r, 3)."""
    return pose_array_positions(msg)


def stamp_to_ns(stamp):
    """Return a builtin_interfaces/Time as integer nanoseconds."""
    return int(stamp.sec) * 1000000000 + int(stamp.nanosec)


def first_non_finite(values):
    """Return the index tuple of the first non-finite entry of an array, or None."""
    bad = np.argwhere(~np.isfinite(values))
    return tuple(int(i) for i in bad[0]) if bad.size else None


def planar(points, dimension):
    """Return the first ``dimension`` coordinates of (..., 3) points: the core's input."""
    return np.ascontiguousarray(np.asarray(points, dtype=float)[..., :dimension])


def to_xyz(points, plane_z=0.0):
    """Return (..., d) points as (..., 3): z = plane_z for d = 2 (d must be 2 or 3)."""
    points = np.asarray(points, dtype=float)
    if points.shape[-1] == 3:
        return points
    return np.concatenate([points, np.full(points.shape[:-1] + (1,), float(plane_z))],
                          axis=-1)


def normalized_quaternions(quaternions):
    """Return (..., 4) quaternions normalised; zero-length or non-finite ones -> identity."""
    quaternions = np.asarray(quaternions, dtype=float)
    with np.errstate(invalid='ignore', over='ignore'):
        norms = np.linalg.norm(quaternions, axis=-1, keepdims=True)
        good = np.isfinite(norms) & (norms > 0)
        result = np.where(good, quaternions / np.where(good, norms, 1.0), IDENTITY)
    return result


# ---------------------------------------------------------------- time

def time_from_ns(ns):
    """Return builtin_interfaces/Time for integer nanoseconds (>= 0)."""
    ns = int(ns)
    return Time(sec=ns // 1000000000, nanosec=ns % 1000000000)


def duration_from_seconds(seconds):
    """Return builtin_interfaces/Duration for a finite number of seconds (rounded to ns)."""
    ns = int(round(float(seconds) * 1e9))
    return Duration(sec=ns // 1000000000, nanosec=ns % 1000000000)


# ---------------------------------------------------------------- arrays -> messages

def robot_names(configured_names, robot_count):
    """Return the robots' names: the configured ones, or robot_0..robot_{k-1}."""
    if configured_names:
        return list(configured_names)
    return ['robot_%d' % i for i in range(robot_count)]


def path_samples(plan, max_speed, samples_per_leg):
    """
    Return (seconds (M,), positions (M, k, d), waypoint (M,)) of the published poses.

    Every breakpoint is a sample; ``waypoint[j]`` is the index m of the last
    configuration C_m passed at sample j (the orientation rule).
    """
    seconds, positions, _ = plan.sample(samples_per_leg, max_speed=max_speed)
    step = max(int(samples_per_leg), 0) + 1
    waypoint_samples = np.asarray(plan.waypoint_indices) * step
    waypoint = np.searchsorted(waypoint_samples, np.arange(seconds.size), side='right') - 1
    return seconds, positions, waypoint


def plan_to_paths(plan, orientations, frame_id, start_ns, max_speed, samples_per_leg,
                  plane_z=0.0):
    """
    Return one nav_msgs/Path per robot for ``plan`` (see the module docstring).

    orientations (n, k, 4) are the input orientations at the waypoints; start_ns
    the stamp of the first pose. All paths share one Header object per stamp, so
    their stamps are identical by construction.
    """
    seconds, positions, waypoint = path_samples(plan, max_speed, samples_per_leg)
    xyz = to_xyz(positions, plane_z)
    quaternions = normalized_quaternions(orientations)
    offsets = np.rint(seconds * 1e9).astype(np.int64)
    headers = [Header(frame_id=frame_id, stamp=time_from_ns(start_ns + int(offset)))
               for offset in offsets]
    xyz_list = xyz.transpose(1, 0, 2).tolist()
    held = quaternions[waypoint].transpose(1, 0, 2).tolist()
    paths = []
    for robot_xyz, robot_held in zip(xyz_list, held):
        poses = []
        for header, (x, y, z), (qx, qy, qz, qw) in zip(headers, robot_xyz, robot_held):
            # Fill a default PoseStamped in place: its constructor builds the nested
            # defaults anyway, so passing new nested messages would build them twice.
            stamped = PoseStamped()
            stamped.header = header
            pose = stamped.pose
            position = pose.position
            position.x, position.y, position.z = x, y, z
            orientation = pose.orientation
            orientation.x, orientation.y, orientation.z, orientation.w = qx, qy, qz, qw
            poses.append(stamped)
        path = Path(header=Header(frame_id=frame_id, stamp=time_from_ns(start_ns)))
        path.poses = poses
        paths.append(path)
    return paths


def path_positions(path):
    """Return the positions of a nav_msgs/Path as an (M, 3) array."""
    return np.array([(p.pose.position.x, p.pose.position.y, p.pose.position.z)
                     for p in path.poses], dtype=float).reshape(-1, 3)


def path_stamps_ns(path):
    """Return the stamps of a nav_msgs/Path's poses as an (M,) integer array (ns)."""
    return np.array([stamp_to_ns(p.header.stamp) for p in path.poses], dtype=np.int64)


def _colour(index, alpha=1.0):
    r, g, b = PALETTE[index % len(PALETTE)]
    return ColorRGBA(r=r, g=g, b=b, a=alpha)


def _points(xyz):
    points = []
    for x, y, z in np.asarray(xyz, dtype=float).tolist():
        point = Point()
        point.x, point.y, point.z = x, y, z
        points.append(point)
    return points


def plan_markers(plan, frame_id, stamp_ns, plane_z=0.0, names=None):
    """
    Return a visualization_msgs/MarkerArray of the plan for RViz.

    Namespaces: a DELETEALL first (no stale markers), ``obstacles`` (black
    spheres), ``axis`` (the e1 axis, grey), ``lanes`` (one thin line per
    robot lane, a LINE_LIST), ``paths`` (one LINE_STRIP per robot through
    every breakpoint, robot colours), ``waypoints`` (one SPHERE_LIST per
    configuration C_m) and ``labels`` (robot names at C_1).
    """
    header = Header(frame_id=frame_id, stamp=time_from_ns(stamp_ns))
    positions = to_xyz(plan.positions, plane_z)
    k = positions.shape[1]
    names = names or robot_names((), k)
    scale = float(plan.workspace.lane_spacing)
    width = 0.05 * scale
    markers = [Marker(header=header, action=Marker.DELETEALL)]

    def marker(ns, marker_id, kind, colour, size, points=()):
        item = Marker(header=header, ns=ns, id=marker_id, type=kind, action=Marker.ADD,
                      scale=Vector3(x=size, y=size, z=size), color=colour)
        item.pose.orientation.w = 1.0
        item.points = _points(points) if len(points) else []
        return item

    obstacles = to_xyz(plan.workspace.obstacles, plane_z).reshape(-1, 3)
    if len(obstacles):
        markers.append(marker('obstacles', 0, Marker.SPHERE_LIST,
                              ColorRGBA(r=0.0, g=0.0, b=0.0, a=1.0), 0.25 * scale, obstacles))
    axis = to_xyz(plan.axis_segment(), plane_z)
    markers.append(marker('axis', 0, Marker.LINE_STRIP,
                          ColorRGBA(r=0.5, g=0.5, b=0.5, a=0.8), width, axis))
    lanes = to_xyz(plan.lane_segments(), plane_z).reshape(-1, 3)
    markers.append(marker('lanes', 0, Marker.LINE_LIST,
                          ColorRGBA(r=0.6, g=0.6, b=0.6, a=0.5), 0.5 * width, lanes))
    for i in range(k):
        markers.append(marker('paths', i, Marker.LINE_STRIP, _colour(i), width,
                              positions[:, i]))
    for m, index in enumerate(np.asarray(plan.waypoint_indices).tolist()):
        item = marker('waypoints', m, Marker.SPHERE_LIST,
                      ColorRGBA(r=1.0, g=1.0, b=1.0, a=1.0), 0.2 * scale, positions[index])
        item.colors = [_colour(i) for i in range(k)]
        markers.append(item)
    for i in range(k):
        label = marker('labels', i, Marker.TEXT_VIEW_FACING,
                       ColorRGBA(r=0.0, g=0.0, b=0.0, a=1.0), 0.3 * scale)
        x, y, z = positions[0, i].tolist()
        label.pose.position.x, label.pose.position.y = x, y
        label.pose.position.z = z + 0.3 * scale
        label.text = names[i]
        markers.append(label)
    return MarkerArray(markers=markers)


def domain_index_message(plan):
    """Return the std_msgs/UInt32 domain index of a plan."""
    return UInt32(data=int(plan.domain_index))


def empty_path(frame_id, stamp_ns):
    """Return a nav_msgs/Path with no poses: 'no current plan' for a robot."""
    return Path(header=Header(frame_id=frame_id, stamp=time_from_ns(stamp_ns)))


# ---------------------------------------------------------------- the response

def fill_response(response, plan, paths, planning_time, max_speed):
    """Fill every field of a PlanSequence response from a successful plan."""
    response.error_code = 0
    response.error_msg = ''
    response.domain_index = int(plan.domain_index)
    response.domain_count = int(plan.domain_count)
    response.sequential_complexity = int(plan.sequential_complexity or 0)
    response.optimal = bool(plan.optimal)
    response.projection_counts = [int(c) for c in np.asarray(plan.projection_counts).tolist()]
    response.min_clearance = float(plan.min_clearance)
    response.planning_time = duration_from_seconds(planning_time)
    response.duration = duration_from_seconds(plan.duration(max_speed))
    response.paths = paths
    return response


def fill_error(response, code, message, planning_time=0.0, min_clearance=None):
    """
    Fill a PlanSequence response for a refused request (no plan, no paths).

    Every plan field is reset, so a failure after a partial fill leaves nothing behind.
    """
    response.error_code = int(code)
    response.error_msg = str(message)
    response.domain_index = response.domain_count = response.sequential_complexity = 0
    response.optimal = False
    response.projection_counts = []
    response.min_clearance = float(min_clearance) if min_clearance is not None else 0.0
    response.planning_time = duration_from_seconds(planning_time)
    response.duration = Duration()
    response.paths = []
    return response


def plan_messages(outcome, settings):
    """
    Return [(topic, message)] of a successful planning Outcome, as the node publishes them.

    Topics are relative: ``<robot>/plan`` per robot, ``plan_markers``, ``domain_index``.
    """
    messages = [('%s/plan' % name.strip('/'), path)
                for name, path in zip(outcome.names, outcome.paths)]
    messages.append(('plan_markers', plan_markers(outcome.plan, settings.frame_id,
                                                  outcome.start_ns, settings.plane_z,
                                                  outcome.names)))
    messages.append(('domain_index', domain_index_message(outcome.plan)))
    return messages
