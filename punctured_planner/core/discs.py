"""
Disc robots among pillars: the variant 'discs' (doc/design.md section 6).

Robots are discs (balls for d >= 3) of radius R, obstacle j a pillar of radius
rho_j; the surface gap of two robots is |x_a - x_b| - 2R, of a robot and a
pillar |x - q_j| - R - rho_j. Write p(x) for the e1 projection, h(x) for the e2
offset and w_j = R + rho_j + mu_j for the reach of pillar j, where the passing
margin mu_j = max(R, rho_j) / 10 keeps robots off every pillar they pass, as
wide as it may be (w_j = min_spacing / 2 when both radii are 0, so point
robots still keep off point obstacles), and nu = R / 10 is the margin kept
between two robots. For d >= 3 robot i meets pillar j with its own reach
w_ij = sqrt(max(w_j^2 - c_ij^2, 0)), c_ij its distance to q_j across e1 and
e2, which the rise keeps (DiscLayout.reaches): it keeps w_j from q_j exactly
when it keeps w_ij from q_j's projection onto its plane through e1 and e2.
Below, w_j, f_j and z_j are robot i's wherever a robot is pushed.

A required gap c (required_clearance) is planned for by inflating R and every
rho_j by c / 2 (Workspace.disc_layout): a gap >= 0 between the inflated bodies
is a gap >= c between the real ones.

The construction keeps the paper's skeleton, H(C_m), Gamma, H(C_{m+1})^-1
(Remark 2.3), with a new deformation H onto a new kind of base configuration:

* sidestep and rise: robot i rises along e2 by min(s, s_i), s from 0 to
  T = max_i s_i, with its stop s_i = G_i - h_i: G stacks the fleet on the
  staging height top = max_j (h(q_j) + max(z_j, rho_j + g - R)) (above every
  zone, and the slots' gap g - 2R above every pillar) by stacked_heights, so
  every robot ends above every zone, a robot high up rises little, and a robot
  ends D_p - |dp| above each robot below it within D_p = sqrt 2 g along e1
  wherever the weight allows, which under condition (a) is always within
  E = sqrt 2 (2R + nu) across e2 (beyond STACKED_ROBOTS robots every stop is
  top - h_min). Meanwhile each robot in
  the shadow of pillar j (|p(x) - p(q_j)| < w_j) is pushed along e1, away from
  p(q_j) on its own side (a robot whose projection equals p(q_j) counts as
  right of it, as the paper's numbering puts robots after obstacles), by
  lambda_j(u) (w_j - |p(x) - p(q_j)|). Here u is the robot's height relative to
  the pillar and lambda_j(u) = clip((z_j - |u|) / (z_j - f_j), 0, 1) with
  f_j = (sqrt 2 - 1) w_j and z_j = sqrt 2 w_j: w_j lambda_j(u) is the half
  octagon circumscribing the circle of radius w_j, so
  w_j lambda_j(u) >= sqrt(w_j^2 - u^2) for |u| <= w_j. Pushes of several
  pillars add up. Each robot's offsets are then piecewise linear in s with
  kinks only where u crosses +-f_j and +-z_j and at the stops, so the
  breakpoints of all robots together describe the motion exactly. A push
  already due at s = 0 is made first, along e1 only (the sidestep leg). At
  s = T every robot is above every zone, unpushed: the fleet is C with every
  h_i replaced by G_i.
* gather: every robot moves along e1 only, at its risen height, into the
  column of slot rank(x) (the hyperplane p = that slot); slots
  g = max(min_spacing, 2R + nu) apart along e1, centred on the mean robot
  projection (below walls, moved into the room between them: staging_slots);
  rank orders robots by projection, ties by index. A slot is its
  column at height top, the robot's coordinates across e1 and e2 kept
  (d >= 3): the staging line in the plane, the staging hyperplane h = top in
  3-D. Without pillars there is no rise and no height to clear: each segment's
  staging height centres its lanes on the mean e2 offset of its two
  configurations (staging_height; below walls, clipped between them).
* Gamma between base configurations (the paper's section, equation 3.1, with
  shared lanes): every robot moves along e2 within its column to its lane
  top + l g (lane 0 is the staging height itself), slides at that height to
  its next slot's column (and its next coordinates across e1 and e2) and moves
  along e2 within that column to its next base position. Robots whose
  slots keep their order share a lane (shared_lanes), so a segment needs as
  many lanes as its longest run of robots whose order reverses, not k. Below
  walls that leave room for fewer lanes (WallRoom) the robots pass in several
  slides of at most that many lanes (passing_orders; doc/design.md section 17).

Continuity and domains. On a stratum A_i the order of all k + r projections,
ties included, is locally constant, so the side of every push and the ranks
are; the stops and G (continuous in p and h: where two robots' heights meet,
the weight of one in the other's stacking term is 0), the pushes (continuous in p, h and
zero at the shadow's edge), the slot centre and every breakpoint move
continuously. The motion is therefore continuous on every A_{j_1} x ... x
A_{j_n}, hence on every domain of the paper, whose projection counts, domains
and TC_n it shares. Breakpoints that appear as a robot enters a shadow carry
a push of size 0, and two stops that cross split a leg along which every
robot moves linearly, so they do not change the motion.

Theorem (bodies keep a margin). Let S = max(4R, 2R + nu + max_j w_j), which
is 4R when every rho_j <= 0.8R. Suppose in every configuration (a) robot
centres are at least S apart, (b) no robot disc overlaps a pillar
(|x - q_j| >= R + rho_j; validation refuses the rest), and (c) any two pillars
j, l satisfy |p(q_j) - p(q_l)| >= w_j + w_l + 2R + nu or
|h(q_j) - h(q_l)| >= z_j + z_l + 2R + nu or (d >= 3) are w_j + w_l + 2R + nu
apart across e1 and e2. Then every gap of a robot and pillar
j stays >= min(mu_j, its gap in the configurations) and every gap of two
robots >= nu: min_gap >= min(nu, g_C) with nu = R / 10, g_C the smallest
robot-pillar gap of the configurations themselves (a robot touching a pillar
in C_m keeps that gap there), a margin far above the rounding of the
coordinates unless the input itself touches.

Proof. For robots a, b with h_a <= h_b let x be their distance across e2 in
C (the stack sees only |dp| <= x) and y = h_b - h_a. While both rise their e2
difference stays y, then it moves monotonically to G_b - G_a. Under (a),
x < E forces y >= pile_fade, so, as D_p - |dp| >= E - x,
(*) G_b >= G_a + E - x >= top + E - x whenever x < E. Every leg is one
of the following.
(1) Sidestep and rise, robot and pillar j. Each robot follows the path of a
common rise, cut off at its stop above every zone. While |u| > w_j the e2
distance exceeds w_j. While |u| <= w_j, the push of j alone puts the robot at
e1 offset delta + lambda_j (w_j - delta) >= lambda_j w_j >= sqrt(w_j^2 - u^2)
from p(q_j), so at distance >= w_j (gap >= mu_j; for d >= 3 the squared
distance adds c_ij^2 to w_ij^2, which is the pillar's w_j^2); the sidestep moves a robot
straight away from p(q_j), so its gap only grows from C's. Pushes of pillars on the
same side only add to it. A pillar l on the other side pushes only while the
robot is in its shadow and |u_l| < z_l, which puts l within w_j + w_l of
p(q_j) in e1 and within w_j + z_l of h(q_j) in e2, excluded by (c). A robot
pushed towards a pillar l whose shadow it was not in reaches it only if
|p(q_j) - p(q_l)| < w_j + w_l, and then by (c) it is more than z_l + 2R + nu
from h(q_l) in e2.
(2) Sidestep and rise, two robots. (i) While both rise, their e2 and other
coordinates change by the same s, so if those differ by at least 2R + nu the
gap stays >= nu. Otherwise their e1 distance is at least
sqrt(S^2 - (2R + nu)^2) > max w_j, so they are not in one shadow on one side,
and by (c) no robot is pushed by two pillars at once (their shadows and zones
would overlap). If both are pushed towards each other, by j and l, their
zones overlap within 2R + nu in e2, so by (c) p(q_l) - p(q_j) >= w_j + w_l +
2R + nu while they stay within w_j of p(q_j) and w_l of p(q_l): 2R + nu apart
in e1. Otherwise at most one moves towards the other, by at most
w_max = max_j w_j in e1, and (|dp| - w_max)^2 + dh^2 = S^2 - 2 w_max
sqrt(S^2 - dh^2) + w_max^2 grows with dh, so it is at least
(S - w_max)^2 >= (2R + nu)^2 whenever |dp|^2 + dh^2 >= S^2. (ii) While
neither is pushed, their distance across e2 is x and their e2 difference lies
between y and G_b - G_a: if x >= E they are E apart, otherwise by (*) at
least min(S, sqrt(x^2 + (E - x)^2)) >= E / sqrt 2 = 2R + nu. (iii)
Otherwise one is pushed by some j (so it still rises, below top) and the
other has stopped at or above top: the stopped one is b, the higher (the
rising one has risen at least as much, yet is below G_b). a is
eps = z_j - u <= top - h(a) below top and its push is lambda_j (w_j - delta)
<= min(w_j, z_j - |u|) <= eps (z_j - f_j = w_j), so their distance across e2 is at
least x - eps, and by (*) b is at least c = (E - x)_+ above top, so their
e2 distance is at least eps + c. Over eps >= 0, (x - eps)_+^2 + (eps + c)^2
>= (x + c)^2 / 2 and x + c >= E: they stay 2R + nu apart.
(3) Gather. It starts from the risen fleet, pairwise >= 2R + nu apart (by
(*), as in (ii)), and moves along e1 only to columns g apart in projection
order. For robots a, b with rank a < rank b the e1 difference moves linearly
from its start (>= 0) to a multiple of g, so at every instant it is at least
the smaller of its start and g, while the other coordinates stay: the pair keeps
at least the smaller of its start distance and g >= 2R + nu. All of it lies
in h >= top, where every robot is at least z_j >= w_j from every pillar.
(4) Gamma. Each robot moves within its column (the hyperplane p = its slot,
g >= 2R + nu from the next one) between heights >= top, then slides in lanes
g apart in e2 at heights >= top; two robots in one lane keep their order, so
their e1 difference moves linearly between multiples of g: they stay g apart
whatever their other coordinates do; below walls, slide after slide on the
same columns, with lifts within the columns between them. The inverse
legs are the same legs run backwards. Without pillars there is no rise and
(3), (4) hold from C itself. QED.

Outside the condition the plan is made all the same; the exact certificate
(Plan.min_gap) says what it achieved and required_clearance refuses it.
"""

