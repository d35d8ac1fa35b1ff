"""The strata A_i = {C : cp(C) = i} and the desingularisation scale eps(C) (paper, Section 3).

All k + r points count, obstacles included: cp(C) is the number of distinct
values of p over q_1..q_r, x_1..x_k, so r <= cp(C) <= k + r (at least 1 when r = 0).
"""

import numpy as np


def all_projections(robot_projections, obstacle_projections):
    """Return (n, r + k) projections in the paper's numbering: obstacles first, then robots."""
    n = robot_projections.shape[0]
    obstacles = np.broadcast_to(obstacle_projections, (n, obstacle_projections.size))
    return np.concatenate([obstacles, robot_projections], axis=1)


def projection_count(robot_projections, obstacle_projections):
    """Return cp(C_m) for each configuration: distinct projections among all k + r points.

    robot_projections is (n, k), obstacle_projections (r,); the result is (n,) ints.
    """
    gaps = np.diff(np.sort(all_projections(robot_projections, obstacle_projections)), axis=1)
    return 1 + np.count_nonzero(gaps > 0, axis=1)


def epsilon(robot_projections, obstacle_projections, fallback):
    """Return eps(C_m) = min{|p(a) - p(b)| : p(a) != p(b)} / (k + r) for each configuration.

    When every projection coincides (only possible for r <= 1) the set is empty;
    `fallback` / (k + r), a constant, keeps D continuous on that stratum.
    """
    points = all_projections(robot_projections, obstacle_projections)
    gaps = np.diff(np.sort(points), axis=1)
    smallest = np.where(gaps > 0, gaps, np.inf).min(axis=1, initial=np.inf)
    return np.where(np.isfinite(smallest), smallest, fallback) / points.shape[1]
