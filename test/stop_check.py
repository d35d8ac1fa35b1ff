"""
One stop cycle of a node process: start, one call, SIGINT or SIGTERM at a random moment.

The call comes from a fresh ``punctured-planner call`` process each cycle, and
the cycle records whether that process got its reply (doc/design.md section 16).

Shared by the short check in ``make test`` (test/test_clean_stop.py, a few cycles
per install) and the stress benchmark (bench/stop_stress.py, 300 cycles per
install). A cycle is clean when the process exits 0 with no traceback in its
output; a segfault (exit -11), an abort or a hang (still running
``STOP_TIMEOUT_SEC`` after the signal, then killed) is not.
"""

from dataclasses import dataclass
import signal
import subprocess
import time
from typing import Optional

import numpy as np
import yaml

# Seconds a stopped node may take to exit: its shutdown.STOP_TIMEOUT_SEC plus margin.
STOP_TIMEOUT_SEC = 70.0
SIGNALS = (signal.SIGINT, signal.SIGTERM)
# The request of a cycle: n configurations of k robots (k drawn from ROBOTS), so a
# signal sent within MAX_DELAY_SEC of the call lands before, during or after it.
ROBOTS = (8, 512)
CONFIGURATIONS = 3
MAX_DELAY_SEC = 0.3
# Seconds the fresh client process waits for its reply.
CALL_TIMEOUT_SEC = 15.0
OBSTACLES = '[-2.0, 0.5, 0.0, 0.0, -0.5, 0.0, 2.5, 0.0, 0.0]'
# What ``punctured-planner call`` prints once it has a response.
ANSWERED = b'# error_code'


@dataclass
class Cycle:
    """What one cycle did and how the process ended."""

    signal_name: str
    robots: int
    delay_sec: float  # from sending the call to sending the signal
    served: bool  # the service was discovered
    during_call: bool  # the signal went out while the call was unanswered
    answered: bool  # the response arrived
    returncode: Optional[int]  # None: still running after STOP_TIMEOUT_SEC (killed)
    output: str

    @property
    def traceback(self):
        """Return whether the process printed a Python traceback."""
        return 'Traceback (most recent call last)' in self.output

    @property
    def segfault(self):
        """Return whether the process died of SIGSEGV."""
        return self.returncode == -signal.SIGSEGV or 'Segmentation fault' in self.output

    @property
    def clean(self):
        """Return whether the process exited 0 with no traceback."""
        return self.returncode == 0 and not self.traceback

    def describe(self):
        """Return a one-line account of the cycle, with the output when it was not clean."""
        line = ('%s at %.3f s after the call (k=%d, %s), exit %s'
                % (self.signal_name, self.delay_sec, self.robots,
                   'during the call' if self.during_call else
                   'answered before' if self.answered else 'not served', self.returncode))
        return line if self.clean else line + ':\n' + self.output[-4000:]


def random_request(rng, k, n=CONFIGURATIONS):
    """
    Return a PlanSequence request of n configurations of k robots in a square.

    Also the requests of bench/service_roundtrip.py.
    """
    from geometry_msgs.msg import Pose
    from geometry_msgs.msg import PoseArray
    from punctured_planner_interfaces.srv import PlanSequence
    spread = max(10.0, 2.0 * np.sqrt(k))
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


def node_arguments(namespace):
    """Return the ROS arguments of a cycle's node: its namespace and three obstacles."""
    return ['--ros-args', '-r', '__ns:=' + namespace, '-p', 'obstacles:=' + OBSTACLES]


def draw(rng):
    """Return a random (signal number, robots k, delay s): SIGINT or SIGTERM, k in ROBOTS."""
    return (SIGNALS[rng.integers(len(SIGNALS))], int(ROBOTS[rng.integers(len(ROBOTS))]),
            float(rng.uniform(0.0, MAX_DELAY_SEC)))


