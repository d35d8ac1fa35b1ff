"""
Command-line client ``punctured-planner``.

``punctured-planner call REQUEST.yaml`` sends a PlanSequence request to a
running planner node and prints the response as YAML; it does the job of
``ros2 service call`` where ros2cli is not installed (ROS 2 from PyPI wheels).
The request file has the same shape as the ``ros2 service call`` payload.

``punctured-planner plan REQUEST.yaml [--params FILE]`` answers the same
request offline, without a ROS graph: the node's checks and conversions
(:mod:`punctured_planner.ros.planning`) with the parameters of a ROS parameter
file; ``--png``/``--gif`` draw the plan and ``--mcap`` records it as the node
would publish it.
"""

import argparse
from collections.abc import Sequence
import contextlib
import math
import os
import sys
import time
from typing import Any
from typing import TYPE_CHECKING

import yaml

if TYPE_CHECKING:  # rclpy and the ros modules load only where a command needs them
    from rclpy.executors import Executor
    from rclpy.node import Node
    from rclpy.task import Future

    from punctured_planner.ros.settings import PlannerSettings
    from punctured_planner.ros.snapshot import Outcome

# The command's own node, in its private Context (ros/client.py).
CLI_NODE = 'punctured_planner_cli'
EXIT_OK = 0
EXIT_PLANNER_ERROR = 1
EXIT_USAGE = 2
EXIT_NO_SERVICE = 3
EXIT_INTERRUPTED = 130  # 128 + SIGINT, as a shell reports a tool stopped by Ctrl-C
EXIT_BROKEN_PIPE = 141  # 128 + SIGPIPE, as a shell reports a tool whose reader went away


def ros_name(text: str) -> str:
    """
    Return text if it is a valid ROS name for a service or a node, else raise ArgumentTypeError.

    A name rclpy refuses raised from inside it, a traceback and exit 1 (the code of a
    planner error).
    """
    from punctured_planner.ros.parameters import rcl_reason
    from rclpy.expand_topic_name import expand_topic_name
    from rclpy.validate_full_topic_name import validate_full_topic_name
    try:
        validate_full_topic_name(expand_topic_name(text, 'punctured_planner', '/'),
                                 is_service=True)
    except Exception as error:  # noqa: B902 - rclpy raises ValueError or its own kinds
        raise argparse.ArgumentTypeError('%r is not a valid ROS name: %s'
                                         % (text, rcl_reason(error)))
    return text


