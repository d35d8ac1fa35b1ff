"""
Closed loop over real DDS: planner_node, fleet_sim and plan_executor as processes.

Three disc robots, one at half speed, one with 100 ms command latency, 5%
velocity noise, 1 m/s^2 bases and a plan timed for them (unlimited, the plan turns its
corners at full speed, and the late robot, 0.1 m off its reference in its latency
alone, left the tolerance of 0.2 m on a loaded machine: 0.205 m). One run checks the
refusals (no plan, a robot not heard, odometry in another frame), a goal that waits
for its plan, a full execution with a stale robot in the middle (the clock holds,
then resumes), the true gap, the arrival, a cancel, and Ctrl-C of the executor in
the middle of a goal (the goal ends STOPPED, exit 0, no traceback, robots stopped,
the simulator serving on). A second graph runs the same scene with differential-drive robots: only
linear.x and angular.z commanded, the centres within the tolerance, each robot
ending on its goal facing the requested heading. The figures for 20 robots are
in bench/.
"""

import itertools
import re
import signal
import time

from conftest import NodeProcess
from conftest import venv_script
import numpy as np
import pytest

pytestmark = [pytest.mark.ros, pytest.mark.slow]

NAMES = ['r0', 'r1', 'r2']
START = [[-1.5, -1.2, 0.0], [0.0, -1.4, 0.0], [1.5, -1.2, 0.0]]
GOAL = [[-1.5, 1.2, 0.0], [0.0, 1.4, 0.0], [1.5, 1.2, 0.0]]
OBSTACLES = [-1.0, 0.3, 0.0, 0.1, -0.3, 0.0, 1.2, 0.0, 0.0]
RADIUS = 0.1
PARAMETERS = """
/**:
  ros__parameters:
    frame_id: map
    robot_names: [r0, r1, r2]
    obstacles: %(obstacles)s
/**/planner_node:
  ros__parameters:
    variant: spread
    robot_radius: %(radius)s
    min_spacing: 0.5
    lane_spacing: 0.5
    max_speed: 1.0
    max_acceleration: 1.0
/**/fleet_sim:
  ros__parameters:
    initial_positions: %(start)s
    robot_radius: %(radius)s
    speed_limit: 1.0
    speed_factors: [0.5, 1.0, 1.0]
    latencies: [0.0, 0.1, 0.0]
    velocity_noise: 0.05
    max_acceleration: [1.0]
/**/plan_executor:
  ros__parameters:
    speed_limit: 1.0
    discovery_timeout: 1.0
""" % {'obstacles': OBSTACLES, 'start': [v for p in START for v in p], 'radius': RADIUS}
# The same scene with TurtleBot-like differential robots (0.3 m/s, 1.9 rad/s).
DIFFERENTIAL = PARAMETERS.replace('max_speed: 1.0', 'max_speed: 0.3').replace(
    'speed_limit: 1.0', 'speed_limit: 0.3').replace(
    'speed_factors: [0.5, 1.0, 1.0]', 'speed_factors: [0.8, 1.0, 1.0]').replace(
    'velocity_noise: 0.05\n', 'velocity_noise: 0.05\n    drive: [differential]\n'
    '    yaw_rate_limit: 1.9\n    max_yaw_acceleration: 8.0\n'
).replace('discovery_timeout: 1.0\n', 'discovery_timeout: 1.0\n    drive: [differential]\n'
          '    yaw_rate_limit: 1.9\n')
# The headings the differential robots are asked to end in (rad).
FINAL_YAWS = [np.pi / 2, np.pi, -np.pi / 2]


