"""
The planner node over real DDS: in process (its own Context and executor thread).

Topics in (obstacles, robot_states, odometry), the PlanSequence service, each
robot's Path, the domain index and the markers out; every error code; parameter
changes. The client is the ``ros_client`` fixture (another Context).
"""

import gc
import math
import threading
import time

from conftest import RosClient
import numpy as np
from planner_helpers import CONFIGURATIONS
from planner_helpers import core_plan
from planner_helpers import flat
from planner_helpers import InProcessPlanner
from planner_helpers import Latest
from planner_helpers import make_request
from planner_helpers import OBSTACLES
from planner_helpers import path_array
from planner_helpers import pose_array
import pytest

pytestmark = pytest.mark.ros


def _types():
    from geometry_msgs.msg import PoseArray
    from nav_msgs.msg import Odometry
    from nav_msgs.msg import Path
    from punctured_planner_interfaces.srv import PlanSequence
    from std_msgs.msg import UInt32
    from visualization_msgs.msg import MarkerArray
    return PlanSequence, PoseArray, Path, UInt32, MarkerArray, Odometry


@pytest.fixture
def planner():
    """Return a function starting in-process planner nodes; all closed after the test."""
    started = []

    def start(**parameters):
        node = InProcessPlanner(**parameters)
        started.append(node)
        return node

    yield start
    for node in started:
        node.close()


def service_client(ros_client, node):
    """Return a PlanSequence client of node, once the service is discovered."""
    plan_sequence = _types()[0]
    client = ros_client.node.create_client(plan_sequence, node.name('plan_sequence'))
    ros_client.wait_for_service(client)
    return client


def test_topics_in_one_path_per_robot_out(planner, ros_client):
    """Obstacles and robot state from topics; each robot's Path matches the core's plan."""
    plan_sequence, pose_array_type, path_type, uint32, marker_array, _ = _types()
    from punctured_planner.ros.qos import LATCHED
    node = planner(robot_count=4)
    names = ['robot_%d' % i for i in range(4)]
    paths = {name: Latest(ros_client.node, path_type, node.name(name + '/plan'))
             for name in names}
    domain = Latest(ros_client.node, uint32, node.name('domain_index'))
    markers = Latest(ros_client.node, marker_array, node.name('plan_markers'))
    obstacles = ros_client.node.create_publisher(pose_array_type, node.name('obstacles'),
                                                 LATCHED)
    obstacles.publish(pose_array(OBSTACLES))
    states = ros_client.node.create_publisher(pose_array_type, node.name('robot_states'), 10)
    client = service_client(ros_client, node)

    assert ros_client.spin_until(
        lambda: node.node.snapshot().obstacles.source.endswith('/obstacles'), 10)

    def state_seen():
        states.publish(pose_array(CONFIGURATIONS[0]))
        return node.node.snapshot().state is not None

    assert ros_client.spin_until(state_seen, 10), 'robot_states never arrived'
    assert node.node.snapshot().state.source == 'robot_states'

    before = time.time_ns()
    request = make_request(CONFIGURATIONS[1:], use_current_state=True, max_speed=0.5)
    response = ros_client.call(client, request)
    assert response.error_code == plan_sequence.Response.NONE, response.error_msg
    expected = core_plan()
    assert response.domain_index == expected.domain_index
    assert response.domain_count == expected.domain_count == 13
    assert response.sequential_complexity == expected.sequential_complexity
    assert response.optimal is True
    assert list(response.projection_counts) == expected.projection_counts.tolist()
    assert response.min_clearance == expected.min_clearance
    assert response.duration.sec + response.duration.nanosec * 1e-9 == pytest.approx(
        expected.duration(0.5), abs=1e-9)
    assert len(response.paths) == 4
    # Refused while the request's lists are gathered: named as the request labels them.
    empty = ros_client.call(client, make_request([[], CONFIGURATIONS[2]],
                                                 use_current_state=True))
    assert empty.error_code == plan_sequence.Response.INVALID_REQUEST
    assert empty.error_msg == ('configuration 1 (request configurations[0]) '
                               'has no robots'), empty.error_msg

    assert ros_client.spin_until(
        lambda: all(s.last is not None for s in paths.values()) and domain.last is not None
        and markers.last is not None, 10), 'plan topics not received'
    first_stamps = None
    for i, name in enumerate(names):
        path = paths[name].last
        assert path == response.paths[i]
        assert path.header.frame_id == 'map'
        positions, stamps = path_array(path)
        # every distinct breakpoint is a pose, exactly; z back on the plane
        assert np.array_equal(positions[:, :2], expected.sample(0, 0.5).positions[:, i])
        assert np.all(positions[:, 2] == 0.0)
        if first_stamps is None:
            first_stamps = stamps
        assert np.array_equal(stamps, first_stamps), 'robots must share their stamps'
    assert first_stamps[0] >= before
    assert np.allclose(first_stamps - first_stamps[0], expected.sample(0, 0.5).values * 1e9,
                       atol=2)
    assert domain.last.data == expected.domain_index
    namespaces = {}
    for marker in markers.last.markers:
        namespaces.setdefault(marker.ns, []).append(marker)
    assert len(namespaces['paths']) == 4 and len(namespaces['waypoints']) == 3
    assert len(namespaces['obstacles'][0].points) == 3
    assert 'lanes' in namespaces and 'axis' in namespaces

    # a late subscriber still gets the latched plan
    late = Latest(ros_client.node, path_type, node.name('robot_2/plan'))
    late_domain = Latest(ros_client.node, uint32, node.name('domain_index'))
    assert ros_client.spin_until(lambda: late.last is not None
                                 and late_domain.last is not None, 10)
    assert late.last == response.paths[2]
    assert late_domain.last.data == expected.domain_index


