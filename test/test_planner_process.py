"""
The installed planner_node across processes, and ``punctured-planner call`` against it.

The node runs from its console script with the bundled default scenario; the
client is rclpy in this process or the ``punctured-planner`` command.
"""

import os
import subprocess

from conftest import REPO_ROOT
from conftest import venv_script
import numpy as np
from planner_helpers import Latest
from planner_helpers import path_array
from planner_helpers import scenario_plan
import pytest
import yaml

SCENARIO = os.path.join(REPO_ROOT, 'config', 'default_scenario.yaml')
EXAMPLE = os.path.join(REPO_ROOT, 'config', 'example_request.yaml')

pytestmark = pytest.mark.ros


def example_request():
    """Return config/example_request.yaml as a PlanSequence request."""
    from punctured_planner.ros.msg_dict import fill_message
    from punctured_planner_interfaces.srv import PlanSequence
    with open(EXAMPLE, encoding='utf-8') as stream:
        return fill_message(PlanSequence.Request(), yaml.safe_load(stream))


def test_default_scenario_across_processes(planner_process, ros_client, ros_env):
    """The node plans the example request at once; the CLI call succeeds too."""
    from nav_msgs.msg import Path
    from punctured_planner_interfaces.srv import PlanSequence
    node = planner_process(params_file=SCENARIO)
    client = ros_client.node.create_client(PlanSequence, node.name('plan_sequence'))
    ros_client.wait_for_service(client)
    latched = Latest(ros_client.node, Path, node.name('robot_3/plan'))

    response = ros_client.call(client, example_request())
    assert response.error_code == PlanSequence.Response.NONE, response.error_msg + node.log()
    expected = scenario_plan()
    assert response.domain_index == expected.domain_index
    assert len(response.paths) == 4
    for i, path in enumerate(response.paths):
        assert np.array_equal(path_array(path)[0][:, :2],
                              expected.sample(0, 0.5).positions[:, i])
    # waypoint C_3 carries the request's orientation (yaw 90 degrees)
    final = response.paths[0].poses[-1].pose.orientation
    assert final.z == pytest.approx(0.7071067811865476) and final.w == pytest.approx(
        0.7071067811865476)
    assert ros_client.spin_until(lambda: latched.last is not None, 10)
    assert latched.last == response.paths[3]

    result = subprocess.run(
        [venv_script('punctured-planner'), 'call', EXAMPLE,
         '--service', node.name('plan_sequence'), '--wait', '20'],
        env=ros_env, capture_output=True, text=True, timeout=60)
    assert result.returncode == 0, result.stderr + node.log()
    data = yaml.safe_load(result.stdout)
    assert data['error_code'] == 0 and data['domain_index'] == expected.domain_index
    assert len(data['paths']) == 4

    node.assert_running()
    assert 'snapshot: 3 obstacles from the parameter (set at ' in node.log()
    assert node.stop() == 0, node.log()


@pytest.mark.parametrize('arguments', [
    ('-p', 'dimension:=5'), ('-p', 'variant:=fast'),
    ('-p', 'obstacles:=[0.5, 0.5, 0.0, 3.0, 0.5, 0.0]',
     '-p', 'workspace_bounds:=[0.0, 1.0, 0.0, 1.0]'),
], ids=['out-of-range', 'refused-by-validation', 'obstacles-beyond-the-walls'])
def test_invalid_parameters_stop_the_node(planner_process, arguments):
    """A bad parameter at start-up: exit code 2 and the reason, not a traceback."""
    node = planner_process(*arguments)
    try:
        code = node.proc.wait(timeout=60)
    except subprocess.TimeoutExpired:
        pytest.fail('planner_node kept running with %s:\n%s' % (arguments, node.log()))
    assert code == 2, node.log()
    assert 'invalid parameters' in node.log()


@pytest.mark.parametrize('content, reason', [
    (None, 'No such file or directory'),
    ('a: [\n', 'not YAML'),
    ('/**/planner_node:\n  ros__parameters:\n    robot_radiuss: 0.2\n',
     "unknown parameter 'robot_radiuss' of planner_node"),
    ('/**/planer_node:\n  ros__parameters:\n    robot_radius: 0.2\n',
     'no section applies to planner_node'),
], ids=['missing', 'not-yaml', 'misspelt-name', 'misspelt-section'])
def test_a_parameter_file_the_node_cannot_use_stops_it(planner_process, tmp_path, content,
                                                       reason):
    """
    Exit 2 and the reason, as ``punctured-planner plan --params`` says it.

    rcl raised a traceback (exit 1) for a file it cannot read; a misspelt name or
    section started the node on its defaults without a word.
    """
    path = tmp_path / 'params.yaml'
    if content is not None:
        path.write_text(content)
    node = planner_process(params_file=path)
    try:
        code = node.proc.wait(timeout=60)
    except subprocess.TimeoutExpired:
        pytest.fail('planner_node kept running with %s:\n%s' % (content, node.log()))
    assert code == 2, node.log()
    assert 'invalid parameters' in node.log() and reason in node.log(), node.log()
    assert 'Traceback' not in node.log()