class Graph:
    """The three processes and the test's client: action, service, parameters, topics."""

    def __init__(self, client, env, tmp_path, namespace, parameters=PARAMETERS):
        """Start the nodes in one namespace and connect the client to them."""
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from punctured_planner.ros.qos import LATCHED
        from punctured_planner_interfaces.action import ExecutePlan
        from punctured_planner_interfaces.srv import PlanSequence
        from rclpy.action import ActionClient
        from rclpy.parameter_client import AsyncParameterClient
        from std_msgs.msg import Float64
        params = tmp_path / 'execution.yaml'
        params.write_text(parameters, encoding='utf-8')
        self.client = client
        self.namespace = namespace
        self.processes = {
            name: NodeProcess([venv_script(name), '--ros-args', '-r', '__ns:=' + namespace,
                               '--params-file', str(params)], env,
                              str(tmp_path / (name + '.log')), namespace)
            for name in ('planner_node', 'fleet_sim', 'plan_executor')}
        node = client.node
        self.plan_sequence = node.create_client(PlanSequence, self.name('plan_sequence'))
        self.action = ActionClient(node, ExecutePlan, self.name('execute_plan'))
        self.sim_parameters = AsyncParameterClient(node, self.name('fleet_sim'))
        self.executor_parameters = AsyncParameterClient(node, self.name('plan_executor'))
        self.odometry = {}
        self.commands = {name: [] for name in NAMES}
        for name in NAMES:
            node.create_subscription(Odometry, self.name(name + '/odom'),
                                     lambda msg, name=name: self.odometry.__setitem__(
                                         name, msg), 10)
            node.create_subscription(Twist, self.name(name + '/cmd_vel'),
                                     lambda msg, name=name: self.commands[name].append(
                                         (time.monotonic(), msg)), 10)
        self.gap = []
        node.create_subscription(Float64, self.name('fleet_sim/min_gap'),
                                 lambda msg: self.gap.append(msg.data), LATCHED)

    def connect(self):
        """Wait until every node is discovered and every robot has reported."""
        client = self.client
        client.wait_for_service(self.plan_sequence, 30)
        assert self.action.wait_for_server(timeout_sec=30), self.logs()
        assert self.sim_parameters.wait_for_services(timeout_sec=30), self.logs()
        assert self.executor_parameters.wait_for_services(timeout_sec=30), self.logs()
        assert client.spin_until(lambda: len(self.odometry) == len(NAMES), 30), self.logs()

    def name(self, relative):
        """Return the absolute name of a relative topic, service, action or node."""
        return '%s/%s' % (self.namespace, relative)

    def logs(self):
        """Return every process's output, for failure messages."""
        return '\n'.join('--- %s\n%s' % (n, p.log()) for n, p in self.processes.items())

    def plan(self, configurations, orientations=None):
        """Plan from the robots' current state; return the response."""
        from punctured_planner_interfaces.srv import PlanSequence
        from planner_helpers import pose_array
        request = PlanSequence.Request(use_current_state=True)
        request.configurations = [pose_array(c, orientations=orientations)
                                  for c in configurations]
        response = self.client.call(self.plan_sequence, request)
        deadline = time.monotonic() + 10
        while (response.error_code == PlanSequence.Response.NO_ROBOT_STATE
               and time.monotonic() < deadline):
            # the planner's own odometry subscriptions may match a little later than ours
            self.client.spin_until(lambda: False, 0.2)
            response = self.client.call(self.plan_sequence, request)
        assert response.error_code == 0, response.error_msg + self.logs()
        # the latched plan reaches the executor on its own topic, maybe after the response
        executor = self.processes['plan_executor']
        assert self.client.spin_until(
            lambda: 'plan %d:' % response.plan_id in executor.log(), 10), self.logs()
        return response

    def set_sim(self, **values):
        """Set fleet_sim parameters; fail unless every one is accepted."""
        self._set(self.sim_parameters, values)

    def set_executor(self, **values):
        """Set plan_executor parameters; fail unless every one is accepted."""
        self._set(self.executor_parameters, values)

    def _set(self, parameters, values):
        from rclpy.parameter import Parameter
        future = parameters.set_parameters(
            [Parameter(name, value=value) for name, value in values.items()])
        assert self.client.spin_until(future.done, 10)
        assert all(r.successful for r in future.result().results), future.result()

    def send(self, plan_id=0):
        """Send a goal; return (goal handle, feedback list)."""
        from punctured_planner_interfaces.action import ExecutePlan
        feedback = []
        future = self.action.send_goal_async(
            ExecutePlan.Goal(plan_id=plan_id),
            feedback_callback=lambda msg: feedback.append((time.monotonic(), msg.feedback)))
        assert self.client.spin_until(future.done, 10)
        handle = future.result()
        assert handle.accepted
        return handle, feedback

    def result(self, handle, timeout_sec=60):
        """Wait for a goal's result message."""
        future = handle.get_result_async()
        assert self.client.spin_until(future.done, timeout_sec), self.logs()
        return future.result().result

    def positions(self):
        """Return where the robots are now, by their latest odometry: (k, 3)."""
        return np.array([[o.pose.pose.position.x, o.pose.pose.position.y,
                          o.pose.pose.position.z] for o in
                         (self.odometry[name] for name in NAMES)])

    def speeds(self):
        """Return how fast the robots move now, by their latest odometry: (k,)."""
        return np.array([np.hypot(o.twist.twist.linear.x, o.twist.twist.linear.y)
                         for o in (self.odometry[name] for name in NAMES)])


