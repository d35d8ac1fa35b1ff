"""
An independent check of a clearance certificate: dense samples and exact rationals.

A plan is a piecewise-linear synchronous motion through breakpoints
``positions`` (V, k, d). Between two breakpoints the relative position of two
robots, or of a robot and a fixed obstacle, is (1 - f) r0 + f r1; this module
re-derives its minimum without the core's code, two ways:

* dense: every pair on every leg at ``samples_per_leg`` + 1 evenly spaced f,
  with a norm that scales before squaring (no underflow, no overflow);
* exact: the closed-form minimum in rational arithmetic (``fractions``), for
  the (leg, pair) candidates that a float pass puts near the claimed value.

The breakpoints are the motion (they are what a Path carries), so both checks
take the float breakpoints as exact and interpolate relative positions, never
absolute ones: no cancellation at coordinates near 1e9.
"""

from fractions import Fraction
import math

import numpy as np

# Unit roundoff of float64.
UNIT_ROUNDOFF = np.finfo(float).eps / 2
# Agreement required between the certificate and the independent checks: this
# fraction of the claimed value plus ROUNDING_ULPS unit roundoffs of the scale
# (the largest coordinate), the rounding a float64 closed form cannot avoid.
RELATIVE = 1e-9
ROUNDING_ULPS = 8


def relative_positions(positions, obstacles):
    """
    Return (relative (V, P, d), first (P,), second (P,)) over the pairs that can collide.

    The pairs are every robot pair and every (robot, obstacle) pair; second >= k
    names obstacle second - k.
    """
    positions = np.asarray(positions, dtype=float)
    obstacles = np.asarray(obstacles, dtype=float).reshape(-1, positions.shape[2])
    count, k, d = positions.shape
    points = np.concatenate(
        [positions, np.broadcast_to(obstacles, (count, len(obstacles), d))], axis=1)
    first, second = np.triu_indices(points.shape[1], 1)
    keep = first < k
    first, second = first[keep], second[keep]
    return points[:, first] - points[:, second], first, second


def scaled_norm(vectors):
    """Return the Euclidean norms along the last axis without underflow or overflow."""
    largest = np.abs(vectors).max(axis=-1)
    safe = np.where(largest > 0, largest, 1.0)
    return largest * np.sqrt(((vectors / safe[..., None]) ** 2).sum(axis=-1))


def coordinate_scale(positions, obstacles):
    """Return the largest absolute coordinate of the motion and the obstacles."""
    return max(float(np.abs(positions).max(initial=0.0)),
               float(np.abs(np.asarray(obstacles, dtype=float)).max(initial=0.0)))


def dense_minimum(positions, obstacles, samples_per_leg=32):
    """Return the smallest pair distance over samples_per_leg + 1 points of every leg."""
    relative, _, _ = relative_positions(positions, obstacles)
    if relative.shape[1] == 0:
        return np.inf
    fractions = np.linspace(0.0, 1.0, samples_per_leg + 1)[:, None, None, None]
    samples = (1.0 - fractions) * relative[None, :-1] + fractions * relative[None, 1:]
    return float(scaled_norm(samples).min())


def float_leg_minima(relative):
    """Return the (V - 1, P) closed-form minima per leg and pair, in scaled float64."""
    start, end = relative[:-1], relative[1:]
    scale = np.maximum(np.abs(start).max(axis=-1), np.abs(end).max(axis=-1))
    safe = np.where(scale > 0, scale, 1.0)[..., None]
    start, end = start / safe, end / safe
    velocity = end - start
    speed2 = (velocity * velocity).sum(axis=-1)
    with np.errstate(divide='ignore', invalid='ignore'):
        t = np.where(speed2 > 0, -(start * velocity).sum(axis=-1) / speed2, 0.0)
    t = np.clip(t, 0.0, 1.0)[..., None]
    return scaled_norm((1.0 - t) * start + t * end) * safe[..., 0]


def exact_leg_minimum_squared(start, end):
    """Return the exact squared minimum of |(1 - f) start + f end| over f in [0, 1]."""
    r0 = [Fraction(float(v)) for v in start]
    r1 = [Fraction(float(v)) for v in end]
    velocity = [b - a for a, b in zip(r0, r1)]
    speed2 = sum(v * v for v in velocity)
    t = Fraction(0)
    if speed2:
        t = min(Fraction(1), max(Fraction(0), -sum(a * v for a, v in zip(r0, velocity)) / speed2))
    return sum((a + t * v) ** 2 for a, v in zip(r0, velocity))


def exact_minimum(positions, obstacles, claimed):
    """
    Return (exact squared minimum over the candidates, (leg, first, second) reaching it).

    Candidates are every (leg, pair) whose float closed form is within 1e-6 of
    ``claimed`` (plus rounding) or is the float minimum; the float pass is
    accurate to a few unit roundoffs, so no other pair can be closer.
    """
    relative, first, second = relative_positions(positions, obstacles)
    minima = float_leg_minima(relative)
    scale = coordinate_scale(positions, obstacles)
    limit = min(claimed, float(minima.min())) * (1 + 1e-6) + 64 * UNIT_ROUNDOFF * scale
    candidates = np.argwhere(minima <= limit)
    best, where = None, None
    for leg, pair in candidates[np.argsort(minima[tuple(candidates.T)])][:64]:
        value = exact_leg_minimum_squared(relative[leg, pair], relative[leg + 1, pair])
        if best is None or value < best:
            best, where = value, (int(leg), int(first[pair]), int(second[pair]))
    return best, where


def fraction_sqrt(value):
    """Return the float square root of a non-negative Fraction, even far outside float range."""
    if value == 0:
        return 0.0
    shift = (value.numerator.bit_length() - value.denominator.bit_length()) // 2
    return math.sqrt(float(value / Fraction(4) ** shift)) * 2.0 ** shift


def assert_certificate_agrees(positions, obstacles, claimed, samples_per_leg=32):
    """
    Assert ``claimed`` is the motion's minimum clearance, by dense samples and exactly.

    Never a silent collision: no sample is closer than claimed (1 - RELATIVE)
    minus the rounding allowance, and the exact minimum equals claimed within
    RELATIVE plus ROUNDING_ULPS unit roundoffs of the coordinate scale.
    Returns (dense minimum, exact minimum).
    """
    positions = np.asarray(positions, dtype=float)
    assert np.all(np.isfinite(positions)), 'non-finite breakpoint'
    assert claimed > 0, 'certificate %r is not positive' % claimed
    allowance = ROUNDING_ULPS * UNIT_ROUNDOFF * coordinate_scale(positions, obstacles)
    dense = dense_minimum(positions, obstacles, samples_per_leg)
    assert dense >= claimed * (1 - RELATIVE) - 2 * allowance, \
        'dense sample %r below the certificate %r' % (dense, claimed)
    squared, where = exact_minimum(positions, obstacles, claimed)
    low = max(claimed * (1 - RELATIVE) - allowance, 0.0)
    high = claimed * (1 + RELATIVE) + allowance
    assert Fraction(low) ** 2 <= squared <= Fraction(high) ** 2, \
        'exact minimum %r at (leg, robot, other) %s disagrees with the certificate %r' \
        % (fraction_sqrt(squared), where, claimed)
    return dense, fraction_sqrt(squared)