from bisect import bisect_left
from dataclasses import dataclass

import numpy as np

from .frame import Frame
from .walls import box_corners, line_section

# The push zone of pillar j in relative height u: full push for |u| <= FULL w_j,
# none beyond ZONE w_j, linear between. The push to w_j lambda_j(u) then traces
# the octagon's half circumscribing the circle of radius w_j: the tangents at
# 0 and 45 degrees meet at u = (sqrt 2 - 1) w_j, the 45 degree one reaches the
# axis at u = sqrt 2 w_j.
FULL, ZONE = np.sqrt(2.0) - 1.0, np.sqrt(2.0)
# The body margins as fractions: mu_j = MARGIN max(R, rho_j) past pillar j, nu = MARGIN R
# between two robots (module docstring). Every body gap of the plan keeps one of them.
MARGIN = 0.1
# Every stop is a breakpoint of the whole motion: k more per rise. Beyond this many robots
# (k is constant on a domain) the fleet rises as one (by top - h_min, a single stop), which
# keeps a plan of 200 robots within its time budget (doc/design.md section 6).
STACKED_ROBOTS = 64

SIDESTEP, RISE, GATHER = 'sidestep', 'rise', 'gather'
LIFT, SLIDE, DROP = 'lift', 'slide', 'drop'


@dataclass(frozen=True)
class WallRoom:
    """
    What walls leave the construction (doc/design.md section 17).

    lanes: how many lanes floor + l g keep R + nu (the robots' margin nu = R / 10) from
    the walls' far side, at least 2, the fewest that pass robots (passing_orders); low,
    high: the range of e1 projections where the staging line goes when it fits
    (staging_slots), unbounded where no range applies; floor, ceiling: the lowest and
    the highest height a lane may take (floor the staging height top with pillars;
    without, the staging height moves between them, staging_height).
    """

    lanes: int
    low: float
    high: float
    floor: float
    ceiling: float

    @classmethod
    def from_walls(cls, frame: Frame, bounds: np.ndarray, robot_radius: float,
                   top: float | None, pitch: float) -> 'WallRoom':
        """
        Return the room below walls bounds (d, 2) for robots of radius R above height top.

        The far side is the second farthest corner of the walls' box along e2: in an axis
        frame the far wall, in an oblique one the height beyond which the box narrows to
        its farthest corner. Without pillars (top None) the lanes may stand anywhere
        between the near side (the second nearest corner, likewise) and the far side,
        each R + nu inside. The range is where a robot keeps R + nu from every wall at the
        lowest lane and at the highest of those lanes (walls.line_section); the box is
        convex, so its section along e1 at a height is an interval whose ends are convex
        and concave in the height, and within both ranges is within every one between. If
        they do not meet (the two lanes passing needs may stand beyond the far side), the
        range at the lowest lane alone; if that is empty too, or the robots'
        coordinates across e1 and e2 (d >= 3, e1 not an axis) move them along the walls'
        axes as well, none. The margin nu keeps an oblique frame's rounding (which put a
        staged robot 1e-16 beyond a wall) far from the walls.
        """
        keep = (1.0 + MARGIN) * robot_radius
        corners = np.sort(frame.offset(box_corners(bounds)))
        floor = float(corners[1]) + keep if top is None else top
        ceiling = float(corners[-2]) - keep
        lanes = max(2, int(np.floor((ceiling - floor) / pitch)) + 1)
        low, high = line_section(bounds, frame.origin + floor * frame.e2, frame.e1, keep)
        if low > high or (frame.e1.size > 2 and np.count_nonzero(frame.e1) > 1):
            return cls(lanes, -np.inf, np.inf, floor, ceiling)
        top_lane = line_section(bounds,
                                frame.origin + (floor + (lanes - 1) * pitch) * frame.e2,
                                frame.e1, keep)
        both = (max(low, top_lane[0]), min(high, top_lane[1]))
        return cls(lanes, *(both if both[0] <= both[1] else (low, high)), floor, ceiling)