@pytest.fixture
def graph(ros_client, ros_env, tmp_path):
    """Start the graph; stop every process after the test."""
    yield from started_graph(ros_client, ros_env, tmp_path, 'pp_exec', PARAMETERS)


@pytest.fixture
def differential_graph(ros_client, ros_env, tmp_path):
    """Start the graph of differential robots; stop every process after the test."""
    yield from started_graph(ros_client, ros_env, tmp_path, 'pp_exec_dd', DIFFERENTIAL)


def started_graph(ros_client, ros_env, tmp_path, tag, parameters):
    """Yield a connected Graph; stop every process afterwards."""
    import os
    started = Graph(ros_client, ros_env, tmp_path, '/%s_%d' % (tag, os.getpid()), parameters)
    try:
        started.connect()
        yield started
    finally:
        # rclpy does not destroy an ActionClient with its node: a live one left in this
        # process makes later forked workers (flake8's) crash at exit
        started.action.destroy()
        for process in started.processes.values():
            process.stop()


def test_plan_to_motion_over_dds(graph):
    from nav_msgs.msg import Odometry
    from punctured_planner_interfaces.action import ExecutePlan
    result_type = ExecutePlan.Result
    client = graph.client

    # refused: no plan yet, then a plan id that is not there
    result = graph.result(graph.send(0)[0])
    assert result.error_code == result_type.NO_PLAN and 'no plan' in result.error_msg

    response = graph.plan([GOAL])
    assert response.plan_id == 1
    assert response.tracking_tolerance == pytest.approx(response.min_gap / 2)
    assert 0 < response.min_gap < response.min_clearance  # bodies: the surface gap
    result = graph.result(graph.send(7)[0])
    assert result.error_code == result_type.NO_PLAN and 'plan 7' in result.error_msg

    # refused: a robot it does not hear from, then odometry in another frame
    graph.set_sim(muted_robots=['r2'])
    time.sleep(0.6)
    result = graph.result(graph.send(1)[0])
    assert result.error_code == result_type.UNKNOWN_ROBOTS, result.error_msg
    assert 'r2' in result.error_msg and 'r0' not in result.error_msg
    graph.set_sim(muted_robots=[], frame_id='odom')
    result = graph.result(graph.send(1)[0])
    assert result.error_code == result_type.FRAME_MISMATCH, result.error_msg
    assert "'odom'" in result.error_msg and "'map'" in result.error_msg
    graph.set_sim(frame_id='map')
    time.sleep(0.3)

    # executed, with r2's odometry gone for a while in the middle
    handle, feedback = graph.send(1)
    assert client.spin_until(lambda: feedback and feedback[-1][1].plan_time > 1.0, 20)
    graph.set_sim(muted_robots=['r2'])
    assert client.spin_until(lambda: feedback[-1][1].stale_robots == ['r2'], 5), graph.logs()
    stale_at = feedback[-1][1].plan_time
    # the clock brakes within the plan's acceleration limit (0.6 of 1 m/s^2: 1.7 s from
    # 1 m/s at most, 0.83 s of plan time), then holds
    assert client.spin_until(lambda: feedback[-1][1].clock_rate == 0.0, 3), graph.logs()
    held = feedback[-1][1].plan_time
    assert stale_at <= held < stale_at + 1.0
    client.spin_until(lambda: False, 0.5)
    assert feedback[-1][1].plan_time == held and feedback[-1][1].clock_rate == 0.0
    graph.set_sim(muted_robots=[])
    assert client.spin_until(lambda: feedback[-1][1].plan_time > held + 0.5, 10)
    # odometry that is no pose is ignored (warned): before, one NaN position made the clock
    # jump to the plan's end and every robot get NaN velocities for good
    not_a_pose = Odometry()
    not_a_pose.header.frame_id = 'map'
    not_a_pose.pose.pose.position.x = float('nan')
    publisher = client.node.create_publisher(Odometry, graph.name('r1/odom'), 10)
    for _ in range(5):
        publisher.publish(not_a_pose)
        client.spin_until(lambda: False, 0.04)
    client.node.destroy_publisher(publisher)
    result = graph.result(handle)
    assert result.error_code == result_type.NONE, result.error_msg + graph.logs()
    executed = result.executed_duration.sec + result.executed_duration.nanosec * 1e-9
    planned = response.duration.sec + response.duration.nanosec * 1e-9
    assert planned < executed < 2 * 1.5 * planned + 3.0
    assert max(result.max_tracking_errors) <= response.tracking_tolerance
    assert client.spin_until(lambda: graph.gap, 5)
    assert graph.gap[-1] >= 0.0, graph.processes['fleet_sim'].log()
    client.spin_until(lambda: False, 0.3)
    assert np.linalg.norm(graph.positions() - GOAL, axis=1).max() <= 0.02
    executor_log = graph.processes['plan_executor'].log()
    assert 'odometry of r1 ignored: its position (nan, ' in executor_log, executor_log
    assert all(np.isfinite([m.linear.x, m.linear.y, m.angular.z]).all()
               for name in NAMES for _, m in graph.commands[name])
    # the same plan again, its robots now at its end: refused, never driven back in a
    # straight line to a start its certificate needs
    result = graph.result(graph.send(1)[0])
    assert result.error_code == result_type.NOT_AT_START, result.error_msg
    named = dict(re.findall(r'(r\d) ([0-9.]+) m', result.error_msg))
    assert sorted(named) == NAMES, result.error_msg
    assert all(abs(float(named[name]) - np.linalg.norm(np.subtract(GOAL[i], START[i])))
               <= 0.02 for i, name in enumerate(NAMES)), result.error_msg

    # a goal sent before its plan waits for it (the planner answers before it publishes),
    # then a cancel: every robot is commanded zero at once and stops
    handle, feedback = graph.send(2)
    assert graph.plan([START]).plan_id == 2
    assert client.spin_until(lambda: feedback and feedback[-1][1].plan_time > 1.0, 20)
    assert graph.speeds().max() > 0.1
    # the mode holds for the goal's whole run: switched to reference now, the goal still
    # commands its robots, and the cancel still sends them zero (it sent nothing before)
    graph.set_executor(mode='reference')
    cancel = handle.cancel_goal_async()
    asked = time.monotonic()
    assert client.spin_until(cancel.done, 5)
    result = graph.result(handle)
    assert result.error_code == result_type.CANCELED
    client.spin_until(lambda: False, 0.5)
    for name in NAMES:
        last = graph.commands[name][-1]
        assert last[0] - asked < 0.2 and last[1].linear.x == last[1].linear.y == 0.0, name
    # braking at 1 m/s^2 from at most 1 m/s
    assert client.spin_until(lambda: graph.speeds().max() < 1e-9, 1.5), graph.speeds()
    graph.set_executor(mode='velocity')

    # a robot that cannot move, its odometry fresh, holds the clock: the goal ends
    # CLOCK_HELD after hold_timeout (before, the fleet waited for it for good)
    graph.set_sim(speed_factors=[1.0, 0.0, 1.0])
    graph.set_executor(hold_timeout=1.0)
    graph.plan([GOAL])
    handle, feedback = graph.send(0)
    result = graph.result(handle, 30)
    assert result.error_code == result_type.CLOCK_HELD, result.error_msg + graph.logs()
    assert 'hold_timeout 1 s' in result.error_msg, result.error_msg
    assert 'the clock waits for r1 ' in result.error_msg, result.error_msg
    assert client.spin_until(lambda: graph.speeds().max() < 1e-9, 1.5), graph.speeds()
    # hold_timeout 0: the goal's first step, whose rate rises from 0 under the plan's
    # acceleration limit, is no hold (before, every such goal ended CLOCK_HELD at once)
    graph.set_sim(speed_factors=[0.5, 1.0, 1.0])
    graph.set_executor(hold_timeout=0.0)
    graph.plan([START])
    handle, feedback = graph.send(0)
    ended = handle.get_result_async()
    assert client.spin_until(lambda: ended.done() or (
        feedback and feedback[-1][1].plan_time > 0.2), 20), graph.logs()
    assert not ended.done(), ended.result().result.error_msg
    handle.cancel_goal_async()
    assert client.spin_until(ended.done, 10)
    graph.set_executor(hold_timeout=5.0)

    # goals that wait for a plan not out yet: a cancel ends one at once, a newer goal
    # preempts one; before, the cancel was accepted and ignored (the plan, once out, ran
    # to its end) and a waiting goal, once its plan came, took over from the newer one
    # running, which never got a result
    waiting, _ = graph.send(50)
    client.spin_until(lambda: False, 0.3)
    asked = time.monotonic()
    cancel = waiting.cancel_goal_async()
    assert client.spin_until(cancel.done, 5)
    result = graph.result(waiting)
    assert result.error_code == result_type.CANCELED, result.error_msg
    assert 'waiting for plan 50' in result.error_msg
    assert time.monotonic() - asked < 2.0, 'a cancel does not wait for the plan'
    first, _ = graph.send(51)
    client.spin_until(lambda: False, 0.3)
    second, _ = graph.send(52)
    result = graph.result(first)
    assert result.error_code == result_type.PREEMPTED, result.error_msg
    assert 'waiting for plan 51' in result.error_msg
    assert graph.result(second).error_code == result_type.NO_PLAN

    # Ctrl-C of the executor in the middle of a goal: exit 0, robots stopped
    graph.plan([GOAL])
    handle, feedback = graph.send(0)
    assert client.spin_until(lambda: feedback and feedback[-1][1].plan_time > 0.5, 20)
    executor = graph.processes['plan_executor']
    executor.proc.send_signal(signal.SIGINT)
    # the goal ends with a code of its own, its result out before the node goes, also to
    # a client that asks for it only after the stop began (doc/design.md section 16)
    client.spin_until(lambda: False, 0.1)
    stopped = handle.get_result_async()
    assert client.spin_until(stopped.done, 10), executor.log()
    assert stopped.result().result.error_code == result_type.STOPPED, executor.log()
    assert executor.proc.wait(timeout=10) == 0, executor.log()
    assert client.spin_until(lambda: graph.speeds().max() < 1e-9, 1.5), graph.speeds()
    graph.processes['fleet_sim'].assert_running()
    for name in ('fleet_sim', 'plan_executor'):
        process = graph.processes[name]
        assert process.stop() == 0
        assert 'Traceback' not in process.log(), process.log()