def request_data(rng, k, n=CONFIGURATIONS):
    """Return the request of :func:`random_request` as ``punctured-planner call`` reads it."""
    request = random_request(rng, k, n)
    return {'configurations': [
        {'header': {'frame_id': 'map'},
         'poses': [{'position': {'x': pose.position.x, 'y': pose.position.y}}
                   for pose in configuration.poses]}
        for configuration in request.configurations], 'max_speed': request.max_speed}


def caller_command(caller, request_path, service):
    """Return the command of one ``punctured-planner call`` (``caller``) of ``service``."""
    return caller + ['call', request_path, '--service', service, '--no-paths', '--timeout',
                     str(CALL_TIMEOUT_SEC)]


def wait_for_text(path, text, process, timeout_sec):
    """Wait until the file at ``path`` holds ``text`` or ``process`` exited; return if it does."""
    deadline = time.monotonic() + timeout_sec
    while time.monotonic() < deadline:
        with open(path, 'rb') as stream:
            if text in stream.read():
                return True
        if process.poll() is not None:
            return False
        time.sleep(0.002)
    return False


def run_cycle(client_node, command, env, namespace, log_path, choice, rng, caller,
              cwd=None, freeze_sec=None):
    """
    Run one cycle of ``command`` (a planner_node in ``namespace``); return a Cycle.

    ``client_node`` (the caller's rclpy node) only waits for the service; the
    call itself is a fresh ``caller`` process (the ``punctured-planner``
    command as a list), as a fleet's one-shot tool would call: its reader is
    matched for the first time when the reply goes out. ``choice`` is (signal
    number, k, delay s) as :func:`draw` returns it: the signal goes out
    ``delay`` seconds after the node logged the request, whose k robots are
    drawn from ``rng``. With ``freeze_sec``, the caller is frozen (SIGSTOP) from
    the moment the node took the call, so that it reads nothing while its reply
    goes out; the signal goes out ``delay`` seconds after the node logged how the
    call ended (the reply is written before), and the caller resumes
    ``freeze_sec`` after the signal.
    """
    from punctured_planner_interfaces.srv import PlanSequence
    number, k, delay = choice
    request_path = log_path + '.request.yaml'
    with open(request_path, 'w') as stream:
        yaml.safe_dump(request_data(rng, k), stream)
    call_log_path = log_path + '.call'
    with open(log_path, 'wb') as log, open(call_log_path, 'wb') as call_log:
        process = subprocess.Popen(command, env=env, cwd=cwd, stdout=log,
                                   stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
        client = client_node.create_client(PlanSequence, namespace + '/plan_sequence')
        call = None
        try:
            served = client.wait_for_service(timeout_sec=30.0)
            call = subprocess.Popen(
                caller_command(caller, request_path, namespace + '/plan_sequence'), env=env,
                stdout=call_log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
            taken = served and wait_for_text(log_path, b'plan_sequence #1:', call, 30.0)
            if freeze_sec is not None:
                call.send_signal(signal.SIGSTOP)
                wait_for_text(log_path, b'plan_sequence #1: planned', process, 30.0)
            time.sleep(delay)
            during = taken and call.poll() is None
            process.send_signal(number)
            if freeze_sec is not None:
                time.sleep(freeze_sec)
                call.send_signal(signal.SIGCONT)
            try:
                returncode: Optional[int] = process.wait(STOP_TIMEOUT_SEC)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
                returncode = None
            call.wait(CALL_TIMEOUT_SEC + 30.0)
        finally:
            for child in (process, call):
                if child is not None and child.poll() is None:
                    child.kill()
                    child.wait()
            client_node.destroy_client(client)
    with open(log_path, 'rb') as stream:
        output = stream.read().decode('utf-8', 'replace')
    with open(call_log_path, 'rb') as stream:
        answered = ANSWERED in stream.read()
    return Cycle(signal.Signals(number).name, k, delay, served, during, answered, returncode,
                 output)
