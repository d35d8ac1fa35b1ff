"""
Stress of plan_sequence under concurrent load, with CPU hogs beside it (issue 21).

``--rounds`` times: start the installed planner_node (the obstacles and variant
of test/test_reliability.py's load test), publish obstacles and robot states
alternating between two sets at 50 Hz, and run ``--clients`` processes of
test/reliability_client.py at once, ``--calls`` calls each (half plain
requests, half with ``use_current_state``), as that test does. ``--hogs``
busy-loop processes run beside it all (issue 21: two, on this 2-core machine).
The clients never call again after a lost call, so a call answered only after
a retry cannot hide here.

Prints per round and in total: calls, lost calls (no answer within 20 s),
calls answered with an error code, and the node's "not sent" errors (replies
rmw could not send, doc/design.md section 15). Printed, not asserted.

    .venv/bin/python bench/load_stress.py                     # 20 x 4 x 250, 2 hogs
    .venv/bin/python bench/load_stress.py --rounds 3 --hogs 0
    .venv/bin/python bench/load_stress.py --client-qos rclpy  # the depth-10 default
"""

import argparse
import collections
import json
import os
import subprocess
import sys
import threading
import time

from node_session import planner_session

TEST_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'test')
CLIENT = os.path.join(TEST_DIR, 'reliability_client.py')
sys.path.insert(0, TEST_DIR)
# The load scenario of test/test_reliability.py, the same client's (one place).
from reliability_client import CONFIGURATIONS  # noqa: E402
from reliability_client import OBSTACLES  # noqa: E402
from reliability_client import OTHER_OBSTACLES  # noqa: E402
from reliability_client import STATES  # noqa: E402
PARAMETERS = {'obstacles': '[%s]' % ','.join(str(v) for p in OBSTACLES for v in p),
              'variant': 'spread', 'max_speed': '0.5', 'max_state_age': '0.0'}
NOT_SENT = 'not sent to the client'
COLLECT_TIMEOUT_SEC = 600.0


def spec(configurations, use_state):
    """Return the reliability_client request description."""
    return {'configurations': [['map', [list(p) for p in c]] for c in configurations],
            'use_current_state': use_state, 'max_speed': 0.0, 'samples_per_leg': 0}


class Inputs:
    """Publish obstacles (latched) and robot states, alternating two sets, in a thread."""

    def __init__(self, node, namespace, rate_hz):
        """Create the publishers on ``node``; start() begins publishing."""
        from punctured_planner.ros.qos import LATCHED
        self.obstacles = node.create_publisher(
            pose_array_type(), namespace + '/obstacles', LATCHED)
        self.states = node.create_publisher(pose_array_type(), namespace + '/robot_states',
                                            10)
        self.period = 1.0 / rate_hz
        self.count = 0
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)

    def start(self):
        """Start publishing."""
        self._thread.start()

    def _run(self):
        sets = [pose_array(points) for points in (OBSTACLES, OTHER_OBSTACLES)]
        states = [pose_array(points) for points in STATES]
        started = time.monotonic()
        while not self._stop.is_set():
            self.obstacles.publish(sets[self.count % 2])
            self.states.publish(states[(self.count // 3) % 2])
            self.count += 1
            self._stop.wait(max(0.0, started + self.count * self.period - time.monotonic()))

    def stop(self):
        """Stop publishing."""
        self._stop.set()
        self._thread.join(timeout=5)


def pose_array_type():
    """Return geometry_msgs/PoseArray (imported late: rclpy)."""
    from geometry_msgs.msg import PoseArray
    return PoseArray


def pose_array(points):
    """Return a PoseArray in frame map of (x, y, z) points."""
    from geometry_msgs.msg import Pose
    msg = pose_array_type()()
    msg.header.frame_id = 'map'
    for x, y, z in points:
        pose = Pose()
        pose.position.x, pose.position.y, pose.position.z = x, y, z
        msg.poses.append(pose)
    return msg


def run_round(session, args):
    """Run one round against a fresh node; return a Counter of outcomes."""
    service = session.namespace + '/plan_sequence'
    specs = [dict(spec(CONFIGURATIONS, False), client_qos=args.client_qos),
             dict(spec(CONFIGURATIONS[1:], True), client_qos=args.client_qos)]
    inputs = Inputs(session.node, session.namespace, args.rate)
    inputs.start()
    counts = collections.Counter({key: 0 for key in ('calls', 'lost', 'error code')})
    try:
        processes = [subprocess.Popen(
            [sys.executable, CLIENT, service, str(args.calls), json.dumps(specs[i % 2])],
            env=dict(os.environ), cwd=TEST_DIR, stdout=subprocess.PIPE,
            stderr=subprocess.PIPE, text=True) for i in range(args.clients)]
        for process in processes:
            out, err = process.communicate(timeout=COLLECT_TIMEOUT_SEC)
            records = [json.loads(line) for line in out.splitlines() if line.startswith('{')]
            if not records or not records[-1].get('done'):
                counts['client failures'] += 1
                print('client failed (%s): %s' % (process.returncode, err[-1000:]))
            for record in records[:-1]:
                counts['calls'] += 1
                if record.get('lost'):
                    counts['lost'] += 1
                elif record['error_code'] != 0:
                    counts['error code'] += 1
    finally:
        inputs.stop()
    with open(session.log_path, encoding='utf-8', errors='replace') as stream:
        log = stream.read()
    counts['not sent'] += log.count(NOT_SENT)
    counts['node tracebacks'] += log.count('Traceback')
    return counts


def start_hogs(count):
    """Start ``count`` busy-loop processes; return them."""
    return [subprocess.Popen([sys.executable, '-c', 'while True: pass']) for _ in range(count)]


def main(argv=None):
    """Run the rounds; print the counts; return 0."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--rounds', type=int, default=20)
    parser.add_argument('--clients', type=int, default=4)
    parser.add_argument('--calls', type=int, default=250, help='per client')
    parser.add_argument('--rate', type=float, default=50.0, help='input rate, Hz')
    parser.add_argument('--hogs', type=int, default=2, help='CPU hog processes beside')
    parser.add_argument('--client-qos', choices=('project', 'rclpy'), default='project',
                        help="clients' service QoS: ros.qos.CLIENT_QOS, or rclpy's "
                        'default (depth 10)')
    args = parser.parse_args(argv)
    hogs = start_hogs(args.hogs)
    total = collections.Counter()
    started = time.monotonic()
    try:
        for number in range(1, args.rounds + 1):
            with planner_session('load%d' % number, PARAMETERS, 'info',
                                 domain_offset=80) as session:
                if not session.node.create_client(
                        service_type(), session.namespace + '/plan_sequence').wait_for_service(
                        timeout_sec=30.0):
                    raise RuntimeError('service not discovered: ' + session.log_path)
                counts = run_round(session, args)
            total.update(counts)
            print('round %2d: %s' % (number, dict(sorted(counts.items()))), flush=True)
    finally:
        for hog in hogs:
            hog.kill()
            hog.wait()
    print('%d rounds of %d x %d calls, %.0f Hz inputs, %d hogs, client QoS %s, %.0f s: %s'
          % (args.rounds, args.clients, args.calls, args.rate, args.hogs, args.client_qos,
             time.monotonic() - started, dict(sorted(total.items()))))
    return 0


def service_type():
    """Return the PlanSequence service type (imported late: rclpy)."""
    from punctured_planner_interfaces.srv import PlanSequence
    return PlanSequence


if __name__ == '__main__':
    sys.exit(main())
