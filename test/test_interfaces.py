"""
The generated PlanSequence type, and a real round trip over Fast DDS.

The server is the installed ``planner_node`` console script in its own process;
the client is rclpy in this process with its own Context.
"""

import os
import subprocess
import sys

from conftest import REPO_ROOT
from conftest import venv_script
from punctured_planner.core import ErrorCode
import pytest
import yaml

# The one table of error codes is the core's; the .srv constants must be it, name for name.
EXPECTED_CONSTANTS = {code.name: int(code) for code in ErrorCode}

EXPECTED_REQUEST_FIELDS = {
    'configurations': 'sequence<geometry_msgs/PoseArray>',
    'use_current_state': 'boolean',
    'max_speed': 'double',
    'samples_per_leg': 'int32',
}

EXPECTED_RESPONSE_FIELDS = {
    'error_code': 'uint16',
    'error_msg': 'string',
    'domain_index': 'uint32',
    'domain_count': 'uint32',
    'sequential_complexity': 'uint32',
    'optimal': 'boolean',
    'projection_counts': 'sequence<uint32>',
    'dropped_configurations': 'sequence<uint32>',
    'min_clearance': 'double',
    'min_gap': 'double',
    'planning_time': 'builtin_interfaces/Duration',
    'duration': 'builtin_interfaces/Duration',
    'paths': 'sequence<nav_msgs/Path>',
    'waypoint_indices': 'sequence<uint32>',
    'plan_id': 'uint64',
    'tracking_tolerance': 'double',
}

EXPECTED_PLAN_FIELDS = {
    'plan_id': 'uint64',
    'robot_names': 'sequence<string>',
    'paths': 'sequence<nav_msgs/Path>',
    'max_speed': 'double',
    'max_acceleration': 'double',
    'robot_radius': 'double',
    'obstacles': 'sequence<geometry_msgs/Point>',
    'obstacle_radii': 'sequence<double>',
    'min_gap': 'double',
    'tracking_tolerance': 'double',
}

EXPECTED_EXECUTE_PLAN = {
    'Goal': {'plan_id': 'uint64'},
    'Result': {'error_code': 'uint16', 'error_msg': 'string', 'plan_id': 'uint64',
               'executed_duration': 'builtin_interfaces/Duration',
               'max_tracking_errors': 'sequence<double>', 'min_gap': 'double'},
    'Feedback': {'plan_time': 'double', 'plan_duration': 'double', 'clock_rate': 'double',
                 'max_tracking_errors': 'sequence<double>', 'min_gap': 'double',
                 'stale_robots': 'sequence<string>'},
}
EXECUTE_PLAN_CODES = {'NONE': 0, 'NO_PLAN': 1, 'UNKNOWN_ROBOTS': 2, 'FRAME_MISMATCH': 3,
                      'UNSAFE_PLAN': 4, 'CANCELED': 5, 'PREEMPTED': 6, 'STOPPED': 7,
                      'ODOMETRY_LOST': 8, 'NOT_AT_START': 9, 'CLOCK_HELD': 10,
                      'UNKNOWN': 99}


def _plan_sequence():
    from punctured_planner_interfaces.srv import PlanSequence
    return PlanSequence


def make_request(n_configurations=3, n_robots=4, frame_id='map'):
    """Return a PlanSequence request with a simple grid of robot positions."""
    from geometry_msgs.msg import Pose
    from geometry_msgs.msg import PoseArray
    request = _plan_sequence().Request()
    for m in range(n_configurations):
        configuration = PoseArray()
        configuration.header.frame_id = frame_id
        for i in range(n_robots):
            pose = Pose()
            pose.position.x = float(i) + 0.25 * m
            pose.position.y = 1.0 + m
            pose.orientation.w = 1.0
            configuration.poses.append(pose)
        request.configurations.append(configuration)
    return request


def test_fields_and_types():
    plan_sequence = _plan_sequence()
    assert plan_sequence.Request.get_fields_and_field_types() == EXPECTED_REQUEST_FIELDS
    assert plan_sequence.Response.get_fields_and_field_types() == EXPECTED_RESPONSE_FIELDS


