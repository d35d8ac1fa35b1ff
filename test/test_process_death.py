"""
A process killed (SIGKILL) in the middle of an execution: nothing lost, nothing hangs.

The graph of test_plan_execution_dds.py (planner_node, fleet_sim,
plan_executor as processes, three disc robots), with short timeouts so each
test takes seconds. One test per process killed (doc/design.md section 13,
"A process dies mid-execution"):

* fleet_sim: every robot is commanded zero within one control period of its
  odometry being declared stale, the goal ends ODOMETRY_LOST after
  ``hold_timeout``, the planner and the executor serve on;
* planner_node: the execution does not need it and ends NONE;
* plan_executor: fleet_sim stops every robot after its ``command_timeout``,
  the client stops waiting once the feedback is silent, the planner serves on.
"""

import time

import numpy as np
import pytest
from test_plan_execution_dds import GOAL
from test_plan_execution_dds import NAMES
from test_plan_execution_dds import OBSTACLES
from test_plan_execution_dds import RADIUS
from test_plan_execution_dds import START
from test_plan_execution_dds import started_graph

pytestmark = [pytest.mark.ros, pytest.mark.slow]

ODOM_TIMEOUT = 0.3
HOLD_TIMEOUT = 1.0
COMMAND_TIMEOUT = 0.3
CONTROL_PERIOD = 1.0 / 20.0  # plan_executor's control_rate, and fleet_sim's rate
# What DDS delivery and a loaded 2-core machine may add to a deadline (s).
SLACK = 0.25
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
    max_speed: 0.5
/**/fleet_sim:
  ros__parameters:
    initial_positions: %(start)s
    robot_radius: %(radius)s
    speed_limit: 1.0
    command_timeout: %(command_timeout)s
/**/plan_executor:
  ros__parameters:
    speed_limit: 1.0
    discovery_timeout: 1.0
    odom_timeout: %(odom_timeout)s
    hold_timeout: %(hold_timeout)s