def test_renamed_node_keeps_its_companion_apart(planner_process, ros_client):
    """Under -r __node:=NAME (a launch name=) the companions are NAME_server, _inputs, _outputs."""
    from punctured_planner_interfaces.srv import PlanSequence
    node = planner_process('-r', '__node:=fleet_planner')
    client = ros_client.node.create_client(PlanSequence, node.name('plan_sequence'))
    ros_client.wait_for_service(client)
    namespace = node.name('')[:-1]

    def names():
        return [name for name, ns in ros_client.node.get_node_names_and_namespaces()
                if ns == namespace]
    assert ros_client.spin_until(lambda: len(names()) >= 4, 10), names()
    assert sorted(names()) == ['fleet_planner', 'fleet_planner_inputs', 'fleet_planner_outputs',
                               'fleet_planner_server']
    assert node.stop() == 0, node.log()


def test_a_path_subscriber_with_incompatible_qos_is_warned_about(planner_process, ros_client):
    """
    A subscriber to a robot's path that asks for a deadline: the node logs rclpy's warning.

    The path publishers' QoS event handlers are spun on the outputs node's thread
    (nodes/planner.py): they still fire, naming the topic and the policy.
    """
    from nav_msgs.msg import Path
    from punctured_planner.ros.qos import LATCHED
    from punctured_planner_interfaces.srv import PlanSequence
    from rclpy.duration import Duration
    from rclpy.qos import QoSProfile
    node = planner_process(params_file=SCENARIO)
    client = ros_client.node.create_client(PlanSequence, node.name('plan_sequence'))
    ros_client.wait_for_service(client)
    response = ros_client.call(client, example_request())
    assert response.error_code == PlanSequence.Response.NONE, response.error_msg + node.log()
    # The latched writers offer no deadline: a reader that requires one is incompatible.
    demanding = QoSProfile(depth=1, reliability=LATCHED.reliability,
                           durability=LATCHED.durability, deadline=Duration(seconds=1))
    ros_client.node.create_subscription(Path, node.name('robot_3/plan'), lambda _: None,
                                        demanding)
    # rclpy names the topic as the node created it: relative.
    warning = "New subscription discovered on topic 'robot_3/plan', requesting incompatible QoS"
    assert ros_client.spin_until(lambda: warning in node.log(), 20), node.log()
    assert 'Last incompatible policy: DEADLINE' in node.log()
    assert node.stop() == 0, node.log()


def test_plans_answered_in_a_burst_all_reach_a_reader_of_plan(planner_process, ros_client):
    """
    Ten requests at once, every other one a large plan: a depth-16 reader gets all ten.

    plan kept one message: a large plan still going out when the next was written was
    dropped for every reader (4 of 10 such plans; a goal for one ended NO_PLAN although
    its caller had it). plan_executor reads plan with that depth (ros.goals.PLAN_HISTORY).
    """
    from punctured_planner.ros.goals import PLAN_HISTORY
    from punctured_planner.ros.qos import latched
    from punctured_planner_interfaces.msg import Plan
    from punctured_planner_interfaces.srv import PlanSequence
    node = planner_process(params_file=SCENARIO)
    heard = []
    ros_client.node.create_subscription(Plan, node.name('plan'),
                                        lambda m: heard.append(m.plan_id),
                                        latched(PLAN_HISTORY))
    client = ros_client.node.create_client(PlanSequence, node.name('plan_sequence'))
    ros_client.wait_for_service(client)
    requests = []
    for i in range(10):
        request = example_request()
        request.samples_per_leg = 300 if i % 2 == 0 else 0
        requests.append(request)
    sent = [client.call_async(request) for request in requests]
    assert ros_client.spin_until(lambda: all(f.done() for f in sent), 120), node.log()
    assert all(f.result().error_code == 0 for f in sent)
    answered = {f.result().plan_id for f in sent}
    assert ros_client.spin_until(lambda: answered <= set(heard), 60), (answered, heard)
