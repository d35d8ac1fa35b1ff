"""
Holonomic disc robots with a slow robot, command latency and velocity noise.

The robots never turn: their body frame is the odometry frame, so a command's
linear velocity is applied as it is (the executor rotates world velocities
into each robot's body frame from its odometry orientation). Per robot i and
step dt, with the latest command whose latency has passed (none, or one older
than ``command_timeout``: 0):

    v_i = speed_factor_i * sat(command, speed_limit) * (1 + velocity_noise * xi),

xi standard normal per axis; the centre moves by v_i dt on a straight line. The
true gap (:class:`punctured_planner.execution.Bodies`) is exact over each step.
"""

from collections import deque
from dataclasses import dataclass
from dataclasses import field

import numpy as np

from ..execution.bodies import Bodies
from ..execution.execution import saturate


@dataclass(frozen=True)
class FleetSettings:
    """The fleet's physics (the fleet_sim node's parameters of the same names)."""

    bodies: Bodies = field(default_factory=Bodies)
    speed_limit: float = 1.0
    speed_factors: np.ndarray | None = None   # (k,), None: all 1
    latencies: np.ndarray | None = None       # (k,) seconds, None: all 0
    velocity_noise: float = 0.0
    command_timeout: float = 0.5
    seed: int = 0


@dataclass(frozen=True)
class Contact:
    """Two bodies that started touching at time (s): kind, indices, gap (m)."""

    time: float
    kind: str
    first: int
    second: int
    gap: float


class Fleet:
    """k robots at centres (k, 3); commands in, positions and the true gap out."""

    def __init__(self, positions: np.ndarray, settings: FleetSettings):
        """Place the robots at rest; no command yet."""
        self.positions = np.array(positions, dtype=float).reshape(-1, 3)
        k = len(self.positions)
        self.configure(settings)
        self.velocities = np.zeros((k, 3))
        self._pending: list[deque] = [deque() for _ in range(k)]  # (apply_time, velocity)
        self._active = np.zeros((k, 3))
        self._active_since = np.full(k, -np.inf)
        self._rng = np.random.default_rng(settings.seed)
        gaps, _, _ = settings.bodies.pair_gaps(self.positions)
        self._touching = gaps < 0
        self.min_gap = float(gaps.min(initial=np.inf))

    def configure(self, settings: FleetSettings) -> None:
        """Take new physics settings from the next command and step on (bodies stay)."""
        k = len(self.positions)
        self.settings = settings
        self.speed_factors = (np.ones(k) if settings.speed_factors is None
                              else np.asarray(settings.speed_factors, dtype=float))
        self.latencies = (np.zeros(k) if settings.latencies is None
                          else np.asarray(settings.latencies, dtype=float))

    @property
    def robot_count(self) -> int:
        """Return k."""
        return len(self.positions)

    def command(self, robot: int, velocity: np.ndarray, now: float) -> None:
        """Queue a robot's commanded velocity (3,), received at now; it applies after latency."""
        self._pending[robot].append((now + self.latencies[robot],
                                     np.asarray(velocity, dtype=float)))

    def _commanded(self, now: float) -> np.ndarray:
        """Return the (k, 3) commands in force at now (latest applied, 0 if timed out)."""
        for robot, pending in enumerate(self._pending):
            while pending and pending[0][0] <= now:
                self._active_since[robot], self._active[robot] = pending.popleft()
        timed_out = now - self._active_since > self.settings.command_timeout
        commanded = self._active.copy()
        commanded[timed_out] = 0.0
        return commanded

    def step(self, now: float, dt: float) -> list:
        """Move every robot for dt seconds from time now; return the new Contacts."""
        s = self.settings
        commanded = saturate(self._commanded(now), s.speed_limit)
        noise = 1.0 + s.velocity_noise * self._rng.standard_normal(commanded.shape)
        self.velocities = self.speed_factors[:, None] * commanded * noise
        start = self.positions
        self.positions = start + self.velocities * dt
        gaps, a, b = s.bodies.pair_gaps(start, self.positions)
        if gaps.size:
            self.min_gap = min(self.min_gap, float(gaps.min()))
        touching = gaps < 0
        k = self.robot_count
        contacts = [Contact(now, 'robots' if b[i] < k else 'obstacle', int(a[i]),
                            int(b[i]) if b[i] < k else int(b[i]) - k, float(gaps[i]))
                    for i in np.flatnonzero(touching & ~self._touching)]
        self._touching = touching
        return contacts
