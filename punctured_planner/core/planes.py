"""
Coordinate-first arrays (d, ...) of a piecewise-linear motion, and the boxes that bound it.

The certificate (doc/design.md section 9) and the refinement (section 14) keep
their motions coordinate first: each coordinate of every point is one contiguous
plane, so a length is d products added plane by plane. Both prune pairs
exactly with the same bound: the motion is linear between its breakpoints, so
the box of a point's breakpoints over a run of legs holds all of that run, and
two points whose boxes stay farther apart than some distance never come nearer
there.
"""

import numpy as np


def planes_dot(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """Return (...) the dot products of coordinate-first vectors (d, ...), plane by plane."""
    total = first[0] * second[0]
    for axis in range(1, first.shape[0]):
        total += first[axis] * second[axis]
    return total


def planes_length(vectors: np.ndarray) -> np.ndarray:
    """Return (...) the lengths of coordinate-first vectors (d, ...)."""
    return np.sqrt(planes_dot(vectors, vectors))


def run_boxes(planes: np.ndarray, begins: np.ndarray,
              ends: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return (low, high), each (d, runs, ...): every point's box over each run of legs.

    planes (d, U, ...) holds the breakpoints; run i is breakpoints begins[i]
    to ends[i], both included, and runs follow each other (ends[i] is
    begins[i + 1]). The motion is linear between breakpoints, so the box of a
    run's breakpoints holds all of the run.
    """
    piece = planes[:, begins[0]:ends[-1] + 1]
    offsets = begins - begins[0]
    low = np.minimum(np.minimum.reduceat(piece, offsets, axis=1), planes[:, ends])
    high = np.maximum(np.maximum.reduceat(piece, offsets, axis=1), planes[:, ends])
    return low, high


def box_distance(first_low: np.ndarray, first_high: np.ndarray, second_low: np.ndarray,
                 second_high: np.ndarray) -> np.ndarray:
    """
    Return (...) how far apart two boxes (d, ...) stay: a lower bound on their points' distance.

    A point box (a pillar's centre) is its own low and high.
    """
    gap = np.maximum(first_low - second_high, second_low - first_high)
    np.maximum(gap, 0.0, out=gap)
    return planes_length(gap)
