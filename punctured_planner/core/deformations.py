"""
The deformations that carry any configuration onto the axis: D, S and phi.

* D, the desingularisation (paper, Section 3): robot with paper index j = r + i
  (i = 1..k) moves by t (j - 1) eps(C) e1; only for cp(C) < k + r.
* S, our spreading leg (doc/design.md section 5, variant 'spread'): robots move
  along e1 only, keeping their order and their interval between obstacle
  projections, to the nearest positions that are `min_spacing` apart.
* phi, the projection onto the axis (paper, equation (3.2)): x + t (p(x) e1 - x).
"""

import numpy as np

try:
    from scipy.optimize import isotonic_regression
except ImportError:  # SciPy < 1.12: Ubuntu 24.04's python3-scipy (ROS 2 Jazzy) is 1.11
    isotonic_regression = None


def pool_adjacent_violators(values: np.ndarray) -> np.ndarray:
    """
    Return the non-decreasing least-squares fit of values (unit weights).

    The classic pool-adjacent-violators pass; used only where SciPy lacks
    scipy.optimize.isotonic_regression (before 1.12).
    """
    means, counts = [], []
    for value in values:
        means.append(float(value))
        counts.append(1)
        while len(means) > 1 and means[-2] > means[-1]:
            mean, count = means.pop(), counts.pop()
            means[-1] = (means[-1] * counts[-1] + mean * count) / (counts[-1] + count)
            counts[-1] += count
    return np.repeat(means, counts)


def isotonic_fit(values: np.ndarray) -> np.ndarray:
    """Return the non-decreasing least-squares fit of values: SciPy's, or the fallback."""
    if isotonic_regression is None:
        return pool_adjacent_violators(values)
    return isotonic_regression(values).x


def desingularizing_shift(projection_counts: np.ndarray, eps: np.ndarray, robot_count: int,
                          obstacle_count: int) -> np.ndarray:
    """Return the (n, k) e1 shift of D(C, 1): (j - 1) eps(C) for paper index j, 0 in A_{k+r}."""
    indices = obstacle_count + np.arange(robot_count)
    singular = projection_counts < robot_count + obstacle_count
    return np.where(singular[:, None], indices[None, :] * eps[:, None], 0.0)


def desingularize(configurations: np.ndarray, shift: np.ndarray, e1: np.ndarray) -> np.ndarray:
    """Return D(C, 1) = C + shift e1 for configurations (n, k, d) and shifts (n, k)."""
    return configurations + shift[..., None] * e1


def _interval_spacing(lengths, counts, min_spacing):
    """Return the spacing used in each interval: min_spacing, or evenly what fits."""
    with np.errstate(divide='ignore', invalid='ignore'):
        return np.minimum(min_spacing, lengths / (counts + 1))


def spread(projections: np.ndarray, sorted_obstacle_projections: np.ndarray,
           min_spacing: float) -> tuple[np.ndarray, np.ndarray]:
    """
    Return S(C, 1) projections: the nearest order-preserving spaced positions.

    projections (n, k) are pairwise distinct and distinct from the obstacle
    projections (they come out of D). In each interval between consecutive
    obstacle projections, with m robots and spacing g = min(min_spacing,
    length / (m + 1)), the robots move to the Euclidean projection of their
    positions onto {y : y_1 >= a + g, y_{i+1} - y_i >= g, y_m <= b - g}. With
    z_i = y_i - i g this is isotonic regression with common bounds
    [a, b - (m + 1) g], solved by clipping the unconstrained isotonic fit. A
    projection onto a convex set is 1-Lipschitz, and order and counts are
    locally constant on A_{k+r}, so S is continuous there.
    Returns (spread projections (n, k), spacing used per robot (n, k)).
    """
    n, k = projections.shape
    bounds = np.concatenate([[-np.inf], sorted_obstacle_projections, [np.inf]])
    interval = np.searchsorted(sorted_obstacle_projections, projections)
    # One group per (configuration, interval); robots sorted inside each group.
    group = np.arange(n)[:, None] * bounds.size + interval
    flat = projections.ravel()
    order = np.lexsort((flat, group.ravel()))
    group_sorted = group.ravel()[order]
    size = group_sorted.size
    first = np.empty(size, dtype=bool)  # whether each sorted robot starts its group
    first[0] = True
    np.not_equal(group_sorted[1:], group_sorted[:-1], out=first[1:])
    starts = np.flatnonzero(first)
    member = np.cumsum(first) - 1  # the group of each sorted robot
    sizes = np.diff(starts, append=size)
    rank = np.arange(size) - starts[member]
    count = sizes[member]
    interval_sorted = interval.ravel()[order]
    low, high = bounds[interval_sorted], bounds[interval_sorted + 1]
    spacing = _interval_spacing(high - low, count, min_spacing)
    z = flat[order] - (rank + 1) * spacing
    # Only groups whose shifted positions are out of order need a fit: an
    # ordered z is its own isotonic regression (up to the rounding of pooled
    # ties). A descent across two groups marks the first of them.
    disordered = np.zeros(starts.size, dtype=bool)
    disordered[member[:-1][z[1:] < z[:-1]]] = True
    for start, block_size in zip(starts[disordered].tolist(), sizes[disordered].tolist()):
        block = slice(start, start + block_size)
        z[block] = isotonic_fit(z[block])
    z = np.clip(z, low, high - (count + 1) * spacing)
    result = np.empty(n * k)
    result[order] = z + (rank + 1) * spacing
    used = np.empty(n * k)
    used[order] = spacing
    return result.reshape(n, k), used.reshape(n, k)