@dataclass(frozen=True, eq=False)
class PillarClearance:
    """
    What the bodies' sizes fix before any frame: each pillar's reach and clearance, the pitch.

    reach w_j = R + rho_j + mu_j; pitch g the slots' and lanes'; clear_j how far
    beyond pillar j's centre along e2 the fleet stages (top, DiscLayout): above its
    zone, and as far above the pillar as the slots keep robots apart; robot_radius
    the R they are for.
    """

    reach: np.ndarray
    apart: float
    pitch: float
    clear: np.ndarray
    robot_radius: float

    @classmethod
    def from_radii(cls, robot_radius: float, obstacle_radius: np.ndarray,
                   min_spacing: float) -> 'PillarClearance':
        """Return the clearance of pillars of radii (r,) for robots of radius R."""
        # A passing margin for every pillar size: mu_j = 0 (rho_j >= R, before) let bodies
        # graze. S stays 4R while w_j <= 1.9R (rho_j <= 0.8R); wider margins make
        # neighbouring pillars' zones overlap more often (measured in bench/).
        margin = MARGIN * np.maximum(robot_radius, obstacle_radius)
        reach = robot_radius + obstacle_radius + margin
        reach = np.where(reach > 0, reach, 0.5 * min_spacing)
        apart = (2.0 + MARGIN) * robot_radius
        pitch = max(min_spacing, apart)
        # A robot staged clear of pillar j passes it with at least the slots' gap g - 2R.
        clear = np.maximum(ZONE * reach, obstacle_radius + pitch - robot_radius)
        return cls(reach, apart, pitch, clear, robot_radius)


