"""Properties of the construction over random and degenerate inputs (hypothesis)."""

from functools import partial

from core_inputs import axis_obstacles, configuration_with_count
from core_strategies import requests
from hypothesis import assume, given, HealthCheck, settings
from hypothesis import strategies as st
import numpy as np
from punctured_planner.core import plan, Workspace
import pytest

PROPERTY = settings(max_examples=150, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
VARIANTS = st.sampled_from(['paper', 'spread'])
# The construction's own motion; the refinement's properties are test_core_refine.py's.
base = partial(plan, refine=False)


def dense_minimum(p, samples_per_leg=40):
    """Return the smallest pairwise and robot-obstacle distance over dense samples."""
    positions = p.sample(samples_per_leg).positions
    smallest = np.inf
    k = positions.shape[1]
    if k > 1:
        a, b = np.triu_indices(k, 1)
        smallest = np.linalg.norm(positions[:, a] - positions[:, b], axis=2).min()
    obstacles = p.workspace.obstacles
    if len(obstacles):
        gaps = positions[:, :, None, :] - obstacles[None, None]
        smallest = min(smallest, np.linalg.norm(gaps, axis=3).min())
    return smallest


@PROPERTY
@given(requests(), VARIANTS)
def test_waypoints_are_the_input_bit_for_bit(request, variant):
    """The motion passes through every configuration at its waypoint, exactly."""
    obstacles, configurations, _ = request
    p = base(Workspace(obstacles, dimension=obstacles.shape[1], variant=variant), configurations)
    n = len(configurations)
    assert np.array_equal(p.positions[p.waypoint_indices], configurations)
    tau = np.arange(n) / (n - 1)
    assert np.array_equal(p.times[p.waypoint_indices], tau)
    assert np.array_equal(p.position(tau), configurations)
    assert np.all(np.diff(p.times) > 0)


@PROPERTY
@given(requests(), VARIANTS)
def test_certified_clearance_is_positive_and_agrees_with_dense_check(request, variant):
    """Certificate > 0, never above a dense sample, and reached where it says."""
    obstacles, configurations, _ = request
    p = base(Workspace(obstacles, dimension=obstacles.shape[1], variant=variant), configurations)
    clearance = p.clearance
    if clearance.kind == 'none':
        assert len(obstacles) == 0 and configurations.shape[1] == 1
        return
    assert clearance.distance > 0
    assert dense_minimum(p) >= clearance.distance * (1 - 1e-12)
    at = p.position(clearance.tau)
    a, b = clearance.indices
    other = at[b] if clearance.kind == 'robots' else obstacles[b]
    assert np.linalg.norm(at[a] - other) == pytest.approx(clearance.distance, rel=1e-9, abs=1e-12)


@PROPERTY
@given(requests(), VARIANTS)
def test_domain_is_the_sum_of_projection_counts(request, variant):
    """The domain l = cp(C_1) + ... + cp(C_n), inside its range; index and count follow."""
    obstacles, configurations, mode = request
    ws = Workspace(obstacles, dimension=obstacles.shape[1], variant=variant)
    p = base(ws, configurations)
    n, k, _ = configurations.shape
    r = len(obstacles)
    projections = ws.frame.project(configurations)
    counts = np.array([np.unique(np.r_[row, ws.obstacle_projections]).size for row in projections])
    assert p.projection_counts.tolist() == counts.tolist()
    assert p.domain == counts.sum()
    assert n * max(r, 1) <= p.domain <= n * (k + r)
    assert p.domain_index == p.domain - n * max(r, 1)
    assert p.domain_count == (n * k + 1 if r else n * (k - 1) + 1)
    if mode == 'lowest':
        assert p.domain == n * max(r, 1)


@PROPERTY
@given(requests(), VARIANTS)
def test_determinism_bit_for_bit(request, variant):
    """The same input gives the same plan, even through a fresh workspace."""
    obstacles, configurations, _ = request
    first = base(Workspace(obstacles, dimension=obstacles.shape[1], variant=variant),
                 configurations)
    second = base(Workspace(obstacles.copy(), dimension=obstacles.shape[1], variant=variant),
                  configurations.copy())
    assert np.array_equal(first.times, second.times)
    assert np.array_equal(first.positions, second.positions)
    assert first.clearance == second.clearance


def perturb_within_domain(rng, configurations, obstacles, size):
    """Move robots by at most `size` keeping every projection pattern (frame = axes)."""
    perturbed = configurations + rng.uniform(-size, size, configurations.shape) / 2
    for m, configuration in enumerate(configurations):
        values = np.unique(configuration[:, 0])
        shifts = rng.uniform(-size, size, values.size) / 2
        shifts[np.isin(values, obstacles[:, 0])] = 0.0
        group = np.searchsorted(values, configuration[:, 0])
        perturbed[m, :, 0] = configuration[:, 0] + shifts[group]
    return perturbed


# Lipschitz constant of the plan inside a domain, max|breakpoint change| over
# max|robot perturbation|: at most 1 + 2 (k + r - 1) / (k + r) < 3, since eps
# moves by at most 2 / (k + r) per unit and D shifts by (j - 1) eps; S adds
# nothing (isotonic regression and clipping are monotone and commute with
# shifts, so they do not expand the sup norm). Measured worst over 1,500
# hypothesis inputs, both variants: 1.77.
CONTINUITY_CONSTANT = 3.0


@PROPERTY
@given(requests(), VARIANTS, st.integers(0, 2 ** 32 - 1))
def test_continuity_inside_a_domain(request, variant, seed):
    """A perturbation that keeps every projection pattern moves breakpoints proportionally."""
    obstacles, configurations, _ = request
    d = obstacles.shape[1]
    ws = Workspace(obstacles, dimension=d, variant=variant)
    size = 1e-7
    perturbed = perturb_within_domain(np.random.default_rng(seed), configurations, obstacles,
                                      size)
    before, after = base(ws, configurations), base(ws, perturbed)
    assert before.projection_counts.tolist() == after.projection_counts.tolist()
    moved = np.linalg.norm(perturbed - configurations, axis=2).max()
    change = np.linalg.norm(after.positions - before.positions, axis=2).max()
    assert change <= CONTINUITY_CONSTANT * moved * (1 + 1e-6) + 1e-12


@pytest.mark.parametrize('r, k, n, d', [(0, 3, 2, 2), (1, 2, 3, 3), (2, 3, 2, 2),
                                        (3, 4, 3, 4), (5, 2, 2, 2)])
def test_every_domain_value_is_hit(r, k, n, d):
    """Across many random inputs every l in n max(r, 1) .. n (k + r) occurs."""
    rng = np.random.default_rng(r * 100 + k * 10 + n)
    obstacles = axis_obstacles(rng, r, d)
    ws = Workspace(obstacles, dimension=d)
    low, high = n * max(r, 1), n * (k + r)
    hit = set()
    for _ in range(60 * (high - low + 1)):
        targets = rng.integers(max(r, 1), k + r + 1, size=n)
        request = [configuration_with_count(rng, obstacles, k, t) for t in targets]
        p = base(ws, request)
        assert p.projection_counts.tolist() == targets.tolist()
        hit.add(p.domain)
    assert hit == set(range(low, high + 1))


@PROPERTY
@given(requests(), VARIANTS, st.booleans(),
       st.lists(st.integers(-1000, 1000), min_size=4, max_size=4))
def test_a_translated_request_gets_the_motion_translated(request, variant, refine, shift):
    """
    Moving obstacles and robots by v moves the motion by v: the axis follows the obstacles.

    With the frame's origin at 0, obstacles and robots near y = 100 made every robot
    travel to y = 0 and back (doc/design.md section 4). v is whole, so grid inputs move
    exactly (float ones up to rounding, which the tolerance covers); the frame is an
    axis frame, whose projections v moves exactly too.
    """
    obstacles, configurations, _ = request
    d = obstacles.shape[1]
    assume(len(obstacles) > 0)  # without them nothing fixes the axis: it stays through 0
    v = np.array(shift[:d], dtype=float)
    moved = Workspace(obstacles + v, variant=variant)
    # Not a moment-curve frame: moving one could make equal projections unequal.
    assume(np.count_nonzero(moved.frame.e1) == 1)
    p = plan(Workspace(obstacles, variant=variant), configurations, refine=refine)
    q = plan(moved, configurations + v, refine=refine)
    assert q.domain_index == p.domain_index
    assert np.array_equal(q.times, p.times)
    scale = 1.0 + np.abs(p.positions).max()
    assert np.allclose(q.positions - v, p.positions, rtol=0, atol=1e-9 * scale * 1000)
