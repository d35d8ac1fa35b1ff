"""The paper variant reproduces the paper's construction exactly (doc/design.md section 3)."""

from fractions import Fraction
from functools import partial

import numpy as np
from punctured_planner.core import ErrorCode, plan, PlanningError, Workspace
from punctured_planner.core.complexity import sequential_complexity
from punctured_planner.core.sections import PAPER_FRACTIONS
import pytest

# These tests check the construction itself (doc/design.md sections 3, 5), not its
# refinement (section 14).
base = partial(plan, refine=False)

WORKED_OBSTACLES = [[0.0, 0.0], [1.0, 0.0]]
WORKED_REQUEST = [[[0.5, 1.0], [0.5, -2.0]], [[3.0, 0.5], [-1.0, 2.0]]]


def test_worked_example_breakpoints_exactly():
    """The worked example of doc/design.md section 10, breakpoint by breakpoint."""
    p = base(Workspace(WORKED_OBSTACLES), WORKED_REQUEST)
    expected = np.array([
        [[0.5, 1], [0.5, -2]], [[0.75, 1], [0.875, -2]], [[0.75, 0], [0.875, 0]],
        [[0.75, 3], [0.875, 4]], [[3, 3], [-1, 4]], [[3, 0], [-1, 0]],
        [[3, 0.5], [-1, 2]], [[3, 0.5], [-1, 2]]])
    assert np.array_equal(p.positions, expected)
    assert [Fraction(t).limit_denominator(100) for t in p.times] == [
        Fraction(f).limit_denominator(100) for f in PAPER_FRACTIONS]
    assert p.projection_counts.tolist() == [3, 4]
    assert (p.domain, p.domain_index, p.domain_count) == (7, 3, 5)
    assert p.sequential_complexity == 5 and p.optimal
    assert p.min_clearance == 0.125
    assert p.clearance.kind == 'robots' and p.clearance.indices == (0, 1)
    assert p.clearance.tau == pytest.approx(1 / 3)


def test_figure_two_desingularisation_and_obstacle_shared_projection():
    """Figure 2: x_2 above q_1, x_1 and x_3 on one vertical line; three segments."""
    obstacles = [[float(i), 0.0] for i in range(5)]
    first = [[2.5, 2.0], [0.0, 3.0], [2.5, -3.0]]
    second = [[4.5, 1.0], [-1.0, 1.0], [1.5, 2.0]]
    third = [[0.5, -1.0], [2.5, 1.0], [3.5, 0.5]]
    p = base(Workspace(obstacles), [first, second, third])
    # cp: {0,1,2,3,4,2.5} = 6 -> D runs; eps = 0.5 / 8; paper indices 6, 7, 8.
    assert p.projection_counts.tolist() == [6, 8, 8]
    eps = 0.5 / 8
    shifted = np.array(first) + np.array([[5 * eps, 0], [6 * eps, 0], [7 * eps, 0]])
    assert np.array_equal(p.positions[1], shifted)
    assert np.array_equal(p.positions[2], np.c_[shifted[:, 0], np.zeros(3)])
    assert np.array_equal(p.positions[3], np.c_[shifted[:, 0], [6.0, 7.0, 8.0]])
    assert np.array_equal(p.positions[4], [[4.5, 6.0], [-1.0, 7.0], [1.5, 8.0]])
    # In the top stratum D is the identity: its legs have zero length.
    assert np.array_equal(p.positions[6], p.positions[7])
    assert p.waypoint_indices.tolist() == [0, 7, 14]
    for m, configuration in enumerate([first, second, third]):
        assert np.array_equal(p.positions[p.waypoint_indices[m]], configuration)
    assert p.times[7] == 0.5 and p.times[-1] == 1.0
    assert p.domain == 22 and p.domain_range == (15, 24) and p.domain_count == 10


def test_robot_sharing_projection_with_obstacle_moves_off_it():
    """A robot straight above an obstacle is shifted by r eps before projecting."""
    p = base(Workspace([[0.0, 0.0], [2.0, 0.0]]), [[[2.0, 1.0]], [[5.0, 1.0]]])
    assert p.projection_counts.tolist() == [2, 3]
    eps = 2.0 / 3
    assert np.array_equal(p.positions[1], [[2.0 + 2 * eps, 1.0]])
    assert p.min_clearance > 0