def test_differential_robots_over_dds(differential_graph):
    """Only linear.x and angular.z reach the robots; within delta; on goal, facing FINAL_YAWS."""
    from geometry_msgs.msg import Twist
    from punctured_planner_interfaces.action import ExecutePlan
    from scipy.spatial.transform import Rotation
    graph, client = differential_graph, differential_graph.client
    quaternions = Rotation.from_euler('z', np.array(FINAL_YAWS)[:, None]).as_quat()
    response = graph.plan([GOAL], quaternions)
    handle, _ = graph.send(response.plan_id)
    result = graph.result(handle, timeout_sec=90)
    assert result.error_code == ExecutePlan.Result.NONE, result.error_msg + graph.logs()
    assert max(result.max_tracking_errors) <= response.tracking_tolerance
    assert client.spin_until(lambda: graph.gap, 5)
    assert graph.gap[-1] >= 0.0, graph.processes['fleet_sim'].log()
    client.spin_until(lambda: False, 0.5)
    assert np.linalg.norm(graph.positions() - GOAL, axis=1).max() <= 0.02
    yaws = [Rotation.from_quat([o.pose.pose.orientation.x, o.pose.pose.orientation.y,
                                o.pose.pose.orientation.z, o.pose.pose.orientation.w]
                               ).as_euler('xyz')[2] for o in
            (graph.odometry[name] for name in NAMES)]
    assert np.abs(np.angle(np.exp(1j * (np.array(yaws) - FINAL_YAWS)))).max() <= 0.05
    commands = [m for name in NAMES for _, m in graph.commands[name]]
    assert len(commands) > 100 and any(m.angular.z != 0.0 for m in commands)
    assert all(m.linear.y == 0.0 and m.linear.z == 0.0 for m in commands)
    sim = graph.processes['fleet_sim']
    assert 'linear.y' not in sim.log()
    # a sideways command reaches r0 twice: ignored, and said once
    publisher = client.node.create_publisher(Twist, graph.name('r0/cmd_vel'), 10)
    for _ in range(2):
        publisher.publish(Twist(linear=graph_vector(0.0, 0.2)))
        client.spin_until(lambda: False, 0.2)
    assert client.spin_until(lambda: 'linear.y' in sim.log(), 5), sim.log()
    client.spin_until(lambda: False, 0.3)
    assert sim.log().count('linear.y = 0.2 ignored') == 1, sim.log()
    assert np.linalg.norm(graph.positions()[0] - GOAL[0]) <= 0.02


