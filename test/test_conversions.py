"""Message conversions and the published messages of a plan, without DDS."""

import math

import numpy as np
from planner_helpers import CONFIGURATIONS
from planner_helpers import core_plan
from planner_helpers import make_request
from planner_helpers import OBSTACLES
from planner_helpers import path_positions
from planner_helpers import path_stamps_ns
from planner_helpers import pose_array
from punctured_planner.ros import conversions
from punctured_planner.ros import publications
import pytest

YAW_90 = [0.0, 0.0, math.sqrt(0.5), math.sqrt(0.5)]


def test_durations_and_times_round_to_nanoseconds():
    d = conversions.duration_from_seconds(1.9999999999)
    assert (d.sec, d.nanosec) == (2, 0)
    d = conversions.duration_from_seconds(0.25)
    assert (d.sec, d.nanosec) == (0, 250000000)
    t = conversions.time_from_ns(3 * 10 ** 9 + 7)
    assert (t.sec, t.nanosec) == (3, 7) and conversions.stamp_to_ns(t) == 3 * 10 ** 9 + 7


def test_quaternions_are_normalised_or_identity():
    q = conversions.normalized_quaternions([[0, 0, 2, 0], [0, 0, 0, 0], [math.nan, 0, 0, 1],
                                            [math.inf, 0, 0, 0]])
    assert q.tolist() == [[0, 0, 1, 0], [0, 0, 0, 1], [0, 0, 0, 1], [0, 0, 0, 1]]
    # finite ones whose sum of squares overflows or underflows are still normalised
    q = conversions.normalized_quaternions([[1e200, 0, 0, 0], [0, 1e-170, 0, 0],
                                            [1e308, 1e308, 0, 0]])
    assert np.allclose(q, [[1, 0, 0, 0], [0, 1, 0, 0], [0.5 ** 0.5, 0.5 ** 0.5, 0, 0]])


def test_odometry_reports_its_speed_and_a_twist_not_finite_as_none():
    """The twist's speed for the at-rest start; NaN would have held every goal."""
    from nav_msgs.msg import Odometry
    msg = Odometry()
    msg.pose.pose.orientation.w = 1.0
    msg.twist.twist.linear.x, msg.twist.twist.linear.y = 0.3, 0.4
    assert conversions.robot_odometry(msg, 0).speed == pytest.approx(0.5)
    msg.twist.twist.linear.x = math.nan
    assert conversions.robot_odometry(msg, 0).speed == 0.0


def test_message_arrays_round_trip():
    msg = pose_array(CONFIGURATIONS[1], orientations=[YAW_90] * 4)
    assert np.array_equal(conversions.pose_array_positions(msg), CONFIGURATIONS[1])
    positions, orientations = conversions.pose_array_poses(msg)
    assert np.array_equal(positions, CONFIGURATIONS[1])
    assert np.array_equal(orientations, [YAW_90] * 4)
    assert [a.shape for a in conversions.pose_array_poses(pose_array([]))] == [(0, 3), (0, 4)]
    # a request's configurations, one after the other in one array
    positions, orientations = conversions.pose_arrays_poses(
        [pose_array(CONFIGURATIONS[0]), pose_array([]), msg])
    assert np.array_equal(positions, np.concatenate([CONFIGURATIONS[0], CONFIGURATIONS[1]]))
    assert np.array_equal(orientations[len(CONFIGURATIONS[0]):], [YAW_90] * 4)
    assert conversions.pose_array_positions(pose_array([])).shape == (0, 3)
    assert conversions.obstacles_from_parameter([]).shape == (0, 3)
    assert np.array_equal(conversions.to_xyz(np.ones((2, 2)), 1.5), [[1, 1, 1.5]] * 2)


