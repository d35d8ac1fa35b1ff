"""The clearance certificate: exact closed form, and its pruning for many robots drops nothing."""

import numpy as np
from punctured_planner.core import certificate, ErrorCode, plan, PlanningError, Workspace
from punctured_planner.core.certificate import certify, segment_minimum
import pytest


def test_segment_minimum_closed_form():
    """Crossing, receding, approaching-but-stopping and motionless relative motions."""
    start = np.array([[-1.0, 0.5], [1.0, 0.0], [3.0, 0.0], [0.0, 2.0]])
    velocity = np.array([[2.0, 0.0], [1.0, 0.0], [-1.0, 0.0], [0.0, 0.0]])
    squared, t = segment_minimum(start.T, velocity.T)
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
        monkeypatch.setattr(certificate, '_RUN_FILTER_ENTRIES', 10 ** 18)
        direct = certify(p.times, p.positions, obstacles)
        monkeypatch.undo()
        assert pruned.distance == direct.distance
        assert pruned.kind == direct.kind


@pytest.mark.parametrize('lattice', [False, True])
def test_the_run_filter_keeps_both_certificates_of_bodies(monkeypatch, lattice):
    """Every pair on every leg, or only where the runs' boxes allow: the same Clearances."""
    rng = np.random.default_rng(7)
    k, v = 40, 120
    if lattice:  # many exact ties: robots on a grid, moving in lockstep along rows
        grid = np.stack(np.meshgrid(np.arange(8.0), np.arange(5.0)), -1).reshape(k, 2)
        positions = grid + np.linspace(0.0, 3.0, v)[:, None, None] * [1.0, 0.0]
    else:
        positions = np.cumsum(rng.normal(0.0, 0.3, (v, k, 2)), axis=0)
    obstacles = rng.uniform(-3, 8, (3, 2))
    radii = np.concatenate([np.full(k, 0.2), [0.1, 0.3, 0.5]])
    times = np.linspace(0.0, 1.0, v)
    results = []
    for entries in (0, 10 ** 18):
        monkeypatch.setattr(certificate, '_RUN_FILTER_ENTRIES', entries)
        results.append(certificate.certify_bodies(times, positions, obstacles, radii))
    assert results[0] == results[1]


def test_far_from_the_origin_tiny_gaps_are_refused_not_trusted():
    """At 1e9 a projection gap of 1e-6 is below the resolution: refused, never a silent touch."""
    obstacles = [[1e9, 0.0], [1e9 + 10.0, 0.0]]
    request = [[[1e9 + 1.0, 2.0], [1e9 + 1.0 + 1e-6, -3.0]], [[1e9 + 4.0, 1.0], [1e9 + 6.0, 1.0]]]
    with pytest.raises(PlanningError) as error:
        plan(Workspace(obstacles), request)
    assert error.value.code == ErrorCode.CLEARANCE_BELOW_REQUIRED
    assert 'numerical resolution' in str(error.value) and 'robots 0 and 1' in str(error.value)
    spread_plan = plan(Workspace(obstacles, variant='spread'), request)
    assert spread_plan.min_clearance >= 0.5 * (1 - 1e-9)


@pytest.mark.parametrize('coordinate', [1e16, -1e300])
def test_coordinates_beyond_the_supported_range_are_refused(coordinate):
    """Squared distances must not overflow: coordinates beyond +-1e15 are INVALID_REQUEST."""
    with pytest.raises(PlanningError) as error:
        plan(Workspace([], dimension=2), [[[0.0, 0.0], [1.0, 1.0]], [[coordinate, 0.0], [2, 2]]])
    assert error.value.code == ErrorCode.INVALID_REQUEST
    assert 'configuration 1, robot 0' in str(error.value)


def test_tiny_but_resolvable_coordinates_plan_and_certify():
    """Robots 1e-9 apart near the origin, lanes scaled down: certified, positive clearance."""
    ws = Workspace([[0.0, 0.0]], lane_spacing=1e-9, min_spacing=1e-10, variant='spread')
    p = plan(ws, [[[1e-9, 1e-9], [2e-9, 1e-9]], [[-1e-9, -1e-9], [3e-9, 2e-9]]])
    assert 0 < p.min_clearance <= 1e-9
    assert p.min_clearance >= p.clearance_bound * (1 - 1e-9)


@pytest.mark.parametrize('robots', [3, 70])
def test_one_pass_gives_both_certificates_of_bodies(robots):
    """certify_bodies equals certify without and with radii (direct and pruned paths)."""
    rng = np.random.default_rng(robots)
    positions = rng.uniform(-5, 5, (6, robots, 2))
    obstacles = rng.uniform(-5, 5, (4, 2))
    radii = np.concatenate([np.full(robots, 0.05), rng.uniform(0.0, 0.5, 4)])
    times = np.linspace(0.0, 1.0, 6)
    both = certificate.certify_bodies(times, positions, obstacles, radii)
    assert both.clearance == certify(times, positions, obstacles)
    assert both.gap == certify(times, positions, obstacles, radii)
    assert both.gap.distance < both.clearance.distance


def test_a_gap_below_the_required_clearance_is_named_before_the_resolution():
    """
    A required_clearance the plan misses by overlapping bodies is refused for the gap.

    make run's request with required_clearance 2 m: the inflated bodies break the
    discs theorem's condition, the plan takes robot 0's centre through pillar 1's
    (centre distance 0, gap -0.33 m), and the refusal blamed the numerical resolution
    of coordinates a few metres large.
    """
    workspace = Workspace([[-2.0, 0.5], [0.0, -0.5], [2.5, 0.0]], variant='discs',
                          robot_radius=0.18, obstacle_radius=0.15, required_clearance=2.0)
    request = [[[-3.0, -2.0], [-1.0, -2.5], [1.0, -2.0], [3.0, -2.5]],  # its C_1 - C_3
               [[-2.0, -1.5], [0.0, 1.5], [1.5, -1.5], [3.5, 1.0]],
               [[3.0, 3.0], [1.0, 3.5], [-1.0, 3.0], [-3.0, 3.5]]]
    with pytest.raises(PlanningError) as error:
        plan(workspace, request)
    assert error.value.code == ErrorCode.CLEARANCE_BELOW_REQUIRED
    words = str(error.value)
    assert 'surface to surface (gap), < required 2' in words, words
    assert 'resolution' not in words, words


def test_many_disc_robots_are_certified_as_every_pair_gives(monkeypatch):
    """70 disc robots (the pruned path): the surface gap of evaluating every pair."""
    rng = np.random.default_rng(1)
    positions = rng.uniform(-10, 10, (4, 70, 2))
    radii = np.full(70, 0.2)
    times = np.linspace(0.0, 1.0, 4)
    pruned = certify(times, positions, np.zeros((0, 2)), radii)
    monkeypatch.setattr(certificate, '_DIRECT_ROBOTS', 10 ** 6)
    direct = certify(times, positions, np.zeros((0, 2)), radii)
    assert pruned.distance == direct.distance


def test_a_tie_is_reported_at_its_first_leg():
    """40 robots of a grid translating in exact steps: every leg ties; the first is named."""
    grid = np.stack(np.meshgrid(np.arange(8.0), np.arange(5.0)), -1).reshape(40, 2)
    positions = grid + (0.5 * np.arange(100))[:, None, None] * np.array([1.0, 0.0])
    assert certify(np.linspace(0.0, 1.0, 100), positions, np.zeros((0, 2))).leg == 0
