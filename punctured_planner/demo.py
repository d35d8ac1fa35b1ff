"""
``make demo``: a simulated fleet, the planner and the executor, from plan to motion.

1. starts ``fleet_sim``, ``planner_node`` and ``plan_executor`` (processes, one
   parameter file: config/demo.yaml, or config/demo_differential.yaml for
   ``make demo DRIVE=differential``; ``--drive`` overrides both nodes' ``drive``)
   in the namespace ``/demo``;
2. plans from the robots' current state through config/demo_request.yaml
   (``use_current_state``);
3. executes the plan through the ExecutePlan action;
4. prints the executed duration, the simulator's true smallest gap, how far
   each robot ended from its goal and from its requested heading, and the
   executed duration against the slowest robot's straight-line bound and
   against the plan retimed at that robot's speed;
5. writes ``demo.mcap`` (the plan, every reference pose, cmd_vel and odometry
   message, at their arrival times) and ``demo.gif`` (the executed motion, top
   view), and reads the MCAP back to count cmd_vel messages with a non-zero linear.y.

Ctrl-C stops everything cleanly. Exit 0 when the plan was executed, 1 otherwise.
"""

import argparse
from collections.abc import Callable
from collections.abc import Sequence
from dataclasses import dataclass
import os
import signal
import subprocess
import sys
import tempfile
import time
from typing import Any
from typing import cast
from typing import TYPE_CHECKING

import numpy as np
import yaml

from .ros.topics import CMD_VEL
from .ros.topics import ODOM
from .ros.topics import REFERENCE_POSE
from .ros.topics import robot_topic

if TYPE_CHECKING:  # rclpy and ROS message types load where the demo runs them
    from nav_msgs.msg import Odometry
    from rclpy.executors import Executor
    from rclpy.node import Node

CONFIG = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'config')
NODES = ('fleet_sim', 'planner_node', 'plan_executor')
# The planner's latched plan topic, as the recorder hears it (namespace /demo).
PLAN_TOPIC = '/demo/plan'


@dataclass(frozen=True)
class Heard:
    """One recorded message: its topic, the message and its arrival (ns, the node's clock)."""

    topic: str
    message: Any
    arrival_ns: int


class Recorder:
    """A client node that records what the demo needs, with arrival times."""

    def __init__(self, node: 'Node', executor: 'Executor', names: list[str]) -> None:
        """Subscribe node (in /demo, a client session's, spun by executor)."""
        from geometry_msgs.msg import PoseStamped
        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from punctured_planner_interfaces.msg import Plan
        from std_msgs.msg import Float64

        from .ros.qos import LATCHED
        self.node = node
        self.executor = executor
        self.names = names
        self.messages: list[Heard] = []
        self.gap: list[float] = []
        self.odometry: dict[str, Odometry] = {}

        def keep(topic: str) -> Callable[[Any], None]:
            return lambda msg: self.messages.append(
                Heard(topic, msg, self.node.get_clock().now().nanoseconds))

        def heard(name: str, topic: str) -> Callable[[Any], None]:
            return keep('/demo/' + robot_topic(name, topic))

        self.node.create_subscription(Plan, 'plan', keep(PLAN_TOPIC), LATCHED)
        for name in names:
            self.node.create_subscription(PoseStamped, robot_topic(name, REFERENCE_POSE),
                                          heard(name, REFERENCE_POSE), 50)
            self.node.create_subscription(Odometry, robot_topic(name, ODOM),
                                          self._odometry(name, heard(name, ODOM)), 50)
            self.node.create_subscription(Twist, robot_topic(name, CMD_VEL),
                                          heard(name, CMD_VEL), 50)
        self.node.create_subscription(Float64, 'fleet_sim/min_gap',
                                      lambda msg: self.gap.append(cast(Float64, msg).data),
                                      LATCHED)

    def _odometry(self, name, keep):
        def callback(msg: 'Odometry') -> None:
            self.odometry[name] = msg
            keep(msg)
        return callback

    def spin(self, predicate: Callable[[], bool], timeout_sec: float) -> bool:
        """Spin until predicate() or the timeout; return whether it became true."""
        from .ros.client import spin_until
        return spin_until(self.executor, predicate, timeout_sec)


