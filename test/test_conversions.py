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
from punctured_planner import conversions
from punctured_planner import publications
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


def test_message_arrays_round_trip():
    msg = pose_array(CONFIGURATIONS[1], orientations=[YAW_90] * 4)
    assert np.array_equal(conversions.pose_array_positions(msg), CONFIGURATIONS[1])
    assert np.array_equal(conversions.pose_array_orientations(msg), [YAW_90] * 4)
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
    from punctured_planner.parameters import settings_from_values
    from punctured_planner.planning import ObstacleSet
    from punctured_planner.planning import PlanSequenceHandler
    from punctured_planner.planning import Snapshot
    from punctured_planner_interfaces.srv import PlanSequence
    settings = settings_from_values({'obstacles': [v for o in OBSTACLES for v in o]})
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