def test_every_error_code_and_the_node_keeps_serving(planner, ros_client, monkeypatch):
    """Each code provoked at least once (priority too); a valid request succeeds after each."""
    plan_sequence, _, path_type, uint32, _, _ = _types()
    codes = plan_sequence.Response
    node = planner(obstacles=flat(OBSTACLES))
    domain = Latest(ros_client.node, uint32, node.name('domain_index'))
    first_path = Latest(ros_client.node, path_type, node.name('robot_0/plan'))
    client = service_client(ros_client, node)
    seen = set()
    c1, c2, c3 = (np.array(c) for c in CONFIGURATIONS)

    def expect(request, code, *words):
        response = ros_client.call(client, request)
        assert response.error_code == code, (response.error_code, response.error_msg)
        assert response.error_msg
        for word in words:
            assert word in response.error_msg, response.error_msg
        assert len(response.paths) == 0 and response.domain_count == 0
        assert gc.isenabled(), 'the collector is back on once the reply is out'
        seen.add(code)
        return response

    def valid():
        response = ros_client.call(client, make_request())
        assert response.error_code == codes.NONE, response.error_msg
        assert gc.isenabled(), 'the collector is back on once the reply is out'
        return response

    def moved(configuration, robot, point):
        result = configuration.copy()
        result[robot] = point
        return result

    expect(make_request([c1]), codes.NO_CONFIGURATIONS, 'at least 2')
    expect(plan_sequence.Request(), codes.NO_CONFIGURATIONS)
    expect(make_request([c2], use_current_state=True), codes.NO_ROBOT_STATE, 'robot_states')
    expect(make_request(samples_per_leg=1001), codes.REQUEST_OVER_LIMITS, 'samples_per_leg')
    expect(make_request(max_speed=math.nan), codes.INVALID_REQUEST, 'max_speed')
    expect(make_request([np.zeros((0, 3)), c2]), codes.INVALID_REQUEST, 'no robots')
    expect(make_request([c1, c2[:3]]), codes.ROBOT_COUNT_MISMATCH, 'configuration 1')
    expect(make_request([c1, moved(c2, 2, [math.inf, 0, 0])]), codes.NON_FINITE_VALUE,
           'configuration 1, robot 2')
    expect(make_request(frame_id='odom'), codes.FRAME_MISMATCH, "'odom'")
    expect(make_request([c1, moved(c2, 3, [3.5, 1.0, 0.25])]), codes.OFF_PLANE,
           'configuration 1, robot 3')
    expect(make_request([c1, moved(c2, 1, c2[0])]), codes.ROBOTS_COINCIDE,
           'configuration 1', 'robots 0 and 1')
    expect(make_request([c1, c2, moved(c3, 3, OBSTACLES[2])]), codes.ROBOT_ON_OBSTACLE,
           'configuration 2', 'robot 3', 'obstacle 2')
    # nothing is published for a refused request
    ros_client.spin_until(lambda: False, 0.3)
    assert domain.last is None and first_path.last is None

    # priority: the smallest code wins
    expect(make_request([c1, moved(c2, 0, [math.nan, 0, 0])], frame_id='odom'),
           codes.NON_FINITE_VALUE)
    expect(make_request([c1, moved(c2, 0, [1, 1, 5])], frame_id='odom'), codes.FRAME_MISMATCH)
    expect(make_request([c1, c2[:3]], samples_per_leg=5000), codes.REQUEST_OVER_LIMITS)
    expect(make_request([c1, np.zeros((0, 3)), c2[:3]]), codes.INVALID_REQUEST)
    expect(make_request([c1, moved(c2, 1, c2[0])], frame_id='odom'), codes.FRAME_MISMATCH)
    expect(make_request([c1, moved(c2, 2, [1e300, 0, 0]), c3[:3]], frame_id='odom'),
           codes.INVALID_REQUEST, 'configuration 1, robot 2', 'beyond')
    expect(make_request(max_speed=1e-12), codes.INVALID_REQUEST, 'raise max_speed')
    valid()
    assert ros_client.spin_until(lambda: domain.last is not None, 10)

    assert all(r.successful for r in node.set_parameters(max_robots=3))
    expect(make_request(), codes.REQUEST_OVER_LIMITS, 'max_robots 3')
    node.set_parameters(max_robots=10000, max_configurations=2)
    expect(make_request(), codes.REQUEST_OVER_LIMITS, 'max_configurations 2')
    node.set_parameters(max_configurations=1000, max_poses=50)
    expect(make_request(), codes.REQUEST_OVER_LIMITS, 'max_poses 50')
    node.set_parameters(max_poses=2000000)
    valid()

    node.set_parameters(robot_count=5)
    expect(make_request(), codes.ROBOT_COUNT_MISMATCH, 'robot_count 5')
    node.set_parameters(robot_count=0)
    valid()

    # A set the node cannot plan in is refused where it arrives, the parameter on set.
    degenerate = node.set_parameters(obstacles=flat(OBSTACLES + OBSTACLES[:1]))[0]
    assert not degenerate.successful
    assert ('OBSTACLES_DEGENERATE with 4 obstacles from the parameter' in degenerate.reason
            and 'obstacle 0 at (-2, 0.5, 0) (from the parameter) and obstacle 3 at (-2, 0.5, '
            '0) (from the parameter) are at the same point' in degenerate.reason), \
        degenerate.reason
    valid()

    node.set_parameters(required_clearance=50.0)
    refused = expect(make_request(), codes.CLEARANCE_BELOW_REQUIRED, 'required 50')
    assert refused.min_clearance == core_plan().min_clearance > 0
    node.set_parameters(required_clearance=0.0)
    valid()

    # walls 0.5 beyond the inputs' box: a robot or a pillar outside, a plan that leaves
    box = [-3.5, 4.0, -3.0, 4.0]
    assert all(r.successful for r in node.set_parameters(workspace_bounds=box))
    expect(make_request([c1, moved(c2, 3, [4.25, 1.0, 0.0])]), codes.OUTSIDE_WORKSPACE,
           'configuration 1: robot 3 is 0.25 beyond the wall x_max (workspace_bounds[1]) = 4 '
           '(centre x = 4.25)')
    expect(make_request([c1, moved(c2, 3, [4.25, 1.0, 0.0]), moved(c3, 0, OBSTACLES[1])]),
           codes.ROBOT_ON_OBSTACLE, 'configuration 2', 'robot 0')  # it ranks before
    outside = node.set_parameters(obstacles=flat(OBSTACLES[:2] + [[2.5, -3.5, 0.0]]))[0]
    assert not outside.successful
    assert ('obstacle 2 at (2.5, -3.5, 0) (from the parameter) is 0.5 beyond the wall y_min '
            '(workspace_bounds[2]) = -3' in outside.reason), outside.reason
    from punctured_planner.core import plan, PlanningError, Workspace
    with pytest.raises(PlanningError) as leaves:  # the construction's lanes leave the box
        plan(Workspace(np.array(OBSTACLES)[:, :2], variant='spread',
                       bounds=np.reshape(box, (2, 2))), np.array(CONFIGURATIONS)[..., :2],
             refine=False)
    assert leaves.value.leg is not None and leaves.value.distance > 0
    node.set_parameters(refine=False)
    expect(make_request(), codes.OUTSIDE_WORKSPACE,
           'the plan takes robot %d %.6g beyond the wall %s (workspace_bounds[%d])' % (
               leaves.value.robots[0], leaves.value.distance, leaves.value.wall.name,
               leaves.value.wall.index),
           'on leg %d (' % leaves.value.leg)
    node.set_parameters(workspace_bounds=[], refine=True)
    valid()

    import punctured_planner.core as core

    def broken(*args, **kwargs):
        raise RuntimeError('injected fault')
    monkeypatch.setattr(core, 'plan', broken)
    expect(make_request(), codes.UNKNOWN, 'injected fault')
    monkeypatch.undo()
    valid()

    documented = {v for k, v in vars(codes).items() if k.isupper() and isinstance(v, int)}
    # OBSTACLES_DEGENERATE is the core's: the node refuses such a set where it arrives;
    # NODE_STOPPING comes only with a stop (test_requests_waiting_past_the_stop_budget_...).
    assert seen == documented - {codes.NONE, codes.OBSTACLES_DEGENERATE, codes.NODE_STOPPING}


