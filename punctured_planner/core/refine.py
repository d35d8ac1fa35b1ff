"""
The refinement: a continuous, certified shortening of every plan (doc/design.md section 14).

The construction fixes which domain a request is in and which way round each
robot goes; the geometry inside that is free. The refined motion is

    y(tau) = x(tau) + delta(tau),

x the construction's motion and delta a displacement field, piecewise linear in
tau with knots at fixed fractions j / K of every segment C_m -> C_{m+1} and zero
at the configurations. y is piecewise linear on the union of x's breakpoints
and the knots, so the certificate stays exact, and the configurations stay
breakpoints, unchanged.

delta is built by a fixed schedule: BLOCKS blocks of SWEEPS red-black sweeps of
over-relaxed smoothing (each knot towards its neighbours' midpoint). A block
first computes every knot's caps from the exact slack (gap minus the margin
g0, the construction's own exact min_gap) over the two knot intervals its hat
function covers: a quarter of its smallest robot-pair slack, half of its
smallest robot-pillar slack; each knot's total move in the block is split into
the fleet's common translation (which robot pairs do not feel) and each
robot's own part, each clipped to its caps and to a fixed step. Gap distance
is 1-Lipschitz in each robot's position, so no gap falls below g0 (the caps
lemma). Every robot's smallest slack is over every pair (pairs that cannot
hold it are skipped, exactly: the same values), so no pair enters or leaves
the checked set; every quantity is a continuous function of the input, and
the number of blocks, sweeps and knots is fixed, so the map stays continuous
on every domain (doc/design.md section 14).

With walls (Constraints.bounds) each robot's change along each axis is kept within
half its slack to the wall behind it (0 where it is beyond that wall), and
where a knot's hat reaches beyond a wall the block starts from a pull
inwards: the motion never reaches farther beyond a wall than the
construction's, and a motion inside stays inside (doc/design.md section 14).
"""

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from .certificate import BOUND_SLACK, certify, evaluates_every_pair, segment_minimum
from .pairs import point_pairs
from .planes import box_distance, planes_length, run_boxes
from .timing import leg_at
from .walls import wall_slack

# Knots per segment: the field is piecewise linear on the j / KNOTS fractions.
KNOTS = 64
# A block computes the caps once (the costly part: the exact slack of every pair
# near enough to matter), then runs SWEEPS red-black sweeps of over-relaxed smoothing
# (successive over-relaxation: O(KNOTS) sweeps where plain smoothing, like diffusion,
# needs O(KNOTS^2)), each knot's total move in the block clipped to its caps. Fresh caps
# let robots use the room they made, so more blocks shorten more; but a block's caps
# follow the motion (a pillar cap moves by up to half of what the motion moves), so
# each block can amplify a change of input, and BLOCKS bounds that: on two point robots in
# R^3 among one pillar a 1e-7 change moved the refined motion 7610x that with 12 blocks,
# 153x with 10, 25 - 105x with 8, 5 - 6x with 6 (doc/design.md section 14).
BLOCKS, SWEEPS = 6, 6
# A block's cost grows like k^2 (all pairs near each other somewhere): beyond FULL_ROBOTS
# robots the blocks fall as FULL_ROBOTS / k, and beyond MAX_ROBOTS none is run (the
# construction's plan is returned; k is fixed on a domain, so this keeps continuity).
FULL_ROBOTS, MAX_ROBOTS = 64, 256
# The longest move of a knot in one block, as a share of the fleet's scale.
STEP = 0.2
# Over-relaxation factor: about 2 / (1 + sin(pi / KNOTS)) is the classical optimum; less
# is steadier under the caps: with 1.9 a change of input grew about 3.5x a block from the
# fourth on for a few point fleets (127x in all, doc/design.md section 14), with 1.7 the
# same fleets 5x, and the realistic ones come out as long.
RELAXATION = 1.7
# Caps: a quarter of a robot pair's slack (each robot moves at most that, so the pair's
# distance changes by at most half of it), half of a robot-pillar slack.
PAIR_SHARE, PILLAR_SHARE = 0.25, 0.5
# The common translation of a knot may be at most this multiple of its smallest pair cap
# (4: the smallest pair slack itself; more would make the caps steep, and continuity
# weaker, for nothing but rounding).
_TRANSLATION = 4.0
# Entries (coordinate x leg x robot x robot or pillar) of the slack arrays computed at
# once: a few hundred kB stay in cache (with 1 << 21, megabytes per pass, the caps of a
# 40-robot plan took about 1.5x as long).
_ENTRIES = 1 << 15
# Coordinates up to this size are filtered; beyond, squares could overflow.
_FILTERED_SCALE = 1e150
# Entries (coordinate x knot x robot pair) of the filter's arrays computed at once.
_FILTER_ENTRIES = 1 << 17


