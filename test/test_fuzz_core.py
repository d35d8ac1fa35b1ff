"""
Fuzzing the core with malformed and extreme requests (issue 7, items 1 and 2).

Every call either raises PlanningError with a documented code, naming the
configuration, robots and obstacle at fault, or returns a plan whose
certificate is positive, above the numerical resolution, and agrees with an
independent dense and exact check (test/motion_check.py): never a silent
collision. About 2,300 requests in all (the ``max_examples`` below).

Guaranteed range (measured here, stated for msg_docs):

* Coordinates: finite, |x| <= 1e15 (``MAX_COORDINATE``); beyond, INVALID_REQUEST;
  NaN or infinite, NON_FINITE_VALUE.
* A plan is returned only if its exact clearance D satisfies
  D >= required_clearance and D > 1e-12 x S, S the largest absolute coordinate of
  the motion (robots, lanes, obstacles); otherwise CLEARANCE_BELOW_REQUIRED. So
  near 1e9, plans whose robots pass closer than about 1e-3 are refused, never
  trusted; at unit scale, robots 1e-9 apart are planned and certified.
* The certificate D agrees with the exact minimum over the float breakpoints
  within 1e-9 D + 8 u S (u = 1.1e-16): relative 1e-9 whenever D >= 1e-6 S; near
  the resolution limit the float64 rounding of the closed form dominates (seen
  up to 4e-5 relative at S = 3e11, D = 1). Since D > 1e-12 S, the true minimum
  is always at least D (1 - 1e-3) > 0.
* Lengths (lane_spacing, min_spacing, the radii, required_clearance): 0 where
  allowed, else between 1e-100 and 1e15 (core.limits; far beyond any node
  parameter), else INVALID_REQUEST naming the option. The certificate rescales
  far-from-unit coordinates by a power of two, so even a motion at 1e-160 is
  certified exactly (test_subnormal_scale_...).
"""

from fractions import Fraction

from hypothesis import event, given, HealthCheck, settings
from hypothesis import strategies as st
import hypothesis.extra.numpy as hnp
from motion_check import assert_certificate_agrees, exact_minimum, UNIT_ROUNDOFF
import numpy as np
from punctured_planner.core import ErrorCode, MAX_COORDINATE, plan, PlanningError, Workspace
from punctured_planner.core.certificate import certify, RELATIVE_RESOLUTION
from punctured_planner.core.limits import lengths_in_range
import pytest

FUZZ = settings(max_examples=1200, deadline=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much,
                                       HealthCheck.data_too_large])
EXTREME = settings(FUZZ, max_examples=800)
WORKSPACE = settings(FUZZ, max_examples=300)
# What a coordinate can be replaced with: the fault it makes (None: still valid).
BAD_VALUES = [(np.nan, 'nan'), (np.inf, 'nan'), (-np.inf, 'nan'),
              (1e300, 'range'), (-1e300, 'range'), (1e16, 'range'),
              (np.nextafter(MAX_COORDINATE, np.inf), 'range'),
              (MAX_COORDINATE, None), (-MAX_COORDINATE, None),
              (1e-300, None), (-5e-324, None), (-0.0, None)]
MUTATIONS = ('bad_value', 'coincide', 'on_obstacle', 'drop_robot', 'extra_robot',
             'wrong_dimension', 'flat', 'no_robots', 'few_configurations')
CODES = {int(code) for code in ErrorCode} - {int(ErrorCode.NONE)}


def unique_rows(values):
    """Return the rows of a 2-D array without repeats, in first-seen order."""
    _, first = np.unique(values, axis=0, return_index=True)
    return values[np.sort(first)]


@st.composite
def workspaces(draw, dimension):
    """Return a valid Workspace on a small integer grid, both variants."""
    count = draw(st.integers(0, 5))
    grid = draw(hnp.arrays(np.int8, (count, dimension), elements=st.integers(-6, 6)))
    obstacles = unique_rows(grid.astype(float)).reshape(-1, dimension)
    variant = draw(st.sampled_from(['paper', 'spread']))
    required = draw(st.sampled_from([0.0, 0.0, 0.05, 0.3]))
    return Workspace(obstacles, dimension=dimension, variant=variant,
                     required_clearance=required)


