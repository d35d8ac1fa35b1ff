"""
Exact clearance certificate of a piecewise-linear synchronous motion.

Between two breakpoints every robot moves linearly, so the relative position
of two robots (or of a robot and a fixed obstacle) is r(t) = r0 + t v on
t in [0, 1] and its minimum norm is reached at t* = clip(-<r0, v> / <v, v>, 0, 1).
Evaluating that closed form for every leg and every pair gives the exact
minimum distance over the whole motion (doc/design.md section 9), not a sample.

For many robots the pairs are pruned first, exactly: the closest pair over
all breakpoints gives an upper bound U on the answer, and a pair whose
coordinate ranges over a leg stay more than U apart on some axis cannot beat
it. A sort along the best axis (sweep and prune) finds the other pairs. Where
every pair is evaluated, runs of legs are pruned the same way: a pair whose
boxes over a run of legs stay farther apart than the run starts' closest
pair is not evaluated there (_near_runs).
"""

from dataclasses import dataclass
from dataclasses import replace
from operator import attrgetter

import numpy as np
from scipy.spatial import cKDTree

from .pairs import point_pairs, PointPair, with_obstacles
from .planes import box_distance, planes_dot, planes_length, run_boxes

# A clearance is trusted only above this fraction of the coordinate scale: the
# breakpoints and the closed form each round to a few ulps of the largest
# coordinate, so anything closer than ~1e4 ulps may be an artefact.
RELATIVE_RESOLUTION = 1e-12
# Coordinate scales certified as they are; outside, rescaled by a power of two.
_UNSCALED = (2.0 ** -60, 2.0 ** 60)
# Up to this many robots every pair is evaluated on every leg (cheapest there).
_DIRECT_ROBOTS = 64
# Elements of (legs x pairs x d) arrays handled per chunk: bounds peak memory.
_CHUNK_ELEMENTS = 1 << 22
# Elements of the (d x legs x pairs) arrays of one pass of the closed form: a few
# hundred kB stay in cache and in malloc's arenas; one pass over megabytes is about
# four times slower (fresh pages for every temporary).
_PASS_ELEMENTS = 1 << 16
# Legs per run of the exact pair filter (_near_runs): boxes over fewer legs prune more
# pairs, each run costs a pass of its own (with 16 legs, 40-robot plans keep 3 - 6% of
# the pairs' runs refined, 8 - 11% unrefined).
_RUN_LEGS = 16
# Pair-legs (pairs x legs) from which the run filter pays for its boxes: measured on
# point and disc plans, refined and not, it took 2-4x as long as evaluating every pair
# below 10,000 (k = 8: 449 against 124 us on 145 breakpoints), broke even near 25,000
# and saved a quarter at 36,000 (k = 20) and two thirds at 130,000 (k = 40).
_RUN_FILTER_ENTRIES = 1 << 15
# The pair filters' allowance for rounding (here and in refine.py), as a share of the
# coordinate and radius scale: the closed form and the bounds each round to a few ulps
# of it, 1e5 times less.
BOUND_SLACK = 1e-9


@dataclass(frozen=True)
class Clearance:
    """
    The minimum distance of a motion and where it is reached.

    kind is 'robots' (indices = two robots) or 'obstacle' (indices = robot,
    obstacle); leg is the breakpoint interval [leg, leg + 1] and fraction the
    position inside it, so tau = times[leg] + fraction (times[leg+1] - times[leg]).
    kind is 'none' (distance inf) when there is nothing to collide with.
    resolution is the smallest distance the motion's coordinates can certify.
    """

    distance: float
    kind: str
    indices: tuple
    leg: int
    fraction: float
    tau: float
    resolution: float = 0.0


@dataclass(frozen=True)
class _Closest:
    """The smallest value found (a distance or a surface gap), its pair and where it is."""

    value: float
    leg: int
    first: int     # a robot
    second: int    # a robot, or obstacle second - k
    fraction: float


_NOT_FOUND = _Closest(np.inf, 0, 0, 0, 0.0)
# The key of min() over _Closest values (the first of equals wins).
_BY_VALUE = attrgetter('value')


@dataclass(frozen=True)
class _PairMinima:
    """Each pair's smallest distance over the legs (pairs,), its leg and its fraction."""

    distance: np.ndarray
    leg: np.ndarray
    fraction: np.ndarray