def graph_vector(x, y):
    """Return a geometry_msgs/Vector3 (x, y, 0)."""
    from geometry_msgs.msg import Vector3
    return Vector3(x=float(x), y=float(y))


_lone = itertools.count(1)


@pytest.fixture
def lone_executor(ros_client, ros_env, tmp_path):
    """Start plan_executor alone in a namespace of its own; yield (process, action client)."""
    import os

    from punctured_planner_interfaces.action import ExecutePlan
    from rclpy.action import ActionClient
    namespace = '/pp_exec_alone_%d_%d' % (os.getpid(), next(_lone))
    executor = NodeProcess([venv_script('plan_executor'), '--ros-args', '-r',
                            '__ns:=' + namespace], ros_env,
                           str(tmp_path / 'plan_executor.log'), namespace)
    action = ActionClient(ros_client.node, ExecutePlan, namespace + '/execute_plan')
    try:
        assert action.wait_for_server(timeout_sec=30), executor.log()
        yield executor, action
    finally:
        action.destroy()
        executor.stop()


def test_a_goal_waiting_for_its_plan_ends_stopped_at_a_stop(ros_client, lone_executor):
    """SIGINT while a goal waits for its plan: the goal ends STOPPED, exit 0 (no result lost)."""
    from punctured_planner_interfaces.action import ExecutePlan
    executor, action = lone_executor
    sent = action.send_goal_async(ExecutePlan.Goal(plan_id=99))
    assert ros_client.spin_until(sent.done, 10) and sent.result().accepted
    ros_client.spin_until(lambda: False, 0.3)
    executor.proc.send_signal(signal.SIGINT)
    result = sent.result().get_result_async()
    assert ros_client.spin_until(result.done, 10), executor.log()
    assert result.result().result.error_code == ExecutePlan.Result.STOPPED, executor.log()
    assert 'waiting for plan 99' in result.result().result.error_msg
    assert executor.proc.wait(timeout=10) == 0, executor.log()
    assert 'Traceback' not in executor.log(), executor.log()


