"""
The strata A_i = {C : cp(C) = i} and the desingularisation scale eps(C) (paper, Section 3).

All k + r points count, obstacles included: cp(C) is the number of distinct
values of p over q_1..q_r, x_1..x_k, so r <= cp(C) <= k + r (at least 1 when r = 0;
doc/design.md section 2).
"""

import numpy as np


def all_projections(robot_projections: np.ndarray,
                    obstacle_projections: np.ndarray) -> np.ndarray:
    """Return (..., r + k) projections in the paper's numbering: obstacles first, then robots."""
    k = robot_projections.shape[-1]
    r = obstacle_projections.size
    points = np.empty(robot_projections.shape[:-1] + (r + k,))
    points[..., :r] = obstacle_projections
    points[..., r:] = robot_projections
    return points


def projection_gaps(robot_projections: np.ndarray,
                    obstacle_projections: np.ndarray) -> np.ndarray:
    """
    Return the (..., k + r - 1) gaps between consecutive sorted projections of each C_m.

    robot_projections is (..., k): any number of configurations, of any batch shape.
    """
    ordered = np.sort(all_projections(robot_projections, obstacle_projections), axis=-1)
    return ordered[..., 1:] - ordered[..., :-1]


def projection_count(gaps: np.ndarray) -> np.ndarray:
    """
    Return cp(C_m) for each configuration: distinct projections among all k + r points.

    gaps are the (..., k + r - 1) sorted projection gaps; the result is (...) ints.
    """
    # (gaps > 0).sum is count_nonzero's own sum, without its Python wrapper
    return 1 + (gaps > 0).sum(axis=-1, dtype=np.intp)


def epsilon(gaps: np.ndarray, fallback: float) -> np.ndarray:
    """
    Return eps(C_m) = min{|p(a) - p(b)| : p(a) != p(b)} / (k + r) for each configuration.

    When every projection coincides (only possible for r <= 1) the set is empty;
    `fallback` / (k + r), a constant, keeps D continuous on that stratum.
    """
    smallest = np.minimum.reduce(gaps, axis=1, where=gaps > 0, initial=np.inf)
    return np.where(np.isfinite(smallest), smallest, fallback) / (gaps.shape[1] + 1)
