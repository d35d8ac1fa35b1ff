"""
The refinement (punctured_planner/core/refine.py, doc/design.md section 14).

Over random and degenerate requests (shared projections, robots on a pillar's
projection, tight lattices at exactly the discs condition) and every variant:
the refined plan's exact gap never falls below its margin, the margin is the
construction's own exact gap (up to the rounding of the same motion evaluated
at more breakpoints), the configurations are breakpoints bit for bit, the
domain is the construction's, the result is deterministic, and a 1e-7 change
inside a domain moves the motion, as a function of normalised time, by at most
100 times that.
"""

from core_strategies import lattice_requests, requests, same_cells
from hypothesis import assume, example, given, HealthCheck, settings, strategies as st
import numpy as np
from punctured_planner.core import ErrorCode, plan, PlanningError, Workspace
from punctured_planner.core.certificate import certify_bodies, RELATIVE_RESOLUTION
from punctured_planner.core.pairs import point_radii
from punctured_planner.core.plan import Plan
from punctured_planner.core.refine import Constraints, refine
from punctured_planner.core.walls import smallest_leg_slack
import pytest

PROPERTY = settings(max_examples=80, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
VARIANTS = st.sampled_from(['paper', 'spread', 'discs'])
RADII = st.sampled_from([0.0, 0.05])
# The continuity target: motion change / input change inside a domain.
CONTINUITY = 100.0
# The change of input the continuity tests make, per coordinate.
NUDGE = 1e-7
# Where the continuity tests compare two motions: normalised time.
TAU = np.linspace(0.0, 1.0, 3001)


def workspace_for(obstacles, variant, radius):
    """Return the Workspace of a generated request; radii only for 'discs'."""
    radius = radius if variant == 'discs' else 0.0
    return Workspace(obstacles, dimension=obstacles.shape[1], variant=variant,
                     robot_radius=radius, obstacle_radius=radius)


def nudged(configurations, seed):
    """Return configurations with every coordinate moved by at most NUDGE, from seed."""
    return configurations + np.random.default_rng(seed).uniform(-NUDGE, NUDGE,
                                                                configurations.shape)


def refined(workspace, configurations):
    """Return the refined plan, or reject the example if the input is refused."""
    try:
        return plan(workspace, configurations, certify=False)
    except PlanningError:
        assume(False)
        raise


def check_refinement(p):
    """Assert the refinement's guarantees on one refined plan."""
    raw = p.raw
    assert p.min_gap >= p.margin, (p.min_gap, p.margin, p.gap)
    assert p.margin <= raw.min_gap
    assert p.margin >= raw.min_gap - p.clearance.resolution
    assert np.array_equal(p.positions[p.waypoint_indices], p.configurations)
    assert np.array_equal(p.times[p.waypoint_indices], raw.times[raw.waypoint_indices])
    assert np.all(np.diff(p.times) >= 0)
    assert np.array_equal(p.projection_counts, raw.projection_counts)
    assert (p.domain, p.domain_index, p.domain_count, p.sequential_complexity) == (
        raw.domain, raw.domain_index, raw.domain_count, raw.sequential_complexity)
    assert len(p.leg_names) == p.times.size - 1


@PROPERTY
@given(requests(max_robots=6, max_obstacles=4, max_configurations=3), VARIANTS, RADII)
def test_gap_waypoints_domain_on_random_and_degenerate_requests(request, variant, radius):
    """Every guarantee on grids, shared columns, the lowest stratum and floats."""
    obstacles, configurations, _ = request
    p = refined(workspace_for(obstacles, variant, radius), configurations)
    check_refinement(p)
    again = refined(workspace_for(obstacles, variant, radius), configurations)
    assert np.array_equal(again.positions, p.positions)
    assert np.array_equal(again.times, p.times)


@PROPERTY
@given(lattice_requests())
def test_gap_waypoints_domain_on_tight_lattices(case):
    """At exactly the discs condition many pairs have no slack: they must not move."""
    workspace, configurations = case
    check_refinement(refined(workspace, configurations))


@PROPERTY
@given(requests(max_robots=5, max_obstacles=4, max_configurations=3, modes=('float',)),
       VARIANTS, RADII, st.integers(0, 2 ** 31))
def test_a_small_change_inside_a_domain_moves_the_refined_motion_little(request, variant,
                                                                        radius, seed):
    """Continuity, measured: a 1e-7 change that keeps every cp moves the motion <= 100x."""
    obstacles, configurations, _ = request
    assume(np.all(np.abs(configurations) < 1e3))
    workspace = workspace_for(obstacles, variant, radius)
    moved = nudged(configurations, seed)
    before, after = refined(workspace, configurations), refined(workspace, moved)
    assume(same_cells(workspace, configurations, moved))
    change = np.abs(before.position(TAU) - after.position(TAU)).max()
    assert change <= CONTINUITY * NUDGE, change / NUDGE


def test_the_refined_motion_is_shorter_and_its_stamps_work():
    """A realistic discs fleet: much shorter than the construction, timed and sampled as it."""
    rng = np.random.default_rng(3)
    pillars = np.array([[1.0, 1.0], [3.0, 2.5], [5.0, 1.2]])
    starts = np.stack([np.linspace(0.2, 5.8, 6), np.full(6, -0.5)], axis=1)
    goals = starts[rng.permutation(6)] + [0.0, 4.0]
    workspace = Workspace(pillars, variant='discs', robot_radius=0.2, obstacle_radius=0.15)
    p = plan(workspace, [starts, goals, starts])
    raw = plan(workspace, [starts, goals, starts], refine=False)

    def length(motion):
        return np.linalg.norm(np.diff(motion.positions, axis=0), axis=2).sum()

    assert length(p) < 0.9 * length(raw)
    assert p.min_gap >= p.margin > 0
    samples = p.sample(2, max_speed=0.5)
    assert np.all(np.diff(samples.values) > 0)
    assert np.array_equal(samples.positions[samples.waypoints], p.configurations)
    assert p.duration(0.5) < raw.duration(0.5)


def test_required_clearance_is_judged_on_the_refined_plan():
    """A required gap above what the refined plan keeps is refused, naming the closest pair."""
    pillars = np.array([[0.0, 0.0]])
    request = [[[-2.0, -1.0], [2.0, -1.0]], [[2.0, 1.5], [-2.0, 1.5]]]
    loose = Workspace(pillars, variant='discs', robot_radius=0.2, obstacle_radius=0.1)
    p = plan(loose, request)
    strict = Workspace(pillars, variant='discs', robot_radius=0.2, obstacle_radius=0.1,
                       required_clearance=3.7)
    with pytest.raises(PlanningError) as caught:
        plan(strict, request)
    assert caught.value.code == ErrorCode.CLEARANCE_BELOW_REQUIRED
    assert p.min_gap >= p.margin
    met = Workspace(pillars, variant='discs', robot_radius=0.2, obstacle_radius=0.1,
                    required_clearance=0.3)
    assert plan(met, request).min_gap >= 0.3


def refined_with_walls(raw, bounds):
    """Return raw's Plan refined by core.refine with walls at bounds (None for none)."""
    workspace = raw.workspace
    k = raw.positions.shape[1]
    radii = point_radii(k, workspace.robot_radius, workspace.obstacle_radii)
    rounding = RELATIVE_RESOLUTION * float(np.abs(raw.positions).max(initial=1.0))
    return Plan.refined(raw, refine(raw.times, raw.positions, raw.waypoint_indices,
                                    Constraints(workspace.obstacles, radii, raw.min_gap,
                                                rounding, bounds)))


def wall_bounds(raw, share, seed):
    """Return walls around the configurations and pillars, share of their side beyond them."""
    d = raw.positions.shape[2]
    points = np.concatenate([raw.configurations.reshape(-1, d), raw.workspace.obstacles])
    low, high = points.min(axis=0), points.max(axis=0)
    side = max(float((high - low).max()), 1.0)
    spare = share * side * np.random.default_rng(seed).uniform(0.5, 1.0, (d, 2))
    keep = raw.workspace.robot_radius + raw.workspace.obstacle_radii.max(initial=0.0)
    return np.stack([low - keep - spare[:, 0], high + keep + spare[:, 1]], axis=1)


@PROPERTY
@given(requests(max_robots=6, max_obstacles=4, max_configurations=3), VARIANTS, RADII,
       st.sampled_from([0.0, 0.05, 0.3, 3.0]), st.integers(0, 2 ** 31))
# A robot exactly at a wall on a leg along it: a knot inserted there by (1 - f) a + f a
# rounded an ulp beyond the wall (found with 1,500 examples).
@example((np.array([[0.0, 0.0]]), np.array([[[2.210938, 0.0]], [[2.210938, 1.0]]]), 'float'),
         'spread', 0.0, 0.0, 0)
def test_walls_never_take_a_robot_farther_out_and_keep_every_guarantee(request, variant,
                                                                       radius, share, seed):
    """Beyond a wall no farther than the construction; inside stays inside; gaps kept."""
    obstacles, configurations, _ = request
    assume(np.all(np.abs(configurations) < 1e3))
    workspace = workspace_for(obstacles, variant, radius)
    try:
        raw = plan(workspace, configurations, certify=False, refine=False)
    except PlanningError:
        assume(False)
        raise
    bounds = wall_bounds(raw, share, seed)
    motion = refined_with_walls(raw, bounds)
    radius = workspace.robot_radius
    before = smallest_leg_slack(raw.positions, bounds, radius).slack
    after = smallest_leg_slack(motion.positions, bounds, radius).slack
    resolution = 1e-9 * max(1.0, float(np.abs(bounds).max()))
    assert after >= min(before, 0.0) - resolution, (before, after)
    if before >= 0:
        assert after >= 0
    assert np.array_equal(motion.positions[motion.waypoint_indices], raw.configurations)
    radii = point_radii(raw.positions.shape[1], radius, workspace.obstacle_radii)
    gap = certify_bodies(motion.times, motion.positions, workspace.obstacles, radii).gap
    assert gap.distance >= motion.margin


@PROPERTY
@given(requests(max_robots=5, max_obstacles=4, max_configurations=3, modes=('float',)),
       VARIANTS, RADII, st.integers(0, 2 ** 31))
def test_with_walls_a_small_change_inside_a_domain_moves_the_refined_motion_little(
        request, variant, radius, seed):
    """
    Continuity with walls (half the request's side beyond it): a 1e-7 change, <= 100x.

    Or at most twice what the same change does without walls: the refinement's
    own figure, which the test without walls bounds (with 12 blocks it went above
    100x on a few inputs, e.g. four collinear point robots in R^4: up to 114x).
    """
    obstacles, configurations, _ = request
    assume(np.all(np.abs(configurations) < 1e3))
    workspace = workspace_for(obstacles, variant, radius)
    moved = nudged(configurations, seed)
    try:
        before = plan(workspace, configurations, certify=False, refine=False)
        after = plan(workspace, moved, certify=False, refine=False)
    except PlanningError:
        assume(False)
        raise
    assume(same_cells(workspace, configurations, moved))
    bounds = wall_bounds(before, 0.5, seed)

    def change(walls):
        first, second = refined_with_walls(before, walls), refined_with_walls(after, walls)
        return np.abs(first.position(TAU) - second.position(TAU)).max()

    with_walls = change(bounds)
    assert with_walls <= max(CONTINUITY * NUDGE, 2.0 * change(None)), with_walls / NUDGE


def test_a_plan_inside_its_walls_is_returned_and_one_outside_refused():
    """plan() refines against the walls; a motion it cannot bring inside is refused."""
    pillars = np.array([[1.0, 1.0], [3.0, 2.5], [5.0, 1.2]])
    starts = np.stack([np.linspace(0.2, 5.8, 6), np.full(6, -0.5)], axis=1)
    goals = starts[::-1] + [0.0, 4.0]
    options = {'variant': 'discs', 'robot_radius': 0.2, 'obstacle_radius': 0.15}
    raw = plan(Workspace(pillars, **options), [starts, goals], refine=False)
    roomy = wall_bounds(raw, 0.0, 0)
    roomy[:, 0] = np.minimum(roomy[:, 0], raw.positions.min(axis=(0, 1)) - 0.3)
    roomy[:, 1] = np.maximum(roomy[:, 1], raw.positions.max(axis=(0, 1)) + 0.3)
    # Walls around the raw motion, in its frame (theirs would be another one).
    p = plan(Workspace(pillars, bounds=roomy, frame=raw.workspace.frame, **options),
             [starts, goals])
    assert smallest_leg_slack(p.positions, roomy, 0.2).slack >= 0
    # A pillar 0.8 m above the starts leaves one lane below it, and no frame has room.
    low_pillar = pillars - [[0.0, 0.7], [0.0, 0.0], [0.0, 0.0]]
    tight = np.array([[-0.05, 6.05], [-0.75, 3.45]])
    with pytest.raises(PlanningError) as caught:
        plan(Workspace(low_pillar, bounds=tight, **options), [starts, goals - [0.0, 0.3]])
    assert caught.value.code == ErrorCode.OUTSIDE_WORKSPACE
    assert 'on leg' in str(caught.value)  # refused after planning, not as input


def test_the_configurations_knots_have_no_room_to_move():
    """A knot at a configuration gets caps 0 whatever its neighbours' slack: it is held."""
    from punctured_planner.core.refine import _knot_caps, KNOTS
    caps = _knot_caps(np.ones((2 * KNOTS, 3)))
    assert np.all(caps[::KNOTS] == 0.0) and np.all(caps[1:KNOTS] == 1.0)


def _block_of(pair, pillar, lower=None, shape=(5, 2, 2)):
    """Return a refinement block whose caps are these constants: (N knots, k robots, d)."""
    from types import SimpleNamespace

    from punctured_planner.core.refine import _Block
    n, k, d = shape
    walls = None if lower is None else np.full(shape, lower)
    caps = SimpleNamespace(pair=np.full((n, k), pair), pillar=np.full((n, k), pillar),
                           lower=walls, upper=walls)
    return _Block(caps, 10.0)


def test_a_blocks_common_and_own_moves_together_keep_the_pillar_cap():
    """The lemma's premise: |common + own| <= the pillar cap, whatever the fleet wants."""
    wanted = np.zeros((2, 2, 5))
    wanted[0] = 1.0
    wanted[0, 0] += 0.5
    common, own = _block_of(10.0, 1.0).clip(wanted)
    assert np.all(np.linalg.norm(common + own, axis=0) <= 1.0 + 1e-12)


def test_a_blocks_common_and_own_moves_together_keep_the_walls_range():
    """Per axis, common + own stays within each robot's range towards each wall."""
    wanted = np.zeros((2, 2, 5))
    wanted[0] = 1.0
    common, own = _block_of(10.0, 10.0, lower=0.3).clip(wanted)
    assert np.all(common + own <= 0.3 + 1e-12) and np.all(common + own >= -0.3 - 1e-12)
