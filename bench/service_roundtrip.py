"""
Service round trip of planner_node across processes, against the transport's floor (Fast DDS).

Starts the installed ``planner_node`` console script in its own process (three
obstacles, spread variant, no robot_count), discovers ``plan_sequence`` from
this process and times complete calls: request out, plan, paths built, the
response back and deserialised here (the node publishes the plan after the
response: msg_docs/topics.md). Seeded random requests, n configurations of k robots.

The floor, measured in the same run: an echo server in a process of its own
(this script with ``--echo-server``, spun the way the node is) answers the same
requests over the same DDS with prebuilt responses of the same size (the
offline plan of each request, built before serving). Its round trip is what rclpy
and DDS cost alone: the request taken and converted, the response converted,
serialised, sent, deserialised here. Calls to the two alternate, and each call to
the echo server waits until the node's publications of the plan before it are out
(its Plan message, published last, has arrived here): the node publishes after its
reply, and a floor timed while the node publishes beside it on a 2-core machine is
slowed by it (README: at load 2-3 it was half as long again).

    .venv/bin/python bench/service_roundtrip.py                 # k = 8, n = 3
    .venv/bin/python bench/service_roundtrip.py -k 8 512 --refine false  # transport only
    .venv/bin/python bench/service_roundtrip.py --sweep         # k in 2, 8, 64, 512, 2048

Prints median and p90 round trip, the floor's median, ours / floor, the node's
own planning_time and the response size. Uses its own ROS_DOMAIN_ID (pid
based) and localhost discovery.
"""

import argparse
import os
import signal
import subprocess
import sys
import time

from node_session import planner_session
import numpy as np
from punctured_planner.ros.client import call_service
from punctured_planner.ros.conversions import duration_to_seconds

sys.path.insert(0, os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))),
                                'test'))
from stop_check import random_request  # noqa: E402 - test/ helper, as bench/stop_stress.py

OBSTACLES = [-2.0, 0.5, 0.0, 0.0, -0.5, 0.0, 2.5, 0.0, 0.0]
SWEEP = (2, 8, 64, 512, 2048)
MAX_POSES = 100000000


def calls_for(k):
    """Return how many timed calls to make for k robots (fewer for large k)."""
    return 200 if k <= 8 else 100 if k <= 64 else 20 if k <= 512 else 6


def call(executor, client, request, timeout_sec=120.0):
    """Send request through the project's client loop; return the response (None on timeout)."""
    return call_service(executor, client, request, timeout_sec)


def settings(refine):
    """Return the node's settings in this benchmark (as its -p parameters set them)."""
    from punctured_planner.ros.settings import PLANNER
    return PLANNER.settings({'obstacles': OBSTACLES, 'max_poses': MAX_POSES,
                             'refine': refine})


def requests_for(k, n, calls, seed=1):
    """Return the seeded requests of one k: two warm-up calls, then ``calls`` timed ones."""
    rng = np.random.default_rng(seed)
    return [random_request(rng, k, n) for _ in range(calls + 2)]


def _key(request):
    """Return what tells the benchmark's requests apart: k and the first robot's x."""
    poses = request.configurations[0].poses
    return len(poses), poses[0].position.x


def echo_server(ks, n, calls, refine):
    """
    Serve ``echo_sequence``: for each request the benchmark sends, a prebuilt response.

    Each is the offline plan's response to that very request (the node's size
    to the byte), built before serving: the floor of the round trip, with no
    planning and no message building per call. Runs until SIGINT or SIGTERM,
    like the node (punctured_planner.ros.runtime).
    """
    from punctured_planner.cli import offline_plan
    from punctured_planner.ros.runtime import NodeGroup
    from punctured_planner.ros.runtime import run_nodes
    from punctured_planner_interfaces.srv import PlanSequence
    from rclpy.node import Node
    prebuilt = {}
    for k in ks:
        for request in requests_for(k, n, calls or calls_for(k)):
            outcome = offline_plan(request, settings(refine))
            assert outcome.ok, outcome.response.error_msg
            prebuilt[_key(request)] = outcome.response

    def make_nodes(context):
        node = Node('echo_server', context=context)
        node.create_service(PlanSequence, 'echo_sequence',
                            lambda request, _: prebuilt[_key(request)])
        return NodeGroup([node])
    return run_nodes('echo_server', make_nodes, args=sys.argv)


def timed_call(executor, client, request):
    """Return (seconds, response) of one call; raise if it failed."""
    started = time.perf_counter()
    response = call(executor, client, request)
    seconds = time.perf_counter() - started
    if response is None or response.error_code != 0:
        raise RuntimeError('call failed: %s' % (response and response.error_msg))
    return seconds, response


def wait_published(executor, published, plan_id, timeout_sec=60.0):
    """Spin until the node's Plan plan_id has arrived (published last: all its topics are out)."""
    deadline = time.monotonic() + timeout_sec
    while plan_id not in published:
        if time.monotonic() > deadline:
            raise RuntimeError('plan %d not published within %g s' % (plan_id, timeout_sec))
        executor.spin_once(timeout_sec=0.01)


