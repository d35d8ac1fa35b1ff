"""
Command-line client ``punctured-planner``.

``punctured-planner call REQUEST.yaml`` sends a PlanSequence request to a
running planner node and prints the response as YAML; it does the job of
``ros2 service call`` where ros2cli is not installed (ROS 2 from PyPI wheels).
The request file has the same shape as the ``ros2 service call`` payload.
"""

import argparse
import sys
import time

import yaml

EXIT_OK = 0
EXIT_PLANNER_ERROR = 1
EXIT_USAGE = 2
EXIT_NO_SERVICE = 3


def load_request(path):
    """Read a YAML request file (``-`` for standard input) into plain data."""
    if path == '-':
        return yaml.safe_load(sys.stdin)
    with open(path, encoding='utf-8') as stream:
        return yaml.safe_load(stream)


def build_request(data):
    """Return a PlanSequence.Request filled from plain data (the ros2 YAML shape)."""
    from punctured_planner.msg_dict import fill_message
    from punctured_planner_interfaces.srv import PlanSequence
    return fill_message(PlanSequence.Request(), data)


def call_service(node, executor, client, request, timeout_sec):
    """
    Call ``client`` once; return the response, or None on timeout.

    Spins ``executor`` with spin_once until the future is done: in rclpy 7.1
    repeated spin_until_future_complete leaves stale tasks behind.
    """
    future = client.call_async(request)
    deadline = time.monotonic() + timeout_sec
    while not future.done():
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            client.remove_pending_request(future)
            return None
        executor.spin_once(timeout_sec=min(remaining, 0.1))
    return future.result()


def _call(args):
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from punctured_planner.msg_dict import constant_names
    from punctured_planner.msg_dict import message_to_dict
    from punctured_planner_interfaces.srv import PlanSequence

    try:
        request = build_request(load_request(args.request))
    except (OSError, yaml.YAMLError, ValueError) as error:
        print('punctured-planner: bad request: %s' % error, file=sys.stderr)
        return EXIT_USAGE

    context = rclpy.context.Context()
    rclpy.init(context=context)
    executor = SingleThreadedExecutor(context=context)
    node = rclpy.create_node('punctured_planner_cli', context=context)
    try:
        client = node.create_client(PlanSequence, args.service)
        if not client.wait_for_service(timeout_sec=args.wait):
            print('punctured-planner: service %s not available after %.1f s'
                  % (args.service, args.wait), file=sys.stderr)
            return EXIT_NO_SERVICE
        executor.add_node(node)
        response = call_service(node, executor, client, request, args.timeout)
        if response is None:
            print('punctured-planner: no response from %s within %.1f s'
                  % (args.service, args.timeout), file=sys.stderr)
            return EXIT_NO_SERVICE
        data = message_to_dict(response)
        if args.no_paths:
            data['paths'] = '(%d paths omitted)' % len(response.paths)
        yaml.safe_dump(data, sys.stdout, sort_keys=False)
        names = [n for n in constant_names(PlanSequence.Response, response.error_code)
                 if n != 'NONE' or response.error_code == 0]
        print('# error_code %d (%s)%s' % (
            response.error_code, '/'.join(names) or 'undocumented',
            ': ' + response.error_msg if response.error_msg else ''), file=sys.stderr)
        if response.error_code != PlanSequence.Response.NONE:
            return EXIT_PLANNER_ERROR
        return EXIT_OK
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def make_parser():
    """Return the argument parser of ``punctured-planner``."""
    parser = argparse.ArgumentParser(
        prog='punctured-planner',
        description='Client tools for the punctured_planner ROS 2 node.')
    commands = parser.add_subparsers(dest='command', required=True)
    call = commands.add_parser(
        'call', help='send a PlanSequence request (YAML file) and print the response')
    call.add_argument('request', help="YAML request file, '-' for standard input")
    call.add_argument('--service', default='/plan_sequence',
                      help='service name (default: %(default)s)')
    call.add_argument('--wait', type=float, default=10.0,
                      help='seconds to wait for the service to appear (default: %(default)s)')
    call.add_argument('--timeout', type=float, default=60.0,
                      help='seconds to wait for the response (default: %(default)s)')
    call.add_argument('--no-paths', action='store_true',
                      help='print only the number of paths, not the poses')
    call.set_defaults(func=_call)
    return parser


def main(argv=None):
    """Entry point of the ``punctured-planner`` console script."""
    args = make_parser().parse_args(argv)
    try:
        return args.func(args)
    except KeyboardInterrupt:
        return 130


if __name__ == '__main__':
    sys.exit(main())