@dataclass(frozen=True, eq=False)
class DiscLayout:
    """
    What the construction fixes per workspace: the pillars and pitches.

    The pillars (r, d) and their projections and e2 offsets in the frame, reach
    w_j and zone half-height z_j per pillar (for d >= 3 each robot's reach is
    less, reaches), the staging
    height top (with pillars; without, each segment's staging_height), the least
    distance apart 2R + nu that every robot pair keeps, the pitch g of the slots
    and the lanes, the stack's reach D_p and fade (stacked_heights; module
    docstring), and with walls the room they leave (WallRoom; None without).
    """

    frame: Frame
    pillars: np.ndarray
    pillar_projections: np.ndarray
    pillar_offsets: np.ndarray
    reach: np.ndarray
    zone: np.ndarray
    top: float
    apart: float
    pitch: float
    pile_reach: float
    pile_fade: float
    walls: WallRoom | None

    @classmethod
    def from_sizes(cls, frame: Frame, obstacles: np.ndarray, sizes: PillarClearance,
                   bounds: np.ndarray | None = None) -> 'DiscLayout':
        """
        Return the layout for pillars (r, d) of sizes (PillarClearance, robots of radius R).

        bounds (d, 2), or None for no walls, give the room the walls leave (WallRoom).
        """
        reach, apart, pitch, robot_radius = (sizes.reach, sizes.apart, sizes.pitch,
                                             sizes.robot_radius)
        offsets = frame.offset(obstacles)
        # Above every pillar's clearance (PillarClearance).
        top = float((offsets + sizes.clear).max()) if len(obstacles) else 0.0
        separation = max(4.0 * robot_radius, apart + float(reach.max(initial=0.0)))
        # The stack keeps the slots' pitch where it can; the fade is what condition (a)
        # allows for the least it must keep, sqrt 2 (2R + nu) (module docstring).
        fade = np.sqrt(max(separation ** 2 - 2.0 * apart ** 2, 0.0))
        return cls(frame, obstacles, frame.project(obstacles), offsets, reach, ZONE * reach,
                   top, apart, pitch, np.sqrt(2.0) * pitch, float(fade),
                   None if bounds is None
                   else WallRoom.from_walls(frame, bounds, robot_radius,
                                            top if len(obstacles) else None, pitch))

    def reaches(self, configuration: np.ndarray) -> np.ndarray:
        """
        Return (k, r) the reach of each pillar for each robot of configuration (k, d).

        In the plane w_j. For d >= 3 the rise and the pushes move a robot along e1
        and e2 only, so its distance c across them to pillar j stays, and it keeps
        w_j from q_j exactly when it keeps sqrt(w_j^2 - c^2) from q_j's projection
        onto its plane through e1 and e2: 0 (no shadow) for c >= w_j.
        """
        reach = np.broadcast_to(self.reach, (len(configuration), self.reach.size))
        if self.frame.e1.size == 2:
            return reach
        across = np.linalg.norm(_across(configuration[:, None] - self.pillars[None], self.frame),
                                axis=-1)
        return np.sqrt(np.maximum(reach * reach - across * across, 0.0))

    def conflicting_pillars(self) -> np.ndarray:
        """
        Return the (c, 2) index pairs j < l of pillars that break condition (c).

        Condition (c): |p(q_j) - p(q_l)| >= w_j + w_l + 2R + nu or
        |h(q_j) - h(q_l)| >= z_j + z_l + 2R + nu, z the zone half-heights, or (d >= 3)
        the two are w_j + w_l + 2R + nu apart across e1 and e2 (then no robot near
        one of them across those is pushed by the other).
        """
        first, second = np.triu_indices(self.reach.size, 1)
        across = (np.linalg.norm(_across(self.pillars[first] - self.pillars[second],
                                         self.frame), axis=-1)
                  >= self.reach[first] + self.reach[second] + self.apart)
        wide = (np.abs(self.pillar_projections[first] - self.pillar_projections[second])
                >= self.reach[first] + self.reach[second] + self.apart)
        tall = (np.abs(self.pillar_offsets[first] - self.pillar_offsets[second])
                >= self.zone[first] + self.zone[second] + self.apart)
        bad = ~(wide | tall | across)
        return np.stack([first[bad], second[bad]], axis=1)


