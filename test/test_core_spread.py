"""The 'spread' variant: same domains as the paper's, with a clearance a robot can rely on."""

from functools import partial

from core_strategies import requests
from hypothesis import given, HealthCheck, settings
import numpy as np
from punctured_planner.core import deformations
from punctured_planner.core import ErrorCode, plan, PlanningError, Workspace
from punctured_planner.core.deformations import pool_adjacent_violators, spread
import pytest

# These tests check the construction itself (doc/design.md sections 3, 5), not its
# refinement (section 14).
base = partial(plan, refine=False)

PROPERTY = settings(max_examples=150, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])


def test_hand_example_paper_touches_spread_keeps_its_spacing():
    """Far apart robots with nearly equal projections: paper 1e-7 on the axis, spread 0.5."""
    obstacles = [[0.0, 0.0], [3.0, 0.0]]
    request = [[[1.5, 5.0], [1.5 + 1e-7, -5.0]], [[-2.0, 1.0], [5.0, -1.0]]]
    paper = base(Workspace(obstacles), request)
    spread_plan = base(Workspace(obstacles, variant='spread', min_spacing=0.5), request)
    assert paper.min_clearance < 1e-6
    assert spread_plan.clearance_bound == 0.5
    assert spread_plan.min_clearance >= spread_plan.clearance_bound
    assert spread_plan.domain == paper.domain and spread_plan.domain_index == paper.domain_index


def test_short_interval_spaces_evenly_what_fits():
    """Three robots between obstacles 1 apart: spacing 1/4, evenly, order kept."""
    projections = np.array([[0.1, 0.11, 0.12, 5.0]])
    result, used = spread(projections, np.array([0.0, 1.0]), 0.5)
    assert np.allclose(result[0, :3], [0.25, 0.5, 0.75])
    assert np.allclose(used[0], [0.25, 0.25, 0.25, 0.5])
    assert result[0, 3] == 5.0


def test_spread_moves_only_as_far_as_the_spacing_requires():
    """Robots already spaced stay put; a crowded pair moves apart symmetrically."""
    result, _ = spread(np.array([[-3.0, 2.0, 2.1, 9.0]]), np.array([0.0, 5.0]), 0.5)
    assert result[0, 0] == -3.0 and result[0, 3] == 9.0
    assert np.allclose(result[0, 1:3], [1.8, 2.3])


def test_lanes_start_one_spacing_beyond_the_obstacles():
    """Spread lanes: lane_spacing apart, the first lane_spacing above the highest obstacle."""
    ws = Workspace([[0.0, 2.0], [1.0, -1.0]], variant='spread', lane_spacing=0.75)
    p = base(ws, [[[0.5, 0.5], [2.0, 0.0]], [[3.0, 1.0], [-1.0, 1.0]]])
    # The lanes are e2 offsets from the axis; at y = 2 + 0.75 and 2 + 1.5 in the plane.
    assert np.allclose(p.lane_segments()[:, :, 1], [[2.75, 2.75], [3.5, 3.5]])


@PROPERTY
@given(requests())
def test_same_domain_as_the_paper_variant(request):
    """Both variants give the same domain and domain index for every input."""
    obstacles, configurations, _ = request
    d = obstacles.shape[1]
    paper = base(Workspace(obstacles, dimension=d), configurations, certify=False)
    spread_plan = base(Workspace(obstacles, dimension=d, variant='spread'), configurations,
                       certify=False)
    assert spread_plan.projection_counts.tolist() == paper.projection_counts.tolist()
    assert (spread_plan.domain, spread_plan.domain_index) == (paper.domain, paper.domain_index)


@PROPERTY
@given(requests())
def test_certified_clearance_never_below_the_bound(request):
    """min(s / (k + r) where D runs, s elsewhere, g, lane_spacing) bounds the certificate."""
    obstacles, configurations, _ = request
    d = obstacles.shape[1]
    p = base(Workspace(obstacles, dimension=d, variant='spread', min_spacing=0.5,
                       lane_spacing=1.0), configurations)
    if p.clearance.kind == 'none':
        return
    assert p.clearance_bound > 0
    assert p.min_clearance >= p.clearance_bound * (1 - 1e-12)


@PROPERTY
@given(requests())
def test_spread_configurations_keep_the_bound_on_the_axis(request):
    """After S every robot's projection is at least the bound from every other point's."""
    obstacles, configurations, _ = request
    d = obstacles.shape[1]
    p = base(Workspace(obstacles, dimension=d, variant='spread', min_spacing=0.5),
             configurations, certify=False)
    legs = int(p.waypoint_indices[1])
    spread_stages = [v for v in range(len(p.positions)) if v % legs in (2, legs - 2)]
    projections = p.frame.project(p.positions[spread_stages])
    points = np.concatenate([projections, np.broadcast_to(
        p.workspace.obstacle_projections, (len(spread_stages), len(obstacles)))], axis=1)
    gaps = np.diff(np.sort(points, axis=1), axis=1)
    if gaps.size:
        assert gaps.min() >= p.clearance_bound * (1 - 1e-9)


def test_required_clearance_refuses_with_pair_leg_and_distance():
    """A plan below required_clearance: CLEARANCE_BELOW_REQUIRED naming pair, leg, distance."""
    obstacles = [[0.0, 0.0], [1.0, 0.0]]
    request = [[[0.4, 5.0], [0.6, -5.0]], [[-2.0, 1.0], [5.0, -1.0]]]
    ws = Workspace(obstacles, variant='spread', min_spacing=0.5, required_clearance=0.4)
    with pytest.raises(PlanningError) as error:
        base(ws, request)
    assert error.value.code == ErrorCode.CLEARANCE_BELOW_REQUIRED
    message = str(error.value)
    assert 'robots 0 and 1' in message or 'robot 0 and obstacle' in message
    assert 'leg' in message and '0.333333 < required 0.4' in message
    relaxed = Workspace(obstacles, variant='spread', min_spacing=0.5, required_clearance=0.3)
    assert base(relaxed, request).min_clearance == pytest.approx(1 / 3)


def test_python_isotonic_fit_is_scipys_bit_for_bit():
    """pool_adjacent_violators (small blocks, SciPy < 1.12) gives SciPy's fit to the bit."""
    from scipy.optimize import isotonic_regression
    rng = np.random.default_rng(5)
    for size in (1, 2, 3, 7, 40, 100):
        for values in (rng.normal(size=size).round(2), rng.integers(0, 3, size) * 0.1,
                       rng.normal(size=size) * 1e3 - np.arange(size) * 7.0):
            fit = np.array(pool_adjacent_violators(values))
            assert np.array_equal(fit.view(np.int64), isotonic_regression(values).x.view(np.int64))


def test_spread_without_scipy_isotonic_regression(monkeypatch):
    """With SciPy's isotonic regression missing, S uses the Python fit and spreads the same."""
    rng = np.random.default_rng(2)
    # 50 robots crowded into (0, 1): one block longer than those fitted in Python anyway
    projections = np.concatenate([rng.uniform(0.1, 0.9, 50), [2.2, 2.1001, 5.0]])[None]
    expected, _ = spread(np.sort(projections), np.array([0.0, 1.0, 3.0]), 0.5)
    monkeypatch.setattr(deformations, 'isotonic_regression', None)
    fallback, _ = spread(np.sort(projections), np.array([0.0, 1.0, 3.0]), 0.5)
    assert np.array_equal(fallback, expected)