@st.composite
def malformed_requests(draw):
    """
    Return (workspace, request as passed, configurations as arrays): a grid request with faults.

    Between zero and three mutations from MUTATIONS; the container is an (n, k, d)
    array when the shapes allow it, else a list of arrays or nested lists.
    """
    d = draw(st.sampled_from([2, 3, 4]))
    ws = draw(workspaces(d))
    n = draw(st.integers(2, 5))
    k = draw(st.integers(1, 8))
    grid = draw(hnp.arrays(np.int8, (n, k, d), elements=st.integers(-6, 6)))
    items = list(grid / 2.0)
    for mutation in draw(st.lists(st.sampled_from(MUTATIONS), max_size=3)):
        event('mutation: ' + mutation)
        m = draw(st.integers(0, len(items) - 1)) if items else None
        if m is None:
            break
        rows = items[m].shape[0] if items[m].ndim == 2 else 0
        if mutation == 'bad_value' and items[m].size:
            value, _ = draw(st.sampled_from(BAD_VALUES))
            flat = items[m].reshape(-1).copy()
            flat[draw(st.integers(0, flat.size - 1))] = value
            items[m] = flat.reshape(items[m].shape)
        elif mutation == 'coincide' and rows >= 2:
            a, b = draw(st.lists(st.integers(0, rows - 1), min_size=2, max_size=2, unique=True))
            items[m] = items[m].copy()
            items[m][b] = items[m][a]
        elif mutation == 'on_obstacle' and rows and ws.obstacle_count \
                and items[m].shape[1] == d:
            items[m] = items[m].copy()
            robot = draw(st.integers(0, rows - 1))
            items[m][robot] = ws.obstacles[draw(st.integers(0, ws.obstacle_count - 1))]
        elif mutation == 'drop_robot' and rows:
            items[m] = np.delete(items[m], draw(st.integers(0, rows - 1)), axis=0)
        elif mutation == 'extra_robot' and items[m].ndim == 2:
            extra = np.full((1, items[m].shape[1]), 7.25)
            items[m] = np.concatenate([items[m], extra])
        elif mutation == 'wrong_dimension' and items[m].ndim == 2:
            columns = draw(st.sampled_from([0, 1, d - 1, d + 1]))
            items[m] = np.resize(items[m], (items[m].shape[0], columns))
        elif mutation == 'flat':
            items[m] = items[m].reshape(-1)
        elif mutation == 'no_robots':
            items[m] = np.empty((0, d))
        elif mutation == 'few_configurations':
            items = items[:draw(st.integers(0, 1))]
    container = draw(st.sampled_from(['array', 'list', 'nested']))
    shapes = {item.shape for item in items}
    if container == 'array' and len(shapes) <= 1:
        request = np.array(items).reshape((len(items),) + (shapes.pop() if shapes else (0, d)))
    elif container == 'nested':
        request = [item.tolist() for item in items]
        items = [np.asarray(item, dtype=float) for item in request]
    else:
        request = items
    return ws, request, items


def first_index(mask):
    """Return the first index (C order) where mask is true, as ints, or None."""
    hits = np.argwhere(mask)
    return tuple(int(v) for v in hits[0]) if hits.size else None


def documented_faults(items, obstacles):
    """
    Return the faults of a request as [(code, configuration, robot)], by the documented order.

    msg_docs/PlanSequence.md and ErrorCode: a request with several faults reports
    the smallest code; configuration is the first one at fault. Robot-robot and
    robot-obstacle faults carry robot None (the test checks the named ones).
    """
    d = obstacles.shape[1]
    if len(items) < 2:
        return [(ErrorCode.NO_CONFIGURATIONS, None, None)]
    for m, item in enumerate(items):
        if item.ndim != 2 or item.shape[1] != d:
            return [(ErrorCode.INVALID_REQUEST, m, None)]
    k = items[0].shape[0]
    if k == 0:
        return [(ErrorCode.INVALID_REQUEST, 0, None)]
    faults = []
    for m, item in enumerate(items):
        if item.shape[0] != k:
            faults.append((ErrorCode.ROBOT_COUNT_MISMATCH, m, None))
            break
    if faults:
        # A count mismatch hides later per-coordinate faults, except the range check.
        far = [m for m, item in enumerate(items)
               if np.any(np.isfinite(item) & (np.abs(item) > MAX_COORDINATE))]
        if far:
            faults.append((ErrorCode.INVALID_REQUEST, far[0], None))
        return sorted(faults)
    stacked = np.stack(items)
    nonfinite = first_index(~np.isfinite(stacked))
    if nonfinite:
        faults.append((ErrorCode.NON_FINITE_VALUE,) + nonfinite[:2])
    far = first_index(np.abs(np.nan_to_num(stacked, posinf=0, neginf=0)) > MAX_COORDINATE)
    if far:
        faults.append((ErrorCode.INVALID_REQUEST,) + far[:2])
    if faults:
        return sorted(faults)
    same = stacked[:, :, None, :] == stacked[:, None, :, :]
    same = np.all(same, axis=3) & ~np.eye(k, dtype=bool)
    coincide = first_index(same.any(axis=(1, 2)))
    if coincide:
        return [(ErrorCode.ROBOTS_COINCIDE, coincide[0], None)]
    on = first_index(np.all(stacked[:, :, None, :] == obstacles[None, None], axis=3)
                     .any(axis=(1, 2)))
    if on:
        return [(ErrorCode.ROBOT_ON_OBSTACLE, on[0], None)]
    return []