def _run(recorder, request, mcap_path, gif_path, fleet):
    """
    Plan request and execute the plan; write the recording and the GIF; return the exit code.

    fleet is fleet_sim's settings (speed limit and factors).
    """
    from punctured_planner_interfaces.action import ExecutePlan
    from punctured_planner_interfaces.srv import PlanSequence
    from rclpy.action import ActionClient

    from .ros import conversions
    from .ros.client import call_service
    from .ros.client import FEEDBACK_SILENCE_SEC
    from .ros.client import GoalWatch
    from .ros.client import wait_for_result
    from .ros.qos import CLIENT_QOS
    node = recorder.node
    client = node.create_client(PlanSequence, 'plan_sequence', qos_profile=CLIENT_QOS)
    action = ActionClient(node, ExecutePlan, 'execute_plan')
    if not (client.wait_for_service(timeout_sec=30) and action.wait_for_server(timeout_sec=30)
            and recorder.spin(lambda: len(recorder.odometry) == len(recorder.names), 30)):
        print('demo: the nodes did not come up', file=sys.stderr)
        return 1
    response = call_service(recorder.executor, client, request, 30)
    deadline = time.monotonic() + 10
    while (response is not None and response.error_code == PlanSequence.Response.NO_ROBOT_STATE
           and time.monotonic() < deadline):
        # the planner's own odometry subscriptions may match a little later than ours
        recorder.spin(lambda: False, 0.2)
        response = call_service(recorder.executor, client, request, 30)
    if response is None or response.error_code != 0:
        print('demo: planning failed: %s' % (response.error_msg if response else 'no answer'),
              file=sys.stderr)
        return 1
    planned = conversions.duration_to_seconds(response.duration)
    print('planned plan %d: %d robots, %.2f s at %.2f m/s, min gap %.3f m, tolerance %.3f m'
          % (response.plan_id, len(response.paths), planned, request.max_speed,
             response.min_gap, response.tracking_tolerance))
    watch = GoalWatch()
    goal = action.send_goal_async(ExecutePlan.Goal(plan_id=response.plan_id),
                                  feedback_callback=watch.heard)
    if not recorder.spin(goal.done, 10):
        print('demo: plan_executor did not answer the goal', file=sys.stderr)
        return 1
    result = wait_for_result(recorder.executor, goal.result(), watch, 600)
    if result is None:
        print('demo: no result from plan_executor: no feedback for %g s (it went away)'
              % FEEDBACK_SILENCE_SEC, file=sys.stderr)
        return 1
    recorder.spin(lambda: False, 0.3)
    executed = conversions.duration_to_seconds(result.executed_duration)
    gap = recorder.gap[-1] if recorder.gap else float('nan')
    print('executed: %s in %.2f s (plan %.2f s); true smallest gap %.4f m; largest tracking '
          'error %.3f m (tolerance %.3f m)' % (
              result.error_msg or result.error_code, executed, planned, gap,
              max(result.max_tracking_errors, default=0.0), response.tracking_tolerance))
    _print_arrival(recorder, response)
    _print_ratios(recorder, executed, fleet)
    _write(recorder, response, mcap_path, gif_path)
    _check_commands(mcap_path)
    return 0 if result.error_code == 0 else 1


def _print_arrival(recorder, response):
    """Print each robot's distance to its goal and its heading error to its last pose."""
    from .execution.unicycle import wrap
    from .execution.unicycle import yaws
    from .ros import conversions
    for i, name in enumerate(recorder.names):
        pose = conversions.odometry_pose(recorder.odometry[name])
        path = conversions.path_arrays(response.paths[i])
        heading = float(wrap(yaws(pose.orientation[None]) - yaws(path.orientations[-1:]))[0])
        print('%s: %.4f m from its goal, heading %+.4f rad from the requested one'
              % (name, np.linalg.norm(pose.position - path.positions[-1]), heading))


def _print_ratios(recorder, executed, fleet):
    """
    Print the executed duration over the slowest robot's two lower bounds.

    Its straight line at its speed (speed_limit x its speed factor), and the
    published plan retimed at that speed under the plan's acceleration limit.
    """
    from .core.timing import stamps
    from .ros import conversions
    # the latched plan may reach this late-joined subscriber after the goal's result
    recorder.spin(lambda: any(h.topic == PLAN_TOPIC for h in recorder.messages), 10)
    plan = next(h.message for h in recorder.messages if h.topic == PLAN_TOPIC)
    reference = conversions.plan_reference(plan)
    factors = np.asarray(fleet.speed_factors or [1.0] * reference.robot_count)
    slowest = int(np.argmin(factors))
    speed = fleet.speed_limit * factors[slowest]
    straight = np.linalg.norm(reference.positions[-1] - reference.positions[0], axis=1)
    bound = float(straight[slowest]) / speed
    retimed = float(stamps(reference.positions, plan.max_speed * factors[slowest],
                           plan.max_acceleration, plan.tracking_tolerance)[-1])
    print('slowest robot %s (%.2f m/s): executed %.2f s = %.2fx its straight-line bound '
          '%.2f s, %.2fx the plan at its speed %.2f s (plan %.2f s at %.2f m/s, %.2f m/s^2: '
          'executed / plan %.2f)' % (
              plan.robot_names[slowest], speed, executed, executed / bound, bound,
              executed / retimed, retimed, reference.duration, plan.max_speed,
              plan.max_acceleration, executed / reference.duration))


