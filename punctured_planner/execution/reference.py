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
"""

from dataclasses import dataclass

import numpy as np

from ..core.timing import corner_jump, speed_profile, SpeedProfile


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
              max_speed: float, max_acceleration: float, min_gap: float) -> 'Reference':
        """Return the Reference of poses stamped under both limits (0: linear in time)."""
        if max_acceleration <= 0:
            return cls(seconds, positions, orientations)
        return cls(seconds, positions, orientations,
                   speed_profile(positions, max_speed, max_acceleration,
                                 corner_jump(max_acceleration, min_gap)))

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
        last = self.seconds.size - 2
        return int(np.clip(np.searchsorted(self.seconds, s, side='right') - 1, 0,
                           max(last, 0)))

    def _along(self, j: int, s: float) -> tuple[float, float, float]:
        """
        Return (fraction, speed, acceleration) of interval j at plan time s.

        fraction of the interval's segment covered, and the rates of that
        fraction per second and per second squared.
        """
        start, end = self.seconds[j], self.seconds[j + 1]
        if self.profile is None:
            return (s - start) / (end - start), 1.0 / (end - start), 0.0
        length = float(self.profile.lengths[j])
        if length <= 0:
            return 0.0, 0.0, 0.0
        # the profile's own duration, stretched to the stamps (they differ by rounding)
        scale = float(self.profile.durations()[j]) / (end - start)
        state = self.profile.state_at(j, (s - start) * scale)
        return (state.distance / length, state.speed * scale / length,
                state.acceleration * scale * scale / length)

    def position(self, s: float) -> np.ndarray:
        """Return the (k, 3) reference positions at plan time s (clamped to the plan)."""
        if self.seconds.size == 1 or s <= self.seconds[0]:
            return self.positions[0]
        if s >= self.seconds[-1]:
            return self.positions[-1]
        j = self._interval(s)
        fraction = self._along(j, s)[0]
        return (1.0 - fraction) * self.positions[j] + fraction * self.positions[j + 1]

    def velocity(self, s: float) -> np.ndarray:
        """Return the (k, 3) reference velocities d position / d s at plan time s (0 outside)."""
        if self.seconds.size == 1 or s < self.seconds[0] or s >= self.seconds[-1]:
            return np.zeros_like(self.positions[0])
        j = self._interval(s)
        step = self.positions[j + 1] - self.positions[j]
        if self.profile is None:
            return step / (self.seconds[j + 1] - self.seconds[j])
        return step * self._along(j, s)[1]

    def acceleration(self, s: float) -> np.ndarray:
        """Return the (k, 3) reference accelerations at plan time s (0 outside, 0 if linear)."""
        if self.seconds.size == 1 or s < self.seconds[0] or s >= self.seconds[-1]:
            return np.zeros_like(self.positions[0])
        j = self._interval(s)
        return (self.positions[j + 1] - self.positions[j]) * self._along(j, s)[2]

    def orientation(self, s: float) -> np.ndarray:
        """Return the (k, 4) orientations held at plan time s."""
        if s >= self.seconds[-1]:
            return self.orientations[-1]
        return self.orientations[self._interval(s)]
