"""
Stress check of the clean stop: start, one call, SIGINT or SIGTERM at a random moment (issue 13).

For each install (the venv's console script; the colcon install built from a
copy of this checkout with the README's command), ``--cycles`` times: start
planner_node, wait for its service, send one call (k = 8 or 512 robots, n = 3) from a
fresh ``punctured-planner call`` process, send SIGINT or SIGTERM a random 0-0.3 s
after the node took the call (during or after the plan), wait for the exit.
Counts non-zero exits, tracebacks, segfaults and hangs (no exit within 40 s),
how many signals landed during a call and how many of those calls got their
reply. Seeded; the logs of unclean cycles are kept. ``make test`` runs a few of the
same cycles (test/test_clean_stop.py, test/test_colcon_build.py).

    .venv/bin/python bench/stop_stress.py                        # 300 per install
    .venv/bin/python bench/stop_stress.py --cycles 20 --install venv
    .venv/bin/python bench/stop_stress.py --install colcon --workspace ws  # reuse a build
    .venv/bin/python bench/stop_stress.py --install venv --cycles 20 --freeze-sec 0.5
"""

import argparse
import collections
import os
import shutil
import sys
import tempfile
import time

TEST_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), 'test')
sys.path.insert(0, TEST_DIR)
from colcon_workspace import build_workspace  # noqa: E402 - test/ helpers
from colcon_workspace import installed_node_command  # noqa: E402
from colcon_workspace import venv_env  # noqa: E402
import numpy as np  # noqa: E402
from stop_check import draw  # noqa: E402
from stop_check import node_arguments  # noqa: E402
from stop_check import run_cycle  # noqa: E402


def stress(install, command, cycles, seed, cwd, env, client, caller, keep_dir,
           freeze_sec=None):
    """Run the cycles of one install; print progress and the counts; return the failures."""
    rng = np.random.default_rng(seed)
    counts = collections.Counter()
    log_path = os.path.join(keep_dir, 'cycle.log')
    started = time.monotonic()
    for number in range(cycles):
        namespace = '/pp_stress_%s_%d_%d' % (install, os.getpid(), number)
        cycle = run_cycle(client, command(namespace), env, namespace, log_path,
                          draw(rng), rng, caller, cwd=cwd, freeze_sec=freeze_sec)
        counts[cycle.signal_name] += 1
        counts['during a call'] += cycle.during_call
        counts['during a call, answered'] += cycle.during_call and cycle.answered
        counts['not served'] += not cycle.served
        counts['non-zero exit'] += cycle.returncode not in (0, None)
        counts['traceback'] += cycle.traceback
        counts['segfault'] += cycle.segfault
        counts['hang (killed)'] += cycle.returncode is None
        if cycle.during_call and not cycle.answered:
            print('  cycle %d: reply lost: %s' % (number, cycle.describe().splitlines()[0]),
                  flush=True)
        if not cycle.clean:
            counts['unclean'] += 1
            kept = os.path.join(keep_dir, '%s_%03d.log' % (install, number))
            shutil.copy(log_path, kept)
            print('  cycle %d: %s (log %s)' % (number, cycle.describe().splitlines()[0], kept),
                  flush=True)
        if (number + 1) % 25 == 0:
            print('  %s: %d cycles, %d unclean, %.0f s' % (
                install, number + 1, counts['unclean'], time.monotonic() - started), flush=True)
    print('%s install, %d cycles (%d SIGINT, %d SIGTERM; %d during a call, %d of them '
          'answered): %d non-zero exits, %d tracebacks, %d segfaults, %d hangs, %d not served'
          % (install, cycles, counts['SIGINT'], counts['SIGTERM'], counts['during a call'],
             counts['during a call, answered'], counts['non-zero exit'], counts['traceback'],
             counts['segfault'], counts['hang (killed)'], counts['not served']), flush=True)
    return counts['unclean'] + counts['not served']


def main(argv=None):
    """Run the stress check; exit 1 if any cycle was not clean."""
    parser = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    parser.add_argument('--cycles', type=int, default=300, help='per install (default 300)')
    parser.add_argument('--install', choices=('venv', 'colcon', 'both'), default='both')
    parser.add_argument('--workspace', help='an already built colcon workspace to use')
    parser.add_argument('--seed', type=int, default=13)
    parser.add_argument('--freeze-sec', type=float,
                        help='freeze each caller from the moment the node takes its call '
                             'until this long after the signal, which goes out after the '
                             'reply (test/stop_check.py run_cycle)')
    args = parser.parse_args(argv)
    os.environ.setdefault('ROS_DOMAIN_ID', str(1 + (os.getpid() + 70) % 101))
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    os.environ.setdefault('ROS_LOG_DIR', tempfile.mkdtemp(prefix='pp_stress_log_'))
    keep_dir = tempfile.mkdtemp(prefix='pp_stress_')
    import rclpy
    context = rclpy.context.Context()
    rclpy.init(context=context, args=[])
    client = rclpy.create_node('stress_client', context=context)
    caller = [os.path.join(os.path.dirname(sys.executable), 'punctured-planner')]
    print('ROS_DOMAIN_ID %s; logs of unclean cycles in %s'
          % (os.environ['ROS_DOMAIN_ID'], keep_dir), flush=True)
    failures = 0
    try:
        if args.install in ('venv', 'both'):
            script = os.path.join(os.path.dirname(sys.executable), 'planner_node')
            failures += stress('venv', lambda ns: [script] + node_arguments(ns), args.cycles,
                               args.seed, None, dict(os.environ), client, caller, keep_dir,
                               args.freeze_sec)
        if args.install in ('colcon', 'both'):
            env = venv_env(os.environ)
            workspace = args.workspace or os.path.join(keep_dir, 'ws')
            if not args.workspace:
                result = build_workspace(workspace, env)
                if result.returncode != 0:
                    print(result.stdout[-3000:])
                    return 1
            failures += stress(
                'colcon', lambda ns: installed_node_command(workspace, node_arguments(ns)),
                args.cycles, args.seed + 1, workspace, env, client, caller, keep_dir,
                args.freeze_sec)
    finally:
        client.destroy_node()
        rclpy.try_shutdown(context=context)
    return 1 if failures else 0


if __name__ == '__main__':
    sys.exit(main())