def assert_names_culprit(error, items, obstacles):
    """Check that the error's robots and obstacle are really at fault, and that it says so."""
    message = str(error)
    assert message.startswith(error.code.name + ': ')
    if error.configuration is not None and error.code != ErrorCode.CLEARANCE_BELOW_REQUIRED:
        assert 'configuration %d' % error.configuration in message
    if error.code == ErrorCode.ROBOTS_COINCIDE:
        a, b = error.robots
        assert a < b and np.array_equal(items[error.configuration][a],
                                        items[error.configuration][b])
        assert 'robots %d and %d' % (a, b) in message
    elif error.code == ErrorCode.ROBOT_ON_OBSTACLE:
        (robot,) = error.robots
        assert np.array_equal(items[error.configuration][robot], obstacles[error.obstacle])
        assert 'robot %d is on obstacle %d' % (robot, error.obstacle) in message
    elif error.code == ErrorCode.NON_FINITE_VALUE:
        (robot,) = error.robots
        assert not np.all(np.isfinite(items[error.configuration][robot]))
        assert 'robot %d' % robot in message
    elif error.code == ErrorCode.ROBOT_COUNT_MISMATCH:
        assert len(items[error.configuration]) != len(items[0])


def assert_valid_plan(p, ws, configurations):
    """Check a returned plan: waypoints exact, certificate positive, independently confirmed."""
    configurations = np.asarray(configurations, dtype=float)
    assert np.array_equal(p.positions[p.waypoint_indices], configurations)
    assert np.all(np.diff(p.times) >= 0) and p.times[0] == 0 and p.times[-1] == 1
    assert np.all(np.isfinite(p.positions))
    clearance = p.min_clearance
    if p.clearance.kind == 'none':
        assert ws.obstacle_count == 0 and configurations.shape[1] == 1
        return
    assert clearance >= ws.required_clearance
    assert clearance > resolution_of(p.positions, ws.obstacles)
    assert_certificate_agrees(p.positions, ws.obstacles, clearance)


def resolution_of(positions, obstacles):
    """Return the documented resolution: 1e-12 of the largest coordinate of the motion."""
    return RELATIVE_RESOLUTION * max(np.abs(positions).max(initial=0.0),
                                     np.abs(obstacles).max(initial=0.0))


def assert_refusal_is_honest(ws, configurations, error):
    """Check a CLEARANCE_BELOW_REQUIRED refusal: the exact clearance really is too small."""
    uncertified = plan(ws, configurations, certify=False)
    resolution = resolution_of(uncertified.positions, ws.obstacles)
    limit = max(ws.required_clearance, resolution)
    squared, where = exact_minimum(uncertified.positions, ws.obstacles,
                                   uncertified.min_clearance)
    allowance = 8 * UNIT_ROUNDOFF * max(resolution / 1e-12, 1.0)
    assert squared <= Fraction(limit * (1 + 1e-9) + allowance) ** 2, \
        'refused although the exact clearance is above %r (at %s)' % (limit, where)
    a, b = uncertified.clearance.indices
    culprit = ('robots %d and %d' % (a, b) if uncertified.clearance.kind == 'robots'
               else 'robot %d and obstacle %d' % (a, b))
    assert culprit in str(error)
    assert error.configuration is not None
    assert 'C_%d -> C_%d' % (error.configuration + 1, error.configuration + 2) in str(error)


