"""Message conversions, parameter validation and the request pipeline, without DDS."""

import math
import os

from conftest import REPO_ROOT
import numpy as np
from planner_helpers import CONFIGURATIONS
from planner_helpers import core_plan
from planner_helpers import make_request
from planner_helpers import OBSTACLES
from planner_helpers import pose_array
from punctured_planner import conversions
from punctured_planner.parameters import load_parameter_file
from punctured_planner.parameters import PARAMETERS
from punctured_planner.parameters import Settings
from punctured_planner.parameters import settings_from_values
from punctured_planner.planning import ObstacleSet
from punctured_planner.planning import Planner
from punctured_planner.planning import Snapshot
from punctured_planner.recording import message_definition
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
    stamps = [conversions.path_stamps_ns(path) for path in paths]
    for i, path in enumerate(paths):
        assert np.array_equal(stamps[i], stamps[0])
        positions = conversions.path_positions(path)
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
    markers = conversions.plan_markers(core_plan(), 'map', 0, 0.0, ['a', 'b', 'c', 'd'])
    kinds = [m.ns for m in markers.markers]
    assert markers.markers[0].action == markers.markers[0].DELETEALL
    assert kinds.count('paths') == 4 and kinds.count('waypoints') == 3
    assert [m.text for m in markers.markers if m.ns == 'labels'] == ['a', 'b', 'c', 'd']


def test_settings_validation_gives_reasons():
    assert settings_from_values({}) == Settings()
    assert {spec.name for spec in PARAMETERS} == set(Settings.__dataclass_fields__)
    for spec in PARAMETERS:
        assert getattr(Settings(), spec.name) == (tuple(spec.default)
                                                  if isinstance(spec.default, list)
                                                  else spec.default), spec.name
    good = settings_from_values({'plane_z': 1, 'obstacles': [0, 0, 0], 'robot_names': None})
    assert good.plane_z == 1.0 and good.obstacles == (0.0, 0.0, 0.0)
    bad = [({'dimension': 4}, 'dimension'), ({'variant': 'x'}, 'variant'),
           ({'obstacles': [1.0]}, 'multiple of 3'), ({'obstacles': [math.nan] * 3}, 'finite'),
           ({'robot_names': ['a', 'a']}, 'unique'), ({'robot_names': ['a b']}, 'ROS name'),
           ({'robot_names': ['a'], 'robot_count': 2}, 'robot_count'),
           ({'frame_id': ''}, 'frame_id'), ({'lane_spacing': 0.0}, 'lane_spacing'),
           ({'max_speed': True}, 'max_speed'), ({'dimension': 2.0}, 'integer'),
           ({'nonsense': 1}, 'unknown'), ({'robot_count': 5, 'max_robots': 4}, 'max_robots')]
    for values, words in bad:
        with pytest.raises(ValueError, match=words):
            settings_from_values(values)


def test_parameter_files(tmp_path):
    values = load_parameter_file(os.path.join(REPO_ROOT, 'config', 'default_scenario.yaml'))
    settings = settings_from_values(values)
    assert settings.robot_count == 4 and len(settings.obstacles) == 9
    path = tmp_path / 'p.yaml'
    path.write_text('/**:\n  ros__parameters: {variant: paper}\n'
                    'other_node:\n  ros__parameters: {variant: spread}\n'
                    '/fleet/planner_node:\n  ros__parameters: {max_speed: 2}\n')
    assert load_parameter_file(str(path)) == {'variant': 'paper', 'max_speed': 2}
    path.write_text('- not a mapping\n')
    with pytest.raises(ValueError):
        load_parameter_file(str(path))


def snapshot(**values):
    settings = settings_from_values(values)
    return Snapshot(settings, ObstacleSet(conversions.obstacles_from_parameter(
        settings.obstacles)))


def test_planner_caches_one_workspace_per_obstacle_set():
    from punctured_planner_interfaces.srv import PlanSequence
    planner = Planner()
    base = snapshot(obstacles=[v for o in OBSTACLES for v in o])
    first = planner.workspace(base.settings, np.array(OBSTACLES)[:, :2])
    assert planner.workspace(base.settings, np.array(OBSTACLES)[:, :2]) is first
    paper = settings_from_values({'variant': 'paper'})
    assert planner.workspace(paper, np.array(OBSTACLES)[:, :2]) is not first
    outcome = planner.handle(make_request(), PlanSequence.Response(), base, 0)
    assert outcome.ok and outcome.names == ['robot_0', 'robot_1', 'robot_2', 'robot_3']
    assert outcome.start_ns > 0
    assert outcome.workspace is first


def test_over_limit_requests_are_refused_before_conversion():
    """REQUEST_OVER_LIMITS from list lengths: fast, whatever the values."""
    import time
    from geometry_msgs.msg import Pose
    from geometry_msgs.msg import PoseArray
    from punctured_planner_interfaces.srv import PlanSequence
    request = PlanSequence.Request()
    huge = PoseArray()
    huge.poses = [Pose()] * 20001  # one shared Pose: cheap to build
    request.configurations = [huge, huge]
    started = time.perf_counter()
    outcome = Planner().handle(request, PlanSequence.Response(), snapshot(), 0)
    elapsed = time.perf_counter() - started
    assert outcome.response.error_code == PlanSequence.Response.REQUEST_OVER_LIMITS
    assert 'max_robots 10000' in outcome.response.error_msg
    assert elapsed < 0.01


def test_full_definition_text_for_recordings():
    text = message_definition('nav_msgs/msg/Path')
    assert text.startswith('# An array of poses')
    assert text.count('=' * 80 + '\nMSG: ') == 6
    for name in ('std_msgs/msg/Header', 'builtin_interfaces/msg/Time',
                 'geometry_msgs/msg/PoseStamped', 'geometry_msgs/msg/Pose',
                 'geometry_msgs/msg/Point', 'geometry_msgs/msg/Quaternion'):
        assert ('MSG: %s\n' % name) in text
    with pytest.raises(LookupError):
        message_definition('nav_msgs/msg/NoSuchType')


def test_request_yaml_integers_out_of_range_are_refused():
    """An int32 field given 99999999999 is a clear error, not a silently wrapped value."""
    from punctured_planner.msg_dict import fill_message
    from punctured_planner_interfaces.srv import PlanSequence
    with pytest.raises(ValueError, match='outside the range of int32'):
        fill_message(PlanSequence.Request(), {'samples_per_leg': 99999999999})
    request = fill_message(PlanSequence.Request(), {'samples_per_leg': -1})
    assert request.samples_per_leg == -1