def test_a_goal_for_a_plan_that_is_no_plan_ends_at_once_saying_why(ros_client, lone_executor):
    """
    A goal waiting for plan 7 ends NO_PLAN as soon as plan 7 arrives malformed, with why.

    Before, it waited PLAN_WAIT_SEC and ended "plan 7 is not there" (the reason was only in
    the executor's log), and a goal for the latest plan ran an older one.
    """
    from planner_helpers import faulty_plan
    from punctured_planner.nodes.executor import PLAN_WAIT_SEC
    from punctured_planner.ros.qos import LATCHED
    from punctured_planner_interfaces.action import ExecutePlan
    from punctured_planner_interfaces.msg import Plan
    executor, action = lone_executor
    publisher = ros_client.node.create_publisher(Plan, executor.name('plan'), LATCHED)
    try:
        sent = action.send_goal_async(ExecutePlan.Goal(plan_id=7))
        assert ros_client.spin_until(sent.done, 10) and sent.result().accepted
        ros_client.spin_until(lambda: False, 0.3)
        message = faulty_plan('nan')
        message.plan_id = 7
        published = time.monotonic()
        publisher.publish(message)
        result = sent.result().get_result_async()
        assert ros_client.spin_until(result.done, 10), executor.log()
        waited = time.monotonic() - published
        ended = result.result().result
        assert ended.error_code == ExecutePlan.Result.NO_PLAN, ended
        assert waited < PLAN_WAIT_SEC, (waited, ended.error_msg)
        assert ended.error_msg.startswith(
            'plan 7 on %s was ignored: plan 7: the path of robot_2 has a non-finite pose'
            % executor.name('plan')), ended.error_msg
        latest = action.send_goal_async(ExecutePlan.Goal(plan_id=0))
        assert ros_client.spin_until(latest.done, 10) and latest.result().accepted
        result = latest.result().get_result_async()
        assert ros_client.spin_until(result.done, 10), executor.log()
        assert result.result().result.error_msg.startswith('the latest, plan 7 on'), \
            result.result().result
        assert 'Traceback' not in executor.log(), executor.log()
    finally:
        ros_client.node.destroy_publisher(publisher)


def test_a_plan_whose_robot_topics_rcl_refuses_is_ignored_saying_why(ros_client,
                                                                     lone_executor):
    """
    A robot named with 240 characters: its topics are too long here; the plan is no plan.

    plan_executor subscribed to its odometry as the plan came: rcl's exception ended the
    node (exit 1), the waiting goal lost its result, and a restart crashed again on the
    latched plan.
    """
    from planner_helpers import faulty_plan
    from punctured_planner.ros.qos import LATCHED
    from punctured_planner_interfaces.action import ExecutePlan
    from punctured_planner_interfaces.msg import Plan
    executor, action = lone_executor
    publisher = ros_client.node.create_publisher(Plan, executor.name('plan'), LATCHED)
    try:
        sent = action.send_goal_async(ExecutePlan.Goal(plan_id=7))
        assert ros_client.spin_until(sent.done, 10) and sent.result().accepted
        message = faulty_plan('long name')
        message.plan_id = 7
        publisher.publish(message)
        result = sent.result().get_result_async()
        assert ros_client.spin_until(result.done, 10), executor.log()
        ended = result.result().result
        assert ended.error_code == ExecutePlan.Result.NO_PLAN, ended
        assert "the topics of robot 'rrrr" in ended.error_msg, ended.error_msg
        assert 'no valid topic names in namespace %s' % executor.name('')[:-1] in \
            ended.error_msg, ended.error_msg
        assert executor.proc.poll() is None and 'Traceback' not in executor.log(), \
            executor.log()
    finally:
        ros_client.node.destroy_publisher(publisher)