def test_plan_message_and_execute_plan_action():
    from punctured_planner_interfaces.action import ExecutePlan
    from punctured_planner_interfaces.msg import Plan
    assert Plan.get_fields_and_field_types() == EXPECTED_PLAN_FIELDS
    for part, fields in EXPECTED_EXECUTE_PLAN.items():
        assert getattr(ExecutePlan, part).get_fields_and_field_types() == fields, part
    result = ExecutePlan.Result
    declared = {name: getattr(result, name) for name in dir(result)
                if name.isupper() and isinstance(getattr(result, name), int)}
    assert declared == EXECUTE_PLAN_CODES
    assert ExecutePlan.Goal().plan_id == 0


def test_request_defaults():
    request = _plan_sequence().Request()
    assert list(request.configurations) == []
    assert request.use_current_state is False
    assert request.max_speed == 0.0
    assert request.samples_per_leg == -1


def test_error_code_constants_are_the_core_error_codes():
    """The core's ErrorCode and PlanSequence.srv: the same names, the same values."""
    response_cls = _plan_sequence().Response
    for name, value in EXPECTED_CONSTANTS.items():
        assert getattr(response_cls, name) == value, name
    declared = {name for name in dir(response_cls)
                if name.isupper() and isinstance(getattr(response_cls, name), int)}
    assert declared == set(EXPECTED_CONSTANTS)
    assert response_cls().error_code == response_cls.NONE


def test_srv_file_is_installed_into_the_venv():
    installed = os.path.join(sys.prefix, 'share', 'punctured_planner_interfaces',
                             'srv', 'PlanSequence.srv')
    source = os.path.join(REPO_ROOT, 'punctured_planner_interfaces', 'srv',
                          'PlanSequence.srv')
    with open(installed, encoding='utf-8') as a, open(source, encoding='utf-8') as b:
        assert a.read() == b.read(), 'installed interfaces are stale: run `make setup`'


@pytest.mark.ros
def test_round_trip_between_processes(planner_process, ros_client):
    plan_sequence = _plan_sequence()
    node = planner_process()
    client = ros_client.node.create_client(plan_sequence, node.name('plan_sequence'))
    ros_client.wait_for_service(client)
    node.assert_running()

    for request in (plan_sequence.Request(), make_request(), make_request(5, 7)):
        response = ros_client.call(client, request)
        assert isinstance(response, plan_sequence.Response)
        assert response.error_code in EXPECTED_CONSTANTS.values()
        if not request.configurations:
            # an empty sequence is never plannable
            assert response.error_code != plan_sequence.Response.NONE
            assert response.error_msg
        if response.error_code != plan_sequence.Response.NONE:
            assert response.error_msg, 'an error code always comes with a message'

    # the node keeps serving: many calls in a row
    for _ in range(20):
        assert ros_client.call(client, make_request(2, 2)) is not None
    node.assert_running()
    assert node.stop() == 0, node.log()


@pytest.mark.ros
def test_cli_call_against_node(planner_process, ros_env, tmp_path):
    node = planner_process()
    request_file = tmp_path / 'request.yaml'
    request_file.write_text(
        'configurations:\n'
        '  - header: {frame_id: map}\n'
        '    poses: [{position: {x: 0.0, y: 1.0}}, {position: {x: 2.0, y: 1.0}}]\n'
        '  - header: {frame_id: map}\n'
        '    poses: [{position: {x: 1.0, y: 2.0}}, {position: {x: 3.0, y: 2.0}}]\n'
        'max_speed: 0.5\n', encoding='utf-8')
    result = subprocess.run(
        [venv_script('punctured-planner'), 'call', str(request_file),
         '--service', node.name('plan_sequence'), '--wait', '20', '--no-paths'],
        env=ros_env, capture_output=True, text=True, timeout=60)
    assert 'error_code:' in result.stdout, result.stdout + result.stderr + node.log()
    data = yaml.safe_load(result.stdout)
    assert data['error_code'] in EXPECTED_CONSTANTS.values()
    assert result.returncode == (0 if data['error_code'] == 0 else 1), result.stderr
    node.assert_running()


def test_cli_rejects_unknown_field(ros_env, tmp_path):
    request_file = tmp_path / 'bad.yaml'
    request_file.write_text('configurationz: []\n', encoding='utf-8')
    result = subprocess.run(
        [venv_script('punctured-planner'), 'call', str(request_file)],
        env=ros_env, capture_output=True, text=True, timeout=60)
    assert result.returncode == 2
    assert "unknown field 'configurationz'" in result.stderr
