"""
Time parameterisation of a synchronous piecewise-linear motion (doc/design.md section 8).

Any reparameterisation common to all robots keeps the motion collision-free,
so each leg gets the duration that lets its fastest robot move at max_speed.
With an acceleration limit a (:class:`SpeedProfile`) the path length sigma
(the fastest robot's displacement, summed over the legs) follows a speed
profile with |sigma''| <= a, slowed into every corner so that no robot's
velocity jumps there by more than :func:`corner_jump`.
"""

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import numpy.typing as npt

# Share beta of the tracking tolerance delta a corner's velocity jump may cost: a robot of
# acceleration a lags a jump dv by at most dv^2 / (2 a) (doc/design.md section 8).
CORNER_SHARE = 0.1


def leg_at(times: np.ndarray, at: npt.ArrayLike) -> np.ndarray:
    """
    Return the leg j, [times[j], times[j + 1]), holding each time of at (same shape).

    times (V,) are a motion's breakpoint times (or stamps), V >= 2; a time at or
    beyond the last one is in the last leg, one before the first in the first.
    """
    return np.clip(np.searchsorted(times, at, side='right') - 1, 0, max(times.size - 2, 0))


def leg_lengths(positions: np.ndarray) -> np.ndarray:
    """Return the (V - 1,) largest robot displacement along each leg."""
    steps = positions[1:] - positions[:-1]  # np.diff's own difference, without its wrapper
    if steps.shape[1] == 0:
        return np.zeros(steps.shape[0])
    return np.sqrt(np.einsum('vkd,vkd->vk', steps, steps)).max(axis=1)


def length_times(positions: np.ndarray, waypoint_indices: np.ndarray) -> np.ndarray:
    """
    Return (V,) breakpoint parameters with waypoint m at tau_m = m / (n - 1).

    Inside a segment each leg takes a share of [tau_m, tau_{m+1}] proportional
    to its length (its fastest robot's displacement): continuous in the
    positions, and a leg of length 0 takes no time. In a segment in which no
    robot moves the legs share it evenly: the motion is the same whatever the
    shares, and moves by no more than the segment's length near such a segment.
    """
    n = len(waypoint_indices)
    lengths = leg_lengths(positions)
    times = np.empty(len(positions))
    for m in range(n - 1):
        first, last = waypoint_indices[m], waypoint_indices[m + 1]
        cumulative = np.concatenate([[0.0], np.cumsum(lengths[first:last])])
        shares = (cumulative / cumulative[-1] if cumulative[-1] > 0
                  else np.linspace(0.0, 1.0, cumulative.size))
        times[first:last + 1] = (m + shares) / (n - 1)
    times[waypoint_indices] = np.arange(n) / (n - 1)
    return times


def _positive_finite(*limits: float | np.ndarray) -> bool:
    """Return whether every limit (a number or an array of them) is positive and finite."""
    return all(bool(np.all((np.asarray(limit) > 0) & (np.asarray(limit) < np.inf)))
               for limit in limits)


def breakpoint_stamps(positions: np.ndarray, max_speed: float) -> np.ndarray:
    """Return (V,) seconds from the start at which the robots reach each breakpoint."""
    if not _positive_finite(max_speed):
        raise ValueError('max_speed must be positive and finite')
    stamps = np.zeros(len(positions))
    np.add.accumulate(leg_lengths(positions) / max_speed, out=stamps[1:])
    return stamps


def tracking_tolerance(min_gap: float, wall_gap: float) -> float:
    """
    Return delta = min(min_gap / 2, wall_gap): the largest safe deviation from a reference.

    Two bodies each within delta of their references close by at most 2 delta <=
    min_gap, a body and a pillar by delta; a body and a wall (its reference wall_gap
    from it) by delta <= wall_gap: a robot within the tolerance that ignored the walls
    could touch a wall its reference passes closer than min_gap / 2 (doc/design.md
    section 13). The timing law spends a share of it on the corners (corner_jump).
    """
    return min(0.5 * float(min_gap), float(wall_gap))