@dataclass(frozen=True)
class _Runs:
    """Runs of _RUN_LEGS legs and the pairs evaluated in each (_near_runs)."""

    firsts: np.ndarray   # (R,) each run's first leg
    kept: np.ndarray     # (R, pairs) bool


def segment_minimum(start: np.ndarray, velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """
    Return (min squared distance, t*) of |start + t velocity| over t in [0, 1], elementwise.

    start and velocity are coordinate first, shape (d, ...) (one contiguous
    plane per coordinate: much faster than a trailing axis of 2 or 3); the
    result has shape (...). The distance is taken from the closest point
    itself, not from |r0|^2 - <r0, v>^2 / |v|^2, which cancels catastrophically
    when robots nearly touch.
    """
    speed2 = planes_dot(velocity, velocity)
    t = planes_dot(start, velocity)
    # Where nothing moves t is 0 already (a dot product with 0): any divisor keeps it.
    np.maximum(speed2, np.finfo(float).tiny, out=speed2)
    np.divide(t, speed2, out=t)
    np.negative(t, out=t)
    np.maximum(t, 0.0, out=t)
    np.minimum(t, 1.0, out=t)
    closest = t * velocity
    closest += start
    return planes_dot(closest, closest), t


def _argmin_over_legs(start, end, legs, a, b, offsets=None):
    """
    Return the _Closest of the pairs (a[i], b[i]) over legs: the smallest segment minimum.

    start and end are (d, legs, pairs). value is the distance, or with offsets
    (pairs,) the distance minus the pair's offset (a surface gap): then each
    pair's own minimum over the legs counts, and the smallest gap may belong to
    a pair that is not the closest.
    """
    if offsets is None:
        squared, fractions = segment_minimum(start, end - start)
        leg, pair = divmod(int(np.argmin(squared)), squared.shape[1])
        return _Closest(float(np.sqrt(squared[leg, pair])), int(legs[leg]), int(a[pair]),
                        int(b[pair]), float(fractions[leg, pair]))
    relative = np.concatenate([start, end[:, -1:]], axis=1)
    return _smallest(_per_pair_minima(relative, np.arange(relative.shape[2])), legs, offsets,
                     a, b)


def _per_pair_minima(planes, a, b=None, runs=None):
    """
    Return each pair's _PairMinima: its smallest distance over the legs, and where.

    planes is (d, V, N): points at the breakpoints, coordinate first; the pairs
    are (a[i], b[i]), or with b None the points themselves are the pairs'
    relative positions (a selects them). The legs are taken a cache-sized pass
    at a time (_PASS_ELEMENTS), each pass gathering its own pairs; with runs
    (_Runs of _near_runs) a pass is one run and takes only the pairs kept there
    (a pair kept in no run keeps distance inf).
    """
    d, v, _ = planes.shape
    count = a.size
    best = np.full(count, np.inf)
    leg = np.zeros(count, dtype=int)
    fraction = np.zeros(count)
    passes: list[tuple[int, slice | np.ndarray]]
    if runs is None:
        step = max(1, _PASS_ELEMENTS // max(1, d * count))
        passes = [(first, slice(None)) for first in range(0, v - 1, step)]
    else:
        step = _RUN_LEGS
        passes = [(int(first), np.flatnonzero(kept))
                  for first, kept in zip(runs.firsts, runs.kept)]
    for first, pairs in passes:
        chosen = a[pairs]
        if chosen.size == 0:
            continue
        last = min(first + step, v - 1)
        window = planes[:, first:last + 1]
        relative = (np.take(window, chosen, axis=-1) if b is None
                    else _pair_differences(window, chosen, b[pairs]))
        start, end = relative[:, :-1], relative[:, 1:]
        squared, fractions = segment_minimum(start, end - start)
        pass_leg = np.argmin(squared, axis=0)
        columns = np.arange(chosen.size)
        value = squared[pass_leg, columns]
        # Strictly better only: each pair keeps the first leg of its smallest distance.
        better = value < best[pairs]
        improved = np.arange(count)[pairs][better]
        best[improved] = value[better]
        leg[improved] = first + pass_leg[better]
        fraction[improved] = fractions[pass_leg, columns][better]
    return _PairMinima(np.sqrt(best), leg, fraction)


def _near_runs(planes, a, b, offsets, slack):
    """
    Return the _Runs: runs of _RUN_LEGS legs, and the pairs that matter in each.

    For each offsets (pairs,) of the list the smallest value is the smallest
    distance - offsets over every pair and leg; a run's first breakpoint (and
    the last breakpoint) bounds it from above, and a pair's boxes over a run
    (the motion is linear between breakpoints) bound its distance there from
    below. A pair whose bound exceeds every smallest value by more than slack
    (far above rounding) cannot hold one in that run, nor tie: its legs there
    change no pair's smallest that any smallest value takes (design, 9).
    """
    v = planes.shape[1]
    firsts = np.arange(0, v - 1, _RUN_LEGS)
    ends = np.append(firsts[1:], v - 1)
    low, high = run_boxes(planes, firsts, ends)
    lower = box_distance(np.take(low, a, axis=-1), np.take(high, a, axis=-1),
                         np.take(low, b, axis=-1), np.take(high, b, axis=-1))
    lower -= slack
    upper = planes_length(_pair_differences(planes[:, np.append(firsts, v - 1)], a, b))
    kept = np.zeros(lower.shape, dtype=bool)
    for offset in offsets:
        kept |= lower - offset <= float((upper - offset).min())
    return _Runs(firsts, kept)


def _smallest(minima, legs, offsets, a, b):
    """Return the _Closest of the pair (a[i], b[i]) whose distance - offset is smallest."""
    values = minima.distance - offsets
    pair = int(np.argmin(values))
    return _Closest(float(values[pair]), int(legs[minima.leg[pair]]), int(a[pair]), int(b[pair]),
                    float(minima.fraction[pair]))


def _coordinate_first(points):
    """Return (V, N, d) points as a contiguous (d, V, N) array."""
    return np.ascontiguousarray(np.moveaxis(points, 2, 0))


def _pair_differences(planes, a, b):
    """
    Return planes[..., a] - planes[..., b], contiguous with the pairs last.

    np.take keeps that layout; a fancy index on the last axis would put the pairs
    first in memory and make every later pass strided (about 3x slower).
    """
    return np.take(planes, a, axis=-1) - np.take(planes, b, axis=-1)


def _pairs_minimum(points, legs, a, b, offsets=None):
    """Return the _Closest of the pairs (a[i], b[i]) over legs."""
    best = _NOT_FOUND
    planes = _coordinate_first(points)
    step = max(1, _CHUNK_ELEMENTS // max(1, a.size * points.shape[2]))
    for first in range(0, legs.size, step):
        chunk = legs[first:first + step]
        start = _pair_differences(planes[:, chunk], a, b)
        end = _pair_differences(planes[:, chunk + 1], a, b)
        best = min(best, _argmin_over_legs(start, end, chunk, a, b, offsets),
                   key=_BY_VALUE)
    return best


def _pruned_minima(planes, a, b, offsets):
    """
    Return _per_pair_minima of the pairs (a, b) wherever they can hold a smallest value.

    A smallest value: the smallest distance - offsets over every pair, for each
    offsets (pairs,) of the list; every pair that holds one, and every leg on
    which it does, is evaluated (_near_runs), so each such pair's
    (distance, leg, fraction) is the same as over every leg. Below
    _RUN_FILTER_ENTRIES pair-legs every pair is evaluated on every leg: faster.
    """
    if a.size * (planes.shape[1] - 1) < _RUN_FILTER_ENTRIES:
        return _per_pair_minima(planes, a, b)
    scale = _scale(planes) + max(float(np.abs(offset).max(initial=0.0)) for offset in offsets)
    return _per_pair_minima(planes, a, b, _near_runs(planes, a, b, offsets,
                                                     BOUND_SLACK * scale))


def _direct_minimum(points, robot_count, obstacle_count, offsets=None):
    """Return the _Closest over every pair and every leg."""
    a, b = point_pairs(robot_count, obstacle_count)
    minima = _pruned_minima(
        _coordinate_first(points), a, b, [np.zeros(a.size) if offsets is None else offsets])
    return _smallest(minima, np.arange(points.shape[0] - 1), 0.0 if offsets is None else offsets,
                     a, b)


def _breakpoint_bound(positions, obstacles):
    """
    Return an upper bound on the clearance: the closest pair at a few breakpoints.

    Any instant's closest pair bounds the minimum; the first and last breakpoint
    and every tenth in between keep the bound tight without a tree per breakpoint.
    Without obstacles (an empty (0, d) array) it bounds the closest robot pair.
    """
    bound = np.inf
    obstacle_tree = cKDTree(obstacles) if len(obstacles) else None
    for configuration in positions[np.unique(np.r_[0:len(positions):10, -1])]:
        bound = min(bound, cKDTree(configuration).query(configuration, k=2)[0][:, 1].min())
        if obstacle_tree is not None:
            bound = min(bound, obstacle_tree.query(configuration)[0].min())
    return bound


def _sweep_pairs(start, end, bound):
    """
    Return robot pairs (a, b) whose coordinate ranges over one leg come within bound.

    Sorting the ranges' lower ends along the axis that leaves the fewest pairs,
    robot i is paired with the robots after it whose lower end is at most
    hi_i + bound. Every other pair stays more than bound apart on that axis.
    """
    low, high = np.minimum(start, end), np.maximum(start, end)
    best = None
    for axis in range(start.shape[1]):
        order = np.argsort(low[:, axis], kind='stable')
        ends = np.searchsorted(low[order, axis], high[order, axis] + bound, side='right')
        counts = np.maximum(ends - np.arange(order.size) - 1, 0)
        if best is None or counts.sum() < best[2].sum():
            best = (order, ends, counts)
    assert best is not None  # d >= 1 axes
    order, ends, counts = best
    first = np.repeat(np.arange(order.size), counts)
    offsets = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    return order[first], order[first + 1 + offsets]


def _pruned_robot_minimum(positions, legs, bound):
    """Return the _Closest robot pair (its distance), pruning by sweep."""
    best = _NOT_FOUND
    for leg in legs:
        a, b = _sweep_pairs(positions[leg], positions[leg + 1], bound)
        if a.size == 0:
            continue
        # Only the leg's two breakpoints: the whole motion made contiguous per leg costs
        # O(V) each, O(V^2) in all.
        found = _pairs_minimum(positions[leg:leg + 2], np.array([0]), a, b)
        if found.value < best.value:
            best = replace(found, leg=int(leg))
    return best


def _moving_legs(positions):
    """Return the indices of legs along which something moves (at least one leg)."""
    moving = np.flatnonzero(np.any(positions[1:] != positions[:-1], axis=(1, 2)))
    return moving if moving.size else np.array([0])


def _closest(points, k, radii=None):
    """
    Return the _Closest pair of points; second >= k names obstacle second - k.

    points is (V, k + r, d): the robots at every breakpoint, then the obstacles.
    value is the smallest distance or, with radii (k + r,) of the points, the
    smallest surface gap: distance minus both radii.
    """
    v, _, d = points.shape
    r = points.shape[1] - k
    positions, obstacles = points[:, :k], points[0, k:]
    a, b = point_pairs(k, r)
    offsets = None if radii is None else radii[a] + radii[b]
    if k <= _DIRECT_ROBOTS:
        if a.size * v * d <= _CHUNK_ELEMENTS:
            return _direct_minimum(points, k, r, offsets)
        return _pairs_minimum(points, np.arange(v - 1), a, b, offsets)
    # Many robots: every robot-obstacle pair, and the robot pairs the sweep keeps. All
    # robot pairs have one offset (2R), so the closest robot pair has the smallest gap.
    legs = _moving_legs(positions)
    best = _NOT_FOUND
    if r:
        a, b = a[a.size - k * r:], b[b.size - k * r:]
        best = _pairs_minimum(
            points, legs, a, b, None if offsets is None else offsets[offsets.size - k * r:])
    bound = _breakpoint_bound(positions, obstacles if radii is None else obstacles[:0])
    found = _pruned_robot_minimum(positions, legs, bound)
    if radii is not None:
        found = replace(found, value=found.value - 2 * radii[0])
    return min(best, found, key=_BY_VALUE)


def _scale(points):
    """Return the largest coordinate magnitude of stacked robots and obstacles."""
    return float(np.abs(points).max(initial=0.0))


def _scaled(positions, obstacles, radii):
    """
    Return (points (V, k + r, d), radii, exponent, resolution), rescaled by 2^-exponent.

    Far from unit scale the coordinates are multiplied by a power of two
    (exact), so squared distances neither overflow nor fall into subnormals.
    """
    points = with_obstacles(positions, obstacles)
    scale = _scale(points)
    exponent = 0
    if scale > 0 and not _UNSCALED[0] <= scale <= _UNSCALED[1]:
        exponent = int(np.frexp(scale)[1])
        points = np.ldexp(points, -exponent)
        radii = None if radii is None else np.ldexp(radii, -exponent)
    return points, radii, exponent, RELATIVE_RESOLUTION * scale


def _clearance(found, times, k, exponent, resolution):
    """Return the Clearance of a _Closest found by _closest."""
    leg, fraction = found.leg, found.fraction
    value = float(np.ldexp(found.value, exponent))
    tau = float(times[leg] + fraction * (times[leg + 1] - times[leg]))
    pair = PointPair.from_points(found.first, found.second, k)
    return Clearance(value, pair.kind, (pair.first, pair.second), leg, fraction, tau,
                     resolution)


def _nothing(positions, obstacles, resolution):
    """Return the Clearance of a motion with no pair (one robot, no obstacle), or None."""
    k, r = positions.shape[1], len(obstacles)
    if k == 0 or (k == 1 and r == 0):
        return Clearance(np.inf, 'none', (), 0, 0.0, 0.0, resolution)
    return None


def evaluates_every_pair(positions: np.ndarray, obstacles: np.ndarray) -> bool:
    """
    Return whether certify takes every pair's closed form on every leg, unscaled.

    Then its gap is the smallest, over every pair, of the pair's smallest
    distance over every leg (segment_minimum on the differences of the
    breakpoints, as given) less the pair's radii, exactly; robots and pillars
    (V, k, d) and (r, d).
    """
    v, k, d = positions.shape
    pairs = k * (k - 1) // 2 + k * len(obstacles)
    scale = max(_scale(positions), _scale(obstacles))
    return (k <= _DIRECT_ROBOTS and pairs * v * d <= _CHUNK_ELEMENTS
            and (scale == 0 or _UNSCALED[0] <= scale <= _UNSCALED[1]))


def certify(times: np.ndarray, positions: np.ndarray, obstacles: np.ndarray,
            radii: np.ndarray | None = None) -> Clearance:
    """
    Return the Clearance of the motion through breakpoints (times (V,), positions (V, k, d)).

    Exact (closed form per leg) over every robot pair and every robot-obstacle
    pair; the pruning for many robots drops only pairs that cannot be closest.
    With radii (k + r,), robots' then obstacles', the Clearance's distance is
    the smallest surface gap, |a - b| - radius_a - radius_b, and where it is.
    """
    k = positions.shape[1]
    points, radii, exponent, resolution = _scaled(positions, obstacles, radii)
    nothing = _nothing(positions, obstacles, resolution)
    if nothing is not None:
        return nothing
    return _clearance(_closest(points, k, radii), times, k, exponent, resolution)


@dataclass(frozen=True)
class BodyCertificates:
    """The two exact certificates of a motion of bodies: centre distance and surface gap."""

    clearance: Clearance
    gap: Clearance


def certify_bodies(times: np.ndarray, positions: np.ndarray, obstacles: np.ndarray,
                   radii: np.ndarray) -> BodyCertificates:
    """
    Return the motion's centre-distance and surface-gap Clearances, exactly.

    certify twice, but where every pair is evaluated on every leg (up to
    _DIRECT_ROBOTS robots) both come from one pass: each pair's own minimum
    over the legs gives the closest pair and the pair with the smallest gap.
    """
    k, r = positions.shape[1], len(obstacles)
    points, radii, exponent, resolution = _scaled(positions, obstacles, radii)
    nothing = _nothing(positions, obstacles, resolution)
    if nothing is not None:
        return BodyCertificates(nothing, nothing)
    v, _, d = points.shape
    a, b = point_pairs(k, r)
    if k > _DIRECT_ROBOTS or a.size * v * d > _CHUNK_ELEMENTS:
        return BodyCertificates(
            _clearance(_closest(points, k), times, k, exponent, resolution),
            _clearance(_closest(points, k, radii), times, k, exponent, resolution))
    planes = _coordinate_first(points)
    both = [np.zeros(a.size), radii[a] + radii[b]]
    minima = _pruned_minima(planes, a, b, both)
    legs = np.arange(v - 1)
    return BodyCertificates(*(_clearance(_smallest(minima, legs, offsets, a, b), times, k,
                                         exponent, resolution) for offsets in both))