def _check_commands(mcap_path):
    """Read the MCAP back; print how many cmd_vel messages it holds, how many with linear.y."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    with open(mcap_path, 'rb') as stream:
        commands = [message for _, channel, _, message in make_reader(
            stream, decoder_factories=[DecoderFactory()]).iter_decoded_messages()
            if channel.topic.endswith('/' + CMD_VEL)]
    sideways = sum(1 for message in commands if message.linear.y != 0.0)
    print('%s: %d cmd_vel messages, %d with a non-zero linear.y'
          % (mcap_path, len(commands), sideways))


def _write(recorder, response, mcap_path, gif_path):
    """Write demo.mcap and demo.gif from the recorded messages."""
    from .ros import conversions
    from .ros.recording import write_mcap
    from .viz.motion import render_motion
    messages = recorder.messages
    write_mcap(mcap_path, [(h.topic, h.message) for h in messages],
               [h.arrival_ns for h in messages], {'plan_id': response.plan_id})
    odometry = [h for h in messages if h.topic.endswith('/' + ODOM)]
    index = {name: i for i, name in enumerate(recorder.names)}
    start = odometry[0].arrival_ns
    frames, times, current = [], [], None
    for heard in odometry:
        name = heard.message.child_frame_id.split('/')[0]
        if current is None:
            current = np.full((len(index), 2), np.nan)
        current[index[name]] = conversions.odometry_pose(heard.message).position[:2]
        if not np.isnan(current).any():
            frames.append(current.copy())
            times.append((heard.arrival_ns - start) * 1e-9)
    positions = np.array(frames)
    plan = next(h.message for h in messages if h.topic == PLAN_TOPIC)
    planned = np.stack([conversions.path_arrays(p).positions[:, :2] for p in plan.paths],
                       axis=1)
    bodies = conversions.plan_bodies(plan)
    obstacles = bodies.obstacles[:, :2]
    gaps = np.minimum.accumulate([bodies.smallest_gap(np.c_[p, np.zeros(len(p))]).value
                                  for p in positions])
    render_motion(gif_path, np.array(times), positions, planned, obstacles,
                  bodies.robot_radius, gaps,
                  title='make demo: plan %d executed' % plan.plan_id)
    print('wrote %s (%d messages) and %s' % (mcap_path, len(messages), gif_path))


def _with_drive(params_path, drive, folder):
    """Return a copy of a parameter file with fleet_sim's and plan_executor's drive set."""
    # a -p override loses to the file's node sections, so the file itself is changed
    with open(params_path, encoding='utf-8') as stream:
        values = yaml.safe_load(stream)
    for node in ('fleet_sim', 'plan_executor'):
        section = values.setdefault('/**/' + node, {}).setdefault('ros__parameters', {})
        section['drive'] = [drive]
    path = os.path.join(folder, 'params.yaml')
    with open(path, 'w', encoding='utf-8') as stream:
        yaml.safe_dump(values, stream)
    return path


def main(argv: Sequence[str] | None = None) -> int:
    """Run the demo; return 0 when the plan was executed."""
    parser = argparse.ArgumentParser(description='From plan to motion with a simulated fleet.')
    parser.add_argument('--params', default=os.path.join(CONFIG, 'demo.yaml'))
    parser.add_argument('--request', default=os.path.join(CONFIG, 'demo_request.yaml'))
    parser.add_argument('--mcap', default='demo.mcap')
    parser.add_argument('--gif', default='demo.gif')
    parser.add_argument('--drive', choices=('holonomic', 'differential'),
                        help="override fleet_sim's and plan_executor's drive (all robots)")
    args = parser.parse_args(argv)
    for path in (args.mcap, args.gif):  # written after the run: say so before it, not after
        folder = os.path.dirname(os.path.abspath(path))
        if not os.path.isdir(folder):
            parser.error('cannot write %s: no folder %s' % (path, folder))
    from .cli import build_request
    from .cli import load_request
    from .ros.parameters import load_parameter_file
    from .ros.settings import FLEET_SIM
    try:  # before any node starts: a bad file is said at once, not after they came up
        fleet = FLEET_SIM.settings(load_parameter_file(args.params, FLEET_SIM))
    except (OSError, yaml.YAMLError, ValueError) as error:
        parser.error('--params %s: %s' % (args.params, error))
    try:
        request = build_request(load_request(args.request))
    except (OSError, yaml.YAMLError, ValueError) as error:
        parser.error('--request %s: %s' % (args.request, error))
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    logs = tempfile.mkdtemp(prefix='punctured_planner_demo_')
    bin_dir = os.path.dirname(sys.executable)
    params = args.params if args.drive is None else _with_drive(args.params, args.drive, logs)
    log_files = [open(os.path.join(logs, name + '.log'), 'wb') for name in NODES]
    processes = [subprocess.Popen(
        [os.path.join(bin_dir, name), '--ros-args', '-r', '__ns:=/demo', '--params-file',
         params], stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        for name, log in zip(NODES, log_files)]
    print('started %s (logs in %s)' % (', '.join(NODES), logs))
    from .ros.client import session
    code = 1
    try:
        with session('demo', namespace='/demo') as ros:
            code = _run(Recorder(ros.node, ros.executor, list(fleet.robot_names)), request,
                        args.mcap, args.gif, fleet)
    except KeyboardInterrupt:
        print('demo: interrupted')
    finally:
        for process in processes:
            process.send_signal(signal.SIGINT)
        for process in processes:
            try:
                process.wait(timeout=15)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        for log in log_files:
            log.close()
    return code


if __name__ == '__main__':
    sys.exit(main())
