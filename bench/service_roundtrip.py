"""
Service round trip of planner_node across processes, over Fast DDS (not part of make test).

Starts the installed ``planner_node`` console script in its own process (three
obstacles, spread variant, no robot_count), discovers ``plan_sequence`` from
this process and times complete calls: request out, plan, paths and markers
built, the plan published on every robot's topic, the response back and
deserialised here. Seeded random requests, n configurations of k robots.

    .venv/bin/python bench/service_roundtrip.py                 # k = 8, n = 3
    .venv/bin/python bench/service_roundtrip.py --sweep         # k in 2, 8, 64, 512, 2048

Prints median and p90 round trip, the node's own planning_time and the response
size. Uses its own ROS_DOMAIN_ID (pid based) and localhost discovery.
"""

import argparse
import os
import sys
import time

from node_session import planner_session
import numpy as np
from punctured_planner.cli import call_service

OBSTACLES = [-2.0, 0.5, 0.0, 0.0, -0.5, 0.0, 2.5, 0.0, 0.0]
SWEEP = (2, 8, 64, 512, 2048)


def calls_for(k):
    """Return how many timed calls to make for k robots (fewer for large k)."""
    return 200 if k <= 8 else 100 if k <= 64 else 20 if k <= 512 else 6


def make_request(rng, k, n, spread=None):
    """Return a PlanSequence request: n configurations of k robots, uniform in a square."""
    from geometry_msgs.msg import Pose
    from geometry_msgs.msg import PoseArray
    from punctured_planner_interfaces.srv import PlanSequence
    spread = spread or max(10.0, 2.0 * np.sqrt(k))
    request = PlanSequence.Request()
    for _ in range(n):
        configuration = PoseArray()
        configuration.header.frame_id = 'map'
        for x, y in rng.uniform(-spread, spread, size=(k, 2)).tolist():
            pose = Pose()
            pose.position.x, pose.position.y = x, y
            configuration.poses.append(pose)
        request.configurations.append(configuration)
    request.max_speed = 1.0
    return request


def call(executor, client, request, timeout_sec=120.0):
    """Send request through the project's client loop; return the response (None on timeout)."""
    return call_service(executor, client, request, timeout_sec)


def measure(executor, client, k, n, calls, seed=1):
    """Return (round trips s, planning times s, response bytes) over `calls` calls."""
    from rclpy.serialization import serialize_message
    rng = np.random.default_rng(seed)
    requests = [make_request(rng, k, n) for _ in range(calls + 2)]
    for request in requests[:2]:  # warm-up: publishers for these robot names, caches
        response = call(executor, client, request)
        if response is None or response.error_code != 0:
            raise RuntimeError('warm-up failed: %s' % (response and response.error_msg))
    trips, planning = [], []
    for request in requests[2:]:
        started = time.perf_counter()
        response = call(executor, client, request)
        trips.append(time.perf_counter() - started)
        if response is None or response.error_code != 0:
            raise RuntimeError('call failed: %s' % (response and response.error_msg))
        planning.append(response.planning_time.sec + response.planning_time.nanosec * 1e-9)
    return np.array(trips), np.array(planning), len(serialize_message(response))


def main(argv=None):
    """Run the benchmark; print one line per k."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--sweep', action='store_true', help='k in %s' % (SWEEP,))
    parser.add_argument('-k', type=int, default=8, help='robots (default: %(default)s)')
    parser.add_argument('-n', type=int, default=3, help='configurations (default: 3)')
    parser.add_argument('--calls', type=int, default=None, help='timed calls per k')
    args = parser.parse_args(argv)
    parameters = {'obstacles': '[%s]' % ','.join(str(v) for v in OBSTACLES),
                  'max_poses': 100000000}
    with planner_session('bench', parameters) as session:
        from punctured_planner_interfaces.srv import PlanSequence
        client = session.node.create_client(PlanSequence, session.namespace + '/plan_sequence')
        started = time.perf_counter()
        if not client.wait_for_service(timeout_sec=30):
            print('service not discovered; node log: %s' % session.log_path)
            return 1
        print('planner_node in its own process, discovered in %.2f s (ROS_DOMAIN_ID %s, %s)'
              % (time.perf_counter() - started, os.environ['ROS_DOMAIN_ID'],
                 os.environ.get('RMW_IMPLEMENTATION', 'default RMW')))
        print('n = %d configurations, 3 obstacles, spread variant, samples_per_leg 0'
              % args.n)
        print('%6s %6s %12s %12s %12s %14s %12s'
              % ('k', 'calls', 'median ms', 'p90 ms', 'min ms', 'planning ms', 'bytes'))
        for k in (SWEEP if args.sweep else (args.k,)):
            calls = args.calls or calls_for(k)
            trips, planning, size = measure(session.executor, client, k, args.n, calls)
            print('%6d %6d %12.3f %12.3f %12.3f %14.3f %12d' % (
                k, calls, np.median(trips) * 1e3, np.percentile(trips, 90) * 1e3,
                trips.min() * 1e3, np.median(planning) * 1e3, size), flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