def _across(vectors: np.ndarray, frame: Frame) -> np.ndarray:
    """Return vectors (..., d) less their e1 and e2 parts: what lies across both."""
    return (vectors - (vectors @ frame.e1)[..., None] * frame.e1
            - (vectors @ frame.e2)[..., None] * frame.e2)


@dataclass(frozen=True)
class Rise:
    """The sidestep and rise of one configuration: e2 shifts (B, k) and e1 offsets (B, k)."""

    lift: np.ndarray
    shift: np.ndarray

    def positions(self, configuration: np.ndarray, frame: Frame) -> np.ndarray:
        """Return the (B + 1, k, d) breakpoints: C, then the robots after each push/rise."""
        moved = (configuration[None] + self.shift[..., None] * frame.e1
                 + self.lift[..., None] * frame.e2)
        return np.concatenate([configuration[None], moved])


def push_factor(relative_height: np.ndarray, full: np.ndarray, zone: np.ndarray) -> np.ndarray:
    """Return lambda_j(u) = clip((zone - |u|) / (zone - full), 0, 1): 1 near, 0 beyond zone."""
    return np.clip((zone - np.abs(relative_height)) / (zone - full), 0.0, 1.0)


def stacked_heights(p: np.ndarray, h: np.ndarray, layout: DiscLayout) -> np.ndarray:
    """
    Return the (k,) heights G the rise ends at: the fleet stacked on the staging height.

    G_i = max(h_i, top, max_j top + (G_j + D_p - |p_i - p_j| - top)_+ w(h_i - h_j)), with
    D_p = pile_reach = sqrt 2 g and the weight w(y) = clip(y / pile_fade, 0, 1): 0 unless
    robot j is below robot i, so the definition runs from the lowest robot up. Under the
    theorem's condition (a) a robot within E = sqrt 2 (2R + nu) of j across e2 is at
    least pile_fade above it, so it ends >= D_p - |dp| above G_j; the weight lets the
    requirement fade out continuously as two robots' heights meet, where (a) puts them
    farther than E apart across e2 (module docstring).
    """
    least = layout.pile_reach - np.abs(p[:, None] - p[None, :])
    # pile_fade = sqrt(S^2 - E^2) > 0 wherever there is a pillar to rise past: S >= 4R > E
    # with a radius, S = the largest reach > 0 without.
    weight = np.clip((h[:, None] - h[None, :]) / layout.pile_fade, 0.0, 1.0)
    floor = np.maximum(h, layout.top)
    heights = floor
    # Every pass settles the robots one level higher in the stack (each G_i depends only on
    # robots below it), so at most k passes reach G, exactly as robot after robot would.
    for _ in range(len(h)):
        above = np.maximum(heights[None, :] + least - layout.top, 0.0) * weight
        settled = np.maximum(floor, layout.top + above.max(axis=1))
        if np.array_equal(settled, heights):
            break
        heights = settled
    return heights