def test_paths_hold_each_waypoints_orientation_and_share_stamps():
    """Every distinct breakpoint a pose; orientation of C_m from C_m until C_{m+1}."""
    p = core_plan()
    orientations = np.zeros((3, 4, 4))
    orientations[..., 3] = 1.0
    orientations[1, :] = YAW_90
    orientations[2, :] = [0.0, 0.0, 1.0, 0.0]  # yaw 180
    samples = p.sample(2, max_speed=0.5)
    paths = conversions.plan_to_paths(samples, orientations, 'map', 10 ** 9, 0.0)
    stamps = [path_stamps_ns(path) for path in paths]
    ends = list(samples.waypoints[1:]) + [len(samples.values)]
    for i, path in enumerate(paths):
        assert np.array_equal(stamps[i], stamps[0])
        positions = path_positions(path)
        assert np.array_equal(positions[:, :2], samples.positions[:, i])
        assert np.array_equal(positions[samples.waypoints, :2], p.configurations[:, i])
        quaternions = np.array([[q.pose.orientation.x, q.pose.orientation.y,
                                 q.pose.orientation.z, q.pose.orientation.w]
                                for q in path.poses])
        for m, (start, end) in enumerate(zip(samples.waypoints, ends)):
            assert np.array_equal(quaternions[start:end], np.tile(orientations[m, i],
                                                                  (end - start, 1)))
    assert stamps[0][0] == 10 ** 9
    assert np.allclose(stamps[0] - 10 ** 9, samples.values * 1e9, atol=2)
    assert np.all(np.diff(stamps[0]) > 0)


def test_stamps_strictly_increase_below_a_nanosecond():
    """Two poses less than 1 ns apart get stamps 1 ns apart, not the same stamp."""
    stamps = conversions.stamps_ns(5, [0.0, 1e-10, 2e-10, 1.0])
    assert stamps.tolist() == [5, 6, 7, 5 + 10 ** 9]


@pytest.mark.parametrize('samples_per_leg', [0, 3])
def test_no_duplicate_pose_in_paths_markers_or_response(samples_per_leg):
    """Issue: 4 robots, 3 configurations gave 19 poses, 8 repeating position and stamp."""
    from punctured_planner.ros.settings import PLANNER
    from punctured_planner.ros.snapshot import ObstacleSet
    from punctured_planner.ros.planning import PlanSequenceHandler
    from punctured_planner.ros.snapshot import Snapshot
    from punctured_planner_interfaces.srv import PlanSequence
    settings = PLANNER.settings({'obstacles': [v for o in OBSTACLES for v in o]})
    snapshot = Snapshot(settings, ObstacleSet(np.array(OBSTACLES)))
    outcome = PlanSequenceHandler().handle(
        make_request(samples_per_leg=samples_per_leg), PlanSequence.Response(), snapshot, 0)
    assert outcome.ok
    response = outcome.response
    assert len(response.waypoint_indices) == 3
    every = np.stack([path_positions(path) for path in response.paths], axis=1)
    for i, path in enumerate(response.paths):
        assert np.all(np.diff(path_stamps_ns(path)) > 0)
        assert np.array_equal(every[list(response.waypoint_indices), i],
                              np.array(CONFIGURATIONS)[:, i])
    # Between consecutive poses some robot moves: no pose repeats for all robots.
    assert np.abs(np.diff(every, axis=0)).max(axis=(1, 2)).min() > 0
    markers = publications.plan_markers(outcome.plan, 'map', 0, 0.0, None, 0.5)
    strips = np.stack([[(q.x, q.y, q.z) for q in m.points]
                       for m in markers.markers if m.ns == 'paths'], axis=1)
    assert np.abs(np.diff(strips, axis=0)).max(axis=(1, 2)).min() > 0


def test_markers_name_every_part():
    markers = publications.plan_markers(core_plan(), 'map', 0, 0.0, ['a', 'b', 'c', 'd'])
    kinds = [m.ns for m in markers.markers]
    assert markers.markers[0].action == markers.markers[0].DELETEALL
    assert kinds.count('paths') == 4 and kinds.count('waypoints') == 3
    assert [m.text for m in markers.markers if m.ns == 'labels'] == ['a', 'b', 'c', 'd']
    assert 'walls' not in kinds
    # below walls, their box's edges: 4 in the plane (at plane_z), 12 in space
    for bounds, edges in (([[-4.0, 4.0], [-3.0, 4.0]], 4),
                          ([[-4.0, 4.0], [-3.0, 4.0], [-1.0, 1.0]], 12)):
        d = len(bounds)
        walled = core_plan(dimension=d, bounds=bounds)
        wall, = [m for m in publications.plan_markers(walled, 'map', 0, 0.5).markers
                 if m.ns == 'walls']
        ends = np.array([(p.x, p.y, p.z) for p in wall.points]).reshape(-1, 2, 3)
        assert len(ends) == edges
        assert np.all((np.diff(ends, axis=1)[:, 0] != 0).sum(axis=1) == 1)  # along one axis
        if d == 2:
            assert np.all(ends[..., 2] == 0.5)
        assert sorted(set(ends[..., 0].ravel())) == [-4.0, 4.0]