def test_parameter_changes_take_effect_and_bad_values_are_refused(planner, ros_client):
    """Variant, samples, speed, frame, dimension, names: the next plan follows them."""
    plan_sequence, _, path_type, _, _, _ = _types()
    node = planner(obstacles=flat(OBSTACLES))
    client = service_client(ros_client, node)

    def call(request=None):
        response = ros_client.call(client, request or make_request())
        assert response.error_code == plan_sequence.Response.NONE, response.error_msg
        return response

    assert len(call().paths[0].poses) == core_plan().sample(0, 1.0).values.size
    assert all(r.successful for r in node.set_parameters(variant='paper'))
    response = call()
    paper = core_plan(variant='paper')
    assert np.array_equal(path_array(response.paths[1])[0][:, :2],
                          paper.sample(0, 1.0).positions[:, 1])
    node.set_parameters(samples_per_leg=2)
    assert len(call().paths[0].poses) == paper.sample(2, 1.0).values.size
    assert len(call(make_request(samples_per_leg=0)).paths[0].poses) == \
        paper.sample(0, 1.0).values.size
    node.set_parameters(max_speed=2.0, samples_per_leg=0)
    response = call()
    assert response.duration.sec + response.duration.nanosec * 1e-9 == pytest.approx(
        paper.duration(2.0), abs=1e-9)
    node.set_parameters(lane_spacing=2.5)
    assert call().min_clearance == core_plan(variant='paper', lane_spacing=2.5).min_clearance

    node.set_parameters(frame_id='world')
    assert call(make_request(frame_id='')).paths[0].header.frame_id == 'world'
    assert ros_client.call(client, make_request()).error_code == \
        plan_sequence.Response.FRAME_MISMATCH
    node.set_parameters(frame_id='map', dimension=3)
    lifted = np.array(CONFIGURATIONS)
    lifted[1, :, 2] = [0.5, -0.5, 1.0, 2.0]
    positions = path_array(call(make_request(lifted)).paths[3])[0]
    assert np.array_equal(positions, core_plan(lifted, variant='paper', lane_spacing=2.5,
                                               dimension=3).sample(0, 2.0).positions[:, 3])
    node.set_parameters(dimension=2, plane_z=1.5)
    assert ros_client.call(client, make_request()).error_code == \
        plan_sequence.Response.OFF_PLANE  # the obstacles (z = 0) are off the plane too
    node.set_parameters(plane_z=0.0)

    old_path = Latest(ros_client.node, path_type, node.name('robot_3/plan'))
    assert ros_client.spin_until(lambda: old_path.last is not None, 10)
    assert all(r.successful for r in node.set_parameters(robot_names=['a', 'b', 'c', 'd']))
    named = Latest(ros_client.node, path_type, node.name('c/plan'))
    response = call()
    assert ros_client.spin_until(lambda: named.last is not None and len(old_path.messages) > 1,
                                 10)
    assert named.last == response.paths[2]
    assert len(old_path.last.poses) == 0, 'a robot no longer planned gets an empty path'
    assert ros_client.call(client, make_request(np.array(CONFIGURATIONS)[:, :3])).error_code \
        == plan_sequence.Response.ROBOT_COUNT_MISMATCH

    refused = {
        'dimension': 4, 'variant': 'fast', 'lane_spacing': -1.0, 'min_spacing': math.nan,
        'max_speed': 'quick', 'obstacles': [1.0, 2.0], 'robot_names': ['a', 'a'],
        'robot_count': 3, 'frame_id': '', 'plane_z': math.inf, 'samples_per_leg': -1,
        'required_clearance': -0.5, 'max_robots': 2, 'workspace_bounds': [0.0, 1.0, 2.0],
    }
    for name, value in refused.items():
        before = node.node.get_parameter(name).value
        results = node.set_parameters(**{name: value})
        assert not results[0].successful, (name, value)
        assert results[0].reason, name
        assert node.node.get_parameter(name).value == before, name
    # names that are not ROS names
    assert not node.set_parameters(robot_names=['1a', 'b', 'c', 'd'])[0].successful
    assert node.node.snapshot().settings.robot_names == ('a', 'b', 'c', 'd')
    call()


