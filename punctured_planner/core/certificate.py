"""Exact clearance certificate of a piecewise-linear synchronous motion.

Between two breakpoints every robot moves linearly, so the relative position
of two robots (or of a robot and a fixed obstacle) is r(t) = r0 + t v on
t in [0, 1] and its minimum norm is reached at t* = clip(-<r0, v> / <v, v>, 0, 1).
Evaluating that closed form for every leg and every pair gives the exact
minimum distance over the whole motion (design.md section 2), not a sample.
"""

from dataclasses import dataclass

import numpy as np

# Elements of (legs x pairs x d) arrays handled per chunk: bounds peak memory.
_CHUNK_ELEMENTS = 1 << 22


@dataclass(frozen=True)
class Clearance:
    """The minimum distance of a motion and where it is reached.

    kind is 'robots' (indices = two robots) or 'obstacle' (indices = robot,
    obstacle); leg is the breakpoint interval [leg, leg + 1] and fraction the
    position inside it, so tau = times[leg] + fraction (times[leg+1] - times[leg]).
    kind is 'none' (distance inf) when there is nothing to collide with.
    """

    distance: float
    kind: str
    indices: tuple
    leg: int
    fraction: float
    tau: float


def segment_minimum(start, velocity):
    """Return (min distance, t*) of |start + t velocity| over t in [0, 1], elementwise.

    start and velocity have shape (..., d); the result has shape (...).
    """
    speed2 = np.einsum('...i,...i->...', velocity, velocity)
    along = np.einsum('...i,...i->...', start, velocity)
    with np.errstate(divide='ignore', invalid='ignore'):
        t = np.where(speed2 > 0, np.clip(-along / speed2, 0.0, 1.0), 0.0)
    closest = start + t[..., None] * velocity
    return np.sqrt(np.einsum('...i,...i->...', closest, closest)), t


def _moving_legs(positions):
    """Return the indices of legs along which something moves (at least one leg)."""
    moving = np.flatnonzero(np.any(positions[1:] != positions[:-1], axis=(1, 2)))
    return moving if moving.size else np.array([0])


def _best(distances, fractions, legs, pair_a, pair_b):
    """Return (distance, leg, a, b, fraction) at the argmin of (legs, pairs) distances."""
    flat = int(np.argmin(distances))
    leg, pair = np.unravel_index(flat, distances.shape)
    return (float(distances[leg, pair]), int(legs[leg]), int(pair_a[pair]),
            int(pair_b[pair]), float(fractions[leg, pair]))


def robot_pair_minimum(positions, legs):
    """Return (distance, leg, a, b, fraction) of the closest robot pair over the given legs."""
    k, d = positions.shape[1:]
    a, b = np.triu_indices(k, 1)
    best = (np.inf, 0, 0, 0, 0.0)
    step = max(1, _CHUNK_ELEMENTS // max(1, a.size * d))
    for first in range(0, legs.size, step):
        chunk = legs[first:first + step]
        start = positions[chunk][:, a] - positions[chunk][:, b]
        end = positions[chunk + 1][:, a] - positions[chunk + 1][:, b]
        distances, fractions = segment_minimum(start, end - start)
        candidate = _best(distances, fractions, chunk, a, b)
        best = min(best, candidate, key=lambda item: item[0])
    return best


def obstacle_minimum(positions, legs, obstacles):
    """Return (distance, leg, robot, obstacle, fraction) of the closest robot-obstacle pair."""
    k, d = positions.shape[1:]
    robot, obstacle = (g.ravel() for g in np.meshgrid(np.arange(k), np.arange(len(obstacles)),
                                                       indexing='ij'))
    start = positions[legs][:, robot] - obstacles[obstacle]
    velocity = positions[legs + 1][:, robot] - positions[legs][:, robot]
    distances, fractions = segment_minimum(start, velocity)
    return _best(distances, fractions, legs, robot, obstacle)


def certify(times, positions, obstacles):
    """Return the Clearance of the motion through breakpoints (times (V,), positions (V, k, d)).

    Exact (closed form per leg) over every robot pair and every robot-obstacle
    pair; legs where nothing moves are covered by their neighbours' end points.
    """
    legs = _moving_legs(positions)
    candidates = []
    if positions.shape[1] > 1:
        distance, leg, a, b, fraction = robot_pair_minimum(positions, legs)
        candidates.append((distance, 'robots', (a, b), leg, fraction))
    if len(obstacles) and positions.shape[1]:
        distance, leg, a, b, fraction = obstacle_minimum(positions, legs, obstacles)
        candidates.append((distance, 'obstacle', (a, b), leg, fraction))
    if not candidates:
        return Clearance(np.inf, 'none', (), 0, 0.0, 0.0)
    distance, kind, indices, leg, fraction = min(candidates, key=lambda item: item[0])
    next_leg = min(leg + 1, times.size - 1)
    tau = float(times[leg] + fraction * (times[next_leg] - times[leg]))
    return Clearance(distance, kind, indices, leg, fraction, tau)