def measure(executor, client, echo, published, k, n, calls, seed=1):
    """
    Return (round trips s, floor round trips s, planning times s, response bytes).

    Each request goes to the node, then, once the node has published that plan
    (``published``: the plan ids seen on its ``plan`` topic), to the echo server.
    """
    from rclpy.serialization import serialize_message
    requests = requests_for(k, n, calls, seed)
    for request in requests[:2]:  # warm-up: publishers for these robot names, caches
        _, response = timed_call(executor, client, request)
        wait_published(executor, published, response.plan_id)
        timed_call(executor, echo, request)
    trips, floor, planning = [], [], []
    for request in requests[2:]:
        seconds, response = timed_call(executor, client, request)
        trips.append(seconds)
        wait_published(executor, published, response.plan_id)
        planning.append(duration_to_seconds(response.planning_time))
        seconds, echoed = timed_call(executor, echo, request)
        floor.append(seconds)
        size = len(serialize_message(response))
        assert len(serialize_message(echoed)) == size, 'echo of another size'
    return np.array(trips), np.array(floor), np.array(planning), size


def main(argv=None):
    """Run the benchmark; print one line per k."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--sweep', action='store_true', help='k in %s' % (SWEEP,))
    parser.add_argument('-k', type=int, nargs='+', default=[8],
                        help='robots, one or more (default: 8)')
    parser.add_argument('-n', type=int, default=3, help='configurations (default: 3)')
    parser.add_argument('--calls', type=int, default=None, help='timed calls per k')
    parser.add_argument('--refine', choices=('true', 'false'), default='true',
                        help="the node's refine parameter (false: no refinement, so that "
                        'its compute time is not counted as transport)')
    parser.add_argument('--echo-server', action='store_true',
                        help='serve the floor (started by this script itself)')
    args, _ = parser.parse_known_args(argv)
    ks = SWEEP if args.sweep else tuple(args.k)
    refine = args.refine == 'true'
    if args.echo_server:
        return echo_server(ks, args.n, args.calls, refine)
    parameters = {'obstacles': '[%s]' % ','.join(str(v) for v in OBSTACLES),
                  'max_poses': MAX_POSES, 'refine': args.refine}
    with planner_session('bench', parameters) as session:
        from punctured_planner.ros.qos import LATCHED
        from punctured_planner_interfaces.msg import Plan
        from punctured_planner_interfaces.srv import PlanSequence
        published = set()
        # Raw: the plan id is the first field (uint64 after the CDR header), and the
        # Plan is never deserialised here (k x M poses of Python objects at large k).
        session.node.create_subscription(
            Plan, session.namespace + '/plan',
            lambda data: published.add(int.from_bytes(data[4:12], 'little')), LATCHED,
            raw=True)
        echo_process = subprocess.Popen(
            [sys.executable, __file__, '--echo-server', '-n', str(args.n)]
            + (['--calls', str(args.calls)] if args.calls else [])
            + (['--sweep'] if args.sweep else ['-k'] + [str(k) for k in ks])
            + ['--refine', args.refine]
            + ['--ros-args', '-r', '__ns:=' + session.namespace + '_echo'],
            stdout=subprocess.DEVNULL, stdin=subprocess.DEVNULL)
        try:
            client = session.node.create_client(PlanSequence,
                                                session.namespace + '/plan_sequence')
            echo = session.node.create_client(PlanSequence,
                                              session.namespace + '_echo/echo_sequence')
            started = time.perf_counter()
            if not (client.wait_for_service(timeout_sec=30)
                    and echo.wait_for_service(timeout_sec=600)):
                print('service not discovered; node log: %s' % session.log_path)
                return 1
            print('planner_node and the echo server in their own processes, discovered in '
                  '%.2f s (ROS_DOMAIN_ID %s, %s)'
                  % (time.perf_counter() - started, os.environ['ROS_DOMAIN_ID'],
                     os.environ.get('RMW_IMPLEMENTATION', 'default RMW')))
            print('n = %d configurations, 3 obstacles, spread variant, samples_per_leg 0, '
                  'refine %s' % (args.n, args.refine))
            print('%6s %6s %10s %10s %10s %10s %12s %12s'
                  % ('k', 'calls', 'median ms', 'p90 ms', 'floor ms', 'ours/floor',
                     'planning ms', 'bytes'))
            for k in ks:
                calls = args.calls or calls_for(k)
                trips, floor, planning, size = measure(session.executor, client, echo,
                                                       published, k, args.n, calls)
                print('%6d %6d %10.3f %10.3f %10.3f %10.2f %12.3f %12d' % (
                    k, calls, np.median(trips) * 1e3, np.percentile(trips, 90) * 1e3,
                    np.median(floor) * 1e3, np.median(trips) / np.median(floor),
                    np.median(planning) * 1e3, size), flush=True)
        finally:
            echo_process.send_signal(signal.SIGINT)
            echo_process.wait(timeout=60)
    return 0


if __name__ == '__main__':
    sys.exit(main())
