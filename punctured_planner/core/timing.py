"""
Time parameterisation of a synchronous piecewise-linear motion (doc/design.md section 8).

Any reparameterisation common to all robots keeps the motion collision-free,
so each leg gets the duration that lets its fastest robot move at max_speed.
"""

import numpy as np
import numpy.typing as npt


def leg_lengths(positions: np.ndarray) -> np.ndarray:
    """Return the (V - 1,) largest robot displacement along each leg."""
    steps = np.diff(positions, axis=0)
    if steps.shape[1] == 0:
        return np.zeros(steps.shape[0])
    return np.sqrt(np.einsum('vkd,vkd->vk', steps, steps)).max(axis=1)


def length_times(positions: np.ndarray, waypoint_indices: np.ndarray) -> np.ndarray:
    """
    Return (V,) breakpoint parameters with waypoint m at tau_m = m / (n - 1).

    Inside a segment each leg takes a share of [tau_m, tau_{m+1}] proportional
    to its length (its fastest robot's displacement): continuous in the
    positions, and a leg of length 0 takes no time.
    """
    n = len(waypoint_indices)
    lengths = leg_lengths(positions)
    times = np.empty(len(positions))
    for m in range(n - 1):
        first, last = waypoint_indices[m], waypoint_indices[m + 1]
        cumulative = np.concatenate([[0.0], np.cumsum(lengths[first:last])])
        times[first:last + 1] = (m + cumulative / cumulative[-1]) / (n - 1)
    times[waypoint_indices] = np.arange(n) / (n - 1)
    return times


def breakpoint_stamps(positions: np.ndarray, max_speed: float) -> np.ndarray:
    """Return (V,) seconds from the start at which the robots reach each breakpoint."""
    if not max_speed > 0:
        raise ValueError('max_speed must be positive')
    return np.concatenate([[0.0], np.cumsum(leg_lengths(positions) / max_speed)])


def resample(values: npt.ArrayLike, positions: np.ndarray, samples_per_leg: int
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Insert samples_per_leg evenly spaced samples inside every leg.

    values (V,) are breakpoint parameters or stamps (both linear inside a
    leg), positions (V, k, d). Returns (values (M,), positions (M, k, d),
    is_breakpoint (M,) bool); every breakpoint is kept exactly.
    """
    values = np.asarray(values, dtype=float)
    if samples_per_leg <= 0:
        return values, positions, np.ones(values.size, dtype=bool)
    fractions = np.arange(samples_per_leg + 1) / (samples_per_leg + 1)
    start_values, start_positions = values[:-1], positions[:-1]
    inner_values = start_values[:, None] + np.diff(values)[:, None] * fractions[None, :]
    inner_positions = (start_positions[:, None]
                       + np.diff(positions, axis=0)[:, None] * fractions[None, :, None, None])
    # Fraction 0 is the breakpoint itself: copy it so it stays bit for bit.
    inner_positions[:, 0] = start_positions
    k, d = positions.shape[1:]
    is_breakpoint = np.zeros(inner_values.shape, dtype=bool)
    is_breakpoint[:, 0] = True
    return (np.concatenate([inner_values.ravel(), values[-1:]]),
            np.concatenate([inner_positions.reshape(-1, k, d), positions[-1:]]),
            np.concatenate([is_breakpoint.ravel(), [True]]))
