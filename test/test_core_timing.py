"""Time parameterisation: the fastest robot of each leg at max_speed; breakpoints kept."""

import numpy as np
from punctured_planner.core import plan, Workspace
import pytest

REQUEST = [[[0.5, 1.0], [0.5, -2.0]], [[3.0, 0.5], [-1.0, 2.0]]]


def test_each_leg_takes_its_fastest_robot_at_max_speed():
    """Leg durations are the largest displacement over max_speed."""
    p = plan(Workspace([[0.0, 0.0], [1.0, 0.0]]), REQUEST, refine=False)
    stamps = p.stamps(2.0)
    steps = np.linalg.norm(np.diff(p.positions, axis=0), axis=2).max(axis=1)
    assert np.allclose(np.diff(stamps), steps / 2.0)
    assert stamps[0] == 0.0 and p.duration(2.0) == stamps[-1]
    # The slide: robot 1 travels 2.25 along its lane, robot 2 only 1.875.
    assert np.isclose(stamps[4] - stamps[3], 2.25 / 2.0)


def test_resampling_keeps_every_breakpoint_bit_for_bit():
    """Extra samples land inside legs; breakpoints and their stamps are unchanged."""
    p = plan(Workspace([[0.0, 0.0], [1.0, 0.0]]), REQUEST, refine=False)
    samples = p.sample(3, max_speed=1.5)
    # The last leg (D^-1 of C_2, in the top stratum) is the only one where nothing moves.
    assert samples.positions.shape[0] == 4 * (p.times.size - 2) + 1
    assert np.array_equal(samples.positions[::4], p.positions[:-1])
    assert np.array_equal(samples.values[::4], p.stamps(1.5)[:-1])
    by_tau = p.sample(3)
    assert np.allclose(by_tau.positions, p.position(by_tau.values))
    assert by_tau.positions.shape[0] == 4 * (p.times.size - 1) + 1


@pytest.mark.parametrize('samples_per_leg', [0, 2])
@pytest.mark.parametrize('variant', ['paper', 'spread'])
def test_no_pose_twice_and_every_configuration_exact(samples_per_leg, variant):
    """Stamps strictly increase (no 0/0 speed); C_m sits exactly at waypoints[m] (refined)."""
    obstacles = [[-2.0, 0.5], [0.0, -0.5], [2.5, 0.0]]
    request = np.array([[[-3.0, -2.0], [-1.0, -2.5], [1.0, -2.0], [3.0, -2.5]],
                        [[-2.0, -1.5], [0.0, 1.5], [1.5, -1.5], [3.5, 1.0]],
                        [[3.0, 3.0], [1.0, 3.5], [-1.0, 3.0], [-3.0, 3.5]]])
    p = plan(Workspace(obstacles, variant=variant), request)
    samples = p.sample(samples_per_leg, max_speed=0.5)
    assert np.all(np.diff(samples.values) > 0)
    assert np.array_equal(samples.positions[samples.waypoints], request)
    steps = np.abs(np.diff(samples.positions, axis=0)).max(axis=(1, 2))
    assert np.all(steps > 0)
    # Nothing is lost: the motion through the samples is the plan's motion.
    taus = np.interp(samples.values, p.stamps(0.5), p.times)
    assert np.allclose(samples.positions, p.position(taus))