def test_without_obstacles_and_with_one():
    """Without obstacles and with one: their own domain ranges and lanes."""
    free = base(Workspace([], dimension=3), np.random.default_rng(1).normal(size=(3, 4, 3)))
    assert free.domain_range == (3, 12) and free.domain_count == 10
    assert free.sequential_complexity == 10 and free.optimal
    assert free.lanes.tolist() == [1.0, 2.0, 3.0, 4.0]
    single = base(Workspace([[0.0, 0.0]]), [[[0.0, 1.0], [0.0, 2.0]], [[1.0, 1.0], [2.0, 2.0]]])
    assert single.projection_counts.tolist() == [1, 3]
    assert single.domain_range == (2, 6) and single.sequential_complexity == 4
    assert not single.optimal and single.min_clearance > 0


@pytest.mark.parametrize('r, d, formula', [
    (0, 3, lambda n, k: n * (k - 1) + 1), (0, 5, lambda n, k: n * (k - 1) + 1),
    (0, 2, lambda n, k: n * (k - 1)), (0, 4, lambda n, k: n * (k - 1)),
    (1, 2, lambda n, k: n * k), (1, 4, lambda n, k: n * k),
    (1, 3, lambda n, k: n * k + 1), (2, 2, lambda n, k: n * k + 1),
    (2, 3, lambda n, k: n * k + 1), (5, 4, lambda n, k: n * k + 1)])
def test_sequential_complexity_table(r, d, formula):
    """Theorem 1.1 (González–Grant) for every case of r and the parity of d."""
    for n in (2, 3, 7):
        for k in (2, 3, 8):
            assert sequential_complexity(n, k, r, d) == formula(n, k)


def test_optimal_exactly_where_the_count_meets_the_theorem():
    """Optimal for r >= 2, for r = 1 and r = 0 with d odd; one above TC_n otherwise."""
    rng = np.random.default_rng(0)
    for r in (0, 1, 2, 3):
        for d in (2, 3):
            obstacles = np.c_[np.arange(r, dtype=float), np.zeros((r, d - 1))]
            p = base(Workspace(obstacles, dimension=d), rng.normal(size=(2, 3, d)) + 0.5)
            assert p.optimal == (r >= 2 or d % 2 == 1)
            assert p.domain_count - p.sequential_complexity == (0 if p.optimal else 1)


def test_frame_falls_back_when_axes_do_not_separate_obstacles():
    """Obstacles sharing x use the y axis; sharing both use a deterministic direction."""
    ws = Workspace([[0.0, 0.0], [0.0, 1.0]])
    assert ws.frame.e1.tolist() == [0.0, 1.0]
    diagonal = Workspace([[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]])
    again = Workspace([[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]])
    assert np.array_equal(diagonal.frame.e1, again.frame.e1)
    assert np.unique(diagonal.obstacle_projections).size == 3
    assert abs(diagonal.frame.e1 @ diagonal.frame.e2) < 1e-12
    p = base(diagonal, [[[0.5, 0.5], [2.0, 2.0]], [[-1.0, 3.0], [0.2, 0.1]]])
    assert p.min_clearance > 0
    lane_base = diagonal.frame.offset(diagonal.obstacles).max()
    assert np.all(p.lanes > lane_base)