def test_plans_published_back_to_back_are_all_kept(ros_client, lone_executor):
    """
    Eight plans published in a burst are all kept (the planner publishes plans so).

    The planner's outputs' thread publishes the plans answered while it published
    another back to back (doc/design.md section 11); read with depth 1, plan_executor
    kept plans 1 and 8 of them, and a goal for any other ended NO_PLAN.
    """
    from planner_helpers import faulty_plan
    from punctured_planner.ros.qos import LATCHED
    from punctured_planner_interfaces.msg import Plan
    executor, _ = lone_executor
    publisher = ros_client.node.create_publisher(Plan, executor.name('plan'), LATCHED)
    try:
        message = faulty_plan('none')
        # Matched both ways first: a reader that matches the writer later gets its
        # latest message only (transient local, depth 1), as from any latched topic.
        message.plan_id = 1
        publisher.publish(message)
        assert ros_client.spin_until(lambda: 'plan 1: 4 robots' in executor.log(), 10), \
            executor.log()
        for plan_id in range(2, 10):
            message.plan_id = plan_id
            publisher.publish(message)
        kept = ['plan %d: 4 robots' % plan_id for plan_id in range(2, 10)]
        assert ros_client.spin_until(lambda: all(k in executor.log() for k in kept), 10), \
            executor.log()
    finally:
        ros_client.node.destroy_publisher(publisher)


def test_a_large_plan_is_taken_apart_from_goals_and_control(ros_client, lone_executor):
    """
    A goal is accepted while a plan of 4 x 43,000 poses is still taken and converted (3 s).

    plan_executor took plans in the thread of its action and its control loop: such a plan,
    not even executed, held them 8.7 s, and the robots of a running goal got no command.
    """
    from planner_helpers import faulty_plan
    from punctured_planner.ros.qos import LATCHED
    from punctured_planner_interfaces.action import ExecutePlan
    from punctured_planner_interfaces.msg import Plan
    executor, action = lone_executor
    publisher = ros_client.node.create_publisher(Plan, executor.name('plan'), LATCHED)
    try:
        message = faulty_plan('none', samples_per_leg=300)
        message.plan_id = 5
        publisher.publish(message)
        ros_client.spin_until(lambda: False, 1.0)  # on its way, then taken
        sent = action.send_goal_async(ExecutePlan.Goal(plan_id=5))
        assert ros_client.spin_until(sent.done, 30) and sent.result().accepted
        assert 'plan 5: 4 robots' not in executor.log(), executor.log()
        assert ros_client.spin_until(lambda: 'plan 5: 4 robots' in executor.log(), 60), \
            executor.log()
    finally:
        ros_client.node.destroy_publisher(publisher)


