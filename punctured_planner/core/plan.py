"""
The plan: the sequential section sigma_{j_1..j_n} as exact breakpoints (paper, Section 4).

`plan` validates the configurations and takes every C_m's projection count
cp(C_m); then builds the variant's construction. For 'paper' and 'spread':
the desingularisation D (only below the top stratum), the spreading leg S
('spread'), the projection phi onto the axis, and Gamma between consecutive
axis configurations as in Remark 2.3. For 'discs': core.discs.section (the same
skeleton onto a staging line above the pillars). The motion is then refined
(core.refine, unless refine=False), certified (required_clearance) and checked
against the walls. Every leg is linear and all robots switch legs together, so
the motion is the piecewise-linear interpolation of its breakpoints, stored
exactly.
"""

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree

from . import discs
from .certificate import (BodyCertificates, certify, certify_bodies, Clearance,
                          RELATIVE_RESOLUTION)
from .complexity import domain_range, sequential_complexity
from .deformations import desingularize, desingularizing_shift, spread
from .errors import ErrorCode, PlanningError
from .pairs import point_radii
from .refine import block_count, Constraints, refine as refine_motion, Refinement
from .sections import compose, lane_heights, SCHEDULES, segment_times
from .space import Workspace
from .strata import epsilon, projection_count, projection_gaps
from .timing import (leg_at, length_times, resample, SpeedProfile, stamps as timed_stamps,
                     tolerance_profile, tracking_tolerance)
from .validation import validate_configurations
from .walls import smallest_leg_slack, WallSlack

# How far a picture's axis (Plan.axis_segment) reaches beyond the projections: this share of
# their spread.
AXIS_MARGIN = 0.08


@dataclass(frozen=True, eq=False)
class Samples:
    """
    The poses of a plan as a robot gets them: one shared list of times, no pose twice.

    values (M,) are stamps in seconds (or parameters tau), positions (M, k, d);
    ``waypoints[m]`` is the index of the pose at C_m, which is present exactly.
    A breakpoint that repeats the previous one's time and positions (the end
    of a leg in which no robot moves) is left out, so stamps strictly increase
    wherever the robots move by more than the stamps' rounding (doc/design.md
    section 8).
    """

    values: np.ndarray
    positions: np.ndarray
    waypoints: np.ndarray

    def last_waypoint(self) -> np.ndarray:
        """Return (M,) the index m of the last configuration C_m passed at each pose."""
        return np.searchsorted(self.waypoints, np.arange(self.values.size), side='right') - 1