def test_parameters_over_the_parameter_service(planner, ros_client):
    """A remote parameter client (what `ros2 param set` uses) sees the same validation."""
    from rclpy.parameter import Parameter
    from rclpy.parameter_client import AsyncParameterClient
    node = planner()
    remote = AsyncParameterClient(ros_client.node, node.name('planner_node'))
    assert remote.wait_for_services(timeout_sec=20)

    def result(future):
        assert ros_client.spin_until(future.done, 20)
        return future.result()

    answer = result(remote.set_parameters([Parameter('variant', value='paper'),
                                           Parameter('dimension', value=7)]))
    assert answer.results[0].successful and not answer.results[1].successful
    values = result(remote.get_parameters(['variant', 'dimension'])).values
    assert values[0].string_value == 'paper' and values[1].integer_value == 2
    described = result(remote.describe_parameters(['lane_spacing', 'dimension'])).descriptors
    assert described[0].description and described[0].floating_point_range
    assert described[1].integer_range[0].to_value == 3

    # workspace_bounds: the core's rule, for the node's dimension, and the reason said
    answer = result(remote.set_parameters([Parameter('workspace_bounds',
                                                     value=[0.0, 5.0, 3.0, 1.0])]))
    assert not answer.results[0].successful
    assert ('the wall y_min (workspace_bounds[2]) = 3 must be below y_max = 1'
            in answer.results[0].reason), answer.results[0].reason
    answer = result(remote.set_parameters([Parameter('workspace_bounds',
                                                     value=[0.0, 5.0, 0.0, 1.0, 0.0, 1.0])]))
    assert not answer.results[0].successful
    assert 'shape (d, 2) = (2, 2)' in answer.results[0].reason
    answer = result(remote.set_parameters([Parameter('workspace_bounds',
                                                     value=[-1.0, 5.0, 0.0, 1.5])]))
    assert answer.results[0].successful
    assert node.node.snapshot().settings.core_bounds.tolist() == [[-1.0, 5.0], [0.0, 1.5]]
    described = result(remote.describe_parameters(['workspace_bounds'])).descriptors[0]
    assert 'OUTSIDE_WORKSPACE' in described.description
    assert described.additional_constraints


def test_empty_list_parameters_have_their_list_type(planner, ros_client):
    """
    [] is a double (string) array over the parameter service, not a byte array nor unset.

    rclpy types an empty list default as a byte array, and [] in a parameter file
    (here None: the override it makes) leaves a parameter unset: ``ros2 param dump``
    wrote null, and loading that dump was refused.
    """
    from rcl_interfaces.msg import ParameterType
    from rclpy.parameter_client import AsyncParameterClient
    node = planner(workspace_bounds=None)
    remote = AsyncParameterClient(ros_client.node, node.name('planner_node'))
    assert remote.wait_for_services(timeout_sec=20)
    future = remote.get_parameters(['workspace_bounds', 'obstacle_radius', 'robot_names'])
    assert ros_client.spin_until(future.done, 20)
    assert [value.type for value in future.result().values] == [
        ParameterType.PARAMETER_DOUBLE_ARRAY, ParameterType.PARAMETER_DOUBLE_ARRAY,
        ParameterType.PARAMETER_STRING_ARRAY]