def test_caller_frame_that_cannot_separate_obstacles_is_refused():
    """Two obstacles with one projection on the caller's e1: OBSTACLES_DEGENERATE."""
    with pytest.raises(PlanningError) as error:
        Workspace([[0.0, 0.0], [0.0, 1.0]], frame=([0, 0], [1, 0], [0, 1]))
    assert error.value.code == ErrorCode.OBSTACLES_DEGENERATE
    assert 'obstacles 0 and 1' in str(error.value)
    with pytest.raises(PlanningError) as error:
        Workspace([[0.0, 0.0]], frame=([0, 0], [1, 0], [1, 1]))
    assert (error.value.code, error.value.option) == (ErrorCode.INVALID_REQUEST, 'frame')
    # an origin beyond the coordinates' range: refused (its plan was NaN, certified inf)
    for origin in ((1e308, 0.0), (1e16, 0.0)):
        with pytest.raises(PlanningError) as error:
            Workspace(np.zeros((0, 2)), variant='discs', frame=(origin, (1, 0), (0, 1)))
        assert (error.value.code, error.value.option) == (ErrorCode.INVALID_REQUEST, 'frame')
        assert 'supported range' in str(error.value)
    # bounds refused name their option too
    with pytest.raises(PlanningError) as error:
        Workspace(np.zeros((0, 2)), bounds=[[1, -1], [-1, 1]])
    assert (error.value.option, error.value.wall.name) == ('bounds', 'x_min')


def test_caller_frame_is_used():
    """A rotated frame: projections and lanes follow it."""
    c, s = np.cos(0.3), np.sin(0.3)
    ws = Workspace([[0.0, 0.0], [1.0, 0.0]], frame=([0, 0], [c, s], [-s, c]))
    p = base(ws, [[[0.3, 2.0]], [[2.0, -1.0]]])
    axis_point = p.positions[2, 0]
    assert abs(axis_point @ np.array([-s, c])) < 1e-12
    # The lane runs along the rotated e1, at its height along the rotated e2.
    lifted, slid = p.positions[3, 0], p.positions[4, 0]
    assert abs((slid - lifted) @ np.array([-s, c])) < 1e-12
    assert lifted @ np.array([-s, c]) == pytest.approx(p.lanes[0])


@pytest.mark.parametrize('request_, code, words', [
    ([[[0.0, 1.0]]], ErrorCode.NO_CONFIGURATIONS, 'at least 2'),
    ([[[0.0, 1.0]], [[0.0, 1.0, 2.0]]], ErrorCode.INVALID_REQUEST, 'configuration 1'),
    ([[[0.0, 1.0]], [[0.0, 1.0], [3.0, 3.0]]], ErrorCode.ROBOT_COUNT_MISMATCH,
     'configuration 1 has 2 robots'),
    ([[[0.0, 1.0], [2.0, 2.0]], [[0.0, np.nan], [3.0, 3.0]]], ErrorCode.NON_FINITE_VALUE,
     'configuration 1, robot 0'),
    ([[[0.0, 1.0], [2.0, 2.0]], [[3.0, 3.0], [3.0, 3.0]]],
     ErrorCode.ROBOTS_COINCIDE, 'configuration 1: robots 0 and 1'),
    ([[[0.0, 1.0], [2.0, 2.0]], [[0.5, 1.0], [1.0, 0.0]]], ErrorCode.ROBOT_ON_OBSTACLE,
     'configuration 1: robot 1 is on obstacle 1'),
])
def test_bad_requests_name_the_culprit(request_, code, words):
    """Each validation error has its code and names configuration, robots, obstacle."""
    with pytest.raises(PlanningError) as error:
        base(Workspace(WORKED_OBSTACLES), request_)
    assert error.value.code == code
    assert words in str(error.value)


def test_coincident_obstacles_are_refused():
    """Two obstacles at one point cannot be punctures of a configuration space."""
    with pytest.raises(PlanningError) as error:
        Workspace([[1.0, 2.0], [0.0, 0.0], [1.0, 2.0]])
    assert error.value.code == ErrorCode.OBSTACLES_DEGENERATE
    assert 'obstacles 0 and 2' in str(error.value)


def test_position_interpolates_and_hits_breakpoints():
    """position(tau) is linear between breakpoints, vectorised over many tau."""
    p = base(Workspace(WORKED_OBSTACLES), WORKED_REQUEST)
    assert np.array_equal(p.position(p.times), p.positions)
    middle = (p.times[3] + p.times[4]) / 2
    assert np.allclose(p.position(middle), (p.positions[3] + p.positions[4]) / 2)
    assert p.position(np.zeros((2, 3))).shape == (2, 3, 2, 2)