def plan_or_refuse(ws, request, items):
    """Plan, then check the outcome against the documented faults of the request."""
    faults = documented_faults(items, ws.obstacles)
    try:
        p = plan(ws, request)
    except PlanningError as error:
        assert int(error.code) in CODES
        event('refused: ' + error.code.name)
        assert_names_culprit(error, items, ws.obstacles)
        if not faults:
            assert error.code == ErrorCode.CLEARANCE_BELOW_REQUIRED, str(error)
            assert_refusal_is_honest(ws, np.stack(items), error)
            return error
        # Documented: the smallest code wins.
        assert error.code == faults[0][0], (str(error), faults)
        expected = [f for f in faults if f[0] == error.code][0]
        assert error.configuration == expected[1], (str(error), faults)
        if expected[2] is not None:
            assert error.robots == (expected[2],), (str(error), faults)
        return error
    assert not faults, 'planned a request with faults %s' % faults
    event('planned')
    assert_valid_plan(p, ws, np.stack(items))
    return p


@FUZZ
@given(malformed_requests())
def test_malformed_requests_get_a_documented_code_or_a_certified_plan(case):
    """NaN, inf, huge, empty, ragged, wrong dimension, coincident, on obstacles, mixed."""
    ws, request, items = case
    plan_or_refuse(ws, request, items)


