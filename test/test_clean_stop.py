"""
Ctrl-C and SIGTERM stop the installed planner_node cleanly, also in the middle of a call.

The short version of bench/stop_stress.py (300 cycles per install): each cycle
starts the venv's planner_node, sends one call and stops the node with SIGINT
or SIGTERM; the node must exit 0 without a traceback. The colcon install gets
the same cycles in test/test_colcon_build.py.
"""

import signal

from conftest import venv_script
import numpy as np
import pytest
from stop_check import draw
from stop_check import node_arguments
from stop_check import run_cycle

pytestmark = [pytest.mark.ros, pytest.mark.slow]

# Both signals during a large call (answered before stopping) and with the node idle.
FIXED = [(signal.SIGINT, 512, 0.02), (signal.SIGTERM, 512, 0.02),
         (signal.SIGINT, 8, 0.25), (signal.SIGTERM, 8, 0.25)]


def stop_cycles(ros_client, command, env, tmp_path, choices, seed, cwd=None):
    """Run one stop cycle per choice; return the Cycles."""
    rng = np.random.default_rng(seed)
    cycles = []
    for number, choice in enumerate(choices):
        namespace = '/pp_stop_%d' % number
        cycles.append(run_cycle(
            ros_client.node, command(namespace), env, namespace,
            str(tmp_path / ('stop_%d.log' % number)), choice, rng,
            [venv_script('punctured-planner')], cwd=cwd))
    return cycles


def assert_clean(cycles):
    """Every cycle exited 0 without a traceback; at least one signal came during a call."""
    assert all(cycle.served for cycle in cycles), [c.describe() for c in cycles]
    unclean = [cycle.describe() for cycle in cycles if not cycle.clean]
    assert not unclean, '\n'.join(unclean)
    during = [cycle for cycle in cycles if cycle.during_call]
    assert during, [c.describe() for c in cycles]
    # The stop keeps the participant until the reply is out (doc/design.md section 16).
    lost = [cycle.describe() for cycle in during if not cycle.answered]
    assert not lost, '\n'.join(lost)


def test_venv_node_stops_cleanly(ros_client, ros_env, tmp_path):
    rng = np.random.default_rng(13)
    choices = FIXED + [draw(rng) for _ in range(2)]
    script = venv_script('planner_node')
    cycles = stop_cycles(ros_client, lambda ns: [script] + node_arguments(ns), ros_env,
                         tmp_path, choices, seed=13)
    assert_clean(cycles)