def test_parameters_set_with_another_type_keep_their_own(planner):
    """
    robot_radius set to the integer 1, obstacles to a bool array []: still double, double array.

    They were taken (dynamic typing), and then get_parameter_types and describe said
    integer and bool array, where msg_docs says double and double array.
    """
    from rclpy.parameter import Parameter
    node = planner(robot_radius=0.1)
    results = node.node.set_parameters([Parameter('robot_radius', value=1),
                                        Parameter('obstacles', Parameter.Type.BOOL_ARRAY, [])])
    assert all(result.successful for result in results), results
    radius, obstacles = (node.node.get_parameter(name) for name in ('robot_radius', 'obstacles'))
    assert (radius.type_, radius.value) == (Parameter.Type.DOUBLE, 1.0)
    assert (obstacles.type_, obstacles.value) == (Parameter.Type.DOUBLE_ARRAY, [])


def test_robot_names_whose_topics_rcl_refuses_are_refused_on_set(planner):
    """
    A valid relative name too long for a topic in the namespace: refused, the old ones kept.

    It was taken, every old subscription destroyed and the new ones failed (the log only
    said so).
    """
    node = planner(robot_names=['a', 'b'])
    result, = node.set_parameters(robot_names=['x' * 300])
    assert not result.successful
    assert "robot_names[0]: the topics of robot 'xxx" in result.reason, result.reason
    assert 'topic length should not exceed' in result.reason, result.reason
    assert node.node.get_parameter('robot_names').value == ['a', 'b']


def test_settings_the_obstacles_parameter_cannot_take_are_refused(planner, ros_client):
    """
    Radii, walls or obstacles the parameter's set cannot be planned with: refused on set.

    The old values stay and the node plans on; no parameter can be deleted (rclpy
    would undeclare it, and every later change would fail on it).
    """
    from rclpy.parameter_client import AsyncParameterClient
    plan_sequence = _types()[0]
    node = planner(obstacles=flat(OBSTACLES), variant='discs', robot_radius=0.2)
    client = service_client(ros_client, node)
    refused = {
        'obstacle_radius': ([0.1, 0.2], 'obstacle_radius must be a scalar or one value per '
                            'obstacle (shape (3,)), got shape (2,); to change obstacles and '
                            'obstacle_radius together'),
        'workspace_bounds': ([-1.0, 5.0, -5.0, 5.0], 'obstacle 0 at (-2, 0.5, 0) (from the '
                             'parameter) is 1 beyond the wall x_min'),
        'obstacles': ([0.0, 0.0, 0.0, 0.0, 0.0, 0.0], 'OBSTACLES_DEGENERATE with 2 obstacles '
                      'from the parameter'),
    }
    for name, (value, words) in refused.items():
        before = node.node.get_parameter(name).value
        results = node.set_parameters(**{name: value})
        assert not results[0].successful, (name, value)
        assert words in results[0].reason, results[0].reason
        assert node.node.get_parameter(name).value == before, name
    off_plane = node.set_parameters(obstacles=[0.0, 0.0, 5.0])[0]
    assert not off_plane.successful and 'OFF_PLANE' in off_plane.reason, off_plane.reason

    remote = AsyncParameterClient(ros_client.node, node.name('planner_node'))
    assert remote.wait_for_services(timeout_sec=20)
    deleted = remote.delete_parameters(['workspace_bounds', 'obstacle_radius'])
    assert ros_client.spin_until(deleted.done, 20)
    assert not any(result.successful for result in deleted.result().results)
    assert 'cannot be deleted' in deleted.result().results[0].reason
    # Every parameter is still there, and changes still take.
    assert all(r.successful for r in node.set_parameters(max_speed=0.5,
                                                         workspace_bounds=[-5.0, 5.0, -5.0,
                                                                           5.0]))
    response = ros_client.call(client, make_request())
    assert response.error_code == plan_sequence.Response.NONE, response.error_msg


def plan_slowly(monkeypatch):
    """
    Make every plan wait for a stop, and the outputs' thread's end; return the Event it sets.

    The plan is in flight as the stop begins, and its reply goes out once the outputs'
    thread has left its loop (planner_nodes, PlannerNode.note_stop; a fixed 1.5 s before).
    """
    import threading

    import punctured_planner.core as core
    from punctured_planner.nodes.planner import PlannerNode
    taken, stopping = threading.Event(), threading.Event()
    real_plan, real_note_stop = core.plan, PlannerNode.note_stop

    def note_stop(self, stop):
        real_note_stop(self, stop)
        stopping.set()

    def slow_plan(*args, **kwargs):
        taken.set()
        assert stopping.wait(20), 'no stop'
        for thread in threading.enumerate():
            if thread.name.endswith('_outputs'):  # ExecutorThreads: 'spin <node>'
                thread.join(20)
        return real_plan(*args, **kwargs)

    monkeypatch.setattr(PlannerNode, 'note_stop', note_stop)
    monkeypatch.setattr(core, 'plan', slow_plan)
    return taken


