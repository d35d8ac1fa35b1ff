"""
Hypothesis strategies for the core: random and degenerate requests.

Coordinates come from a coarse grid so that robots share projections with
each other and with obstacles; modes force all robots onto one vertical line,
or every configuration into the lowest stratum (every robot above an obstacle).
"""

from hypothesis import strategies as st
import numpy as np

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
