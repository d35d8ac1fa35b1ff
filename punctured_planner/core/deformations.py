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


# Blocks up to this long are fitted in Python: SciPy's call costs more than the whole fit
# of a few values, and the spreading leg fits many small groups per request.
_PYTHON_FIT_SIZE = 32


def pool_adjacent_violators(values: list[float]) -> list[float]:
    """
    Return the non-decreasing least-squares fit of values (unit weights).

    Busing's O(n) pool-adjacent-violators pass (J. Stat. Softw. 102, 2022) with
    SciPy's choices: equal neighbours pool (>=) and every block keeps its
    weighted sum, so the result is SciPy's isotonic_regression bit for bit.
    """
    means = list(values)
    size = len(means)
    if size == 0:
        return []
    weights = [1.0] * size
    ends = [0] * (size + 1)  # block b is means[ends[b]:ends[b + 1]]
    ends[1] = 1
    block, i = 0, 1
    while i < size:
        block += 1
        mean, weight = means[i], 1.0
        if means[block - 1] >= mean:
            block -= 1
            total = weights[block] * means[block] + mean
            weight += weights[block]
            mean = total / weight
            while i + 1 < size and mean >= means[i + 1]:  # pool the values ahead
                i += 1
                total += means[i]
                weight += 1.0
                mean = total / weight
            while block > 0 and means[block - 1] >= mean:  # pool the blocks behind
                block -= 1
                total += weights[block] * means[block]
                weight += weights[block]
                mean = total / weight
        means[block], weights[block] = mean, weight
        ends[block + 1] = i + 1
        i += 1
    fit = []
    for b in range(block + 1):
        fit.extend([means[b]] * (ends[b + 1] - ends[b]))
    return fit


def isotonic_fit(values: np.ndarray) -> np.ndarray | list[float]:
    """Return the non-decreasing least-squares fit of values: SciPy's, or the same in Python."""
    if isotonic_regression is None or values.size <= _PYTHON_FIT_SIZE:
        return pool_adjacent_violators(values.tolist())
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
    size = n * k
    bounds = np.empty(sorted_obstacle_projections.size + 2)  # interval i: bounds[i:i + 2]
    bounds[0], bounds[1:-1], bounds[-1] = -np.inf, sorted_obstacle_projections, np.inf
    interval = np.searchsorted(sorted_obstacle_projections, projections)
    # One group per (configuration, interval); robots sorted inside each group.
    group = (np.arange(n)[:, None] * bounds.size + interval).ravel()
    interval = interval.ravel()
    flat = projections.ravel()
    order = np.lexsort((flat, group))
    group_sorted = group[order]
    first = np.empty(size, dtype=bool)  # whether each sorted robot starts its group
    first[0] = True
    np.not_equal(group_sorted[1:], group_sorted[:-1], out=first[1:])
    starts = first.nonzero()[0]
    member = first.cumsum() - 1  # the group of each sorted robot
    sizes = np.bincount(member)
    rank = np.arange(size) - starts[member]
    count = sizes[member]
    interval_sorted = interval[order]
    low, high = bounds[interval_sorted], bounds[interval_sorted + 1]
    # Nothing to warn about: count >= 1, and a length is positive or inf (no obstacles).
    spacing = np.minimum(min_spacing, (high - low) / (count + 1))
    offset = (rank + 1) * spacing
    z = flat[order] - offset
    # Only groups whose shifted positions are out of order need a fit: an
    # ordered z is its own isotonic regression (up to the rounding of pooled
    # ties). A descent across two groups marks the first of them.
    disordered = np.zeros(starts.size, dtype=bool)
    disordered[member[:-1][z[1:] < z[:-1]]] = True
    for start, block_size in zip(starts[disordered].tolist(), sizes[disordered].tolist()):
        block = slice(start, start + block_size)
        z[block] = isotonic_fit(z[block])
    # np.clip's own rule (the upper bound wins where the bounds cross), without its wrapper
    z = np.minimum(np.maximum(z, low), high - (count + 1) * spacing)
    result = np.empty(size)
    result[order] = z + offset
    used = np.empty(size)
    used[order] = spacing
    return result.reshape(n, k), used.reshape(n, k)
