"""The clearance certificate: exact closed form, and its pruning for many robots drops nothing."""

import numpy as np
from punctured_planner.core import certificate, plan, Workspace
from punctured_planner.core.certificate import certify, segment_minimum
import pytest


def test_segment_minimum_closed_form():
    """Crossing, receding, approaching-but-stopping and motionless relative motions."""
    start = np.array([[-1.0, 0.5], [1.0, 0.0], [3.0, 0.0], [0.0, 2.0]])
    velocity = np.array([[2.0, 0.0], [1.0, 0.0], [-1.0, 0.0], [0.0, 0.0]])
    squared, t = segment_minimum(start, velocity)
    assert np.allclose(np.sqrt(squared), [0.5, 1.0, 2.0, 2.0])
    assert np.allclose(t, [0.5, 0.0, 1.0, 0.0])


def test_tiny_clearance_is_exact_not_cancelled():
    """Two robots passing 1e-9 apart far from the origin: no catastrophic cancellation."""
    times = np.array([0.0, 1.0])
    positions = np.array([[[1e3, 1e-9], [1e3 + 1.0, 0.0]], [[1e3 + 2.0, 1e-9], [1e3 + 1.0, 0.0]]])
    clearance = certify(times, positions, np.zeros((0, 2)))
    assert clearance.distance == pytest.approx(1e-9, rel=1e-6)
    assert clearance.tau == 0.5


@pytest.mark.parametrize('seed, spread_out', [(0, True), (1, False), (2, True), (3, False)])
def test_pruned_certificate_equals_all_pairs(monkeypatch, seed, spread_out):
    """For many robots the sweep-and-prune path returns exactly the all-pairs minimum."""
    rng = np.random.default_rng(seed)
    k, n, d = 150, 3, 2 + seed % 2
    scale = 20.0 if spread_out else 2.0
    configurations = rng.uniform(-scale, scale, size=(n, k, d)).round(1 if spread_out else 3)
    configurations[:, : k // 3, 0] = configurations[:, :1, 0]
    keep = [np.unique(c, axis=0, return_index=True)[1] for c in configurations]
    size = min(len(i) for i in keep)
    configurations = np.stack([c[np.sort(i)[:size]] for c, i in zip(configurations, keep)])
    obstacles = np.c_[np.arange(3.0) * 7 + 0.05, np.full((3, d - 1), 0.3)]
    for variant in ('paper', 'spread'):
        p = plan(Workspace(obstacles, variant=variant), configurations, certify=False)
        pruned = certify(p.times, p.positions, obstacles)
        monkeypatch.setattr(certificate, '_DIRECT_ROBOTS', 10 ** 6)
        direct = certify(p.times, p.positions, obstacles)
        monkeypatch.undo()
        assert pruned.distance == direct.distance
        assert pruned.kind == direct.kind
