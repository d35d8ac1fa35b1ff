"""
A plan as references: every robot's position and velocity at any plan time.

The plan's poses are its breakpoints with shared stamps, and linear
interpolation between consecutive poses is exactly the certified motion
(msg_docs/PlanSequence.md, ``paths``). So the reference at plan time s is that
interpolation, and its derivative, constant on each stamp interval, is the
feed-forward velocity. Intervals of zero length (several poses at one stamp)
are skipped.

A plan stamped under an acceleration limit (Plan.msg ``max_acceleration``)
moves along the same segments, but its speed follows the profile the stamps
were made with (doc/design.md section 8): :meth:`Reference.timed` rebuilds it
from the poses, each interval stretched to its stamps, so the poses stay
exact at their stamps; velocity and acceleration are then its derivatives.

:meth:`Reference.retimed` times the same motion for robots slower than the
plan's limits (each robot's own speed and acceleration): a common
reparameterisation of time, so every certificate of the plan still holds.
"""

from dataclasses import dataclass

import numpy as np

from ..core.timing import fleet_profile, leg_at, SpeedProfile, tolerance_profile


@dataclass(frozen=True)
class Progress:
    """
    How far along its segment an interval is at a plan time, and how fast that changes.

    fraction of the segment covered, and its rates per second (speed) and per
    second squared (acceleration).
    """

    fraction: float
    speed: float
    acceleration: float


@dataclass(frozen=True)
class Reference:
    """
    Breakpoints of a synchronous motion: seconds (M,) from its start, positions (M, k, 3).

    orientations (M, k, 4) are quaternions (x, y, z, w), held from each pose to
    the next one.
    """

    seconds: np.ndarray
    positions: np.ndarray
    orientations: np.ndarray
    profile: SpeedProfile | None = None     # None: linear in time between poses

    @classmethod
    def timed(cls, seconds: np.ndarray, positions: np.ndarray, orientations: np.ndarray,
              max_speed: float, max_acceleration: float, tolerance: float) -> 'Reference':
        """
        Return the Reference of poses stamped under both limits (0: linear in time).

        The corners' velocity jumps come from the tracking tolerance, as the
        planner's stamps (core.timing.corner_jump).
        """
        if max_acceleration <= 0:
            return cls(seconds, positions, orientations)
        return cls(seconds, positions, orientations,
                   tolerance_profile(positions, max_speed, max_acceleration, tolerance))

    def retimed(self, max_speeds: np.ndarray, max_accelerations: np.ndarray,
                tolerance: float, stops: np.ndarray | None = None) -> 'Reference':
        """
        Return the same motion timed so that robot i needs at most its own limits (k,).

        No robot faster than the plan: each limit is taken at most the plan's.
        A plan stamped under an acceleration limit, or any plan when every
        max_accelerations is finite, gets :func:`fleet_profile`'s stamps (a plan
        stamped without a limit at its own top speed), at rest at the poses where
        stops (M,) is true (doc/design.md section 8); otherwise the intervals stay
        linear, each at least as long as its slowest robot's move at max_speeds[i].
        Orientations stay with their poses.
        """
        speeds = np.asarray(max_speeds, dtype=float)
        accelerations = np.asarray(max_accelerations, dtype=float)
        if self.profile is not None:
            top_speed, top_acceleration = self.profile.max_speed, self.profile.max_acceleration
        else:
            top_speed, top_acceleration = self._top_speed(), np.inf
        if self.profile is None and not (np.isfinite(accelerations).all() and top_speed > 0):
            moves = np.linalg.norm(np.diff(self.positions, axis=0), axis=2)
            slowest = (moves / speeds).max(axis=1, initial=0.0)
            durations = np.maximum(np.diff(self.seconds), slowest)
            return Reference(np.concatenate([[0.0], np.cumsum(durations)]), self.positions,
                             self.orientations)
        profile = fleet_profile(self.positions, np.minimum(speeds, top_speed),
                                np.minimum(accelerations, top_acceleration), tolerance, stops)
        return Reference(profile.stamps(), self.positions, self.orientations, profile)

    def _top_speed(self) -> float:
        """Return the fastest any robot moves over an interval (m/s): a linear plan's limit."""
        moves = np.linalg.norm(np.diff(self.positions, axis=0), axis=2).max(axis=1, initial=0.0)
        durations = np.diff(self.seconds)
        timed = durations > 0
        return float((moves[timed] / durations[timed]).max(initial=0.0))

    def at_rest(self) -> np.ndarray:
        """Return the (M,) poses at which the reference stands still (its profile's w = 0)."""
        if self.profile is None:
            return np.zeros(self.seconds.size, dtype=bool)
        return self.profile.speeds == 0

    @property
    def duration(self) -> float:
        """Return the plan's duration in seconds (its last stamp)."""
        return float(self.seconds[-1])

    @property
    def robot_count(self) -> int:
        """Return k."""
        return int(self.positions.shape[1])

    def _interval(self, s: float) -> int:
        """Return the index j of the stamp interval [seconds[j], seconds[j+1]) holding s."""
        return int(leg_at(self.seconds, s))

    def _along(self, j: int, s: float) -> Progress:
        """Return the Progress of interval j at plan time s."""
        start, end = self.seconds[j], self.seconds[j + 1]
        if self.profile is None:
            return Progress((s - start) / (end - start), 1.0 / (end - start), 0.0)
        length = float(self.profile.lengths[j])
        if length <= 0:
            return Progress(0.0, 0.0, 0.0)
        # the profile's own duration, stretched to the stamps (they differ by rounding)
        scale = float(self.profile.durations()[j]) / (end - start)
        state = self.profile.state_at(j, (s - start) * scale)
        return Progress(state.distance / length, state.speed * scale / length,
                        state.acceleration * scale * scale / length)

    def position(self, s: float) -> np.ndarray:
        """Return the (k, 3) reference positions at plan time s (clamped to the plan)."""
        if self.seconds.size == 1 or s <= self.seconds[0]:
            return self.positions[0]
        if s >= self.seconds[-1]:
            return self.positions[-1]
        j = self._interval(s)
        fraction = self._along(j, s).fraction
        return (1.0 - fraction) * self.positions[j] + fraction * self.positions[j + 1]

    def velocity(self, s: float) -> np.ndarray:
        """Return the (k, 3) reference velocities d position / d s at plan time s (0 outside)."""
        if self.seconds.size == 1 or s < self.seconds[0] or s >= self.seconds[-1]:
            return np.zeros_like(self.positions[0])
        j = self._interval(s)
        step = self.positions[j + 1] - self.positions[j]
        if self.profile is None:
            return step / (self.seconds[j + 1] - self.seconds[j])
        return step * self._along(j, s).speed

    def acceleration(self, s: float) -> np.ndarray:
        """Return the (k, 3) reference accelerations at plan time s (0 outside, 0 if linear)."""
        if self.seconds.size == 1 or s < self.seconds[0] or s >= self.seconds[-1]:
            return np.zeros_like(self.positions[0])
        j = self._interval(s)
        return (self.positions[j + 1] - self.positions[j]) * self._along(j, s).acceleration

    def orientation(self, s: float) -> np.ndarray:
        """Return the (k, 4) orientations held at plan time s."""
        if s >= self.seconds[-1]:
            return self.orientations[-1]
        return self.orientations[self._interval(s)]
