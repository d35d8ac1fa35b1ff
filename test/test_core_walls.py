"""
Workspace bounds (core.walls): the wall slack, the input checks and the exact plan check.

Random and degenerate inputs: bodies exactly their radius from a wall (inside),
one ulp beyond it (refused, naming the body, the wall and the distance), in
2-D, 3-D and 4-D; motions whose slack is checked against dense samples; and
the priority of OUTSIDE_WORKSPACE among the other codes.
"""

from fractions import Fraction

from core_strategies import lattice_requests, requests, same_cells
from hypothesis import assume, given, HealthCheck, settings, strategies as st
import numpy as np
from punctured_planner.core import ErrorCode, plan, PlanningError, Workspace
from punctured_planner.core.discs import section
from punctured_planner.core.errors import Wall
from punctured_planner.core.plan import Plan
from punctured_planner.core.strata import projection_count, projection_gaps
from punctured_planner.core.validation import validate_configurations
from punctured_planner.core.walls import (checked_bounds, first_outside, smallest_leg_slack,
                                          wall_slack)
import pytest
from test_core_refine import CONTINUITY, NUDGE, nudged, refined_with_walls, TAU

PROPERTY = settings(max_examples=150, deadline=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
# Dyadic values: a centre placed exactly R from a wall is exactly R from it in floats too.
DYADIC = st.integers(-64, 64).map(lambda v: v / 8)
RADIUS = st.sampled_from([0.0, 0.125, 0.25, 0.5])


def box(draw, d):
    """Return (d, 2) dyadic bounds at least 4 wide on every axis."""
    lows = [draw(DYADIC) for _ in range(d)]
    widths = [draw(st.integers(32, 128)) / 8 for _ in range(d)]
    return np.array([[low, low + width] for low, width in zip(lows, widths)])


def slack_by_loops(positions, bounds, radii):
    """Return the exact slack (N, k, d, 2) one body and wall at a time, in rationals."""
    n, k, d = positions.shape
    result = np.empty((n, k, d, 2), dtype=object)
    for m in range(n):
        for i in range(k):
            for a in range(d):
                centre, radius = Fraction(positions[m, i, a]), Fraction(radii[i])
                result[m, i, a, 0] = centre - Fraction(bounds[a, 0]) - radius
                result[m, i, a, 1] = Fraction(bounds[a, 1]) - centre - radius
    return result


def matches_exactly(slack, exact):
    """Return whether every slack has the exact sign and is the exact value within 1 ulp."""
    signs = np.vectorize(lambda v: (v > 0) - (v < 0))(exact)
    close = np.vectorize(lambda v, e: abs(Fraction(v) - e) <= Fraction(abs(np.spacing(v))))
    return np.array_equal(np.sign(slack), signs) and close(slack, exact).all()


@PROPERTY
@given(st.data())
def test_wall_slack_is_each_centre_distance_to_each_wall_minus_its_radius(data):
    """Vectorised slack == the exact definition (its sign exactly), one radius or one each."""
    d = data.draw(st.integers(2, 4))
    bounds = box(data.draw, d)
    n, k = data.draw(st.integers(1, 4)), data.draw(st.integers(1, 6))
    positions = np.array(data.draw(st.lists(
        st.one_of(st.floats(-20, 20), st.sampled_from(bounds.ravel().tolist())),
        min_size=n * k * d, max_size=n * k * d))).reshape(n, k, d)
    radius = data.draw(st.one_of(RADIUS, st.floats(0, 3)))
    radii = np.array(data.draw(st.lists(RADIUS, min_size=k, max_size=k)))
    assert matches_exactly(wall_slack(positions, bounds, radius),
                           slack_by_loops(positions, bounds, np.full(k, radius)))
    exact = slack_by_loops(positions, bounds, radii)
    assert matches_exactly(wall_slack(positions, bounds, radii), exact)
    worst = first_outside(positions, bounds, radii)
    outside = [m for m in range(n) if (exact[m] < 0).any()]
    if not outside:
        assert worst is None
    else:
        assert worst.index == outside[0] and worst.slack < 0
        named = exact[worst.index, worst.body, worst.wall.axis, int(worst.wall.high)]
        # the worst to within the one rounding of the slacks
        assert named - exact[outside[0]].min() <= Fraction(abs(np.spacing(worst.slack)))


@st.composite
def touching(draw):
    """Return (bounds, configurations, m, robot, wall, R): robot exactly R from the wall."""
    d = draw(st.integers(2, 4))
    radius = draw(RADIUS)
    n, k = draw(st.integers(2, 3)), draw(st.integers(1, 5))
    # robots on distinct cells of a lattice of pitch 3, walls 2 to 4 beyond it: the
    # robot moved to a wall stays more than 2R from every other robot
    origin = np.array([draw(DYADIC) for _ in range(d)])
    cells = draw(st.lists(st.tuples(*[st.integers(0, 3)] * d), min_size=n * k,
                          max_size=n * k, unique=True))
    configurations = (origin + 3.0 * np.array(cells, dtype=float)).reshape(n, k, d)
    margins = np.array([[draw(st.integers(16, 32)) / 8 for _ in range(2)] for _ in range(d)])
    bounds = np.stack([origin - margins[:, 0], origin + 9 + margins[:, 1]], axis=1)
    m, robot = draw(st.integers(0, n - 1)), draw(st.integers(0, k - 1))
    wall = Wall(draw(st.integers(0, d - 1)), draw(st.booleans()))
    side = bounds[wall.axis, int(wall.high)]
    configurations[m, robot, wall.axis] = side - radius if wall.high else side + radius
    return bounds, configurations, m, robot, wall, radius


def nudged_out(configurations, m, robot, wall):
    """Return configurations with the robot one ulp further toward the wall."""
    result = configurations.copy()
    value = result[m, robot, wall.axis]
    result[m, robot, wall.axis] = np.nextafter(value, np.inf if wall.high else -np.inf)
    return result


@PROPERTY
@given(touching())
def test_a_robot_exactly_its_radius_from_a_wall_is_inside_one_ulp_beyond_is_refused(case):
    """Degenerate: slack exactly 0 passes; the next float out is named with its wall."""
    bounds, configurations, m, robot, wall, radius = case
    obstacles = np.zeros((0, bounds.shape[0]))
    checked = validate_configurations(configurations, obstacles, radius, None, bounds)
    assert np.array_equal(checked, configurations)
    with pytest.raises(PlanningError) as error:
        validate_configurations(nudged_out(configurations, m, robot, wall), obstacles, radius,
                                None, bounds)
    error = error.value
    assert error.code == ErrorCode.OUTSIDE_WORKSPACE
    assert (error.configuration, error.robots, error.wall) == (m, (robot,), wall)
    assert 0 < error.distance < 1e-12
    assert error.leg is None
    assert f'configuration {m}: robot {robot} is ' in str(error)
    assert f'the wall {wall.name} = ' in str(error)


@PROPERTY
@given(touching())
def test_a_pillar_exactly_its_radius_from_a_wall_is_inside_one_ulp_beyond_is_refused(case):
    """The same rule for pillars, checked with the workspace (their rho from every wall)."""
    bounds, configurations, m, robot, wall, radius = case
    pillars = configurations[m]
    radii = np.full(len(pillars), radius)
    workspace = Workspace(pillars, obstacle_radius=radii, bounds=bounds)
    assert np.array_equal(workspace.bounds, bounds)
    with pytest.raises(PlanningError) as error:
        Workspace(nudged_out(configurations, m, robot, wall)[m], obstacle_radius=radii,
                  bounds=bounds)
    error = error.value
    assert error.code == ErrorCode.OUTSIDE_WORKSPACE
    assert (error.obstacle, error.wall) == (robot, wall) and 0 < error.distance < 1e-12
    assert f'obstacle {robot} at ' in str(error) and wall.name in str(error)


@PROPERTY
@given(st.data())
def test_the_smallest_leg_slack_is_the_exact_minimum_over_the_motion(data):
    """Linear along legs: no sample of any leg is below it, and a breakpoint attains it."""
    d = data.draw(st.integers(2, 3))
    bounds = box(data.draw, d)
    vertices, k = data.draw(st.integers(2, 6)), data.draw(st.integers(1, 4))
    values = data.draw(st.lists(st.floats(-30, 30), min_size=vertices * k * d,
                                max_size=vertices * k * d))
    positions = np.array(values).reshape(vertices, k, d)
    radius = data.draw(RADIUS)
    worst = smallest_leg_slack(positions, bounds, radius)
    fractions = np.linspace(0, 1, 101)[:, None, None, None]
    legs = (1 - fractions) * positions[None, :-1] + fractions * positions[None, 1:]
    sampled = wall_slack(legs, bounds, radius)  # (101, legs, k, d, 2)
    rounding = 1e-13 * max(np.abs(positions).max(), np.abs(bounds).max())  # of the samples
    assert sampled.min() >= worst.slack - rounding
    assert worst.slack == wall_slack(positions, bounds, radius).min()
    leg_minima = sampled.min(axis=(0, 2, 3, 4))
    assert leg_minima[worst.index] <= worst.slack + rounding
    vertex_minima = wall_slack(positions, bounds, radius).min(axis=(1, 2, 3))
    legs_before = np.minimum(vertex_minima[:-1], vertex_minima[1:])[:worst.index]
    assert (legs_before > worst.slack).all()


@settings(max_examples=60, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(requests(max_robots=5, max_obstacles=3, max_configurations=3),
       st.floats(0.05, 3.0), st.sampled_from(['paper', 'spread']))
def test_a_plan_is_inside_its_bounds_or_refused_naming_where_it_leaves(
        request_, margin, variant):
    """Never a plan outside; a refusal names a robot, leg and distance that are true."""
    obstacles, configurations, _ = request_
    points = np.concatenate([configurations.reshape(-1, configurations.shape[2]), obstacles])
    bounds = np.stack([points.min(axis=0) - margin, points.max(axis=0) + margin], axis=1)
    workspace = Workspace(obstacles, dimension=configurations.shape[2], variant=variant,
                          bounds=bounds)
    try:
        result = plan(workspace, configurations)
    except PlanningError as error:
        assert error.code == ErrorCode.OUTSIDE_WORKSPACE, str(error)
        robot, axis, leg = error.robots[0], error.wall.axis, error.leg
        # The refined motion the refusal judged: the construction's, refined against the walls.
        raw = plan(Workspace(obstacles, dimension=configurations.shape[2], variant=variant,
                             frame=workspace.frame), configurations, refine=False)
        ends = refined_with_walls(raw, bounds).positions[leg:leg + 2, robot, axis]
        high, low = ends.max() - bounds[axis, 1], bounds[axis, 0] - ends.min()
        beyond = high if error.wall.high else low
        assert beyond == pytest.approx(error.distance, rel=1e-12) and beyond > 0
        assert f'robot {robot} ' in str(error) and f'on leg {leg} (' in str(error)
        return
    assert (result.positions >= bounds[:, 0]).all() and (result.positions <= bounds[:, 1]).all()


def walled_construction(walled, configurations):
    """Return the discs construction plan() refines and judges below walled's walls."""
    gaps = projection_gaps(walled.frame.project(configurations), walled.obstacle_projections)
    return Plan.discs(walled, configurations, section(configurations, walled.disc_layout),
                      projection_count(gaps))


@settings(max_examples=40, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(lattice_requests(), st.sampled_from([0.0, 0.1, 0.5, 2.0]), st.booleans())
def test_disc_plans_keep_their_radius_from_every_wall_or_are_refused(case, margin, refine):
    """Discs: the walls margin beyond the discs of the inputs and pillars; R counts."""
    workspace, configurations = case
    radius, rho = workspace.robot_radius, workspace.obstacle_radii
    low = np.minimum((configurations - radius).min(axis=(0, 1)),
                     (workspace.obstacles - rho[:, None]).min(axis=0, initial=np.inf))
    high = np.maximum((configurations + radius).max(axis=(0, 1)),
                      (workspace.obstacles + rho[:, None]).max(axis=0, initial=-np.inf))
    # margin 0 touches the outermost disc: a few ulps more, which low - R rounded away
    rounding = 1e-12 * max(1.0, float(np.abs([low, high]).max()))
    bounds = np.stack([low - margin - rounding, high + margin + rounding], axis=1)
    walled = Workspace(workspace.obstacles, variant='discs', robot_radius=radius,
                       obstacle_radius=rho, bounds=bounds)
    try:
        result = plan(walled, configurations, refine=refine)
    except PlanningError as error:
        assert error.code == ErrorCode.OUTSIDE_WORKSPACE, str(error)
        # the motion the refusal judged: the construction's (its lanes below the walls),
        # refined against the walls
        free = walled_construction(walled, configurations)
        free = (refined_with_walls(free, bounds) if refine else free).positions
        leg, robot, wall = error.leg, error.robots[0], error.wall
        ends = free[leg:leg + 2, robot, wall.axis]
        beyond = (ends.max() + radius - bounds[wall.axis, 1] if wall.high
                  else bounds[wall.axis, 0] - (ends.min() - radius))
        assert beyond == pytest.approx(error.distance, rel=1e-9, abs=1e-12) and beyond > 0
        assert f'robot_radius {radius:.6g}' in str(error)
        return
    assert (result.positions - radius >= bounds[:, 0] - 1e-12).all()
    assert (result.positions + radius <= bounds[:, 1] + 1e-12).all()


def test_bounds_are_validated_with_the_expected_and_the_given_shape():
    """Shape, finiteness and low < high: INVALID_REQUEST saying what was wrong."""
    assert checked_bounds(None, 2) is None
    cases = [([0.0, 1.0, 0.0, 1.0], 'must have shape (d, 2) = (2, 2), one [min, max] per axis; '
              'got shape (4,)'),
             ([[0, 1], [0, 1], [0, 1]], 'shape (d, 2) = (2, 2), one [min, max] per axis; got '
              'shape (3, 2)'),
             ([[0, 1], [0, np.inf]], 'bounds must be finite; the wall y_max is inf'),
             ([[0, 1], [2, 2]], 'bounds: the wall y_min = 2 must be below y_max = 2'),
             ([[3, 1], [0, 1]], 'bounds: the wall x_min = 3 must be below x_max = 1'),
             ([['a', 'b'], [0, 1]], 'bounds must be real numbers')]
    for bounds, words in cases:
        with pytest.raises(PlanningError) as error:
            Workspace(np.zeros((0, 2)), bounds=bounds)
        assert error.value.code == ErrorCode.INVALID_REQUEST
        assert words in str(error.value), str(error.value)
    with pytest.raises(PlanningError, match=r'the wall x3_min = 1 must be below x3_max = 0'):
        checked_bounds([[0, 1]] * 3 + [[1, 0]], 4)
    # the wall at fault is data too: the non-finite one, or the low of an empty axis
    for bounds, wall in (([[0, 1], [0, np.inf]], Wall(1, True)),
                         ([[0, 1], [np.nan, 1]], Wall(1, False)),
                         ([[3, 1], [0, 1]], Wall(0, False))):
        with pytest.raises(PlanningError) as error:
            checked_bounds(bounds, 2)
        assert error.value.wall == wall, (bounds, error.value.wall)


def test_outside_workspace_ranks_beside_robot_on_obstacle_and_clearance_below_required():
    """Input: after 10 and 11 (a pillar: after 9); plan: after 12; the first C_m is named."""
    bounds = np.array([[-4.0, 4.0], [-4.0, 4.0]])
    inside = np.array([[[-2.0, -2.0], [2.0, 2.0]], [[2.0, -2.0], [-2.0, 2.0]]])
    obstacles = np.array([[0.0, 0.0]])

    def code(configurations, **options):
        try:
            plan(Workspace(options.pop('obstacles', obstacles), bounds=bounds, **options),
                 configurations)
        except PlanningError as error:
            return error
        return None

    out = inside.copy()
    out[1, 0] = [5.0, 0.0]
    out[0, 1] = [-4.5, 3.0]
    first = code(out)
    assert first.code == ErrorCode.OUTSIDE_WORKSPACE and first.configuration == 0
    assert first.robots == (1,) and first.wall == Wall(0, False) and first.distance == 0.5
    coincide = out.copy()
    coincide[1, 1] = coincide[1, 0]
    assert code(coincide).code == ErrorCode.ROBOTS_COINCIDE
    on = out.copy()
    on[1, 1] = obstacles[0]
    assert code(on).code == ErrorCode.ROBOT_ON_OBSTACLE
    degenerate = np.array([[9.0, 0.0], [9.0, 0.0]])
    assert code(inside, obstacles=degenerate).code == ErrorCode.OBSTACLES_DEGENERATE
    pillar = code(inside, obstacles=np.array([[9.0, 0.0]]))
    assert pillar.code == ErrorCode.OUTSIDE_WORKSPACE and pillar.obstacle == 0
    assert pillar.distance == 5.0 and pillar.wall == Wall(0, True)
    # before any plan: an input outside comes before a clearance that would be too low
    assert code(out, required_clearance=1e9).code == ErrorCode.OUTSIDE_WORKSPACE
    # after planning: a plan below the required clearance is refused first
    tight = np.array([[-2.01, 2.01], [-2.01, 2.01]])
    raw = plan(Workspace(obstacles), inside)
    assert (raw.positions < tight[:, 0]).any() or (raw.positions > tight[:, 1]).any()
    with pytest.raises(PlanningError) as error:
        plan(Workspace(obstacles, required_clearance=1e9, bounds=tight), inside)
    assert error.value.code == ErrorCode.CLEARANCE_BELOW_REQUIRED
    with pytest.raises(PlanningError) as error:
        plan(Workspace(obstacles, bounds=tight), inside)
    assert error.value.code == ErrorCode.OUTSIDE_WORKSPACE and error.value.leg is not None
    # judged on the motion refined against the walls (which comes nearer than raw)
    judged = refined_with_walls(plan(Workspace(obstacles), inside, refine=False),
                                tight).positions
    assert error.value.distance == pytest.approx(
        max((judged - tight[:, 1]).max(), (tight[:, 0] - judged).max()))


def test_the_walls_choose_an_oblique_frame_where_every_wall_has_a_pillar_by_it():
    """
    Pillars by the middle of every wall leave room only in the corners: e2 points to one.

    Staging beyond the farthest pillar along any axis leaves the hall (each pillar
    is 0.4 m from its wall), so every axis frame is refused; the frame the walls
    choose (core.frame.choose_frame: the most area beyond the farthest pillar) is
    diagonal, and its plan stays inside.
    """
    hall = np.array([[0.0, 6.0], [0.0, 6.0]])
    pillars = np.array([[3.1, 5.6], [2.9, 0.4], [0.4, 3.2], [5.6, 2.8]])
    configurations = np.array([[[2.0, 2.5], [3.0, 3.5], [4.0, 2.5]],
                               [[4.0, 3.0], [2.0, 3.2], [3.0, 2.0]]])
    bodies = {'variant': 'discs', 'robot_radius': 0.2, 'obstacle_radius': 0.15}
    walled = Workspace(pillars, bounds=hall, **bodies)
    assert np.all(np.abs(walled.frame.e2) > 0.5), walled.frame.e2
    result = plan(walled, configurations)
    assert (result.positions - 0.2 >= hall[:, 0]).all()
    assert (result.positions + 0.2 <= hall[:, 1]).all()
    # The paper variant's domains in that frame: the discs keep them frame for frame.
    paper = plan(Workspace(pillars, frame=walled.frame), configurations, certify=False)
    assert (paper.domain, paper.domain_index) == (result.domain, result.domain_index)
    assert np.array_equal(paper.projection_counts, result.projection_counts)
    for e1, e2 in (((1, 0), (0, 1)), ((1, 0), (0, -1)), ((0, 1), (1, 0)), ((0, 1), (-1, 0))):
        axes = Workspace(pillars, bounds=hall, frame=((3.0, 3.0), e1, e2), **bodies)
        with pytest.raises(PlanningError) as refused:
            plan(axes, configurations)
        assert refused.value.code == ErrorCode.OUTSIDE_WORKSPACE, (e1, e2)


def test_the_walls_choose_the_frame_with_the_most_room_beyond_the_obstacles():
    """A pillar by the top wall: staging away from it fits where staging above cannot."""
    hall = np.array([[0.0, 6.0], [0.0, 6.0]])
    pillars = np.array([[1.0, 5.3], [3.0, 2.0], [4.5, 3.0]])
    # Two robots low in the hall trade places: their projection order reverses.
    configurations = np.array([[[2.0, 0.8], [4.0, 0.8]], [[4.0, 1.2], [2.0, 1.2]]])
    bodies = {'variant': 'discs', 'robot_radius': 0.2, 'obstacle_radius': 0.15}
    walled = Workspace(pillars, bounds=hall, **bodies)
    # Room along e2 = +y: 6 - 5.3; -y: 2.0 - 0; +x: 6 - 4.5; -x: 1.0 - 0; the most area
    # beyond the farthest pillar lies towards the corner (0, 0).
    assert walled.frame.e2[1] < 0 and walled.frame.e2[0] < 0, walled.frame.e2
    # Without walls the farthest pillar nearest the pillars' middle sets it (upwards).
    assert Workspace(pillars, **bodies).frame.e2[1] > 0
    result = plan(walled, configurations)
    assert (result.positions - 0.2 >= hall[:, 0]).all()
    assert (result.positions + 0.2 <= hall[:, 1]).all()
    axes = Workspace(pillars, bounds=hall, frame=((0.0, 0.0), (1.0, 0.0), (0.0, 1.0)),
                     **bodies)
    with pytest.raises(PlanningError) as refused:
        plan(axes, configurations)
    assert refused.value.code == ErrorCode.OUTSIDE_WORKSPACE
    assert refused.value.wall == Wall(1, True), str(refused.value)


def test_the_room_counts_the_bodies_balls_among_pillars_in_a_low_hall_stage_beside_them():
    """
    Balls among ball pillars in a hall 2 m high stage beside the pillars, not above them.

    The room is the robots' centres' (R inside the walls) beyond each pillar's
    clearance (doc/design.md section 4): counting the pillars' centres alone chose e2 =
    +z, where the bodies fill the hall's height, and the plan left by the ceiling.
    """
    hall = np.array([[-5.0, 5.0], [-5.0, 5.0], [-1.0, 1.0]])
    pillars = np.array([[0.0, 0.0, 0.0], [2.0, 1.0, 0.0], [-2.0, -1.0, 0.0]])
    row = np.array([[-3.0, -3.0, 0.0], [-1.0, -3.0, 0.0], [1.0, -3.0, 0.0], [3.0, -3.0, 0.0]])
    configurations = np.stack([row, -row])
    workspace = Workspace(pillars, bounds=hall, variant='discs', robot_radius=0.2,
                          obstacle_radius=0.3)
    assert workspace.frame.e2[2] == 0.0, workspace.frame.e2
    result = plan(workspace, configurations)
    assert (result.positions - 0.2 >= hall[:, 0]).all()
    assert (result.positions + 0.2 <= hall[:, 1]).all()
    assert result.min_gap >= 0.0


def test_equal_rooms_go_to_the_first_frame_and_rounding_separates_no_pillars():
    """
    Ties of rooms go to the axis frames; rounding alone separates no pillars.

    A tie goes to the first frame whatever qhull's rounding, and a frame that tells two
    pillars apart only by rounding is no candidate (doc/design.md section 4). Every
    direction through the one pillar at a square hall's centre halves it; e1 across the
    line of two pillars gives them projections 4e-16 apart.
    """
    bodies = {'variant': 'discs', 'robot_radius': 0.2, 'obstacle_radius': 0.15}
    for shift in (0.0, 0.1, 7.0):
        hall = np.array([[-10.0 + shift, 10.0 + shift], [-10.0, 10.0]])
        np.testing.assert_array_equal(Workspace([[shift, 0.0]], bounds=hall,
                                                **bodies).frame.e2, [0.0, 1.0])
    diagonal = Workspace([[1.0, 1.0], [3.0, 3.0]], bounds=[[-5.0, 5.0], [-5.0, 5.0]],
                         **bodies)
    assert np.diff(np.sort(diagonal.frame.project(diagonal.obstacles)))[0] > 0.1


def test_without_an_axis_frame_the_walls_still_turn_e2_towards_the_room():
    """
    Without an axis frame, e2 turns to the side of the walls with the more room.

    No axis frame separates three obstacles on two axes; the moment-curve frame's e2
    turns to the side with the more room beyond them (doc/design.md section 4).
    """
    obstacles = np.array([[0.0, 0.0], [0.0, 3.0], [3.0, 0.0]])
    for bounds, far in (([[-1.0, 4.0], [-1.0, 10.0]], 1.0), ([[-1.0, 4.0], [-8.0, 4.0]], -1.0)):
        frame = Workspace(obstacles, variant='paper', bounds=bounds).frame
        assert np.count_nonzero(frame.e1) == 2  # neither axis separates them
        assert np.sign(frame.e2[1]) == far, frame.e2


def test_below_low_walls_the_robots_pass_in_the_lanes_that_fit():
    """
    Six robots reverse their order below a wall: one slide needs six lanes, the hall has three.

    The construction then passes them in several slides of at most WallRoom.lanes lanes
    (core.discs.passing_orders, doc/design.md section 17): inside the walls, bodies
    apart, waypoints exact, the same domain as without walls in the same frame.
    """
    pillars = np.array([[1.0, 1.0], [3.0, 2.5], [5.0, 1.2]])
    starts = np.stack([np.linspace(0.2, 5.8, 6), np.full(6, -0.5)], axis=1)
    configurations = np.stack([starts, starts[::-1] + [0.0, 3.7]])
    options = {'variant': 'discs', 'robot_radius': 0.2, 'obstacle_radius': 0.15}
    bounds = np.array([[-0.3, 6.3], [-0.8, 3.8]])
    walled = Workspace(pillars, bounds=bounds, **options)
    free = Workspace(pillars, frame=walled.frame, **options)
    assert walled.disc_layout.walls.lanes == 3 and free.disc_layout.walls is None
    one_slide = plan(free, configurations, refine=False)
    assert len(one_slide.lanes) == 6
    assert smallest_leg_slack(one_slide.positions, bounds, 0.2).slack < -1.0
    for refine in (False, True):
        result = plan(walled, configurations, refine=refine)
        assert smallest_leg_slack(result.positions, bounds, 0.2).slack >= 0
        assert len(result.lanes) == 3 and result.leg_names.count('slide') > 1
        assert result.min_gap > 0
        np.testing.assert_array_equal(result.positions[result.waypoint_indices],
                                      configurations)
        assert result.domain_index == one_slide.domain_index


def test_below_walls_the_staging_line_moves_into_the_room_between_them():
    """
    A fleet by the wall x = 0: centred on its mean projection, the staging line crosses it.

    Below walls the slots' centre is clipped into the range the walls leave
    (core.discs.staging_slots, WallRoom): the plan is inside and stays in its domain.
    """
    pillars = np.array([[2.0, 2.0], [4.0, 2.5]])
    starts = np.array([[0.3, 0.5], [1.1, 0.5], [1.9, 0.5], [0.3, 1.3], [1.1, 1.3],
                       [0.7, -0.3]])
    configurations = np.stack([starts, starts[::-1]])
    options = {'variant': 'discs', 'robot_radius': 0.2, 'obstacle_radius': 0.15}
    bounds = np.array([[0.0, 6.0], [-0.6, 4.5]])
    walled = Workspace(pillars, bounds=bounds, **options)
    centred = plan(Workspace(pillars, frame=walled.frame, **options), configurations)
    crossed = smallest_leg_slack(centred.positions, bounds, 0.2)
    assert crossed.wall == Wall(axis=0, high=False) and crossed.slack < -0.5
    result = plan(walled, configurations)
    assert smallest_leg_slack(result.positions, bounds, 0.2).slack >= 0
    assert result.min_gap > 0 and result.domain_index == centred.domain_index
    np.testing.assert_array_equal(result.positions[result.waypoint_indices], configurations)


def rows_in_a_hall(seed):
    """
    Return (pillars, configurations, bounds): rows of 3 - 8 discs of R = 0.2 about pillars.

    From seed: a row below one to three pillars, then above them in a random order (often
    with reversing runs the walls leave too few lanes for), then below again in another;
    robots 0.85 m apart or more, the walls 0.05 - 0.5 m beyond the box of it all.
    """
    rng = np.random.default_rng(seed)
    k, count = int(rng.integers(3, 9)), int(rng.integers(1, 4))
    xs = np.sort(rng.choice(np.arange(2 * k), k, replace=False)) * 0.85
    pillars = np.stack([np.arange(count) * 1.7 + rng.uniform(0.0, 0.5),
                        rng.uniform(1.0, 2.0, count)], axis=1)
    below = np.stack([xs, np.full(k, -0.5)], axis=1)
    configurations = np.stack([below, np.stack([xs[rng.permutation(k)], np.full(k, 3.5)],
                                               axis=1), below[rng.permutation(k)]])
    points = np.concatenate([configurations.reshape(-1, 2), pillars])
    spare = 0.2 + rng.uniform(0.05, 0.5)
    return pillars, configurations, np.stack([points.min(axis=0) - spare,
                                              points.max(axis=0) + spare], axis=1)


def passing_change(walled, configurations, seed):
    """
    Return how far a NUDGE of every coordinate moves the motion plan() judges below walls.

    That motion is the walled construction refined against the walls. The example is
    rejected where the change leaves a cell or no segment passes in several slides.
    """
    moved = nudged(configurations, seed)
    assume(same_cells(walled, configurations, moved))
    constructions = [walled_construction(walled, c) for c in (configurations, moved)]
    assume(constructions[0].leg_names.count('slide') > len(configurations) - 1)
    before, after = (refined_with_walls(c, walled.bounds) for c in constructions)
    return np.abs(before.position(TAU) - after.position(TAU)).max()


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(st.integers(0, 2 ** 31))
def test_below_walls_a_small_change_inside_a_domain_moves_the_motion_little(seed):
    """
    Continuity of the walled motion, measured: a 1e-7 change moves it <= 100x that.

    rows_in_a_hall, kept where some segment passes in several slides (the staging line
    moved by the walls too, mostly); the motion plan() judges (the walled construction,
    refined against the walls), before and after a change of every coordinate that
    keeps every projection order.
    """
    pillars, configurations, bounds = rows_in_a_hall(seed)
    walled = Workspace(pillars, variant='discs', robot_radius=0.2, obstacle_radius=0.15,
                       bounds=bounds)
    change = passing_change(walled, configurations, seed)
    assert change <= CONTINUITY * NUDGE, change / NUDGE


def test_below_walls_without_pillars_the_lanes_stand_between_them():
    """
    Six robots reverse by the wall of an aisle 2.4 m wide without a pillar: lanes leave it.

    Without pillars the lanes may stand anywhere between the walls (WallRoom.floor and
    ceiling): the staging height is clipped between them and the robots pass in the
    lanes that fit (doc/design.md section 17): inside, bodies apart, waypoints exact,
    the same domain as without walls.
    """
    # By the wall y = 1.2: even four lanes centred on the fleet would cross it.
    starts = np.stack([np.linspace(-3.5, 3.5, 6), np.full(6, 0.8)], axis=1)
    configurations = np.stack([starts, starts[::-1]])
    options = {'variant': 'discs', 'robot_radius': 0.2, 'obstacle_radius': 0.05}
    bounds = np.array([[-5.0, 5.0], [-1.2, 1.2]])
    walled = Workspace(np.zeros((0, 2)), bounds=bounds, **options)
    centred = plan(Workspace(np.zeros((0, 2)), **options), configurations, refine=False)
    assert len(centred.lanes) == 6 and walled.disc_layout.walls.lanes == 4
    assert smallest_leg_slack(centred.positions, bounds, 0.2).slack < -0.2
    for refine in (False, True):
        result = plan(walled, configurations, refine=refine)
        assert smallest_leg_slack(result.positions, bounds, 0.2).slack >= 0
        assert len(result.lanes) <= 4 and result.leg_names.count('slide') > 1
        assert result.min_gap > 0 and result.domain_index == centred.domain_index
        np.testing.assert_array_equal(result.positions[result.waypoint_indices],
                                      configurations)


def rows_in_an_aisle(seed):
    """
    Return (configurations, bounds): rows of 3 - 8 discs of R = 0.2 reordering in an aisle.

    From seed: three rows of robots 0.85 m or more apart along x, each a random
    permutation of the last, the rows' heights scattered by up to 0.5 m; walls 0.05 - 0.5
    m beyond them along x, an aisle 1.3 - 2.5 m high along y (two to five lanes), no pillar.
    """
    rng = np.random.default_rng(seed)
    k = int(rng.integers(3, 9))
    xs = np.sort(rng.choice(np.arange(2 * k), k, replace=False)) * 0.85
    rows = [np.stack([xs[rng.permutation(k)], rng.uniform(-0.25, 0.25, k)], axis=1)
            for _ in range(3)]
    height = rng.uniform(1.3, 2.5)
    spare = 0.2 + rng.uniform(0.05, 0.5)
    bounds = np.array([[xs[0] - spare, xs[-1] + spare], [-0.5 * height, 0.5 * height]])
    return np.stack(rows), bounds


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.filter_too_much])
@given(st.integers(0, 2 ** 31))
def test_in_an_aisle_without_pillars_the_motion_is_inside_and_continuous(seed):
    """
    Below walls without pillars: inside, waypoints exact, and a 1e-7 change moves it little.

    rows_in_an_aisle, kept where some segment passes in several slides (its staging
    height clipped between the walls, mostly): the walled construction and its
    refinement stay inside, bodies apart, and the refined motion moves <= 100x the
    change of every coordinate (doc/design.md section 17, *Without pillars*).
    """
    configurations, bounds = rows_in_an_aisle(seed)
    walled = Workspace(np.zeros((0, 2)), variant='discs', robot_radius=0.2,
                       obstacle_radius=0.0, bounds=bounds)
    change = passing_change(walled, configurations, seed)
    result = plan(walled, configurations)
    assert smallest_leg_slack(result.positions, bounds, 0.2).slack >= 0 and result.min_gap > 0
    np.testing.assert_array_equal(result.positions[result.waypoint_indices], configurations)
    assert change <= CONTINUITY * NUDGE, change / NUDGE


def test_the_walls_room_is_a_range_between_them_or_none():
    """
    The staging range (WallRoom): inside the walls where it applies, unbounded where not.

    A lane above the far side must not empty the range of a robot that stages at lane 0;
    a frame turned 1e-9 rad must not send the slots ten thousand km away (an empty
    range divided by a tiny e1 component); in 3-D with e1 off the axes the robots'
    coordinates across e1 and e2 move them along the walls' axes, so no range applies
    (doc/design.md section 17).
    """
    turn = 7 * 2 * np.pi / 32
    e2 = np.array([np.cos(turn), np.sin(turn)])
    tilted = Workspace([[5.0, 1.0]], variant='discs', robot_radius=0.2, obstacle_radius=0.1,
                       bounds=[[3.0, 8.5], [0.0, 1.45]],
                       frame=((0.0, 0.0), e2[::-1] * [1, -1], e2))
    construction = plan(tilted, [[[7.0, 0.5]], [[7.5, 0.4]]], refine=False)
    assert smallest_leg_slack(construction.positions, tilted.bounds, 0.2).slack >= 0
    barely = np.array([[np.cos(1e-9), np.sin(1e-9)], [-np.sin(1e-9), np.cos(1e-9)]])
    turned = Workspace([[5.0, 1.0]], variant='discs', robot_radius=0.2, obstacle_radius=0.1,
                       bounds=[[0.0, 10.0], [0.0, 4.16]], frame=((0.0, 0.0), *barely))
    room = turned.disc_layout.walls
    assert 0.2 < room.low < room.high < 9.8, room
    moment = Workspace([[0.0, 0.0, 0.0], [0.0, 1.0, 1.0], [1.0, 0.0, 1.0]], variant='discs',
                       robot_radius=0.2, obstacle_radius=0.1, bounds=[[-3.0, 4.0]] * 3)
    assert np.count_nonzero(moment.frame.e1) == 3
    assert (moment.disc_layout.walls.low, moment.disc_layout.walls.high) == (-np.inf, np.inf)


def test_the_refinement_brings_a_plan_that_leaves_the_walls_inside():
    """
    A hall fleet (bench/hall.py's kind, three robots, six pillars): refined inside the walls.

    The construction's motion leaves the hall (refused, OUTSIDE_WORKSPACE); the refined
    one is inside, keeping its margin (section 14, *Walls*: once inside, never out).
    """
    pillars = np.array([[0.05, 0.1], [2.88, 0.31], [2.67, 3.55], [0.03, 1.41], [3.35, 1.83],
                        [1.11, 3.32]])
    configurations = np.array([[[2.0, 2.75], [3.91, 3.01], [1.67, 1.16]],
                               [[1.19, 3.87], [1.39, 1.43], [1.29, 0.22]],
                               [[1.22, 1.95], [3.18, 1.03], [3.82, 3.47]]])
    workspace = Workspace(pillars, variant='discs', robot_radius=0.2, obstacle_radius=0.15,
                          bounds=np.array([[-0.55, 4.49], [-0.48, 4.45]]))
    with pytest.raises(PlanningError) as refused:
        plan(workspace, configurations, refine=False)
    assert refused.value.code == ErrorCode.OUTSIDE_WORKSPACE
    inside = plan(workspace, configurations)
    assert inside.min_gap >= inside.margin > 0