def test_a_goal_starts_only_with_its_robots_at_rest(ros_client, lone_executor):
    """
    Robots at the plan's start whose odometry reports 0.3 m/s: the goal waits, then starts.

    A goal that preempted a moving one started at once, its robots braking past a
    reference that starts at rest (1.2 delta over DDS); robots that do not stop within
    discovery_timeout end it NOT_AT_START, named with their speeds; settings changed
    while it waits are checked when it starts.
    """
    from nav_msgs.msg import Odometry
    from planner_helpers import faulty_plan
    from punctured_planner.ros import conversions
    from punctured_planner.ros.qos import LATCHED
    from punctured_planner.ros.qos import STATE
    from punctured_planner_interfaces.action import ExecutePlan
    from punctured_planner_interfaces.msg import Plan
    from rclpy.parameter import Parameter
    from rclpy.parameter_client import AsyncParameterClient
    executor, action = lone_executor
    message = faulty_plan('none')
    start = conversions.plan_reference(message).position(0.0)
    node = ros_client.node
    plans = node.create_publisher(Plan, executor.name('plan'), LATCHED)
    odometry = {name: node.create_publisher(Odometry, executor.name(name + '/odom'), STATE)
                for name in message.robot_names}
    speed = [0.3]

    def report():
        for i, (name, publisher) in enumerate(odometry.items()):
            msg = Odometry()
            msg.header.frame_id = message.paths[0].header.frame_id
            msg.pose.pose.position.x, msg.pose.pose.position.y = start[i, :2].tolist()
            msg.pose.pose.orientation.w = 1.0
            msg.twist.twist.linear.x = speed[0]
            publisher.publish(msg)

    timer = node.create_timer(0.05, report)
    try:
        plans.publish(message)
        # the plan and the (moving) robots heard first: no start can be for want of them
        assert ros_client.spin_until(
            lambda: 'plan %d: 4 robots' % message.plan_id in executor.log() and all(
                p.get_subscription_count() for p in odometry.values()), 10), executor.log()
        fed = []
        sent = action.send_goal_async(ExecutePlan.Goal(plan_id=message.plan_id),
                                      feedback_callback=fed.append)
        assert ros_client.spin_until(sent.done, 10) and sent.result().accepted
        ros_client.spin_until(lambda: False, 1.0)
        assert fed == [], 'the goal started with its robots moving'
        speed[0] = 0.0
        assert ros_client.spin_until(lambda: fed, 10), executor.log()
        sent.result().cancel_goal_async()
        result = sent.result().get_result_async()
        assert ros_client.spin_until(result.done, 10), executor.log()
        # still moving after discovery_timeout: NOT_AT_START, the robots and speeds named
        parameters = AsyncParameterClient(node, executor.name('plan_executor'))
        assert parameters.wait_for_services(timeout_sec=10)
        # a stale robot is refused first (UNKNOWN_ROBOTS): odometry that a stalled test
        # process publishes late must not count as stale within the half second
        future = parameters.set_parameters([Parameter('discovery_timeout', value=0.5),
                                            Parameter('odom_timeout', value=5.0)])
        assert ros_client.spin_until(future.done, 10)
        assert all(r.successful for r in future.result().results), future.result()
        speed[0] = 0.3
        ros_client.spin_until(lambda: False, 0.5)  # the moving odometry before the goal
        sent = action.send_goal_async(ExecutePlan.Goal(plan_id=message.plan_id))
        assert ros_client.spin_until(sent.done, 10) and sent.result().accepted
        result = sent.result().get_result_async()
        assert ros_client.spin_until(result.done, 10), executor.log()
        ended = result.result().result
        assert ended.error_code == ExecutePlan.Result.NOT_AT_START, ended
        assert 'still moving 0.5 s after the goal came: robot_0 at 0.300 m/s' in \
            ended.error_msg, ended.error_msg
        # drive changed to a count that does not fit while the goal waits: UNKNOWN_ROBOTS
        # with the reason when it starts, as at its arrival (an internal error, 99, before)
        future = parameters.set_parameters([Parameter('discovery_timeout', value=5.0)])
        assert ros_client.spin_until(future.done, 10)
        assert all(r.successful for r in future.result().results), future.result()
        sent = action.send_goal_async(ExecutePlan.Goal(plan_id=message.plan_id))
        assert ros_client.spin_until(sent.done, 10) and sent.result().accepted
        future = parameters.set_parameters([Parameter('drive',
                                                      value=['holonomic', 'differential'])])
        assert ros_client.spin_until(future.done, 10)
        assert all(r.successful for r in future.result().results), future.result()
        speed[0] = 0.0
        result = sent.result().get_result_async()
        assert ros_client.spin_until(result.done, 10), executor.log()
        ended = result.result().result
        assert ended.error_code == ExecutePlan.Result.UNKNOWN_ROBOTS, ended
        assert 'drive has 2 values for 4 robots' in ended.error_msg, ended.error_msg
        assert 'Traceback' not in executor.log(), executor.log()
    finally:
        node.destroy_timer(timer)
        node.destroy_publisher(plans)
        for publisher in odometry.values():
            node.destroy_publisher(publisher)


def test_a_result_asked_for_after_a_cancel_at_a_stop_is_answered(ros_client, lone_executor):
    """
    A goal canceled and SIGINT at once, its result asked for after the cancel's reply: it comes.

    The stop's grace spin ran only while goals were unfinished; with the goal just ended
    by its cancel, the node went at once and the request was lost (1 in 3 runs).
    """
    from punctured_planner_interfaces.action import ExecutePlan
    executor, action = lone_executor
    sent = action.send_goal_async(ExecutePlan.Goal(plan_id=99))
    assert ros_client.spin_until(sent.done, 10) and sent.result().accepted
    cancel = sent.result().cancel_goal_async()
    executor.proc.send_signal(signal.SIGINT)
    assert ros_client.spin_until(cancel.done, 10), executor.log()
    result = sent.result().get_result_async()
    assert ros_client.spin_until(result.done, 10), executor.log()
    # whichever came first ended it: the cancel, or the stop
    assert result.result().result.error_code in (ExecutePlan.Result.CANCELED,
                                                 ExecutePlan.Result.STOPPED)
    assert executor.proc.wait(timeout=10) == 0, executor.log()