class Plan:
    """
    A synchronous motion through C_1..C_n, stored as breakpoints; min_gap is its exact gap.

    Built by one of its named constructors: ``axis`` (the paper's and the spread
    variant's construction), ``discs`` (the discs variant's) or ``refined`` (a
    construction's motion after core.refine; ``raw`` is then that construction's
    Plan and ``margin`` the gap the refinement keeps).
    """

    def __init__(self, *, workspace: Workspace, configurations: np.ndarray, times: np.ndarray,
                 positions: np.ndarray, leg_names: tuple[str, ...],
                 waypoint_indices: np.ndarray, projection_counts: np.ndarray,
                 lanes: np.ndarray, spacing: np.ndarray | None,
                 raw: 'Plan | None' = None, margin: float | None = None) -> None:
        """Keep the breakpoints and the data the derived attributes need."""
        n, k, d = configurations.shape
        r = workspace.obstacle_count
        self.workspace = workspace
        self.configurations = configurations
        self.times = times
        self.positions = positions
        self.leg_names = leg_names
        self.waypoint_indices = waypoint_indices
        self.projection_counts = projection_counts
        self.domain = int(projection_counts.sum())
        low, high = domain_range(n, k, r)
        self.domain_range = (low, high)
        self.domain_index = self.domain - low
        self.domain_count = high - low + 1
        self.sequential_complexity = sequential_complexity(n, k, r, d)
        self.optimal = self.domain_count == self.sequential_complexity
        self.frame = workspace.frame
        self.variant = workspace.variant
        self.lanes = lanes
        self._spacing = spacing
        self.raw = raw
        self.margin = margin
        self._stamps: dict[tuple[float, float], np.ndarray] = {}

    @classmethod
    def axis(cls, workspace: Workspace, configurations: np.ndarray, positions: np.ndarray,
             projection_counts: np.ndarray, lanes: np.ndarray,
             spacing: np.ndarray) -> 'Plan':
        """Return the paper's or spread variant's plan: its schedule's legs in every segment."""
        n = len(configurations)
        schedule = SCHEDULES[workspace.variant]
        legs = len(schedule.legs)
        return cls(workspace=workspace, configurations=configurations,
                   times=segment_times(n, schedule.fractions), positions=positions,
                   leg_names=schedule.legs * (n - 1), waypoint_indices=np.arange(n) * legs,
                   projection_counts=projection_counts, lanes=lanes, spacing=spacing)

    @classmethod
    def discs(cls, workspace: Workspace, configurations: np.ndarray,
              section: discs.DiscSection, projection_counts: np.ndarray) -> 'Plan':
        """Return the discs variant's plan, its legs timed by their length."""
        return cls(workspace=workspace, configurations=configurations,
                   times=length_times(section.positions, section.waypoint_indices),
                   positions=section.positions, leg_names=section.leg_names,
                   waypoint_indices=section.waypoint_indices,
                   projection_counts=projection_counts, lanes=section.lane_heights,
                   spacing=None)

    @classmethod
    def refined(cls, raw: 'Plan', refinement: Refinement) -> 'Plan':
        """Return raw's refined plan: same domain, lanes and leg names (of the legs it splits)."""
        return cls(workspace=raw.workspace, configurations=raw.configurations,
                   times=refinement.times, positions=refinement.positions,
                   leg_names=tuple(raw.leg_names[leg] for leg in refinement.base_legs.tolist()),
                   waypoint_indices=refinement.waypoint_indices,
                   projection_counts=raw.projection_counts, lanes=raw.lanes,
                   spacing=raw._spacing, raw=raw, margin=refinement.margin)

    @cached_property
    def clearance(self) -> Clearance:
        """Return the exact Clearance certificate (computed once, on first use)."""
        if self.workspace.has_bodies:
            return self._certificates.clearance
        return certify(self.times, self.positions, self.workspace.obstacles)

    @cached_property
    def _certificates(self) -> BodyCertificates:
        """Return the clearance and gap with bodies, both from one pass over pairs and legs."""
        workspace = self.workspace
        k = self.positions.shape[1]
        radii = point_radii(k, workspace.robot_radius, workspace.obstacle_radii)
        return certify_bodies(self.times, self.positions, workspace.obstacles, radii)

    @property
    def min_clearance(self) -> float:
        """Return the exact minimum centre distance over all robot and robot-obstacle pairs."""
        return self.clearance.distance

    @cached_property
    def gap(self) -> Clearance:
        """
        Return the exact surface-gap certificate: its distance is the smallest gap.

        The gap is the centre distance - 2R for two robots and - R - rho_j for a
        robot and obstacle j; with no radius it is the clearance itself.
        """
        if not self.workspace.has_bodies:
            return self.clearance
        return self._certificates.gap

    @property
    def min_gap(self) -> float:
        """Return the exact minimum surface gap over the whole motion; negative means contact."""
        return self.gap.distance

    @cached_property
    def wall_slack(self) -> WallSlack | None:
        """
        Return the exact smallest slack of a robot's body to a wall (None without walls).

        Its slack is the body's distance to the wall (centre less robot_radius), the
        robot, wall and first leg that reach it named (core.walls.smallest_leg_slack).
        """
        bounds = self.workspace.bounds
        return (None if bounds is None
                else smallest_leg_slack(self.positions, bounds, self.workspace.robot_radius))

    @property
    def wall_gap(self) -> float:
        """Return the smallest gap of a robot's body to a wall over the motion (inf: no walls)."""
        return np.inf if self.wall_slack is None else self.wall_slack.slack

    @property
    def tracking_tolerance(self) -> float:
        """Return how far each robot may stray from its reference: min(min_gap / 2, wall_gap)."""
        return tracking_tolerance(self.min_gap, self.wall_gap)

    def segment_of(self, leg: int) -> int:
        """Return m, 0-based, of the segment C_{m+1} -> C_{m+2} that leg [leg, leg + 1] is in."""
        return int(np.searchsorted(self.waypoint_indices, leg, side='right')) - 1

    @cached_property
    def input_separation(self) -> float:
        """Return the smallest robot-robot or robot-obstacle distance in any C_m."""
        obstacles = self.workspace.obstacles
        smallest = np.inf
        for configuration in self.configurations:
            if len(configuration) > 1:
                smallest = min(smallest, cKDTree(configuration).query(configuration, k=2)[0][:, 1]
                               .min())
            if len(obstacles):
                smallest = min(smallest, cKDTree(obstacles).query(configuration)[0].min())
        return float(smallest)

    @cached_property
    def clearance_bound(self) -> float | None:
        """
        Return a lower bound on min_clearance for the 'spread' variant (None for the others).

        bound = min(s / (k + r) if some C_m is singular else s, g, lane_spacing):
        s is the input separation; D moves the robots of a singular C_m by less
        than the smallest projection gap, so its legs keep s / (k + r); S and
        the axis legs keep the spacing g actually used (min_spacing, or less in
        an interval too short for its robots); the slides run in lanes
        lane_spacing apart and beyond the obstacles.
        """
        if self.variant != 'spread' or self._spacing is None:
            return None
        k = self.configurations.shape[1]
        singular = np.any(self.projection_counts < k + self.workspace.obstacle_count)
        separation = self.input_separation
        if singular:
            separation /= k + self.workspace.obstacle_count
        return float(min(separation, self._spacing.min(), self.workspace.lane_spacing))

    def axis_segment(self) -> np.ndarray:
        """
        Return the (2, d) end points of the part of the axis o + s e1 a picture shows.

        It covers every robot's and every obstacle's projection, with AXIS_MARGIN
        times their spread (at least 1) beyond each end.
        """
        values = np.concatenate([self.frame.project(self.positions).ravel(),
                                 self.workspace.obstacle_projections])
        low, high = float(values.min()), float(values.max())
        pad = AXIS_MARGIN * max(high - low, 1.0)
        return self.frame.axis_points(np.array([low - pad, high + pad]))

    def lane_segments(self) -> np.ndarray:
        """
        Return the (L, 2, d) end points of the lanes: the axis segment lifted by each lane.

        One lane per robot (L = k), except for 'discs', whose robots share lanes.
        """
        return self.axis_segment()[None] + self.lanes[:, None, None] * self.frame.e2

    def position(self, tau: npt.ArrayLike) -> np.ndarray:
        """Return the robot positions at parameter(s) tau in [0, 1]: (k, d) or (..., k, d)."""
        tau = np.asarray(tau, dtype=float)
        leg = leg_at(self.times, tau)
        start, end = self.times[leg], self.times[leg + 1]
        with np.errstate(divide='ignore', invalid='ignore'):
            fraction = np.where(end > start, (tau - start) / (end - start), 0.0)
        fraction = np.clip(fraction, 0.0, 1.0)[..., None, None]
        # (1 - f) a + f b, not a + f (b - a): exact at both ends of every leg.
        return (1.0 - fraction) * self.positions[leg] + fraction * self.positions[leg + 1]

    def profile(self, max_speed: float, max_acceleration: float,
                positions: np.ndarray | None = None) -> SpeedProfile:
        """
        Return the SpeedProfile under both limits (doc/design.md section 8).

        positions default to the breakpoints; Plan.sample passes them without
        the repeated ones, which leaves every stamp as it is.
        """
        return tolerance_profile(self.positions if positions is None else positions, max_speed,
                                 max_acceleration, self.tracking_tolerance)

    def stamps(self, max_speed: float, max_acceleration: float = 0.0) -> np.ndarray:
        """
        Return (V,) seconds from the start at each breakpoint, fastest robot at max_speed.

        max_acceleration 0 (unlimited): each leg at max_speed throughout; else the
        profile's stamps, at rest at both ends and slowed into the corners. Computed
        once per pair of limits and kept, read-only: an answer takes the duration and
        then the samples from the same stamps.
        """
        key = (float(max_speed), float(max_acceleration))
        found = self._stamps.get(key)
        if found is None:
            # the tolerance only matters to the corners of a limited profile: no certificate
            # for 0
            found = timed_stamps(self.positions, max_speed, max_acceleration,
                                 self.tracking_tolerance if max_acceleration else 0.0)
            found.flags.writeable = False
            self._stamps[key] = found
        return found

    def duration(self, max_speed: float, max_acceleration: float = 0.0) -> float:
        """Return the duration in seconds of the whole motion under both limits."""
        return float(self.stamps(max_speed, max_acceleration)[-1])

    def sample(self, samples_per_leg: int, max_speed: float | None = None,
               max_acceleration: float = 0.0) -> Samples:
        """
        Return the Samples: every distinct breakpoint and samples_per_leg more inside each leg.

        values are stamps in seconds when max_speed is given, else parameters tau.
        In stamps a leg where no robot moves lasts no time, so its end repeats its
        start and is left out; in tau it still takes its share of [0, 1]. Under an
        acceleration limit the samples are evenly spaced along each leg and
        stamped by the profile.
        """
        values = (self.times if max_speed is None
                  else self.stamps(max_speed, max_acceleration))
        new = self._distinct(values)
        # resample uses the profile only to stamp samples inside the legs: with none,
        # every stamp is a breakpoint's own.
        profile = (self.profile(max_speed, max_acceleration, self.positions[new])
                   if max_speed is not None and max_acceleration > 0 and samples_per_leg > 0
                   else None)
        values, positions, _ = resample(values[new], self.positions[new], samples_per_leg,
                                        profile)
        kept = new.cumsum() - 1
        step = max(int(samples_per_leg), 0) + 1
        return Samples(values, positions, kept[self.waypoint_indices] * step)

    def stamped_breakpoints(self, max_speed: float, max_acceleration: float = 0.0) -> int:
        """Return how many breakpoints sample keeps in stamps: the answer's count, unsampled."""
        return int(self._distinct(self.stamps(max_speed, max_acceleration)).sum())

    @cached_property
    def _moved(self) -> np.ndarray:
        """Return the (V - 1,) mask of breakpoints whose poses differ from the one before."""
        return (self.positions[1:] != self.positions[:-1]).any(axis=(1, 2))

    def _distinct(self, values: np.ndarray) -> np.ndarray:
        """Return the (V,) mask of breakpoints kept: the first, then each new in value or pose."""
        new = np.ones(values.size, dtype=bool)
        new[1:] = (values[1:] != values[:-1]) | self._moved
        return new