def rise(p: np.ndarray, h: np.ndarray, layout: DiscLayout, reach: np.ndarray) -> Rise:
    """
    Return the sidestep and rise of a configuration with projections p and offsets h (k,).

    reach (k, r) is each pillar's for each robot (DiscLayout.reaches): pillar j pushes
    robot i within reach[i, j] of p(q_j), with that reach's full push and zone.

    Robot i rises by min(s, s_i), s_i = G_i - h_i its stop (stacked_heights;
    max(0, top - h_min) for all beyond STACKED_ROBOTS robots), for s from 0 to
    T = max_i s_i. The breakpoints are s = 0 (after the sidestep), every stop,
    and every s in (0, T) where a robot in a pillar's shadow crosses an edge of
    its zone (module docstring).
    """
    if layout.reach.size == 0:
        return Rise(np.zeros((1, len(p))), np.zeros((1, len(p))))
    if len(h) <= STACKED_ROBOTS:
        stops = stacked_heights(p, h, layout) - h
    else:  # one common stop, the same float for every robot: no breakpoint per robot
        stops = np.full(len(h), max(0.0, layout.top - float(h.min())))
    total = float(stops.max())
    signed = p[:, None] - layout.pillar_projections[None, :]
    robots, pillars = np.nonzero(np.abs(signed) < reach)
    reach = reach[robots, pillars]
    full, zone = FULL * reach, ZONE * reach
    # Zone edges in s: u = h + s - h_q crosses -zone, -full, full, zone (all before the
    # robot's stop, which is above every zone).
    edges = (layout.pillar_offsets[pillars] - h[robots])[:, None] + np.stack(
        [-zone, -full, full, zone], axis=1)
    levels = np.unique(np.concatenate([[0.0], stops, np.clip(edges.ravel(), 0.0, total)]))
    lift = np.minimum(levels[:, None], stops[None, :])
    relative = h[robots][:, None] + lift[:, robots].T - layout.pillar_offsets[pillars][:, None]
    depth = reach - np.abs(signed[robots, pillars])
    direction = np.where(signed[robots, pillars] >= 0, 1.0, -1.0)
    push = push_factor(relative, full[:, None], zone[:, None]) * (direction * depth)[:, None]
    shift = np.zeros(lift.shape)
    np.add.at(shift.T, robots, push)
    return Rise(lift, shift)


def staging_ranks(p: np.ndarray) -> np.ndarray:
    """Return the (k,) slot of each robot, from its projection p: its rank, ties by index."""
    rank = np.empty(len(p), dtype=int)
    rank[np.lexsort((np.arange(len(p)), p))] = np.arange(len(p))
    return rank


def staging_slots(p: np.ndarray, rank: np.ndarray, layout: DiscLayout) -> np.ndarray:
    """
    Return the (k,) projections of the slots for robots of projections p (k,).

    Slot rank(x) lies (rank - (k - 1) / 2) g along e1 from the centre: the mean robot
    projection, and below walls the nearest centre that keeps the whole staging line
    in the walls' range (WallRoom), or the range's middle when the line is longer. A
    clip into a range fixed per workspace and k, so continuous in p.
    """
    half = 0.5 * (len(rank) - 1) * layout.pitch
    centre = float(p.mean())
    room = layout.walls
    if room is not None:
        centre = _clip_or_middle(centre, room.low + half, room.high - half)
    return centre + (rank - (len(rank) - 1) / 2) * layout.pitch