def test_requests_waiting_past_the_stop_budget_are_answered_node_stopping(
        ros_client, monkeypatch):
    """
    A stop answers every request that reached the node: planned, or NODE_STOPPING at once.

    The budget (STOP_PLANNING_SEC) set to 0: the request in flight is planned, and
    answered but not published, the two that wait behind it get NODE_STOPPING, and the
    stop ends cleanly (doc/design.md section 16). Before, every waiting request was
    planned and every plan published, and five large ones made the stop overrun its
    timeout, exit 1 and lose three replies.
    """
    import threading

    import punctured_planner.ros.runtime as runtime
    plan_sequence = _types()[0]
    monkeypatch.setattr(runtime, 'STOP_PLANNING_SEC', 0.0)
    taken = plan_slowly(monkeypatch)
    node = InProcessPlanner(obstacles=flat(OBSTACLES))
    client = service_client(ros_client, node)
    domain = Latest(ros_client.node, _types()[3], node.name('domain_index'))
    futures = [client.call_async(make_request()) for _ in range(3)]
    assert ros_client.spin_until(taken.is_set, 20)
    closing = threading.Thread(target=node.close)
    closing.start()
    assert ros_client.spin_until(lambda: all(f.done() for f in futures), 30)
    closing.join(30)
    assert not closing.is_alive()
    codes = sorted(f.result().error_code for f in futures)
    assert codes == [plan_sequence.Response.NONE] + 2 * [plan_sequence.Response.NODE_STOPPING]
    refused = [f.result() for f in futures if f.result().error_code]
    assert all('stopping' in r.error_msg and 'send it again' in r.error_msg for r in refused)
    assert all(len(r.paths) == 0 for r in refused)
    assert not ros_client.spin_until(lambda: domain.last is not None, 2), \
        'a plan answered past the budget is not published'


def test_parameters_answer_while_a_plan_runs(planner, ros_client, monkeypatch):
    """
    ros2 param get is answered while plan_sequence plans: the service has a node of its own.

    A 2,000,000-pose request held the service's thread 18 s, and a parameter get waited
    16 s behind it when the node served both.
    """
    import threading

    import punctured_planner.core as core
    from rclpy.parameter_client import AsyncParameterClient
    taken, release = threading.Event(), threading.Event()
    real_plan = core.plan

    def held_plan(*args, **kwargs):
        taken.set()
        release.wait(20)  # a long plan
        return real_plan(*args, **kwargs)

    monkeypatch.setattr(core, 'plan', held_plan)
    node = planner(obstacles=flat(OBSTACLES))
    client = service_client(ros_client, node)
    remote = AsyncParameterClient(ros_client.node, node.name('planner_node'))
    assert remote.wait_for_services(timeout_sec=20)
    planned = client.call_async(make_request())
    try:
        assert ros_client.spin_until(taken.is_set, 20)
        got = remote.get_parameters(['max_speed'])
        assert ros_client.spin_until(got.done, 5), 'parameters wait for the plan'
        assert got.result().values[0].double_value == node.node.get_parameter('max_speed').value
        assert not planned.done()
    finally:
        release.set()
    assert ros_client.spin_until(planned.done, 20)
    assert planned.result().error_code == 0, planned.result().error_msg


def test_the_service_answers_while_a_plan_is_published(planner, ros_client, monkeypatch):
    """
    The next request is answered while the plan before it is still being published.

    The outputs' thread publishes, in the order the plans were answered. On the
    service's thread, a 1.99 M-pose plan was published for 20 s after its reply, and a
    4-robot request sent behind it waited 39 s (doc/design.md section 11).
    """
    import threading

    from punctured_planner.ros import publications
    from punctured_planner_interfaces.msg import Plan
    publishing, release = threading.Event(), threading.Event()
    real_messages = publications.plan_messages

    def held_messages(*args, **kwargs):
        publishing.set()
        release.wait(20)  # a large plan being published
        return real_messages(*args, **kwargs)

    monkeypatch.setattr(publications, 'plan_messages', held_messages)
    node = planner(obstacles=flat(OBSTACLES))
    client = service_client(ros_client, node)
    published = Latest(ros_client.node, Plan, node.name('plan'))
    try:
        first = ros_client.call(client, make_request())
        assert first.error_code == 0, first.error_msg
        assert ros_client.spin_until(publishing.is_set, 20)
        second = client.call_async(make_request())
        assert ros_client.spin_until(second.done, 10), 'the reply waited for the publishing'
        assert second.result().error_code == 0, second.result().error_msg
        assert published.messages == []
    finally:
        release.set()
    # Both published, in the order answered (a reader of depth 1 may see the last only).
    last = second.result().plan_id
    assert ros_client.spin_until(
        lambda: published.last is not None and published.last.plan_id == last, 20)
    ids = [m.plan_id for m in published.messages]
    assert ids in ([first.plan_id, last], [last]), ids


