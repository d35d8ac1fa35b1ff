"""
Hypothesis strategies for the core: random and degenerate requests.

Coordinates come from a coarse grid so that robots share projections with
each other and with obstacles; modes force all robots onto one vertical line,
or every configuration into the lowest stratum (every robot above an obstacle).
lattice_requests meets the discs theorem's condition exactly (doc/design.md section 6).
"""

from hypothesis import assume, strategies as st
import numpy as np
from punctured_planner.core import ErrorCode, PlanningError, Workspace
from punctured_planner.core.discs import MARGIN

GRID = st.integers(-8, 8).map(lambda v: v / 2)
FLOAT = st.floats(-10, 10, allow_nan=False).map(lambda v: round(v, 6))
MODES = ('grid', 'vertical', 'lowest', 'float')


@st.composite
def requests(draw, max_robots=8, max_obstacles=5, max_configurations=5, modes=MODES):
    """Return (obstacles (r, d), configurations (n, k, d), mode): valid, often degenerate."""
    d = draw(st.sampled_from([2, 3, 4]))
    r = draw(st.integers(0, max_obstacles))
    k = draw(st.integers(1, max_robots))
    n = draw(st.integers(2, max_configurations))
    mode = draw(st.sampled_from(modes))
    xs = draw(st.lists(GRID, min_size=r, max_size=r, unique=True))
    obstacles = [(x,) + tuple(draw(GRID) for _ in range(d - 1)) for x in xs]
    taken = set(obstacles)
    configurations = []
    for _ in range(n):
        if mode == 'vertical':
            xs_allowed = st.just(draw(GRID))
        elif mode == 'lowest':
            xs_allowed = st.sampled_from(xs) if xs else st.just(draw(GRID))
        else:
            xs_allowed = FLOAT if mode == 'float' else GRID
        other = FLOAT if mode == 'float' else GRID
        point = st.tuples(xs_allowed, *([other] * (d - 1)))
        robots = draw(st.lists(point, min_size=k, max_size=k, unique=True)
                      .filter(lambda pts: not taken.intersection(pts)))
        configurations.append(robots)
    return (np.array(obstacles, dtype=float).reshape(r, d),
            np.array(configurations, dtype=float), mode)


def same_cells(workspace, first, second):
    """
    Return whether two requests (n, k, d) lie in the same cells of the strata.

    Every configuration's order of all k + r projections onto e1, ties
    included, must be the same: a stratum is a disjoint union of such cells, and
    the motion is continuous on each (doc/design.md sections 6 and 7) but may
    jump between two, as when a nudge takes a robot 1e-6 from another past it
    (equal projection counts, robots in swapped slots).
    """
    def signs(configurations):
        pillars = np.broadcast_to(workspace.obstacle_projections,
                                  (len(configurations), len(workspace.obstacles)))
        both = np.concatenate([workspace.frame.project(configurations), pillars], axis=1)
        return np.sign(both[:, :, None] - both[:, None, :])

    return np.array_equal(signs(first), signs(second))


def separation(workspace):
    """Return S = max(4R, 2R + nu + max_j w_j), the theorem's robot spacing (design, 6)."""
    radius = workspace.robot_radius
    reach = workspace.disc_layout.reach.max(initial=0.0)
    return max(4 * radius, (2 + MARGIN) * radius + reach)


@st.composite
def lattice_requests(draw):
    """Return (workspace, configurations (n, k, 2)) meeting the theorem's condition exactly."""
    radius = draw(st.sampled_from([0.1, 0.25, 0.3]))
    columns, rows = draw(st.integers(2, 7)), draw(st.integers(2, 6))
    cells = [(c, r) for c in range(columns) for r in range(rows)]
    pillar_cells = draw(st.lists(st.sampled_from(cells), max_size=4, unique=True))
    # Narrower than, as wide as and wider than the robots.
    rho = [draw(st.sampled_from([0.0, 0.5, 0.8, 1.0, 1.5])) * radius for _ in pillar_cells]
    # The lattice pitch is exactly S, which the pillars' radii fix (the theorem's (a)).
    probe = np.stack([np.arange(len(rho)), np.zeros(len(rho))], axis=1)
    pitch = separation(Workspace(probe, dimension=2, variant='discs', robot_radius=radius,
                                 obstacle_radius=np.array(rho)))
    free = [cell for cell in cells if cell not in pillar_cells]
    assume(free)
    k = draw(st.integers(1, min(len(free), 10)))
    n = draw(st.integers(2, 3))
    origin = np.array([draw(st.sampled_from([0.0, 0.37, -1.5])), 0.25])
    chosen = [draw(st.permutations(free))[:k] for _ in range(n)]
    mirror = [(columns - 1 - c, r) for c, r in chosen[0]]
    if draw(st.booleans()) and not set(mirror) & set(pillar_cells):
        chosen[-1] = mirror  # mirror-image goal: C_1 reflected through the lattice's middle
    configurations = [origin + pitch * np.array(cells_, dtype=float) for cells_ in chosen]
    pillars = origin + pitch * np.array(pillar_cells, dtype=float).reshape(-1, 2)
    try:
        workspace = Workspace(pillars, dimension=2, variant='discs', robot_radius=radius,
                              obstacle_radius=np.array(rho))
    except PlanningError as error:  # two pillars in one column share a projection
        assume(error.code != ErrorCode.OBSTACLES_DEGENERATE)
        raise
    assume(len(workspace.disc_layout.conflicting_pillars()) == 0)
    return workspace, np.array(configurations)