def grid_points(cells, dimension):
    """Return the points (len(cells), dimension) of cell numbers on the grid -6 .. 6."""
    cells = np.asarray(cells, dtype=np.int64)
    digits = (cells[:, None] // 13 ** np.arange(dimension)[None, :]) % 13
    return (digits - 6).astype(float)


@st.composite
def extreme_requests(draw):
    """
    Return (workspace, configurations, mode): grid requests at extreme offsets and scales.

    Modes: 'far' (near 1e9 .. 1e15, gaps from 1e-9 to 10), 'close' (unit offsets,
    robots 1e-12 .. 1e-6 apart), 'tiny' (coordinates near 1e-300), 'huge' (1e250 ..
    1e308), 'small_lanes' (every length scaled down to 1e-100 .. 1e-3, lanes too).
    """
    d = draw(st.sampled_from([2, 3]))
    mode = draw(st.sampled_from(['far', 'far', 'close', 'tiny', 'huge', 'small_lanes']))
    event('mode: ' + mode)
    r, k, n = draw(st.integers(0, 4)), draw(st.integers(1, 6)), draw(st.integers(2, 4))
    offset = np.zeros(d)
    lane_spacing = 1.0
    if mode == 'far':
        magnitude = draw(st.sampled_from([1e9, 1e9, 3.3e10, 1e12, 9.99e14]))
        offset = magnitude * np.array(draw(st.lists(st.sampled_from([-1.0, 0.0, 1.0, 0.7]),
                                                    min_size=d, max_size=d)))
        gap = magnitude * 10.0 ** draw(st.floats(-17, -8))
        lane_spacing = draw(st.sampled_from([1.0, gap, 10 * gap]))
    elif mode == 'close':
        offset = np.array(draw(st.lists(st.floats(-10, 10), min_size=d, max_size=d)))
        gap = 10.0 ** draw(st.floats(-12, -6))
        lane_spacing = draw(st.sampled_from([1.0, 1e3 * gap]))
    elif mode == 'tiny':
        gap = 10.0 ** draw(st.floats(-323, -290))
    elif mode == 'huge':
        gap = 10.0 ** draw(st.floats(250, 307))
    else:
        gap = 10.0 ** draw(st.floats(-100, -3))
        lane_spacing = gap
    cells = 13 ** d
    obstacle_cells = draw(st.lists(st.integers(0, cells - 1), min_size=r, max_size=r,
                                   unique=True))
    robot_cells = [draw(st.lists(st.integers(0, cells - 1).filter(
        lambda c: c not in obstacle_cells), min_size=k, max_size=k, unique=True))
        for _ in range(n)]
    obstacles = offset + gap * grid_points(obstacle_cells, d).reshape(-1, d)
    configurations = offset + gap * np.array([grid_points(c, d) for c in robot_cells])
    variant = draw(st.sampled_from(['paper', 'spread']))
    required = draw(st.sampled_from([0.0, 0.0, 0.0, 0.01 * gap]))
    options = {'dimension': d, 'variant': variant, 'lane_spacing': lane_spacing,
               'min_spacing': lane_spacing / 2, 'required_clearance': required}
    return obstacles, options, configurations, mode


@EXTREME
@given(extreme_requests())
def test_extreme_scales_are_certified_or_refused_never_a_silent_collision(case):
    """Near 1e9 with tiny gaps, 1e-9 apart, 1e-300, 1e300: certified plan or clear refusal."""
    obstacles, options, configurations, mode = case
    try:
        ws = Workspace(obstacles, **options)
    except PlanningError as error:
        event('workspace refused: ' + error.code.name)
        assert error.code in (ErrorCode.INVALID_REQUEST, ErrorCode.OBSTACLES_DEGENERATE)
        if error.code == ErrorCode.INVALID_REQUEST and error.obstacle is None:
            # A length beyond the supported ones (core.limits): spacings, the clearance.
            lengths = [options['lane_spacing'], options['min_spacing']]
            lengths += [options['required_clearance']] if options['required_clearance'] else []
            assert not lengths_in_range(lengths, zero=False).all(), str(error)
            assert 'a real number between' in str(error)
        elif error.code == ErrorCode.INVALID_REQUEST:
            assert np.abs(obstacles).max() > MAX_COORDINATE
            assert 'obstacle %d' % error.obstacle in str(error)
        else:
            projections = ws_projections_collide(obstacles)
            assert projections, 'distinct obstacle projections refused: %s' % error
        return
    result = plan_or_refuse(ws, configurations, list(configurations))
    if isinstance(result, PlanningError):
        event('%s refused: %s' % (mode, result.code.name))
    else:
        event('%s planned' % mode)


def ws_projections_collide(obstacles):
    """Return whether no coordinate axis separates the obstacles (the frame then may not)."""
    obstacles = np.asarray(obstacles)
    if len(np.unique(obstacles, axis=0)) < len(obstacles):
        return True
    return all(len(np.unique(obstacles[:, a])) < len(obstacles)
               for a in range(obstacles.shape[1]))


def test_planning_near_1e9_certifies_or_refuses_at_the_resolution():
    """Near 1e9, a 1 m gap is planned and certified; a 1e-6 m gap is refused, not trusted."""
    obstacles = 1e9 + np.array([[0.0, 0.0], [10.0, 0.0]])
    ws = Workspace(obstacles, lane_spacing=1.0)
    wide = 1e9 + np.array([[[2.0, 3.0], [3.0, 3.0]], [[4.0, -2.0], [5.0, 1.0]]])
    p = plan(ws, wide)
    assert_valid_plan(p, ws, wide)
    assert p.min_clearance > 0.1
    tight = wide.copy()
    tight[1, 1] = tight[1, 0] + np.array([1e-6, 0.0])
    with pytest.raises(PlanningError) as refused:
        plan(ws, tight)
    assert refused.value.code == ErrorCode.CLEARANCE_BELOW_REQUIRED
    assert 'numerical resolution' in str(refused.value)
    assert_refusal_is_honest(ws, tight, refused.value)


def test_robots_1e_9_apart_at_unit_scale_are_planned_and_certified():
    """Two robots 1e-9 apart near the origin: a plan whose certificate is about 1e-9 / (k + r)."""
    ws = Workspace([[0.0, 0.0], [1.0, 0.0]])
    configurations = [[[0.5, 1.0], [0.5 + 1e-9, 1.0]], [[2.0, 1.0], [2.0, 1.0 + 1e-9]]]
    p = plan(ws, configurations)
    assert_valid_plan(p, ws, configurations)
    assert 1e-11 < p.min_clearance <= 1e-9


@st.composite
def malformed_workspaces(draw):
    """Return (obstacles, options, fault): obstacle sets and options with one injected fault."""
    d = draw(st.sampled_from([1, 2, 3, 3]))
    r = draw(st.integers(0, 5))
    obstacles = draw(hnp.arrays(np.int8, (r, d), elements=st.integers(-4, 4))).astype(float)
    obstacles = unique_rows(obstacles).reshape(-1, d)
    options = {'dimension': d}
    fault = draw(st.sampled_from(['none', 'nan', 'range', 'duplicate', 'shape',
                                  'mismatch', 'undimensioned', 'variant', 'lane_spacing',
                                  'min_spacing', 'required_clearance']))
    if fault in ('nan', 'range') and len(obstacles):
        value = draw(st.sampled_from([np.nan, np.inf, -np.inf] if fault == 'nan'
                                     else [1e300, -1e16, np.nextafter(MAX_COORDINATE, 2e15)]))
        obstacles[draw(st.integers(0, len(obstacles) - 1)), draw(st.integers(0, d - 1))] = value
    elif fault == 'duplicate' and len(obstacles):
        obstacles = np.concatenate([obstacles, obstacles[-1:]])
    elif fault == 'shape':
        obstacles = obstacles.reshape(-1) if len(obstacles) else np.zeros((1, 1, d))
    elif fault == 'mismatch':
        options['dimension'] = d + 1
    elif fault == 'undimensioned' and not len(obstacles):
        # A (0, d) array still gives d; a flat empty one cannot.
        del options['dimension']
        if draw(st.booleans()):
            obstacles = np.empty(0)
    elif fault in ('lane_spacing', 'min_spacing', 'required_clearance'):
        options[fault] = draw(st.sampled_from([np.nan, np.inf, -1.0] + (
            [] if fault == 'required_clearance' else [0.0])))
    elif fault == 'variant':
        options['variant'] = draw(st.sampled_from(['Paper', '', 'spreads', None]))
    else:
        fault = 'none'
    event('workspace fault: ' + fault)
    return obstacles, options, fault


@WORKSPACE
@given(malformed_workspaces())
def test_malformed_workspaces_raise_a_documented_code_naming_the_obstacle(case):
    """Bad obstacles and options: INVALID_REQUEST, NON_FINITE_VALUE or OBSTACLES_DEGENERATE."""
    obstacles, options, fault = case
    d = options.get('dimension')
    empty = obstacles.size == 0
    harmless = ('nan', 'range', 'mismatch', 'duplicate') if empty else ()
    if fault == 'undimensioned' and obstacles.ndim == 2:
        d, harmless = obstacles.shape[1], ('undimensioned',)
    valid = d is not None and d >= 2 and (fault == 'none' or fault in harmless)
    try:
        ws = Workspace(obstacles, **options)
    except PlanningError as error:
        assert not valid, str(error)
        message = str(error)
        assert message.startswith(error.code.name + ': ')
        if error.code == ErrorCode.NON_FINITE_VALUE:
            assert fault == 'nan'
            assert not np.all(np.isfinite(obstacles[error.obstacle]))
            assert 'obstacle %d' % error.obstacle in message
        elif error.code == ErrorCode.OBSTACLES_DEGENERATE:
            assert fault == 'duplicate'
            assert 'obstacles %d and' % error.obstacle in message
            assert (obstacles == obstacles[error.obstacle]).all(axis=1).sum() == 2
        else:
            assert error.code == ErrorCode.INVALID_REQUEST, message
            if error.obstacle is not None:
                assert np.abs(obstacles[error.obstacle]).max() > MAX_COORDINATE
                assert 'obstacle %d' % error.obstacle in message
        return
    assert valid, 'accepted workspace with fault %s' % fault
    assert ws.obstacles.shape == (len(obstacles), d)


# Known deviations, pinned so that a fix turns them into failures to remove here.

@pytest.mark.parametrize('request_', [
    [[[np.nan, 1.0]], [[1e300, 2.0]]],
    [[[1e300, 1.0]], [[0.5, 2.0], [3.0, 3.0]]],
], ids=['nan-and-huge', 'mismatch-and-huge'])
def test_out_of_range_coordinates_take_priority_as_documented(request_):
    """A request with a coordinate beyond 1e15 reports INVALID_REQUEST (4) first."""
    with pytest.raises(PlanningError) as refused:
        plan(Workspace([[0.0, 0.0], [1.0, 0.0]]), request_)
    assert refused.value.code == ErrorCode.INVALID_REQUEST


@pytest.mark.parametrize('request_', [
    pytest.param([[[0.5, 1.0], [2.0]], [[0.5, 2.0], [2.0, 1.0]]], id='ragged-point'),
    pytest.param([[['a', 'b']], [['c', 'd']]], id='strings'),
    pytest.param(None, id='none'),
    pytest.param(5, id='scalar'),
    pytest.param([[[10 ** 400, 1.0]], [[0.5, 2.0]]], id='huge-int'),
    pytest.param([[[0.5 + 1j, 1.0]], [[0.5, 2.0]]], id='complex'),
    pytest.param([None, None], id='none-items'),
    pytest.param([[1.0, 2.0], [3.0, 4.0]], id='no-points'),
])
def test_non_numeric_requests_raise_planning_error(request_):
    """Requests that are not arrays of real numbers get INVALID_REQUEST, not a crash."""
    with pytest.raises(PlanningError) as refused:
        plan(Workspace([[0.0, 0.0], [1.0, 0.0]]), request_)
    assert refused.value.code == ErrorCode.INVALID_REQUEST


@pytest.mark.parametrize('variant', ['paper', 'spread'])
def test_subnormal_scale_certificate_is_exact(variant):
    """A plan scaled by 2^-532 (about 1e-160), lanes too, certifies to its clearance scaled."""
    ws = Workspace([[0.0, 0.0], [1.0, 0.0]], variant=variant)
    configurations = np.array([[[0.3, 0.7], [0.6, -0.2]], [[0.61, 0.5], [0.2, -0.4]]])
    p = plan(ws, configurations)
    tiny = [np.ldexp(points, -532) for points in (p.positions, ws.obstacles)]
    clearance = certify(p.times, *tiny).distance
    # A power of two scales every step of the closed form exactly, once rescaled.
    assert clearance == np.ldexp(p.min_clearance, -532)
    assert_certificate_agrees(*tiny, clearance)


@pytest.mark.parametrize('options, words', [
    ({'lane_spacing': 1e-160}, 'lane_spacing must be a real number between 1e-100 and 1e+15'),
    ({'min_spacing': 1e300}, 'min_spacing must be a real number between'),
    ({'min_spacing': None}, 'min_spacing must be a real number between 1e-100 and 1e+15, '
                            'got None'),
    ({'lane_spacing': '0.1'}, "got '0.1'"),
    ({'lane_spacing': [1.0]}, 'got [1.0]'),
    ({'lane_spacing': True}, 'got True'),
    ({'required_clearance': 1e-200}, 'required_clearance must be 0 or a real number between'),
    ({'robot_radius': 1e16}, 'robot_radius must be 0 or a real number between'),
    ({'obstacle_radius': [0.1, 1e-120]}, 'obstacle 1: obstacle_radius must be 0 or'),
    ({'bounds': [[-1e308, 1e308], [-1.0, 1.0]]}, 'x_min = -1e+308 is beyond the supported'),
    ({'dimension': 2.5}, 'dimension must be an integer >= 2 or None, got 2.5'),
    ({'obstacles': [], 'dimension': 1}, 'dimension must be an integer >= 2 or None, got 1'),
    ({'frame': ([0, 0], [1, 0])}, 'frame must be a Frame or (origin, e1, e2)'),
    ({'obstacles': [[1.0, 2.0], [3.0]]}, 'the obstacle array is not an array of real numbers'),
    ({'obstacles': [[1 + 1j, 0.0]]}, 'the obstacle array is not an array of real numbers'),
    ({'variant': 'cubes'}, "variant must be one of ('paper', 'spread', 'discs'), got 'cubes'"),
])
def test_options_outside_the_supported_range_are_refused_naming_them(options, words):
    """Lengths outside [1e-100, 1e15] (or 0 where allowed) and odd types: INVALID_REQUEST."""
    options = {'obstacles': [[0.0, 0.0], [1.0, 0.5]], **options}
    with pytest.raises(PlanningError) as refused:
        Workspace(options.pop('obstacles'), **{'variant': 'discs', **options})
    assert refused.value.code == ErrorCode.INVALID_REQUEST
    assert words in str(refused.value)
    named = set(options) & {'lane_spacing', 'min_spacing', 'required_clearance', 'robot_radius',
                            'dimension', 'variant'}
    if named:  # the option at fault as data too
        assert refused.value.option == named.pop()


def test_the_ends_of_the_supported_lengths_are_accepted():
    """Every length at 1e-100 or at 1e15, radii and the clearance at 0 too, is a workspace."""
    for length in (1e-100, 1e15):
        Workspace([[0.0, 0.0]], variant='discs', lane_spacing=length, min_spacing=length,
                  required_clearance=length, robot_radius=length, obstacle_radius=length)
    Workspace([[0.0, 0.0]], variant='discs', required_clearance=0, robot_radius=np.array(0.2),
              obstacle_radius=np.float32(0))