def positive_float(text: str) -> float:
    """Return text as a finite float > 0, or raise argparse.ArgumentTypeError."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f'{text!r} is not a number')
    if not 0 < value < math.inf:
        raise argparse.ArgumentTypeError(f'{text!r} is not a positive finite number')
    return value


def load_request(path: str) -> Any:
    """Read a YAML request file (``-`` for standard input) into plain data."""
    if path == '-':
        return yaml.safe_load(sys.stdin)
    with open(path, encoding='utf-8') as stream:
        return yaml.safe_load(stream)


def build_request(data: Any) -> Any:
    """Return a PlanSequence.Request filled from plain data (the ros2 YAML shape)."""
    from punctured_planner.ros.msg_dict import fill_message
    from punctured_planner_interfaces.srv import PlanSequence
    return fill_message(PlanSequence.Request(), data)


def _request(args):
    """Return the request of args.request, or None after saying why it is bad."""
    try:
        return build_request(load_request(args.request))
    except (OSError, yaml.YAMLError, ValueError) as error:
        print('punctured-planner: bad request: %s' % error, file=sys.stderr)
        return None


def _call(args):
    from punctured_planner.ros.client import call_service
    from punctured_planner.ros.client import session
    from punctured_planner.ros.qos import CLIENT_QOS
    from punctured_planner_interfaces.srv import PlanSequence

    request = _request(args)
    if request is None:
        return EXIT_USAGE
    with session(CLI_NODE) as ros:
        client = ros.node.create_client(PlanSequence, args.service, qos_profile=CLIENT_QOS)
        if not client.wait_for_service(timeout_sec=args.wait):
            print('punctured-planner: service %s not available after %.1f s'
                  % (args.service, args.wait), file=sys.stderr)
            return EXIT_NO_SERVICE
        response = call_service(ros.executor, client, request, args.timeout)
        if response is None:
            print('punctured-planner: no response from %s within %.1f s'
                  % (args.service, args.timeout), file=sys.stderr)
            return EXIT_NO_SERVICE
        return print_response(response, args.no_paths)


def reset_obstacles(node: 'Node', executor: 'Executor', planner_node: str,
                    timeout_sec: float) -> str | None:
    """
    Make a running planner go back to its obstacles parameter; return an error text or None.

    Sets the node's ``obstacles`` parameter to its current value through the
    parameter services: the latest source wins, so the parameter's set replaces
    a set that came on the ``obstacles`` topic (one that outlived its publisher).
    """
    from rclpy.parameter import Parameter
    from rclpy.parameter import parameter_value_to_python
    from rclpy.parameter_client import AsyncParameterClient

    from punctured_planner.ros.client import spin_until

    remote = AsyncParameterClient(node, planner_node)
    if not remote.wait_for_services(timeout_sec=timeout_sec):
        return 'parameter services of %s not available' % planner_node

    def wait(future: 'Future') -> Any | None:
        return future.result() if spin_until(executor, future.done, timeout_sec) else None

    got = wait(remote.get_parameters(['obstacles']))
    if got is None or not got.values:
        return 'no obstacles parameter on %s' % planner_node
    current = parameter_value_to_python(got.values[0])
    try:  # integers too: the parameter is dynamically typed (obstacles: [0, 1, 0])
        values = [float(v) for v in current]
    except (TypeError, ValueError):
        return 'obstacles on %s is %r, not a list of numbers' % (planner_node, current)
    done = wait(remote.set_parameters(
        [Parameter('obstacles', Parameter.Type.DOUBLE_ARRAY, values)]))
    if done is None or not done.results[0].successful:
        return 'setting obstacles on %s failed%s' % (
            planner_node, ': ' + done.results[0].reason if done is not None else '')
    return None


def _reset(args):
    from punctured_planner.ros.client import session
    with session(CLI_NODE) as ros:
        problem = reset_obstacles(ros.node, ros.executor, args.node, args.wait)
    if problem:
        print('punctured-planner: %s' % problem, file=sys.stderr)
        return EXIT_NO_SERVICE
    print('# %s plans among its obstacles parameter again' % args.node, file=sys.stderr)
    return EXIT_OK


def print_response(response: Any, no_paths: bool = False) -> int:
    """Print a PlanSequence response as YAML (code name on stderr); return the exit code."""
    from punctured_planner.ros.msg_dict import constant_names
    from punctured_planner.ros.msg_dict import message_to_dict
    from punctured_planner_interfaces.srv import PlanSequence

    paths = response.paths
    if no_paths:  # not converted at all: 1.5 million poses took 55 s to convert and drop
        response.paths = []
    try:
        data = message_to_dict(response)
    finally:
        response.paths = paths
    if no_paths:
        data['paths'] = '(%d paths omitted)' % len(paths)
    yaml.safe_dump(data, sys.stdout, sort_keys=False)
    names = [n for n in constant_names(PlanSequence.Response, response.error_code)
             if n != 'NONE' or response.error_code == 0]
    print('# error_code %d (%s)%s' % (
        response.error_code, '/'.join(names) or 'undocumented',
        ': ' + response.error_msg if response.error_msg else ''), file=sys.stderr)
    if response.error_code != PlanSequence.Response.NONE:
        return EXIT_PLANNER_ERROR
    return EXIT_OK


def offline_plan(request: Any, settings: 'PlannerSettings',
                 now_ns: int | None = None) -> 'Outcome':
    """
    Answer a PlanSequence request without a ROS graph; return the planning Outcome.

    The obstacles come from the ``obstacles`` parameter; there is no robot
    state, so ``use_current_state`` gets NO_ROBOT_STATE. Raise ValueError, as
    planner_node exits 2 at start-up, if the parameters cannot plan among them.
    """
    from punctured_planner.ros import conversions
    from punctured_planner.ros.planning import PlanSequenceHandler
    from punctured_planner.ros.settings import PLANNER
    from punctured_planner.ros.snapshot import ObstacleSet
    from punctured_planner.ros.snapshot import Snapshot
    from punctured_planner_interfaces.srv import PlanSequence

    handler = PlanSequenceHandler()
    obstacles = ObstacleSet(conversions.obstacles_from_parameter(settings.obstacles))
    handler.check_parameter_obstacles(settings, obstacles, set(PLANNER.by_name))
    snapshot = Snapshot(
        settings, obstacles,
        state=None, state_problem='punctured-planner plan has no robot state (no ROS graph)')
    now_ns = time.time_ns() if now_ns is None else now_ns
    return handler.handle(request, PlanSequence.Response(), snapshot, now_ns)


def _plan(args):
    from punctured_planner.ros.parameters import load_parameter_file
    from punctured_planner.ros.recording import record_plan
    from punctured_planner.ros.settings import PLANNER
    from punctured_planner.render import render_outputs

    try:
        values = load_parameter_file(args.params, PLANNER) if args.params else {}
        settings = PLANNER.settings(values)
    except (OSError, yaml.YAMLError, ValueError) as error:
        print('punctured-planner: bad parameter file: %s' % error, file=sys.stderr)
        return EXIT_USAGE
    request = _request(args)
    if request is None:
        return EXIT_USAGE
    try:
        outcome = offline_plan(request, settings)
    except ValueError as error:
        print('punctured-planner: bad parameter file: %s' % error, file=sys.stderr)
        return EXIT_USAGE
    if outcome.exception is not None:
        print('punctured-planner: %r' % outcome.exception, file=sys.stderr)
    # The files first: a reader of the answer that goes away (| head) ends the printing,
    # and with it, before, the files asked for.
    written: list = []
    problem = None
    if outcome.ok:
        title = os.path.basename(args.request) if args.request != '-' else None
        try:
            written.extend(render_outputs(args, outcome.planned().plan, title=title,
                                          max_speed=outcome.max_speed,
                                          max_acceleration=outcome.max_acceleration))
            if args.mcap:
                written.append(record_plan(args.mcap, outcome, settings))
        except OSError as error:  # the plan is printed all the same
            problem = error
    code = print_response(outcome.response, args.no_paths)
    for path in written:
        print('# wrote %s' % path, file=sys.stderr)
    if problem is not None:
        print('punctured-planner: cannot write the outputs (--png, --gif, --mcap): %s'
              % problem, file=sys.stderr)
        return EXIT_USAGE
    return code


def make_parser(pictures: bool = True) -> argparse.ArgumentParser:
    """
    Return the argument parser of ``punctured-planner``.

    pictures=False leaves out the picture options of ``plan`` (they import
    matplotlib, which ``call`` does not need).
    """
    parser = argparse.ArgumentParser(
        prog='punctured-planner',
        description='Client tools for the punctured_planner ROS 2 node.')
    commands = parser.add_subparsers(dest='command', required=True)
    call = commands.add_parser(
        'call', help='send a PlanSequence request (YAML file) and print the response')
    call.add_argument('request', help="YAML request file, '-' for standard input")
    call.add_argument('--service', default='/plan_sequence', type=ros_name,
                      help='service name (default: %(default)s)')
    call.add_argument('--wait', type=positive_float, default=10.0,
                      help='seconds to wait for the service to appear (default: %(default)s)')
    call.add_argument('--timeout', type=positive_float, default=60.0,
                      help='seconds to wait for the response (default: %(default)s)')
    call.add_argument('--no-paths', action='store_true',
                      help='print only the number of paths, not the poses')
    call.set_defaults(func=_call)
    reset = commands.add_parser(
        'reset-obstacles', help="go back to the node's obstacles parameter, replacing a set "
        "that came on the 'obstacles' topic")
    reset.add_argument('--node', default='/planner_node', type=ros_name,
                       help='the planner node (default: %(default)s)')
    reset.add_argument('--wait', type=positive_float, default=10.0,
                       help='seconds to wait for the node (default: %(default)s)')
    reset.set_defaults(func=_reset)
    plan = commands.add_parser(
        'plan', help='plan a request (YAML file) offline, without a ROS graph, and print '
        'the response; optionally draw or record the plan')
    plan.add_argument('request', help="YAML request file, '-' for standard input")
    plan.add_argument('--params', metavar='FILE',
                      help='ROS parameter file of planner_node, e.g. '
                      'config/default_scenario.yaml (default: the built-in defaults)')
    plan.add_argument('--no-paths', action='store_true',
                      help='print only the number of paths, not the poses')
    plan.add_argument('--mcap', metavar='OUT.mcap',
                      help='record the plan as the node publishes it (the Plan message, '
                      "each robot's Path, the markers, the domain index) for Foxglove / "
                      'ros2 bag')
    if pictures:
        from punctured_planner.render import add_render_arguments
        add_render_arguments(plan)
    plan.set_defaults(func=_plan, png=None, gif=None)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``punctured-planner`` console script."""
    argv = sys.argv[1:] if argv is None else list(argv)
    args = make_parser(pictures=argv[:1] == ['plan']).parse_args(argv)
    try:
        return args.func(args)
    except KeyboardInterrupt:
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        # The reader closed the pipe (`... | head`): stop quietly, as Unix tools do.
        _stdout_to_devnull()
        return EXIT_BROKEN_PIPE
    except OSError as error:  # standard output cannot be written (a full disk), or else
        with contextlib.suppress(OSError):  # nor, perhaps, standard error
            print('punctured-planner: %s' % error, file=sys.stderr)
        try:
            sys.stdout.flush()
        except OSError:
            _stdout_to_devnull()
        return EXIT_USAGE


def _stdout_to_devnull() -> None:
    """Send standard output to /dev/null: the flush at exit cannot fail again."""
    os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())


if __name__ == '__main__':
    sys.exit(main())
