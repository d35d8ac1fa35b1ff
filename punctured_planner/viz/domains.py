"""
Domain index over grids of requests: the data of the domain picture.

domain_values computes l = cp(C_1) + ... + cp(C_n) from the frame projections
as plan() does (the number of distinct projections among obstacles and robots),
vectorised over any number of requests (the tests check it against plan()), and
NaN for a request plan() refuses (a robot on an
obstacle, two robots at one point). The grids vary robot 0 only; the lower
strata are lines and points, so every grid axis contains the special values
(where robot 0 shares a projection with an obstacle or another robot) exactly.
"""

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from ..core import Workspace
from ..core.pairs import point_pairs
from ..core.strata import projection_count, projection_gaps


def snapped_axis(low: float, high: float, count: int, special: npt.ArrayLike = ()) -> np.ndarray:
    """
    Return count evenly spaced values in [low, high], the nearest moved onto each special value.

    The axis stays (nearly) uniform, so it can be drawn as an image, and
    contains every special value inside [low, high] exactly.
    """
    values = np.linspace(low, high, count)
    for value in np.asarray(special, dtype=float).ravel():
        if low <= value <= high:
            values[int(np.argmin(np.abs(values - value)))] = value
    return values


def _invalid(configurations, obstacles):
    """Return (...,) True where some C_m has a robot on an obstacle or two robots at one point."""
    a, b = point_pairs(configurations.shape[-2])
    same = np.all(configurations[..., a, :] == configurations[..., b, :], axis=-1)
    bad = same.any(axis=(-2, -1))
    if len(obstacles):
        on = np.all(configurations[..., :, None, :] == obstacles, axis=-1)
        bad |= on.any(axis=(-3, -2, -1))
    return bad


def domain_values(workspace: Workspace, configurations: npt.ArrayLike) -> np.ndarray:
    """Return the domain l of every request in configurations (..., n, k, d); NaN if refused."""
    configurations = np.asarray(configurations, dtype=float)
    projections = workspace.frame.project(configurations)
    counts = projection_count(projection_gaps(projections, workspace.obstacle_projections))
    values = counts.sum(axis=-1).astype(float)
    values[_invalid(configurations, workspace.obstacles)] = np.nan
    return values


def start_plane_grid(workspace: Workspace, configurations: npt.ArrayLike,
                     xs: Sequence[float] | np.ndarray,
                     ys: Sequence[float] | np.ndarray) -> np.ndarray:
    """Return (len(ys), len(xs)) domains with robot 0 of C_1 at (x, y), all else fixed (d = 2)."""
    base = np.asarray(configurations, dtype=float)
    grid = np.broadcast_to(base, (len(ys), len(xs)) + base.shape).copy()
    grid[:, :, 0, 0, 0] = np.asarray(xs)[None, :]
    grid[:, :, 0, 0, 1] = np.asarray(ys)[:, None]
    return domain_values(workspace, grid)


def start_goal_grid(workspace: Workspace, configurations: npt.ArrayLike,
                    starts: Sequence[float] | np.ndarray,
                    goals: Sequence[float] | np.ndarray) -> np.ndarray:
    """
    Return (len(goals), len(starts)) domains of two-configuration requests C_1, C_2.

    All robots move along x together: in C_1 robot 0's x is the start value
    and every other robot keeps its x offset from robot 0; the same in C_2 with
    the goal value. With one robot this is the plane (x of C_1, x of C_2); with
    offsets equal to obstacle gaps every stratum, hence every domain, is met.
    """
    base = np.asarray(configurations, dtype=float)
    if base.shape[0] != 2:
        raise ValueError('start_goal_grid needs exactly two configurations')
    grid = np.broadcast_to(base, (len(goals), len(starts)) + base.shape).copy()
    offsets = base[:, :, 0] - base[:, :1, 0]
    grid[..., 0, :, 0] = np.asarray(starts)[None, :, None] + offsets[0]
    grid[..., 1, :, 0] = np.asarray(goals)[:, None, None] + offsets[1]
    return domain_values(workspace, grid)


def start_goal_specials(workspace: Workspace, configurations: npt.ArrayLike) -> list[np.ndarray]:
    """Return, per configuration, robot 0's x values where some robot meets an obstacle's x."""
    base = np.asarray(configurations, dtype=float)
    offsets = base[:, :, 0] - base[:, :1, 0]
    obstacle_x = workspace.obstacles[:, 0]
    return [np.unique(obstacle_x[None, :] - offsets[m][:, None]) for m in range(2)]
