"""Message conversions and the published messages of a plan, without DDS."""

import math

import numpy as np
from planner_helpers import CONFIGURATIONS
from planner_helpers import core_plan
from planner_helpers import path_positions
from planner_helpers import path_stamps_ns
from planner_helpers import pose_array
from punctured_planner import conversions
from punctured_planner import publications

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


def test_message_arrays_round_trip():
    msg = pose_array(CONFIGURATIONS[1], orientations=[YAW_90] * 4)
    assert np.array_equal(conversions.pose_array_positions(msg), CONFIGURATIONS[1])
    assert np.array_equal(conversions.pose_array_orientations(msg), [YAW_90] * 4)
    assert conversions.pose_array_positions(pose_array([])).shape == (0, 3)
    assert conversions.obstacles_from_parameter([]).shape == (0, 3)
    assert np.array_equal(conversions.to_xyz(np.ones((2, 2)), 1.5), [[1, 1, 1.5]] * 2)


def test_paths_hold_each_waypoints_orientation_and_share_stamps():
    """Every breakpoint a pose; orientation of C_m from C_m until C_{m+1}; same stamps."""
    p = core_plan()
    orientations = np.zeros((3, 4, 4))
    orientations[..., 3] = 1.0
    orientations[1, :] = YAW_90
    orientations[2, :] = [0.0, 0.0, 1.0, 0.0]  # yaw 180
    samples = 2
    paths = conversions.plan_to_paths(p, orientations, 'map', 10 ** 9, 0.5, samples, 0.0)
    step = samples + 1
    waypoint_samples = p.waypoint_indices * step
    stamps = [path_stamps_ns(path) for path in paths]
    for i, path in enumerate(paths):
        assert np.array_equal(stamps[i], stamps[0])
        positions = path_positions(path)
        assert np.array_equal(positions[::step, :2], p.positions[:, i])
        quaternions = np.array([[q.pose.orientation.x, q.pose.orientation.y,
                                 q.pose.orientation.z, q.pose.orientation.w]
                                for q in path.poses])
        for m, start in enumerate(waypoint_samples):
            end = waypoint_samples[m + 1] if m + 1 < len(waypoint_samples) else len(quaternions)
            assert np.array_equal(quaternions[start:end], np.tile(orientations[m, i],
                                                                  (end - start, 1)))
    assert stamps[0][0] == 10 ** 9
    assert np.allclose(stamps[0][::step] - 10 ** 9, p.stamps(0.5) * 1e9, atol=2)
    assert np.all(np.diff(stamps[0]) >= 0)


def test_markers_name_every_part():
    markers = publications.plan_markers(core_plan(), 'map', 0, 0.0, ['a', 'b', 'c', 'd'])
    kinds = [m.ns for m in markers.markers]
    assert markers.markers[0].action == markers.markers[0].DELETEALL
    assert kinds.count('paths') == 4 and kinds.count('waypoints') == 3
    assert [m.text for m in markers.markers if m.ns == 'labels'] == ['a', 'b', 'c', 'd']