def corner_jump(max_acceleration: float, tolerance: float) -> float:
    """
    Return the largest velocity jump (m/s) a corner may give any robot of a plan.

    A robot that accelerates at max_acceleration toward a velocity that
    jumped by dv lags it by dv^2 / (2 a); this is the dv for which that lag is
    CORNER_SHARE of the tracking tolerance delta (tracking_tolerance).
    """
    return float(np.sqrt(2.0 * max_acceleration * CORNER_SHARE * max(tolerance, 0.0)))


@dataclass(frozen=True)
class LegState:
    """Where the fastest robot is along a leg: distance (m), speed (m/s), acceleration."""

    distance: float
    speed: float
    acceleration: float


@dataclass(frozen=True, eq=False)
class SpeedProfile:
    """
    The speed of the path length sigma along a motion's legs, at rest at both ends.

    lengths (L,) are the legs' lengths in sigma (the fastest robot's
    displacement), speeds (L + 1,) sigma's speed at each breakpoint. Inside a
    leg sigma accelerates at max_acceleration, cruises at most at max_speed,
    then brakes at max_acceleration: the fastest bang-coast-bang between the
    breakpoint speeds, which the passes of :func:`speed_profile` keep
    reachable. Both limits are one value, or (L,) one per leg
    (:func:`fleet_profile`: the robots' own limits).
    """

    lengths: np.ndarray
    speeds: np.ndarray
    max_speed: float | np.ndarray
    max_acceleration: float | np.ndarray

    @cached_property
    def _accelerations(self) -> np.ndarray:
        """Return the (L,) legs' acceleration limits (one value broadcast to every leg)."""
        return np.broadcast_to(np.asarray(self.max_acceleration, dtype=float),
                               self.lengths.shape)

    @cached_property
    def _phases(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Return (L,) peak speeds, accelerating, cruising and braking times of every leg."""
        a, start, end = self.max_acceleration, self.speeds[:-1], self.speeds[1:]
        peak = np.minimum(self.max_speed,
                          np.sqrt(0.5 * (start ** 2 + end ** 2) + a * self.lengths))
        speeding, braking = (peak - start) / a, (peak - end) / a
        cruise = self.lengths - (2.0 * peak ** 2 - start ** 2 - end ** 2) / (2.0 * a)
        with np.errstate(divide='ignore', invalid='ignore'):
            cruising = np.where(peak > 0, np.maximum(cruise, 0.0) / peak, 0.0)
        return peak, speeding, cruising, braking

    def durations(self) -> np.ndarray:
        """Return the (L,) legs' durations in seconds."""
        _, speeding, cruising, braking = self._phases
        return speeding + cruising + braking

    def stamps(self) -> np.ndarray:
        """Return (L + 1,) seconds from the start at each breakpoint."""
        return np.concatenate([[0.0], np.cumsum(self.durations())])

    def time_at(self, leg: int, distances: np.ndarray) -> np.ndarray:
        """Return the seconds from leg's start at which sigma has moved distances along it."""
        a, start = self._accelerations[leg], self.speeds[leg]
        peak, speeding, cruising, _ = (phase[leg] for phase in self._phases)
        reach = (peak ** 2 - start ** 2) / (2.0 * a)
        x = np.clip(distances, 0.0, self.lengths[leg])
        # 2x / (v0 + sqrt(v0^2 + 2ax)): the root of v0 t + a t^2 / 2 = x without cancellation
        rising = 2.0 * x / np.maximum(start + np.sqrt(start ** 2 + 2.0 * a * x), 1e-300)
        coasting = speeding + (x - reach) / max(peak, 1e-300)
        left = np.maximum(x - reach - peak * cruising, 0.0)
        falling = speeding + cruising + 2.0 * left / np.maximum(
            peak + np.sqrt(np.maximum(peak ** 2 - 2.0 * a * left, 0.0)), 1e-300)
        return np.where(x <= reach, rising,
                        np.where(x <= reach + peak * cruising, coasting, falling))

    def state_at(self, leg: int, seconds: float) -> LegState:
        """Return sigma's LegState seconds after leg's start (clamped to the leg)."""
        a, start = float(self._accelerations[leg]), float(self.speeds[leg])
        peak, speeding, cruising, braking = (float(phase[leg]) for phase in self._phases)
        t = min(max(seconds, 0.0), speeding + cruising + braking)
        reach = start * speeding + 0.5 * a * speeding ** 2
        late = t - speeding - cruising
        if t < speeding:
            distance, speed, acceleration = start * t + 0.5 * a * t * t, start + a * t, a
        elif t < speeding + cruising:
            distance, speed, acceleration = reach + peak * (t - speeding), peak, 0.0
        else:
            distance = reach + peak * cruising + peak * late - 0.5 * a * late * late
            speed, acceleration = peak - a * late, -a
        # Rounded, a phase's end can come an ulp past the leg's (a leg that ends cruising,
        # just before its end): never beyond the pose it ends at.
        return LegState(min(distance, float(self.lengths[leg])), speed, acceleration)


def speed_profile(positions: np.ndarray, max_speed: float, max_acceleration: float,
                  jump: float) -> SpeedProfile:
    """
    Return the fastest SpeedProfile of positions (V, k, d) under both limits.

    At rest at the first and the last breakpoint; at a breakpoint where the
    robots' velocities per unit of sigma change by Delta (the largest over
    the robots, across legs in which nothing moves), sigma's speed is at most
    jump / Delta, so no robot's velocity jumps by more than jump. A forward and
    a backward pass make every breakpoint speed reachable within its legs.
    """
    if not _positive_finite(max_speed, max_acceleration):
        raise ValueError('max_speed and max_acceleration must be positive and finite')
    lengths = leg_lengths(positions)
    speeds = _breakpoint_speeds(positions, lengths, np.full(len(lengths), float(max_speed)),
                                np.full(len(lengths), float(max_acceleration)),
                                np.full(positions.shape[1], float(jump)))
    return SpeedProfile(lengths, speeds, float(max_speed), float(max_acceleration))


def tolerance_profile(positions: np.ndarray, max_speed: float, max_acceleration: float,
                      tolerance: float) -> SpeedProfile:
    """Return the speed_profile whose corners spend their share of tolerance (corner_jump)."""
    return speed_profile(positions, max_speed, max_acceleration,
                         corner_jump(max_acceleration, tolerance))


def fleet_profile(positions: np.ndarray, max_speeds: np.ndarray,
                  max_accelerations: np.ndarray, tolerance: float,
                  stops: np.ndarray | None = None) -> SpeedProfile:
    """
    Return the fastest SpeedProfile of positions (V, k, d) for each robot's own limits.

    Robot i moves u_ij w on leg j (|u_ij| <= 1 per unit of sigma), so it stays
    within its max_speeds[i] and max_accelerations[i] (k,) where sigma's speed
    w <= min_i max_speeds[i] / |u_ij| and |w'| <= min_i max_accelerations[i] / |u_ij|
    (the robots that move on leg j); a corner where its u_i changes by
    Delta_i caps w at its own corner_jump / Delta_i; at the breakpoints where
    stops (V,) is true, w is 0 (every robot at rest). With every robot at the
    plan's limits and no stops this is :func:`speed_profile` (doc/design.md
    section 8).
    """
    max_speeds = np.asarray(max_speeds, dtype=float)
    max_accelerations = np.asarray(max_accelerations, dtype=float)
    if not _positive_finite(max_speeds, max_accelerations):
        raise ValueError('every max_speed and max_acceleration must be positive and finite')
    lengths = leg_lengths(positions)
    steps = np.linalg.norm(np.diff(positions, axis=0), axis=2)
    with np.errstate(divide='ignore', invalid='ignore'):
        rates = np.where(lengths[:, None] > 0, steps / lengths[:, None], 0.0)   # |u_ij|
        leg_speeds = np.where(rates > 0, max_speeds / rates, np.inf).min(axis=1)
        leg_accelerations = np.where(rates > 0, max_accelerations / rates,
                                     np.inf).min(axis=1)
    jumps = np.array([corner_jump(a, tolerance) for a in max_accelerations])
    # a leg in which nothing moves has no limit; its value is never used
    fallback = float(max_speeds.max()), float(max_accelerations.max())
    leg_speeds = np.where(np.isfinite(leg_speeds), leg_speeds, fallback[0])
    leg_accelerations = np.where(np.isfinite(leg_accelerations), leg_accelerations,
                                 fallback[1])
    speeds = _breakpoint_speeds(positions, lengths, leg_speeds, leg_accelerations, jumps,
                                stops)
    return SpeedProfile(lengths, speeds, leg_speeds, leg_accelerations)


def _breakpoint_speeds(positions: np.ndarray, lengths: np.ndarray, leg_speeds: np.ndarray,
                       leg_accelerations: np.ndarray, jumps: np.ndarray,
                       stops: np.ndarray | None = None) -> np.ndarray:
    """
    Return the (V,) fastest breakpoint speeds within per-leg limits (L,) and jumps (k,).

    A breakpoint's speed is at most both adjacent legs' speed limits and, at a
    corner, min_i jumps[i] / Delta_i (0 at stops (V,)); then a forward and a
    backward pass.
    """
    steps = np.diff(positions, axis=0)
    moving = np.flatnonzero(lengths > 0)
    caps = np.minimum(np.concatenate([[np.inf], leg_speeds]),
                      np.concatenate([leg_speeds, [np.inf]]))
    caps[[0, -1]] = 0.0
    if moving.size:
        caps[:moving[0] + 1] = 0.0
        caps[moving[-1] + 1:] = 0.0
        rates = steps[moving] / lengths[moving][:, None, None]
        change = np.linalg.norm(np.diff(rates, axis=0), axis=2)
        with np.errstate(divide='ignore', invalid='ignore'):
            corner = np.where(change > 0, jumps / change, np.inf).min(axis=1)
        for before, after, cap in zip(moving[:-1], moving[1:], corner):
            # every breakpoint from the end of one moving leg to the start of the next
            caps[before + 1:after + 1] = np.minimum(caps[before + 1:after + 1], cap)
    speeds = np.where(stops, 0.0, caps) if stops is not None else caps.copy()
    for leg in range(len(lengths)):
        speeds[leg + 1] = min(speeds[leg + 1], np.sqrt(
            speeds[leg] ** 2 + 2 * leg_accelerations[leg] * lengths[leg]))
    for leg in range(len(lengths) - 1, -1, -1):
        speeds[leg] = min(speeds[leg], np.sqrt(
            speeds[leg + 1] ** 2 + 2 * leg_accelerations[leg] * lengths[leg]))
    return speeds


def stamps(positions: np.ndarray, max_speed: float, max_acceleration: float,
           tolerance: float) -> np.ndarray:
    """
    Return (V,) seconds at each breakpoint of positions (V, k, d): the timing law.

    max_acceleration 0 (unlimited): each leg at max_speed throughout
    (:func:`breakpoint_stamps`); else the fastest SpeedProfile, its corners'
    jumps from the tracking tolerance (:func:`corner_jump`).
    """
    if max_acceleration == 0:
        return breakpoint_stamps(positions, max_speed)
    return tolerance_profile(positions, max_speed, max_acceleration, tolerance).stamps()


def resample(values: npt.ArrayLike, positions: np.ndarray, samples_per_leg: int,
             profile: SpeedProfile | None = None
             ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """
    Insert samples_per_leg evenly spaced samples inside every leg.

    values (V,) are breakpoint parameters or stamps, positions (V, k, d).
    Without a profile the values are linear inside a leg; with one (stamps
    under an acceleration limit) each sample's stamp is the profile's time at
    its distance along the leg. Returns (values (M,), positions (M, k, d),
    is_breakpoint (M,) bool); every breakpoint is kept exactly.
    """
    values = np.asarray(values, dtype=float)
    if samples_per_leg <= 0:
        return values, positions, np.ones(values.size, dtype=bool)
    fractions = np.arange(samples_per_leg + 1) / (samples_per_leg + 1)
    start_values, start_positions = values[:-1], positions[:-1]
    if profile is None:
        inner_values = start_values[:, None] + np.diff(values)[:, None] * fractions[None, :]
    else:
        inner_values = start_values[:, None] + np.array(
            [profile.time_at(leg, fractions * length)
             for leg, length in enumerate(profile.lengths)]).reshape(-1, fractions.size)
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