def test_a_plan_answered_as_the_stop_begins_is_published(ros_client, monkeypatch):
    """
    A plan answered after the outputs' thread stopped is published at teardown.

    The request is in flight when the stop begins: the outputs' thread has left its
    loop when the reply goes out, and NodeGroup.before_teardown publishes the plan
    before the participant goes (within STOP_PLANNING_SEC, doc/design.md section 16).
    """
    import threading

    from punctured_planner_interfaces.msg import Plan
    taken = plan_slowly(monkeypatch)
    node = InProcessPlanner(obstacles=flat(OBSTACLES))
    client = service_client(ros_client, node)
    published = Latest(ros_client.node, Plan, node.name('plan'))
    planned = client.call_async(make_request())
    assert ros_client.spin_until(taken.is_set, 20)
    closing = threading.Thread(target=node.close)
    closing.start()
    assert ros_client.spin_until(planned.done, 30)
    assert planned.result().error_code == 0, planned.result().error_msg
    assert ros_client.spin_until(lambda: published.last is not None, 10), 'not published'
    assert published.last.plan_id == planned.result().plan_id
    closing.join(30)
    assert not closing.is_alive()


def test_odometry_assembles_the_current_state(planner, ros_client):
    """With robot_names, each <name>/odom feeds the current state (frame checked)."""
    plan_sequence, _, _, _, _, odometry = _types()
    names = ['r0', 'r1', 'r2', 'r3']
    node = planner(obstacles=flat(OBSTACLES), robot_names=names)
    publishers = [ros_client.node.create_publisher(odometry, node.name(n + '/odom'), 10)
                  for n in names]
    client = service_client(ros_client, node)
    yaw = [0.0, 0.0, 0.3826834323650898, 0.9238795325112867]  # 45 degrees about z

    def publish(frame='map'):
        for i, publisher in enumerate(publishers):
            msg = odometry()
            msg.header.frame_id = frame if i == 2 else 'map'
            msg.header.stamp.sec = 100 + i
            x, y, z = CONFIGURATIONS[0][i]
            msg.pose.pose.position.x, msg.pose.pose.position.y = x, y
            (msg.pose.pose.orientation.x, msg.pose.pose.orientation.y,
             msg.pose.pose.orientation.z, msg.pose.pose.orientation.w) = yaw
            publisher.publish(msg)

    def complete():
        publish()
        state = node.node.snapshot().state
        return state is not None and len(state.positions) == 4

    assert ros_client.spin_until(complete, 10), 'odometry never assembled'
    state = node.node.snapshot().state
    assert state.source.startswith('odometry') and state.stamp_ns == 100 * 10 ** 9
    response = ros_client.call(client, make_request(CONFIGURATIONS[1:],
                                                    use_current_state=True))
    assert response.error_code == plan_sequence.Response.NONE, response.error_msg
    assert list(response.projection_counts) == core_plan().projection_counts.tolist()
    start = response.paths[2].poses[0].pose
    assert (start.position.x, start.position.y) == tuple(CONFIGURATIONS[0][2][:2])
    assert start.orientation.z == pytest.approx(yaw[2]) and start.orientation.w == \
        pytest.approx(yaw[3])

    def odom_frame():
        publish(frame='odom')
        return node.node.snapshot().state.frame_id == 'odom'

    assert ros_client.spin_until(odom_frame, 10)
    response = ros_client.call(client, make_request(CONFIGURATIONS[1:],
                                                    use_current_state=True))
    assert response.error_code == plan_sequence.Response.FRAME_MISMATCH
    assert "current robot state from odometry of r0, r1, r2, r3) is in frame 'odom' (the " \
        'odometry of r2)' in response.error_msg, response.error_msg


def test_robot_names_change_the_subscriptions_in_the_inputs_thread(planner, ros_client):
    """
    robot_names set to 300 robots and back: the subscriptions change in the inputs' thread.

    The odometry of the robots kept still assembles the state. The parameters' thread
    destroyed them while the inputs' executor built its wait set from them: InvalidHandle
    there stopped the node (exit 1), intermittently.
    """
    odometry = _types()[5]
    names = ['r0', 'r1']
    node = planner(obstacles=flat(OBSTACLES), robot_names=names)
    inputs = node.node.inputs
    changed_in = []
    for method in ('create_subscription', 'destroy_subscription'):
        def recorded(*args, _method=getattr(inputs, method), **kwargs):
            changed_in.append(threading.current_thread().name)
            return _method(*args, **kwargs)
        setattr(inputs, method, recorded)
    many = ['r%d' % i for i in range(300)]
    for _ in range(3):
        assert node.set_parameters(robot_names=many)[0].successful
        assert node.set_parameters(robot_names=names)[0].successful
    spin = 'spin ' + inputs.get_fully_qualified_name()
    assert ros_client.spin_until(lambda: len(node.node._odometry_subscriptions) == 2
                                 and len(changed_in) >= 2 * 298, 20), len(changed_in)
    assert set(changed_in) == {spin}, set(changed_in)
    publishers = [ros_client.node.create_publisher(odometry, node.name(n + '/odom'), 10)
                  for n in names]

    def complete():
        for i, publisher in enumerate(publishers):
            msg = odometry()
            msg.header.frame_id = 'map'
            msg.pose.pose.position.x = float(i)
            msg.pose.pose.orientation.w = 1.0
            publisher.publish(msg)
        state = node.node.snapshot().state
        return state is not None and len(state.positions) == 2

    assert ros_client.spin_until(complete, 10), 'odometry never assembled'
    assert node.threads.failure is None, node.threads.failure


