"""Time parameterisation: the fastest robot of each leg at max_speed; breakpoints kept."""

import numpy as np

from punctured_planner.core import plan, Workspace

REQUEST = [[[0.5, 1.0], [0.5, -2.0]], [[3.0, 0.5], [-1.0, 2.0]]]


def test_each_leg_takes_its_fastest_robot_at_max_speed():
    """Leg durations are the largest displacement over max_speed."""
    p = plan(Workspace([[0.0, 0.0], [1.0, 0.0]]), REQUEST)
    stamps = p.stamps(2.0)
    steps = np.linalg.norm(np.diff(p.positions, axis=0), axis=2).max(axis=1)
    assert np.allclose(np.diff(stamps), steps / 2.0)
    assert stamps[0] == 0.0 and p.duration(2.0) == stamps[-1]
    # The slide: robot 1 travels 2.25 along its lane, robot 2 only 1.875.
    assert np.isclose(stamps[4] - stamps[3], 2.25 / 2.0)


def test_resampling_keeps_every_breakpoint_bit_for_bit():
    """Extra samples land inside legs; breakpoints and their stamps are unchanged."""
    p = plan(Workspace([[0.0, 0.0], [1.0, 0.0]]), REQUEST)
    stamps, positions, is_breakpoint = p.sample(3, max_speed=1.5)
    assert positions.shape[0] == 4 * (p.times.size - 1) + 1
    assert np.array_equal(positions[is_breakpoint], p.positions)
    assert np.array_equal(stamps[is_breakpoint], p.stamps(1.5))
    taus, tau_positions, _ = p.sample(3)
    assert np.allclose(tau_positions, p.position(taus))
    assert np.all(np.diff(stamps) >= 0)