@dataclass(frozen=True, eq=False)
class Constraints:
    """
    What the gaps are measured against: pillars (r, d), radii (k + r,), the margin g0.

    rounding is the slack treated as none (the resolution of the coordinates);
    bounds, None or (d, 2) lows and highs of the workspace's walls in the
    motion's coordinates, which every robot's centre keeps its radius inside.
    """

    obstacles: np.ndarray
    radii: np.ndarray
    margin: float
    rounding: float
    bounds: np.ndarray | None = None


@dataclass(frozen=True, eq=False)
class Refinement:
    """
    The refined motion: breakpoint parameters (U,), positions (U, k, d), waypoints' indices.

    base_legs (U - 1,) names the construction's leg each refined leg lies in;
    margin is the gap every pair keeps: g0, or the construction's motion's own
    exact gap on the refined breakpoints where rounding puts that a few ulps
    lower (the same motion, evaluated at more points).
    """

    times: np.ndarray
    positions: np.ndarray
    waypoint_indices: np.ndarray
    base_legs: np.ndarray
    margin: float


@dataclass(frozen=True, eq=False)
class _Union:
    """x on the union of its breakpoints and the knots: times, positions, base legs."""

    times: np.ndarray
    positions: np.ndarray
    base_legs: np.ndarray
    waypoint_indices: np.ndarray


def knot_times(segments: int, per_segment: int) -> np.ndarray:
    """Return the ((n - 1) K + 1,) knots (m + j / K) / (n - 1): fixed fractions of segments."""
    index = np.arange(segments * per_segment + 1)
    m, j = np.divmod(index, per_segment)
    # The last knot is (n - 1 + 0 / K) / (n - 1) = 1 exactly, like every waypoint.
    return (m + j / per_segment) / segments


def union_motion(times: np.ndarray, positions: np.ndarray,
                 waypoint_indices: np.ndarray, knots: np.ndarray) -> _Union:
    """Return x on the union of its breakpoints and the knots; waypoints kept bit for bit."""
    extra = knots[~np.isin(knots, times)]
    leg = leg_at(times, extra)
    fraction = ((extra - times[leg]) / (times[leg + 1] - times[leg]))[:, None, None]
    # (1 - f) a + f b, as Plan.position evaluates x, kept per coordinate between a and b,
    # where the exact point lies: rounded, (1 - f) a + f a can be an ulp off a, and a robot
    # exactly at a wall would then be an ulp beyond it (clipping only moves towards the
    # exact value, continuously).
    start, end = positions[leg], positions[leg + 1]
    inserted = np.clip((1.0 - fraction) * start + fraction * end, np.minimum(start, end),
                       np.maximum(start, end))
    all_times = np.concatenate([times, extra])
    order = np.argsort(all_times, kind='stable')
    rank = np.empty_like(order)
    rank[order] = np.arange(order.size)
    base = np.concatenate([np.arange(times.size), leg])[order]
    # A refined leg lies in the base leg of its start point: breakpoint i starts base
    # leg i, a knot inserted into base leg l starts the rest of l.
    return _Union(all_times[order], np.concatenate([positions, inserted])[order],
                  np.minimum(base[:-1], times.size - 2), rank[waypoint_indices])