def plan(workspace: Workspace, configurations: npt.ArrayLike, certify: bool = True,
         refine: bool = True) -> Plan:
    """
    Return the Plan through configurations (n, k, d) in workspace, or raise PlanningError.

    With refine (the default) the construction's motion is refined (core.refine):
    shorter, with a gap never below the construction's own exact min_gap, in
    the same domain. With certify (the default) the exact certificate is
    computed at once and a plan below workspace.required_clearance is refused
    (its gap when robots or obstacles have a radius). Whatever certify, a plan
    that leaves workspace.bounds is refused (OUTSIDE_WORKSPACE, core.walls:
    exact and linear in the breakpoints), never returned.
    """
    configurations = validate_configurations(configurations, workspace.obstacles,
                                             workspace.robot_radius, workspace.obstacle_radii,
                                             workspace.bounds)
    projections = workspace.frame.project(configurations)
    gaps = projection_gaps(projections, workspace.obstacle_projections)
    counts = projection_count(gaps)
    if workspace.variant == 'discs':
        result = Plan.discs(workspace, configurations,
                            discs.section(configurations, workspace.disc_layout), counts)
    else:
        result = _axis_plan(workspace, configurations, projections, gaps, counts)
    if refine:
        result = _refined(result)
    if certify:
        _check_required_clearance(result)
    _check_inside(result)
    return result


