"""
Soak test of planner_node: 10,000 service calls against one node process (issue 7).

Starts the installed ``planner_node`` console script in its own process (three
obstacles, spread variant, default log level) and calls ``plan_sequence`` from
this process, one call at a time, with a seeded mix of requests:

* valid requests, k robots through n configurations (default k = 8, n = 3);
* every 10th a request the node must refuse, cycling through NaN, coincident
  robots, a wrong frame, too many configurations and too few configurations;
* every 7th with ``use_current_state`` (a robot state is published first);
* every 500 calls a new obstacle set on the ``obstacles`` topic (alternating
  with a fresh random set, so the node's workspace cache keeps turning over).

Prints latency percentiles (valid and refused calls), the node's resident
memory (VmRSS) over the run and its peak (VmHWM) from /proc/<pid>/status, its
CPU time, and the number of failures: a lost call (no answer within 30 s), a
valid request not planned, a bad request answered NONE or UNKNOWN. Printed,
not asserted.

    .venv/bin/python bench/soak.py                  # 10,000 calls
    .venv/bin/python bench/soak.py --calls 2000 -k 16 -n 4
"""

import argparse
import os
import sys
import time

from node_session import planner_session
import numpy as np
from punctured_planner.ros.client import call_service

OBSTACLES = ((-2.0, 0.5, 0.0), (0.0, -0.5, 0.0), (2.5, 0.0, 0.0))
BAD_KINDS = ('nan', 'coincide', 'frame', 'over_limit', 'too_few')
EXPECTED_CODE = {'nan': 6, 'coincide': 10, 'frame': 7, 'over_limit': 3, 'too_few': 1}
MAX_CONFIGURATIONS = 50
TIMEOUT_SEC = 30.0


def proc_status(pid):
    """Return (VmRSS, VmHWM) of a process in MiB, from /proc/<pid>/status."""
    values = {}
    with open('/proc/%d/status' % pid, encoding='ascii') as stream:
        for line in stream:
            name, _, rest = line.partition(':')
            if name in ('VmRSS', 'VmHWM'):
                values[name] = int(rest.split()[0]) / 1024.0
    return values['VmRSS'], values['VmHWM']


def cpu_seconds(pid):
    """Return the user + system CPU seconds a process has used (/proc/<pid>/stat)."""
    with open('/proc/%d/stat' % pid, encoding='ascii') as stream:
        fields = stream.read().rpartition(')')[2].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def pose_array(points, frame_id='map'):
    """Return a geometry_msgs/PoseArray of (x, y) or (x, y, z) points."""
    from geometry_msgs.msg import Pose
    from geometry_msgs.msg import PoseArray
    msg = PoseArray()
    msg.header.frame_id = frame_id
    for point in np.asarray(points, dtype=float).tolist():
        pose = Pose()
        pose.position.x, pose.position.y = point[0], point[1]
        pose.position.z = point[2] if len(point) > 2 else 0.0
        msg.poses.append(pose)
    return msg


def make_request(rng, k, n, kind='valid', use_state=False):
    """Return (PlanSequence request, expected error code or 0) of the given kind."""
    from punctured_planner_interfaces.srv import PlanSequence
    spread = max(10.0, 2.0 * np.sqrt(k))
    configurations = rng.uniform(-spread, spread, size=(n, k, 2)).round(3)
    frame = 'map'
    if kind == 'nan':
        configurations[rng.integers(n), rng.integers(k), rng.integers(2)] = np.nan
    elif kind == 'coincide':
        m = rng.integers(n)
        configurations[m, 1] = configurations[m, 0]
    elif kind == 'frame':
        frame = 'odom'
    elif kind == 'over_limit':
        configurations = np.resize(configurations, (MAX_CONFIGURATIONS + 1, k, 2))
    elif kind == 'too_few':
        configurations = configurations[:1]
    request = PlanSequence.Request()
    request.configurations = [pose_array(c, frame) for c in configurations]
    if use_state and kind == 'valid':
        request.configurations = request.configurations[1:]
        request.use_current_state = True
    request.max_speed = 1.0
    return request, EXPECTED_CODE.get(kind, 0)