@dataclass(frozen=True, eq=False)
class _Knots:
    """
    The knots: times (N,), each breakpoint's knot interval (U,), fraction, index in U.

    partners (N - 1, k), None for one robot: each robot's nearest other robot
    at the first knot of each interval in the construction's motion, the one
    the pair filter measures it against in every block (_near_pairs).
    """

    times: np.ndarray
    interval: np.ndarray
    fraction: np.ndarray
    points: np.ndarray
    partners: np.ndarray | None

    @classmethod
    def of(cls, union: _Union, knots: np.ndarray) -> '_Knots':
        """Return the knots (N,), every one a breakpoint of the union motion, located on it."""
        interval = np.clip(np.searchsorted(knots, union.times, side='right') - 1, 0,
                           knots.size - 2)
        fraction = (union.times - knots[interval]) / (knots[interval + 1] - knots[interval])
        # Every knot is a breakpoint of the union.
        points = np.searchsorted(union.times, knots)
        partners = (_knot_partners(np.moveaxis(union.positions[points[:-1]], 2, 0))
                    if union.positions.shape[1] > 1 else None)
        return cls(knots, interval, np.clip(fraction, 0.0, 1.0), points, partners)

    def field(self, values: np.ndarray) -> np.ndarray:
        """Return (U, k, d) the field at the breakpoints from its values (N, k, d) at knots."""
        f = self.fraction[:, None, None]
        return (1.0 - f) * values[self.interval] + f * values[self.interval + 1]


@lru_cache(maxsize=8)
def _pair_groups(k):
    """
    Return (firsts, order, seconds) to reduce values over the pairs np.triu_indices(k, 1).

    The pairs of robot i as the first are a contiguous run starting at firsts[i]
    (i < k - 1); taken in order, those of robot i as the second start at
    seconds[i - 1] (i > 0).
    """
    a, b = np.triu_indices(k, 1)
    order = np.argsort(b, kind='stable')
    return (np.searchsorted(a, np.arange(k - 1)), order,
            np.searchsorted(b[order], np.arange(1, k)))


def _pair_minimum(values, k):
    """Return (..., k) each robot's smallest value over its pairs of values (..., pairs)."""
    firsts, order, seconds = _pair_groups(k)
    result = np.full(values.shape[:-1] + (k,), np.inf)
    result[..., :-1] = np.minimum.reduceat(values, firsts, axis=-1)
    np.minimum(result[..., 1:], np.minimum.reduceat(np.take(values, order, axis=-1), seconds,
                                                    axis=-1), out=result[..., 1:])
    return result