""" % {'obstacles': OBSTACLES, 'start': [v for p in START for v in p], 'radius': RADIUS,
       'command_timeout': COMMAND_TIMEOUT, 'odom_timeout': ODOM_TIMEOUT,
       'hold_timeout': HOLD_TIMEOUT}


@pytest.fixture
def graph(ros_client, ros_env, tmp_path):
    """Start the graph with short timeouts; stop (or reap) every process after the test."""
    yield from started_graph(ros_client, ros_env, tmp_path, 'pp_death', PARAMETERS)


def moving_goal(graph):
    """Plan START -> GOAL, send its goal with a GoalWatch; return (handle, feedback, watch)."""
    from punctured_planner.ros.client import GoalWatch
    from punctured_planner_interfaces.action import ExecutePlan
    response = graph.plan([GOAL])
    watch = GoalWatch()
    feedback = []

    def heard(msg):
        watch.heard(msg)
        feedback.append(msg.feedback)
    future = graph.action.send_goal_async(ExecutePlan.Goal(plan_id=response.plan_id),
                                          feedback_callback=heard)
    assert graph.client.spin_until(future.done, 10)
    handle = future.result()
    assert handle.accepted
    assert graph.client.spin_until(
        lambda: feedback and feedback[-1].plan_time > 0.5 and graph.speeds().max() > 0.1,
        20), graph.logs()
    return handle, feedback, watch


def planner_answers(graph):
    """Return the error code of a fresh plan call with explicit configurations."""
    from planner_helpers import pose_array
    from punctured_planner_interfaces.srv import PlanSequence
    request = PlanSequence.Request(configurations=[pose_array(START), pose_array(GOAL)])
    return graph.client.call(graph.plan_sequence, request).error_code


def kill(process):
    """SIGKILL a node process; return when it is gone (time.monotonic())."""
    process.proc.kill()
    assert process.proc.wait(timeout=10) == -9
    return time.monotonic()


def test_fleet_sim_killed(graph):
    from nav_msgs.msg import Odometry
    from punctured_planner_interfaces.action import ExecutePlan
    heard = {}
    for name in NAMES:
        graph.client.node.create_subscription(
            Odometry, graph.name(name + '/odom'),
            lambda msg, name=name: heard.__setitem__(name, time.monotonic()), 10)
    handle, feedback, _ = moving_goal(graph)
    killed = kill(graph.processes['fleet_sim'])
    result_future = handle.get_result_async()
    assert graph.client.spin_until(result_future.done, HOLD_TIMEOUT + ODOM_TIMEOUT + 5)
    ended = time.monotonic()
    result = result_future.result().result
    assert result.error_code == ExecutePlan.Result.ODOMETRY_LOST, result.error_msg
    assert all(name in result.error_msg for name in NAMES) and 'hold_timeout' in result.error_msg
    # the goal held hold_timeout once the odometry was declared stale, then it ended
    assert (HOLD_TIMEOUT <= ended - killed
            <= ODOM_TIMEOUT + HOLD_TIMEOUT + 2 * CONTROL_PERIOD + SLACK), graph.logs()
    assert feedback[-1].stale_robots == NAMES and feedback[-1].clock_rate == 0.0
    for name in NAMES:
        commands = graph.commands[name]
        last_odometry = heard[name]
        before = [m for t, m in commands if t < last_odometry]
        assert max(np.hypot(m.linear.x, m.linear.y) for m in before[-5:]) > 0.05, name
        # zero from the first control step that found the odometry stale, on to the end
        stale_at = last_odometry + ODOM_TIMEOUT
        moving = [t for t, m in commands if m.linear.x or m.linear.y or m.angular.z]
        assert moving[-1] < stale_at + CONTROL_PERIOD + SLACK, (name, moving[-1] - stale_at)
        assert commands[-1][0] > moving[-1], name
    # the others serve on: the planner plans, the executor answers a new goal
    assert planner_answers(graph) == 0
    refused = graph.result(graph.send(0)[0], timeout_sec=10)
    assert refused.error_code == ExecutePlan.Result.UNKNOWN_ROBOTS, refused.error_msg
    for name in ('planner_node', 'plan_executor'):
        graph.processes[name].assert_running()


def test_planner_node_killed(graph):
    from punctured_planner.ros.client import wait_for_result
    from punctured_planner_interfaces.action import ExecutePlan
    handle, _, watch = moving_goal(graph)
    kill(graph.processes['planner_node'])
    # the feedback goes on until the result: the client's wait ends with it
    result = wait_for_result(graph.client.executor, handle, watch, 30)
    assert result is not None, graph.logs()
    assert result.error_code == ExecutePlan.Result.NONE, result.error_msg + graph.logs()
    assert graph.client.spin_until(lambda: graph.gap, 5)
    assert graph.gap[-1] >= 0.0
    graph.client.spin_until(lambda: False, 0.3)
    assert np.linalg.norm(graph.positions() - GOAL, axis=1).max() <= 0.02, graph.logs()
    for name in ('fleet_sim', 'plan_executor'):
        graph.processes[name].assert_running()


def test_plan_executor_killed(graph):
    from nav_msgs.msg import Odometry
    from punctured_planner.ros.client import FEEDBACK_SILENCE_SEC
    from punctured_planner.ros.client import wait_for_result
    heard = []  # (arrival, stamp, robot, speed): fleet_sim's clock is the stamp
    for i, name in enumerate(NAMES):
        graph.client.node.create_subscription(
            Odometry, graph.name(name + '/odom'),
            lambda msg, i=i: heard.append((
                time.time(), msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec, i,
                np.hypot(msg.twist.twist.linear.x, msg.twist.twist.linear.y))), 100)
    handle, _, watch = moving_goal(graph)
    killed_at = time.time()
    killed = kill(graph.processes['plan_executor'])
    # fleet_sim stops every robot whose commands stopped coming (command_timeout)
    assert graph.client.spin_until(lambda: graph.speeds().max() < 1e-9, 5), graph.logs()
    graph.client.spin_until(lambda: False, 0.2)
    # judged by the simulator's own stamps: a process of the test or of the simulator
    # stalled by the machine (the sim's step is capped, so its robots stall too) is
    # no late stop, while a robot still driven after the timeout is
    odometry = np.array(heard)
    deadline = killed_at + COMMAND_TIMEOUT + 2 * CONTROL_PERIOD + SLACK
    late = odometry[(odometry[:, 1] > deadline) & (odometry[:, 3] > 1e-9)]
    arrivals, stamps = np.diff(odometry[odometry[:, 2] == 0][:, :2], axis=0).T
    assert not late.size, ('moving %.3f s after the kill' % (late[-1, 1] - killed_at),
                           'longest silence: arrivals %.3f s, stamps %.3f s'
                           % (arrivals.max(), stamps.max()))
    where = graph.positions()
    graph.client.spin_until(lambda: False, 0.5)
    assert np.abs(graph.positions() - where).max() < 1e-9
    # the client does not wait for a result that cannot come
    assert wait_for_result(graph.client.executor, handle, watch, 30) is None
    assert time.monotonic() - killed <= FEEDBACK_SILENCE_SEC + 2 * SLACK
    # the others serve on
    assert planner_answers(graph) == 0
    graph.processes['fleet_sim'].assert_running()
    graph.processes['planner_node'].assert_running()