def test_planning_does_not_block_the_subscriptions(planner, ros_client):
    """While a long plan runs in the service callback, robot_states still come in."""
    plan_sequence, pose_array_type, _, _, _, _ = _types()
    node = planner(max_poses=100000000)
    states = ros_client.node.create_publisher(pose_array_type, node.name('robot_states'), 10)
    client = service_client(ros_client, node)
    rng = np.random.default_rng(7)
    big = np.concatenate([rng.uniform(-50, 50, size=(3, 200, 2)), np.zeros((3, 200, 1))],
                         axis=2)

    def state_seen():
        states.publish(pose_array(CONFIGURATIONS[2]))
        return node.node.snapshot().state is not None

    assert ros_client.spin_until(state_seen, 10)
    future = client.call_async(make_request(big, samples_per_leg=10))  # 39,800 poses
    received = [CONFIGURATIONS[2][0][0]]
    deadline = time.monotonic() + 60
    while not future.done() and time.monotonic() < deadline:
        states.publish(pose_array(CONFIGURATIONS[len(received) % 3]))
        ros_client.executor.spin_once(timeout_sec=0.02)
        state = node.node.snapshot().state
        if state is not None and (not received or state.positions[0, 0]
                                  != received[-1]):
            received.append(state.positions[0, 0])
    assert future.done(), 'the large plan did not finish within 60 s'
    assert future.result().error_code == plan_sequence.Response.NONE
    assert len(received) >= 3, 'robot_states were not processed while planning'


def test_a_second_client_context_gets_the_same_latched_plan(planner, ros_client):
    """Another process-like client (own Context) joining later sees the last plan."""
    plan_sequence, _, path_type, _, _, _ = _types()
    node = planner(obstacles=flat(OBSTACLES))
    response = ros_client.call(service_client(ros_client, node), make_request())
    assert response.error_code == plan_sequence.Response.NONE
    other = RosClient('late_client')
    try:
        late = Latest(other.node, path_type, node.name('robot_1/plan'))
        assert other.spin_until(lambda: late.last is not None, 10)
        assert late.last == response.paths[1]
    finally:
        other.close()


def test_a_bad_obstacle_set_is_refused_on_arrival(planner, ros_client, monkeypatch):
    """Wrong frame, off the plane, outside the walls: warned and refused, the good set stays."""
    from punctured_planner.cli import reset_obstacles
    from punctured_planner.ros.qos import LATCHED
    _, pose_array_type, _, _, _, _ = _types()
    node = planner(obstacles=flat(OBSTACLES), workspace_bounds=[-6.0, 6.0, -6.0, 6.0])
    checked = []
    original = node.node._handler.check_obstacles

    def spy(settings, obstacles):
        checked.append(obstacles)
        return original(settings, obstacles)
    monkeypatch.setattr(node.node._handler, 'check_obstacles', spy)
    publisher = ros_client.node.create_publisher(pose_array_type, node.name('obstacles'),
                                                 LATCHED)
    for bad in (pose_array(OBSTACLES, frame_id='odom'),
                pose_array([[0.0, 0.0, 0.3], [1.0, 0.0, 0.0]]),
                pose_array([[0.0, 0.0, 0.0], [6.5, 0.0, 0.0]])):
        count = len(checked)
        publisher.publish(bad)
        assert ros_client.spin_until(lambda: len(checked) > count, 10)
        assert node.node.snapshot().obstacles.source == 'parameter'
    good = [[5.0, 5.0, 0.0]]
    publisher.publish(pose_array(good))
    assert ros_client.spin_until(
        lambda: node.node.snapshot().obstacles.source.endswith('/obstacles'), 10)
    assert np.array_equal(node.node.snapshot().obstacles.points, good)
    # Back to the parameter's set without `ros2 param set` (punctured-planner reset-obstacles).
    assert reset_obstacles(ros_client.node, ros_client.executor, node.name('planner_node'),
                           10.0) is None
    assert node.node.snapshot().obstacles.source == 'parameter'
    assert np.array_equal(node.node.snapshot().obstacles.points, OBSTACLES)


def test_reset_obstacles_keeps_an_obstacles_parameter_of_integers_or_empty(planner, ros_client):
    """
    punctured-planner reset-obstacles sets the parameter's own value again, integers too.

    The parameter is dynamically typed, so [0, 2, 0, 3, 0, 0] is an integer array; before,
    the command read the double array alone, set [] and reported success.
    """
    from punctured_planner.cli import reset_obstacles
    from punctured_planner.ros.qos import LATCHED
    _, pose_array_type, _, _, _, _ = _types()
    node = planner(obstacles=[0, 2, 0, 3, 0, 0])
    publisher = ros_client.node.create_publisher(pose_array_type, node.name('obstacles'),
                                                 LATCHED)
    publisher.publish(pose_array([[5.0, 5.0, 0.0]]))
    assert ros_client.spin_until(
        lambda: node.node.snapshot().obstacles.source.endswith('/obstacles'), 10)
    assert reset_obstacles(ros_client.node, ros_client.executor, node.name('planner_node'),
                           10.0) is None
    assert node.node.snapshot().obstacles.source == 'parameter'
    assert node.node.snapshot().obstacles.points.tolist() == [[0, 2, 0], [3, 0, 0]]
    # obstacles: [] (no obstacles) as a parameter file gives it: no value type at all
    empty = planner(obstacles=None)
    assert reset_obstacles(ros_client.node, ros_client.executor, empty.name('planner_node'),
                           10.0) is None
    assert empty.node.snapshot().obstacles.points.size == 0