def _knot_partners(knots):
    """
    Return (M, k) each robot's nearest other robot in each of M configurations (d, M, k).

    Of several at the same distance any one; every robot gets another robot
    (the next one where no distance equals the smallest), and any other robot
    keeps the filter exact. Squares too large for floats are inf: a partner
    all the same.
    """
    d, count, k = knots.shape
    a, b = point_pairs(k)
    partners = np.empty((count, k), dtype=np.intp)
    partners[:] = (np.arange(k) + 1) % k
    # About _FILTER_ENTRIES entries at a time.
    rows = max(1, _FILTER_ENTRIES // (d * a.size))
    for first in range(0, count, rows):
        piece = knots[:, first:first + rows]
        with np.errstate(over='ignore'):
            distance = planes_length(np.take(piece, a, axis=2) - np.take(piece, b, axis=2))
        nearest = _pair_minimum(distance, k)
        found = partners[first:first + rows]
        # A pair at a robot's smallest distance names its partner.
        for mine, other in ((a, b), (b, a)):
            row, pair = np.nonzero(distance == np.take(nearest, mine, axis=1))
            found[row, mine[pair]] = other[pair]
    return partners


def _runs(points, legs):
    """Return [(first, last), ...]: runs of whole knot intervals of about legs legs each."""
    runs, first, intervals = [], 0, points.size - 1
    while first < intervals:
        last = int(np.searchsorted(points, points[first] + legs, side='right')) - 1
        last = min(max(last, first + 1), intervals)
        runs.append((first, last))
        first = last
    return runs


def _near_pairs(planes, points, runs, a, b, margin, partners):
    """
    Return (runs, pairs) whether each pair can hold a robot's smallest distance in each run.

    In every interval each robot comes within its partner's distance at the
    interval's first knot (plus margin, far above rounding): the motion passes
    through that knot. Any other robot would do; partners (N - 1, k) are the
    nearest there in the construction's motion (_Knots), which stay near over
    the blocks (a 40-robot plan keeps 16 - 17% of the pairs against 16% for
    the nearest in each block, found over every pair at every knot). A pair
    whose boxes over the run stay farther apart than the largest of those for
    both of its robots is never the smallest of either, so the pairs kept give
    every robot's very minimum.
    """
    firsts = np.array([first for first, _ in runs])
    lasts = np.array([last for _, last in runs])
    knots = planes[:, points[firsts[0]:lasts[-1]]]
    partner = np.take_along_axis(knots, partners[None, firsts[0]:lasts[-1]], axis=2)
    near = np.maximum.reduceat(planes_length(knots - partner), firsts - firsts[0], axis=0)
    near += margin
    low, high = run_boxes(planes, points[firsts], points[lasts])
    apart = box_distance(np.take(low, a, axis=2), np.take(high, a, axis=2),
                         np.take(low, b, axis=2), np.take(high, b, axis=2))
    return apart - margin <= np.maximum(np.take(near, a, axis=1), np.take(near, b, axis=1))


def _near_pillars(planes, points, runs, pillars, offsets, margin):
    """
    Return (runs, k r) whether each robot-pillar pair can hold a robot's smallest slack.

    _near_pairs for pillars (r, d): the slack is the distance less offsets (k, r);
    each robot keeps its smallest at an interval's first knot (plus margin).
    """
    firsts = np.array([first for first, _ in runs])
    lasts = np.array([last for _, last in runs])
    # Pillars ahead of the robots, (d, r, ..., k): every broadcast runs along the k robots,
    # not along a few pillars.
    centres = pillars.T[:, :, None, None]
    pillar_offsets = offsets.T[:, None]
    knots = planes[:, None, points[firsts[0]:lasts[-1]]]
    nearest = (planes_length(knots - centres) - pillar_offsets).min(axis=0)
    near = np.maximum.reduceat(nearest, firsts - firsts[0], axis=0) + margin
    low, high = run_boxes(planes, points[firsts], points[lasts])
    apart = box_distance(low[:, None], high[:, None], centres, centres)
    keep = apart - pillar_offsets - margin <= near
    return np.transpose(keep, (1, 2, 0)).reshape(len(runs), -1)


def _interval_minima(planes, knots, pillars=None, offsets=None):
    """
    Return each robot's exact smallest distance over each knot interval, densely.

    To another robot, (N - 1, k), or with pillars (m, d), to each pillar (whose
    caps take offsets (k, m) from the distance), (N - 1, k, m): the closed form
    on every leg of the union, then the minimum over each interval's legs.
    planes is the motion coordinate first (d, U, k). Dense arrays over a few
    hundred legs cost less than choosing pairs would; a run of whole intervals
    at a time bounds the temporaries (the grouping does not change any value).
    Pairs too far apart
    over a run to hold any robot's smallest (_near_pairs, _near_pillars) are
    left at +inf: every robot's smallest, all the caps use, stays the same.
    """
    d, _, k = planes.shape
    # Robot pairs a < b only (np.take keeps the pairs last and contiguous).
    a, b = point_pairs(k)
    width = a.size if pillars is None else k * pillars.shape[0]
    points = knots.points
    minima = np.full((points.size - 1, width), np.inf)
    runs = _runs(points, max(1, _ENTRIES // (d * max(width, 1))))
    scale = max(float(np.abs(planes).max(initial=0.0)),
                0.0 if pillars is None else float(np.abs(pillars).max(initial=0.0)))
    near = np.ones((len(runs), width), dtype=bool)
    # Squares this large could overflow (inf, nan), which the filter must not drop.
    if scale < _FILTERED_SCALE:
        # The filter's arrays for a batch of runs: about _FILTER_ENTRIES entries.
        batch = max(1, _FILTER_ENTRIES * len(runs) // (d * (points.size - 1) * max(width, 1)))
        for run in range(0, len(runs), batch):
            chosen = runs[run:run + batch]
            margin = BOUND_SLACK * scale
            near[run:run + batch] = (
                _near_pairs(planes, points, chosen, a, b, margin, knots.partners)
                if pillars is None else
                _near_pillars(planes, points, chosen, pillars, offsets,
                              margin + BOUND_SLACK * float(np.abs(offsets).max())))
    for run, (first, last) in enumerate(runs):
        piece = planes[:, points[first]:points[last] + 1]
        starts = points[first:last] - points[first]
        kept = np.flatnonzero(near[run])
        if pillars is not None:
            robot, pillar = np.divmod(kept, pillars.shape[0])
            relative = np.take(piece, robot, axis=2) - pillars.T[:, None, pillar]
        else:
            relative = np.take(piece, a[kept], axis=2) - np.take(piece, b[kept], axis=2)
        squared, _ = segment_minimum(relative[:, :-1], relative[:, 1:] - relative[:, :-1])
        minima[first:last, kept] = np.sqrt(np.minimum.reduceat(squared, starts, axis=0))
    if pillars is not None:
        return minima.reshape(minima.shape[0], k, pillars.shape[0])
    return _pair_minimum(minima, k)


def _pillar_offsets(constraints, k):
    """Return (k, r) what each robot-pillar gap takes from the distance: both radii."""
    return constraints.radii[:k, None] + constraints.radii[None, k:]


@dataclass(frozen=True, eq=False)
class _Nearest:
    """
    The motion (d, U, k) and, over each knot interval, each robot's smallest exact distance.

    robots (N - 1, k) to another robot, pillars (N - 1, k, r) to each pillar
    (+inf where a pair cannot hold the robot's smallest slack); None without
    another robot or without pillars.
    """

    planes: np.ndarray
    robots: np.ndarray | None
    pillars: np.ndarray | None

    @classmethod
    def of(cls, motion: np.ndarray, knots: _Knots, constraints: Constraints) -> '_Nearest':
        """Return the smallest distances of the motion at the union's breakpoints (U, k, d)."""
        k = motion.shape[1]
        planes = np.ascontiguousarray(np.moveaxis(motion, 2, 0))
        robots = _interval_minima(planes, knots) if k > 1 else None
        pillars = (_interval_minima(planes, knots, constraints.obstacles,
                                    _pillar_offsets(constraints, k))
                   if len(constraints.obstacles) else None)
        return cls(planes, robots, pillars)

    def gap(self, knots: _Knots, constraints: Constraints) -> float:
        """
        Return the motion's exact smallest gap, bit for bit certify's on the same breakpoints.

        certify takes every pair's closed form on every leg (when
        evaluates_every_pair) and its smallest distance less both radii (0
        without a positive radius); the knot intervals cover every leg but
        those before the first knot and after the last, taken here. The
        minimum over the robots is the minimum over the pairs, and rounding is
        monotone, so the smallest gap is the same number.
        """
        k = self.planes.shape[2]
        radii = constraints.radii
        radii = radii if np.any(radii > 0) else np.zeros_like(radii)
        points, breakpoints = knots.points, self.planes.shape[1]
        legs = np.concatenate([np.arange(points[0]), np.arange(points[-1], breakpoints - 1)])
        gaps = [np.inf]
        if self.robots is not None:
            a, b = point_pairs(k)
            ends = self.planes[:, np.concatenate([legs, legs + 1])]
            relative = np.take(ends, a, axis=2) - np.take(ends, b, axis=2)
            squared, _ = segment_minimum(relative[:, :legs.size],
                                         relative[:, legs.size:] - relative[:, :legs.size])
            nearest = min(float(self.robots.min()), float(np.sqrt(squared.min(initial=np.inf))))
            gaps.append(float(nearest - (radii[0] + radii[0])))
        if self.pillars is not None:
            offsets = radii[:k, None] + radii[None, k:]
            ends = self.planes[:, np.concatenate([legs, legs + 1]), :, None]
            relative = ends - constraints.obstacles.T[:, None, None, :]
            squared, _ = segment_minimum(relative[:, :legs.size],
                                         relative[:, legs.size:] - relative[:, :legs.size])
            gaps.append(float((self.pillars - offsets).min()))
            gaps.append(float((np.sqrt(squared) - offsets).min(initial=np.inf)))
        return min(gaps)


class _Caps:
    """
    Each robot's caps at every knot: (N, k) for its robot pairs and for the pillars.

    From the exact slack (closed form per leg) of every robot pair and every
    robot-pillar pair over each knot interval: a quarter (PAIR_SHARE) of the
    smallest pair slack, half (PILLAR_SHARE) of the smallest pillar slack, over
    the two intervals each knot's hat covers, at most step (2 step for a
    pillar); 0 at the configurations (design, 14).
    """

    def __init__(self, nearest, knots, constraints, step):
        """Compute the caps from the motion's smallest distances (_Nearest)."""
        intervals, k = knots.points.size - 1, nearest.planes.shape[2]
        floor = constraints.margin + constraints.rounding
        pair = np.full((intervals, k), step)
        if nearest.robots is not None:
            slack = nearest.robots - 2 * constraints.radii[0] - floor
            pair = np.minimum(pair, PAIR_SHARE * np.maximum(slack, 0.0))
        pillar = np.full((intervals, k), 2 * step)
        if nearest.pillars is not None:
            offsets = _pillar_offsets(constraints, k) + floor
            slack = (nearest.pillars - offsets).min(axis=2)
            pillar = np.minimum(pillar, PILLAR_SHARE * np.maximum(slack, 0.0))
        self.pair, self.pillar = _knot_caps(pair), _knot_caps(pillar)
        self.lower = self.upper = self.inward = None
        if constraints.bounds is not None:
            boxes = run_boxes(nearest.planes, knots.points[:-1], knots.points[1:])
            self._walls(boxes, constraints, step)

    def _walls(self, boxes, constraints, step):
        """
        Add the walls: per axis, how far each knot may move down and up, and its pull inwards.

        The signed distance to a wall is linear along a leg, so each box's
        faces give the exact smallest wall slack of an interval. A robot may
        move along each axis by half of its slack from the wall behind it over
        its hat (0 where it is beyond that wall); inward (N, k, d) is, per axis,
        how far the hat reaches beyond the low wall minus how far beyond the
        high one: 0 inside (design, 14).
        """
        low, high = boxes
        keep = constraints.radii[0] + constraints.rounding
        # (N - 1, k, d): the lowest corner's slack to each wall min, the highest's to each max.
        slacks = [wall_slack(np.moveaxis(corner, 0, 2), constraints.bounds, keep)[..., side]
                  for side, corner in enumerate((low, high))]
        self.lower, self.upper = (
            _knot_caps(np.minimum(2 * step, PILLAR_SHARE * np.maximum(slack, 0.0)))
            for slack in slacks)
        below, above = (_knot_caps(np.maximum(-slack, 0.0), np.maximum) for slack in slacks)
        self.inward = below - above


def _knot_caps(bound, reduce=np.minimum):
    """
    Return (N, ...) caps from interval bounds (N - 1, ...): both intervals of each hat.

    reduce np.maximum gives the larger of the two (how far a hat reaches out).
    """
    caps = np.zeros((bound.shape[0] + 1,) + bound.shape[1:])
    caps[1:-1] = reduce(bound[:-1], bound[1:])
    caps[::KNOTS] = 0.0  # the configurations hold
    return caps


def _knots_last(values):
    """
    Return knot values (N, k, d) as the sweeps' contiguous (d, k, N) array.

    Every row is one coordinate of one robot over all knots: adding a knot's
    common part broadcasts over whole rows (with d last, each inner loop would
    be d = 2 long), and the mean over the robots (axis 1) adds them one by one,
    in the order it takes over (N, k, d), so the values are the same.
    """
    return np.ascontiguousarray(np.transpose(values, (2, 1, 0)))


def _clipped(move, caps):
    """Return the moves (d, ...) scaled down to lengths <= caps (...), in place; 0 at cap 0."""
    length = planes_length(move)
    # caps / length where a move is longer than its cap, else 1: the quotient rounds to
    # >= 1 wherever length <= caps, and fmin takes 1 for the 0 / 0 of a zero move at cap 0
    # (a masked division costs three times as much).
    with np.errstate(divide='ignore', invalid='ignore'):
        scale = np.divide(caps, length, out=length)
    move *= np.fmin(scale, 1.0, out=scale)
    return move


class _Block:
    """
    The moves of one block: the fleet's common translation and each robot's own part.

    A common translation leaves every robot pair's distance as it is (up to
    rounding), so robot-pillar caps bound it: |common| <= half the smallest
    pillar cap of the knot, <= step, and <= _TRANSLATION x its smallest pair
    cap (0 where a pair has no slack, so rounding cannot take any); |own| <=
    the pair cap, <= what common leaves of the pillar cap and <= step. Both
    are totals over the block, so a robot's displacement at any instant of the
    block stays within its caps (design, 14). Moves are in the sweeps' layout
    (_knots_last): common (d, 1, N), own (d, k, N).
    """

    def __init__(self, caps, step):
        """Fix the caps of the block."""
        # A translation keeps pair distances, but only up to rounding: where a pair has no
        # slack the common part must be exactly 0. Capping it by a multiple of the
        # smallest pair cap does that and stays continuous.
        self.common_cap = np.minimum(np.minimum(0.5 * caps.pillar.min(axis=1), step),
                                     _TRANSLATION * caps.pair.min(axis=1))
        self.pair, self.pillar = caps.pair.T, caps.pillar.T
        self.own_cap = np.minimum(self.pair, step)
        self.lower = self.upper = None
        if caps.lower is not None:
            self.lower, self.upper = _knots_last(caps.lower), _knots_last(caps.upper)
            # The common part stays within every robot's range along each axis.
            self.common_range = (-self.lower.min(axis=1, keepdims=True),
                                 self.upper.min(axis=1, keepdims=True))

    def clip(self, wanted: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """
        Return (common (d, 1, N), own (d, k, N)): the wanted totals (d, k, N) within the caps.

        common is the fleet's mean, clipped; own what each robot still wants,
        clipped (wanted is overwritten).
        """
        # The mean: the sum over the robots divided by k, as np.mean takes it.
        common = _clipped(np.add.reduce(wanted, axis=1, keepdims=True) / wanted.shape[1],
                          self.common_cap)
        if self.lower is not None:
            # Within every robot's wall limits, so each robot's own part has room around 0.
            common = np.clip(common, *self.common_range)
        left = self.pillar - planes_length(common)
        own = _clipped(np.subtract(wanted, common, out=wanted), np.minimum(self.own_cap, left))
        if self.lower is not None:
            own = np.clip(own, -self.lower - common, self.upper - common)
        return common, own


def _sweep(origin, common, own, block):
    """
    Return (common, own) after one red-black sweep of over-relaxed smoothing.

    Each knot moves RELAXATION x the way to its neighbours' midpoint, the move
    split into the fleet's mean and each robot's own part; knots of one parity
    have no neighbour of the same parity, so each half sweep uses the other
    half's newest values. origin is where the block starts: the construction's
    knots plus the field so far, in that order (all in the layout _knots_last).
    """
    current = np.empty_like(origin)
    for parity in (1, 0):
        np.add(origin, common, out=current)
        current += own
        # The knots of this parity (slices: views, not gathers) and their two neighbours.
        first = parity + (1 - parity) * 2
        index = slice(first, current.shape[2] - 1, 2)
        before, after = slice(first - 1, -2, 2), slice(first + 1, None, 2)
        # RELAXATION x (the neighbours' midpoint - the knot), in place.
        move = current[..., before] + current[..., after]
        move *= 0.5
        move -= current[..., index]
        move *= RELAXATION
        wanted = common + own
        wanted[..., index] += move
        common, own = block.clip(wanted)
    return common, own


def block_count(robot_count: int) -> int:
    """Return the blocks for k robots: BLOCKS, fewer beyond FULL_ROBOTS, none beyond MAX."""
    if robot_count > MAX_ROBOTS:
        return 0
    return max(1, BLOCKS * min(FULL_ROBOTS, robot_count) // max(robot_count, 1))


def fleet_scale(configurations: np.ndarray, obstacles: np.ndarray) -> float:
    """Return the side of the box of the configurations and pillars: the steps' length unit."""
    points = np.concatenate([configurations.reshape(-1, configurations.shape[2]), obstacles])
    return float((points.max(axis=0) - points.min(axis=0)).max())


def refine(times: np.ndarray, positions: np.ndarray, waypoint_indices: np.ndarray,
           constraints: Constraints) -> Refinement:
    """
    Return the refined motion of the construction's motion (times (V,), positions (V, k, d)).

    Every gap of the result stays >= constraints.margin, the configurations are its
    breakpoints exactly, and it is a continuous function of the input (module
    docstring; doc/design.md section 14).
    """
    k, d = positions.shape[1:]
    configurations = positions[waypoint_indices]
    segments = len(waypoint_indices) - 1
    knot_grid = knot_times(segments, KNOTS)
    union = union_motion(times, positions, waypoint_indices, knot_grid)
    knots = _Knots.of(union, knot_grid)
    blocks = block_count(k)
    nearest = _Nearest.of(union.positions, knots, constraints) if blocks else None
    # The first block's distances give the union motion's exact gap where certify would
    # take every pair on every leg with the radii the caps take (one radius for every robot).
    if (nearest is not None and evaluates_every_pair(union.positions, constraints.obstacles)
            and np.all(constraints.radii >= 0)
            and np.all(constraints.radii[:k] == constraints.radii[0])):
        gap = nearest.gap(knots, constraints)
    else:
        gap = certify(union.times, union.positions, constraints.obstacles,
                      constraints.radii if np.any(constraints.radii > 0) else None).distance
    constraints = Constraints(constraints.obstacles, constraints.radii,
                              min(constraints.margin, gap), constraints.rounding,
                              constraints.bounds)
    scale = fleet_scale(configurations, constraints.obstacles)
    base_knots = _knots_last(union.positions[knots.points])
    # The field's values at the knots, in the sweeps' layout (d, k, N).
    values = np.zeros_like(base_knots)
    motion = union.positions
    step = STEP * scale
    for block_index in range(blocks):
        if block_index:
            nearest = _Nearest.of(motion, knots, constraints)
        caps = _Caps(nearest, knots, constraints, step)
        block = _Block(caps, step)
        common, own = ((np.zeros((d, 1, values.shape[2])), np.zeros_like(values))
                       if caps.inward is None else block.clip(_knots_last(caps.inward)))
        origin = base_knots + values
        for _ in range(SWEEPS):
            common, own = _sweep(origin, common, own, block)
        values = values + common + own
        # x + 0.0 is x: a robot held everywhere in an interval keeps x's breakpoints.
        motion = union.positions + knots.field(np.transpose(values, (2, 1, 0)))
    motion[union.waypoint_indices] = configurations
    return Refinement(union.times, motion, union.waypoint_indices, union.base_legs,
                      constraints.margin)