@pytest.mark.parametrize('dimension', [2, 3])
def test_an_obstacle_with_a_radius_is_drawn_as_its_body(dimension):
    """A pillar in the plane: a cylinder standing on it; a ball in space: the ball itself."""
    plan = core_plan(dimension=dimension, variant='discs', robot_radius=0.1,
                     obstacle_radius=0.2)
    pillars = [m for m in publications.plan_markers(plan, 'map', 0, 0.5).markers
               if m.ns == 'pillars']
    centres = conversions.to_xyz(plan.workspace.obstacles, 0.5).reshape(-1, 3)
    assert len(pillars) == len(centres)
    for pillar, centre in zip(pillars, centres):
        middle = np.array([pillar.pose.position.x, pillar.pose.position.y,
                           pillar.pose.position.z])
        size = (pillar.scale.x, pillar.scale.y, pillar.scale.z)
        if dimension == 3:
            assert pillar.type == pillar.SPHERE and size == (0.4, 0.4, 0.4)
            assert np.array_equal(middle, centre)
        else:
            assert pillar.type == pillar.CYLINDER and size[:2] == (0.4, 0.4)
            assert np.array_equal(middle, centre + [0.0, 0.0, 0.5 * size[2]])


def reference_paths(samples, orientations, frame_id, start_ns, plane_z=0.0):
    """Return the Paths as conversions built them before issue 13 (constructed messages)."""
    from geometry_msgs.msg import PoseStamped
    from nav_msgs.msg import Path
    from std_msgs.msg import Header
    xyz = conversions.to_xyz(samples.positions, plane_z)
    quaternions = conversions.normalized_quaternions(orientations)[samples.last_waypoint()]
    stamps = conversions.stamps_ns(start_ns, samples.values).tolist()
    paths = []
    for i in range(xyz.shape[1]):
        path = Path(header=Header(frame_id=frame_id, stamp=conversions.time_from_ns(start_ns)))
        for j, stamp in enumerate(stamps):
            stamped = PoseStamped(header=Header(frame_id=frame_id,
                                                stamp=conversions.time_from_ns(stamp)))
            position, q = stamped.pose.position, stamped.pose.orientation
            position.x, position.y, position.z = xyz[j, i].tolist()
            q.x, q.y, q.z, q.w = quaternions[j, i].tolist()
            path.poses.append(stamped)
        paths.append(path)
    return paths


def float_bits(path):
    """Return every float of a Path's poses as int64 bits (so -0.0 differs from 0.0)."""
    return np.array([(s.pose.position.x, s.pose.position.y, s.pose.position.z,
                      s.pose.orientation.x, s.pose.orientation.y, s.pose.orientation.z,
                      s.pose.orientation.w) for s in path.poses], dtype=float).view(np.int64)


@pytest.mark.parametrize('dimension, frame_id, samples_per_leg', [
    (2, 'map', 0), (2, 'odom', 3), (3, '', 1), (3, 'a_much_longer_frame', 0), (2, 'm', 2)])
def test_paths_and_their_bytes_are_the_reference_messages(dimension, frame_id,
                                                          samples_per_leg):
    """The response's Paths and the topics' bytes hold exactly the reference's values."""
    from nav_msgs.msg import Path
    from rclpy.serialization import deserialize_message
    from rclpy.serialization import serialize_message
    configurations = np.array(CONFIGURATIONS, dtype=float)
    if dimension == 3:
        configurations[:, :, 2] = [[0.5, -1.0, 2.0, 0.0]] * 3
    samples = core_plan(configurations, dimension=dimension).sample(samples_per_leg, 0.7)
    orientations = np.random.default_rng(dimension + samples_per_leg).normal(size=(3, 4, 4))
    orientations[0, 1] = 0.0
    orientations[1, 2, 0] = math.nan
    orientations[2, 3] = [-0.0, 0.0, -0.0, 1.0]
    arguments = (samples, orientations, frame_id, 1234567890 * 10 ** 9 + 987654321)
    expected = reference_paths(*arguments)
    paths = conversions.plan_to_paths(*arguments)
    assert paths == expected
    assert len(paths.serialized) == len(paths) == 4
    for path, reference, data in zip(paths, expected, paths.serialized):
        assert np.array_equal(float_bits(path), float_bits(reference))
        assert len(data) == len(serialize_message(reference))
        decoded = deserialize_message(data, Path)
        assert decoded == reference
        assert np.array_equal(float_bits(decoded), float_bits(reference))