def _axis_plan(workspace, configurations, projections, gaps, counts):
    """Return the paper's or the spread variant's Plan: D, (S,) phi onto the axis, Gamma."""
    n, k, d = configurations.shape
    r = workspace.obstacle_count
    frame = workspace.frame
    eps = epsilon(gaps, workspace.lane_spacing)
    shift = desingularizing_shift(counts, eps, k, r)
    desingularized = desingularize(configurations, shift, frame.e1)
    projections = projections + shift
    stages = [configurations, desingularized]
    if workspace.variant == 'spread':
        spread_projections, spacing = spread(projections, workspace.sorted_obstacle_projections,
                                             workspace.min_spacing)
        stages.append(desingularized + (spread_projections - projections)[..., None] * frame.e1)
        projections = spread_projections
    else:
        spacing = np.full((n, k), np.inf)
    stages.append(frame.axis_points(projections))
    lanes = lane_heights(k, r, workspace.lane_spacing, workspace.lane_base, workspace.variant)
    return Plan.axis(workspace, configurations, compose(stages, lanes, frame.e2), counts, lanes,
                     spacing)


def _refined(raw):
    """
    Return raw refined against its own exact gap (core.refine, doc/design.md section 14).

    Beyond refine.MAX_ROBOTS robots raw itself (its raw attribute None says so).
    """
    if block_count(raw.positions.shape[1]) == 0:
        return raw
    workspace = raw.workspace
    k = raw.positions.shape[1]
    radii = point_radii(k, workspace.robot_radius, workspace.obstacle_radii)
    rounding = RELATIVE_RESOLUTION * float(np.abs(raw.positions).max(initial=1.0))
    constraints = Constraints(workspace.obstacles, radii, raw.min_gap, rounding,
                              workspace.bounds)
    return Plan.refined(raw, refine_motion(raw.times, raw.positions, raw.waypoint_indices,
                                           constraints))