def _clip_or_middle(value: float, low: float, high: float) -> float:
    """
    Return value clipped into [low, high], or the middle of the two when high < low.

    The walls' rule for where the staging line and the lanes go: low and high are
    fixed per workspace and count (of robots, of lanes), so the result is
    continuous in value, and where the line or the lanes are longer than the room
    allows they are centred in it.
    """
    return 0.5 * (low + high) if high < low else float(np.clip(value, low, high))


def shared_lanes(first: np.ndarray, second: np.ndarray) -> np.ndarray:
    """
    Return each robot's lane (0, 1, ...) for the slide from slots first to slots second.

    Robots whose slots keep their order may share a lane: both slides are
    linear between slots g apart, so they stay g apart. Patience sorting puts
    every robot, in first-slot order, on the first lane whose last robot has a
    smaller second slot: as few lanes as the longest run of robots whose order
    reverses. It depends on the two rank orders only.
    """
    lanes = np.empty(len(first), dtype=int)
    tops: list[int] = []  # minus the last second slot of each lane: increasing along the list
    for robot in np.argsort(first).tolist():
        target = -int(second[robot])
        lane = bisect_left(tops, target)
        if lane == len(tops):
            tops.append(target)
        else:
            tops[lane] = target
        lanes[robot] = lane
    return lanes


def transposition_rounds(first: np.ndarray, second: np.ndarray) -> list[np.ndarray]:
    """
    Return the slot orders of odd-even transposition sort from slots first to second.

    Round t swaps the robots of slots i, i + 1 (i = t mod 2, t + 2, ...) whose second
    slots are the other way round; rounds without a swap are left out. The last order
    is second, after at most k rounds; each round's swaps are disjoint and adjacent, so
    two lanes pass them (shared_lanes).
    """
    order = np.argsort(first)  # order[s]: the robot in slot s
    orders = []
    for parity in range(len(first)):
        left = order[parity % 2:-1:2]
        right = order[parity % 2 + 1::2]
        swap = second[left] > second[right]
        if swap.any():
            order = order.copy()
            order[parity % 2:-1:2][swap], order[parity % 2 + 1::2][swap] = (right[swap],
                                                                            left[swap])
            slots = np.empty_like(first)
            slots[order] = np.arange(len(first))
            orders.append(slots)
    return orders


def passing_orders(first: np.ndarray, second: np.ndarray,
                   lane_limit: int | None) -> list[np.ndarray]:
    """
    Return the slot orders Gamma slides through from slots first to second, second last.

    One slide when its shared lanes are at most lane_limit (always without walls).
    Otherwise the orders of transposition_rounds, as few of them as greedily fit: from
    each order the farthest later one whose slide needs at most lane_limit lanes. A
    round swaps only pairs the wrong way round for second, so no pair is swapped back:
    the pairs whose order differs from a given round's only grow, and so does the
    longest run of them that reverses (the lanes), round after round. The farthest
    round that fits is therefore the last of the first ones that do, found in one pass.
    Every round fits in two, so this ends; it depends on the two rank orders only.
    """
    if lane_limit is None or shared_lanes(first, second).max() < lane_limit:
        return [second]
    rounds = transposition_rounds(first, second)
    orders, current, end = [], first, 0
    while end < len(rounds):
        end += 1  # one round always fits
        while end < len(rounds) and shared_lanes(current, rounds[end]).max() < lane_limit:
            end += 1
        current = rounds[end - 1]
        orders.append(current)
    return orders


@dataclass(frozen=True)
class _Staged:
    """One configuration carried to its slots' columns: H(C) as section() needs it."""

    risen: np.ndarray  # the sidestep and rise's stages, C first
    names: list[str]  # their legs
    rank: np.ndarray  # each robot's slot
    columns: np.ndarray  # the gathered fleet, each robot in its slot's column


@dataclass(frozen=True)
class DiscSection:
    """The breakpoints of the whole motion, leg names, waypoints' indices, lanes' e2 offsets."""

    positions: np.ndarray
    leg_names: tuple[str, ...]
    waypoint_indices: np.ndarray
    lane_heights: np.ndarray


