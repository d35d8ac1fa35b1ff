"""
A plan as references: every robot's position and velocity at any plan time.

The plan's poses are its breakpoints with shared stamps, and linear
interpolation between consecutive poses is exactly the certified motion
(msg_docs/PlanSequence.md, ``paths``). So the reference at plan time s is that
interpolation, and its derivative, constant on each stamp interval, is the
feed-forward velocity. Intervals of zero length (several poses at one stamp)
are skipped.
"""

from dataclasses import dataclass

import numpy as np


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

    def position(self, s: float) -> np.ndarray:
        """Return the (k, 3) reference positions at plan time s (clamped to the plan)."""
        if self.seconds.size == 1 or s <= self.seconds[0]:
            return self.positions[0]
        if s >= self.seconds[-1]:
            return self.positions[-1]
        j = self._interval(s)
        start, end = self.seconds[j], self.seconds[j + 1]
        fraction = (s - start) / (end - start)
        return (1.0 - fraction) * self.positions[j] + fraction * self.positions[j + 1]

    def velocity(self, s: float) -> np.ndarray:
        """Return the (k, 3) reference velocities d position / d s at plan time s (0 outside)."""
        if self.seconds.size == 1 or s < self.seconds[0] or s >= self.seconds[-1]:
            return np.zeros_like(self.positions[0])
        j = self._interval(s)
        return (self.positions[j + 1] - self.positions[j]) / (self.seconds[j + 1]
                                                              - self.seconds[j])

    def orientation(self, s: float) -> np.ndarray:
        """Return the (k, 4) orientations held at plan time s."""
        if s >= self.seconds[-1]:
            return self.orientations[-1]
        return self.orientations[self._interval(s)]