def _check_required_clearance(result: Plan) -> None:
    """
    Raise CLEARANCE_BELOW_REQUIRED if the certified clearance is not enough.

    Not enough means below workspace.required_clearance (the surface gap when
    robots or obstacles have a radius, else the centre distance), or a centre
    distance not above the numerical resolution of the coordinates (then
    rounding could hide a touch). A gap below the requirement is named first: a
    plan whose bodies overlap by 0.33 m, a centre passing a pillar's, was refused
    for the resolution of coordinates of a few metres.
    """
    required = result.workspace.required_clearance
    resolution = result.clearance.resolution
    certificate = result.gap
    if certificate.distance < required:
        limit = (f'surface to surface (gap), < required {required:.6g}'
                 if result.workspace.has_bodies else f'< required {required:.6g}')
    elif result.clearance.distance <= resolution:
        certificate = result.clearance
        limit = f'<= {resolution:.3g}, the numerical resolution of coordinates this large'
    else:
        return
    a, b = certificate.indices
    what = '{robots}' if certificate.kind == 'robots' else '{robot} and {obstacle}'
    segment = result.segment_of(certificate.leg)
    raise PlanningError(
        ErrorCode.CLEARANCE_BELOW_REQUIRED,
        f'{what} come within {certificate.distance:.6g} {limit} on leg '
        f'{certificate.leg} ({result.leg_names[certificate.leg]} of segment {{waypoint}} -> '
        f'{{next_waypoint}}) at tau {certificate.tau:.6g}',
        configuration=segment, robots=[a] if certificate.kind == 'obstacle' else [a, b],
        obstacle=b if certificate.kind == 'obstacle' else None, clearance=result.clearance,
        gap=result.gap)


def _check_inside(result: Plan) -> None:
    """
    Raise OUTSIDE_WORKSPACE if some robot of result leaves its workspace's bounds.

    Exact (smallest_leg_slack); the error names the robot, the wall, how far
    beyond it the robot reaches, and the first leg that reaches that far.
    """
    workspace, bounds, worst = result.workspace, result.workspace.bounds, result.wall_slack
    if bounds is None or worst is None or worst.slack >= 0:
        return
    leg = worst.index
    ends = result.positions[leg:leg + 2, worst.body, worst.wall.axis]
    centre = float(ends.max() if worst.wall.high else ends.min())
    raise PlanningError(
        ErrorCode.OUTSIDE_WORKSPACE,
        'the plan takes {robot} '
        f'{worst.words(bounds, centre, workspace.robot_radius, "robot_radius")} on leg {leg} '
        f'({result.leg_names[leg]} of segment {{waypoint}} -> {{next_waypoint}})',
        configuration=result.segment_of(leg), robots=[worst.body], wall=worst.wall,
        distance=worst.beyond, leg=leg)