def staging_height(layout: DiscLayout, offsets: np.ndarray, top_lane: int) -> float:
    """
    Return a segment's staging height: top, or without pillars the fleet's middle.

    offsets (2, k) are the robots' e2 offsets in the segment's two
    configurations, top_lane its highest lane. Without pillars no height needs
    clearing, and the lanes are centred on the mean offset: a continuous
    function of the two configurations, near the fleet wherever the frame's
    origin lies (the axis, h = 0, can be far from it). Below walls that height is
    clipped between the room's floor and its ceiling less the lanes (WallRoom), or
    is the middle where the lanes do not fit: a clip into a range fixed per
    workspace and lane count, so still continuous.
    """
    if layout.reach.size:
        return layout.top
    height = float(offsets.mean()) - 0.5 * top_lane * layout.pitch
    room = layout.walls
    if room is None:
        return height
    return _clip_or_middle(height, room.floor, room.ceiling - top_lane * layout.pitch)


def section(configurations: np.ndarray, layout: DiscLayout) -> DiscSection:
    """
    Return the disc section through configurations (n, k, d): H(C_m), Gamma, H(C_{m+1})^-1.

    Legs along which no robot moves are left out; the configurations stay
    breakpoints, exactly.
    """
    n, k, _ = configurations.shape
    e1, e2 = layout.frame.e1, layout.frame.e2
    deformations = []
    projections = layout.frame.project(configurations)
    offsets = layout.frame.offset(configurations)
    for configuration, p, h in zip(configurations, projections, offsets):
        risen = rise(p, h, layout, layout.reaches(configuration)).positions(configuration,
                                                                            layout.frame)
        names = [SIDESTEP] + [RISE] * (len(risen) - 2)
        rank = staging_ranks(p)
        slots = staging_slots(p, rank, layout)
        # The gather moves along e1 only, into the slots' columns, at the risen heights.
        deformations.append(_Staged(risen, names, rank,
                                    risen[-1] + (slots - p)[:, None] * e1))
    stages, names, ends, heights = [configurations[0]], [''], [], set()
    for m in range(n - 1):
        here, there = deformations[m], deformations[m + 1]
        rank, next_rank, columns, next_columns = here.rank, there.rank, here.columns, there.columns
        # Lane 0 is the staging height itself: its robots need no lift. Below walls the
        # robots may pass in several slides, each within the lanes the walls leave
        # (passing_orders), a lift along each robot's column between two.
        orders = passing_orders(rank, next_rank,
                                None if layout.walls is None else layout.walls.lanes)
        lanes = [shared_lanes(before, after)
                 for before, after in zip([rank, *orders[:-1]], orders)]
        top = staging_height(layout, offsets[m:m + 2], max(int(lane.max()) for lane in lanes))
        # A slot is its column at the staging height, other coordinates (d >= 3) kept:
        # the first slide takes the next configuration's, later ones move along e1 only.
        slots, next_slots = (
            ends_of + (top - layout.frame.offset(ends_of))[:, None] * e2
            for ends_of in (columns, next_columns))
        # Slots one pitch apart on the same centre: an order's lie (order - next rank) g
        # from the next configuration's.
        passed = [next_slots + ((order - next_rank) * layout.pitch)[:, None] * e1
                  for order in orders[:-1]] + [next_slots]
        stages += [*here.risen[1:], columns]
        names += [*here.names, GATHER]
        for before, after, lane in zip([slots, *passed[:-1]], passed, lanes):
            lift = lane * layout.pitch
            heights.update((top + lift).tolist())
            stages += [before + lift[:, None] * e2, after + lift[:, None] * e2]
            names += [LIFT, SLIDE]
        stages += [next_columns, there.risen[-1], *there.risen[-2::-1]]
        names += [DROP, GATHER + '^-1', *(name + '^-1' for name in there.names[::-1])]
        stages[-1] = configurations[m + 1]
        ends.append(len(stages) - 1)
    every = np.stack(stages)
    # A stage equal to the one before it (a leg in which no robot moves) is left out;
    # a configuration left out that way is bit for bit the stage kept before it. The
    # configurations are kept all the same, so a segment in which no robot moves keeps one
    # leg (of length 0) and every waypoint its own breakpoint.
    kept = np.concatenate([[True], np.any(every[1:] != every[:-1], axis=(1, 2))])
    kept[ends] = True
    waypoints = np.concatenate([[0], np.cumsum(kept)[ends] - 1])
    return DiscSection(every[kept], tuple(np.array(names)[kept][1:].tolist()), waypoints,
                       np.array(sorted(heights)))
