"""
How soon a caller that missed part of its reply gets the rest, with and without our profile.

The node keeps running (doc/design.md section 16). For each writer heartbeat
(the package's Fast DDS profile, 100 ms; Fast DDS's own, 3 s, given as a
profile of the user's, which the package then leaves alone), each k in
test/stop_check.py's ROBOTS and each caller kind, ``--trials`` calls from a
fresh ``punctured-planner call`` process: a caller frozen (SIGSTOP) from the
moment the node took its call until ``--freeze-sec`` after the node logged the
plan (the reply is written before), or one left running. The figure is the time
from that log line to the caller's exit with its reply, as min / median / max,
and how many came later than LATE_SEC (they waited for a heartbeat).

    .venv/bin/python bench/reply_repair.py
    .venv/bin/python bench/reply_repair.py --trials 10 --freeze-sec 0.5
"""

import argparse
import os
import signal
import subprocess
import sys
import tempfile
import time

TEST_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'test')
sys.path.insert(0, TEST_DIR)
import numpy as np  # noqa: E402
from punctured_planner.ros.qos import FASTDDS_PROFILE_VARIABLE  # noqa: E402
from stop_check import ANSWERED  # noqa: E402 - test/ helpers
from stop_check import CALL_TIMEOUT_SEC  # noqa: E402
from stop_check import caller_command  # noqa: E402
from stop_check import node_arguments  # noqa: E402
from stop_check import request_data  # noqa: E402
from stop_check import ROBOTS  # noqa: E402
from stop_check import wait_for_text  # noqa: E402
import yaml  # noqa: E402

# A reply later than this after its write waited for a heartbeat: a frozen caller has the
# rest about 0.5 s after it resumes with the package's 100 ms, 3 s after the write with 3 s.
LATE_SEC = 2.0
# Fast DDS's own writer heartbeat, stated as a user's profile.
DEFAULT_HEARTBEAT_PROFILE = """<?xml version="1.0" encoding="UTF-8" ?>
<profiles xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">
  <data_writer profile_name="fast_dds_default" is_default_profile="true">
    <times><heartbeatPeriod><sec>3</sec><nanosec>0</nanosec></heartbeatPeriod></times>
  </data_writer>
</profiles>
"""


def one_call(node, node_log, namespace, env, rng, k, freeze_sec, scratch, number):
    """Return the seconds from the node's 'planned' log line to the caller's exit (or None)."""
    request_path = os.path.join(scratch, 'request_%d.yaml' % number)
    with open(request_path, 'w') as stream:
        yaml.safe_dump(request_data(rng, k), stream)
    # Count from the node's log of this call, the #number-th of its service.
    taken, planned = (('plan_sequence #%d:%s' % (number, tail)).encode()
                      for tail in ('', ' planned'))
    caller = subprocess.Popen(
        caller_command([os.path.join(os.path.dirname(sys.executable), 'punctured-planner')],
                       request_path, namespace + '/plan_sequence'),
        env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    try:
        if not wait_for_text(node_log, taken, caller, 30.0):
            return None
        if freeze_sec is not None:
            caller.send_signal(signal.SIGSTOP)
        if not wait_for_text(node_log, planned, node, 30.0):
            return None
        written = time.monotonic()
        if freeze_sec is not None:
            time.sleep(freeze_sec)
            caller.send_signal(signal.SIGCONT)
        output = caller.communicate(timeout=CALL_TIMEOUT_SEC + 10.0)[0]
        return time.monotonic() - written if ANSWERED in output else None
    finally:
        if caller.poll() is None:
            caller.kill()
            caller.wait()


def run_heartbeat(label, env, args, scratch):
    """Start one planner_node with env; time every case; print a line per case."""
    namespace = '/pp_repair_%d_%s' % (os.getpid(), label.split()[0])
    node_log = os.path.join(scratch, label.split()[0] + '.log')
    script = os.path.join(os.path.dirname(sys.executable), 'planner_node')
    rng = np.random.default_rng(args.seed)
    with open(node_log, 'wb') as log:
        node = subprocess.Popen([script] + node_arguments(namespace), env=env, stdout=log,
                                stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL)
    number = 0
    try:
        for k in ROBOTS:
            for freeze_sec in (args.freeze_sec, None):
                seconds = []
                for _ in range(args.trials):
                    number += 1
                    seconds.append(one_call(node, node_log, namespace, env, rng, k, freeze_sec,
                                            scratch, number))
                delivered = [s for s in seconds if s is not None]
                caller = ('frozen %.1f s' % freeze_sec) if freeze_sec is not None else 'running'
                figures = ('%.2f / %.2f / %.2f s' % (min(delivered), float(np.median(delivered)),
                                                     max(delivered)) if delivered else '-')
                late = sum(s > LATE_SEC for s in delivered)
                print('| %s | %d | %s | %d of %d | %s | %d |' % (
                    label, k, caller, len(delivered), len(seconds), figures, late), flush=True)
    finally:
        node.send_signal(signal.SIGINT)
        node.wait(60.0)


def main(argv=None):
    """Print the table of reply times."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--trials', type=int, default=5, help='calls per case (default 5)')
    parser.add_argument('--freeze-sec', type=float, default=0.5,
                        help='how long after the write a frozen caller resumes (default 0.5)')
    parser.add_argument('--seed', type=int, default=21)
    args = parser.parse_args(argv)
    os.environ.setdefault('ROS_DOMAIN_ID', str(1 + (os.getpid() + 40) % 101))
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    scratch = tempfile.mkdtemp(prefix='pp_repair_')
    os.environ.setdefault('ROS_LOG_DIR', scratch)
    default_profile = os.path.join(scratch, 'fast_dds_default.xml')
    with open(default_profile, 'w') as stream:
        stream.write(DEFAULT_HEARTBEAT_PROFILE)
    package = {key: value for key, value in os.environ.items()
               if key != FASTDDS_PROFILE_VARIABLE}
    print("Seconds from the reply's write (the node's log) to the caller's exit with it, "
          'min / median / max.\n')
    print('| writer heartbeat | k | caller | delivered | seconds | later than %.0f s |'
          % LATE_SEC)
    print('|---|---|---|---|---|---|')
    run_heartbeat('100 ms (the package profile)', package, args, scratch)
    run_heartbeat('3 s (Fast DDS default)', dict(package, **{
        FASTDDS_PROFILE_VARIABLE: default_profile}), args, scratch)
    return 0


if __name__ == '__main__':
    sys.exit(main())