def call(executor, client, request, timeout_sec=TIMEOUT_SEC):
    """Send request through the project's client loop; return the response (None on timeout)."""
    return call_service(executor, client, request, timeout_sec)


def percentiles(values):
    """Return 'p50 / p90 / p99 / max' of seconds, in ms."""
    values = np.asarray(values) * 1e3
    if values.size == 0:
        return '-'
    return '%.2f / %.2f / %.2f / %.2f' % (np.percentile(values, 50), np.percentile(values, 90),
                                          np.percentile(values, 99), values.max())


class Soak:
    """The state of one soak run: clients, publishers, figures."""

    def __init__(self, node, executor, namespace, pid, args):
        """Create the client and the publishers."""
        from geometry_msgs.msg import PoseArray
        from punctured_planner.ros.qos import CLIENT_QOS
        from punctured_planner_interfaces.srv import PlanSequence
        from rclpy.qos import DurabilityPolicy
        from rclpy.qos import QoSProfile
        from rclpy.qos import ReliabilityPolicy
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.executor = executor
        self.pid = pid
        self.args = args
        self.client = node.create_client(PlanSequence, namespace + '/plan_sequence',
                                         qos_profile=CLIENT_QOS)
        self.obstacles = node.create_publisher(PoseArray, namespace + '/obstacles', latched)
        self.states = node.create_publisher(PoseArray, namespace + '/robot_states', 10)
        self.rng = np.random.default_rng(args.seed)
        self.latencies = {'valid': [], 'refused': []}
        self.failures = []
        self.memory = []

    def publish_state(self):
        """Publish a robot state of k robots until a use_current_state call plans from it."""
        state = self.rng.uniform(-20, 20, size=(self.args.k, 2)).round(3)
        for _ in range(100):
            self.states.publish(pose_array(state))
            request, _ = make_request(self.rng, self.args.k, self.args.n, use_state=True)
            response = call(self.executor, self.client, request)
            if response is not None and response.error_code == 0:
                return
            time.sleep(0.05)
        raise RuntimeError('the node never used the published robot state')

    def publish_obstacles(self, index):
        """Publish the default obstacles or a fresh random set (alternately)."""
        if (index // 500) % 2 == 0:
            points = OBSTACLES
        else:
            points = np.c_[self.rng.uniform(-8, 8, size=(3, 2)).round(2), np.zeros(3)]
        self.obstacles.publish(pose_array(points))

    def one_call(self, index):
        """Make call number index; record its latency or its failure."""
        k, n = self.args.k, self.args.n
        kind = BAD_KINDS[(index // 10) % len(BAD_KINDS)] if index % 10 == 9 else 'valid'
        request, expected = make_request(self.rng, k, n, kind, use_state=index % 7 == 3)
        started = time.perf_counter()
        response = call(self.executor, self.client, request)
        elapsed = time.perf_counter() - started
        if response is None:
            self.failures.append((index, kind, 'lost'))
            return
        code = response.error_code
        if kind == 'valid' and code == 10:
            return  # random robots that happen to coincide: refused as documented
        if kind == 'valid' and code != 0:
            self.failures.append((index, kind, '%d %s' % (code, response.error_msg)))
        elif kind != 'valid' and code != expected:
            self.failures.append((index, kind, 'expected %d, got %d %s'
                                  % (expected, code, response.error_msg)))
        else:
            self.latencies['valid' if kind == 'valid' else 'refused'].append(elapsed)

    def run(self):
        """Warm up, then make args.calls calls; sample memory every args.every calls."""
        if not self.client.wait_for_service(timeout_sec=30):
            raise RuntimeError('service not discovered')
        self.publish_obstacles(0)
        self.publish_state()
        for index in range(20):
            self.one_call(index)
        self.latencies = {'valid': [], 'refused': []}
        self.failures = []
        started = time.perf_counter()
        self.memory.append((0, 0.0) + proc_status(self.pid))
        cpu = cpu_seconds(self.pid)
        for index in range(self.args.calls):
            if index % 500 == 0:
                self.publish_obstacles(index)
            self.one_call(index)
            if (index + 1) % self.args.every == 0:
                self.memory.append((index + 1, time.perf_counter() - started)
                                   + proc_status(self.pid))
        return time.perf_counter() - started, cpu_seconds(self.pid) - cpu


def report(soak, elapsed, cpu):
    """Print the figures of a soak run."""
    calls = soak.args.calls
    print('%d calls in %.1f s (%.0f calls/s); node CPU %.1f s (%.2f ms per call)'
          % (calls, elapsed, calls / elapsed, cpu, 1e3 * cpu / calls))
    print('latency ms p50 / p90 / p99 / max: valid (%d) %s; refused (%d) %s'
          % (len(soak.latencies['valid']), percentiles(soak.latencies['valid']),
             len(soak.latencies['refused']), percentiles(soak.latencies['refused'])))
    every = soak.latencies['valid'] + soak.latencies['refused']
    print('latency ms p50 / p99, all calls: %.2f / %.2f'
          % (1e3 * np.percentile(every, 50), 1e3 * np.percentile(every, 99)))
    print('%8s %8s %10s %10s' % ('calls', 's', 'VmRSS MiB', 'VmHWM MiB'))
    for index, seconds, rss, hwm in soak.memory:
        print('%8d %8.1f %10.1f %10.1f' % (index, seconds, rss, hwm))
    rss = np.array([m[2] for m in soak.memory])
    if len(rss) < 2:  # a line through one sample is no slope
        growth = 'n/a (one sample: --every above --calls)'
    else:  # the second half's samples, at least two
        half = min(len(rss) // 2, len(rss) - 2)
        growth = '%.3f MiB per 1000 calls' % (np.polyfit(
            [m[0] for m in soak.memory[half:]], rss[half:], 1)[0] * 1000)
    print('memory: start %.1f MiB, final %.1f MiB, peak (VmHWM) %.1f MiB, growth over the '
          'second half %s' % (rss[0], rss[-1], soak.memory[-1][3], growth))
    print('failures: %d' % len(soak.failures))
    for failure in soak.failures[:20]:
        print('  call %d (%s): %s' % failure)


def main(argv=None):
    """Run the soak; print the figures; return 0 (1 if the service never came up)."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--calls', type=int, default=10000, help='calls (default 10000)')
    parser.add_argument('-k', type=int, default=8, help='robots (default: %(default)s)')
    parser.add_argument('-n', type=int, default=3, help='configurations (default 3)')
    parser.add_argument('--every', type=int, default=1000, help='memory sample period')
    parser.add_argument('--seed', type=int, default=7)
    parser.add_argument('--log-level', default='info', help="the node's (default info)")
    args = parser.parse_args(argv)
    # The robot state is published once, at warm-up: no age limit, or every
    # use_current_state call after max_state_age (0.5 s) would be refused.
    parameters = {'obstacles': '[%s]' % ','.join(str(v) for point in OBSTACLES for v in point),
                  'max_configurations': MAX_CONFIGURATIONS, 'max_state_age': '0.0'}
    with planner_session('soak', parameters, args.log_level, domain_offset=70) as session:
        process = session.process
        soak = Soak(session.node, session.executor, session.namespace, process.pid, args)
        print('planner_node pid %d (ROS_DOMAIN_ID %s, log %s); k = %d, n = %d, seed %d'
              % (process.pid, os.environ['ROS_DOMAIN_ID'], session.log_path, args.k, args.n,
                 args.seed))
        elapsed, cpu = soak.run()
        alive = process.poll() is None
        report(soak, elapsed, cpu)
        print('node process alive at the end: %s' % alive)
    return 0


if __name__ == '__main__':
    sys.exit(main())
