"""
Disc robots, holonomic or differential, with a slow robot, command latency and noise.

Per robot i and step dt, with the latest command whose latency has passed
(none, or one older than ``command_timeout``: 0):

* holonomic: the robot never turns, its body frame is the odometry frame, so
  the command's linear velocity is applied as it is (the executor rotates
  world velocities into each robot's body frame from its odometry orientation):

      u_i moves toward sat(command, speed_limit) by at most max_acceleration_i dt,
      v_i = speed_factor_i * u_i * (1 + velocity_noise * xi),

  xi standard normal per axis (max_acceleration 0: u_i is the command at
  once); the centre moves by v_i dt on a straight line;
* differential (a unicycle): only linear.x and angular.z count (linear.y is
  ignored, as on a real base); each is clipped to its limit, then moves toward
  it at most by its acceleration limit times dt (0: at once), then is scaled by
  speed_factor_i and 1 + velocity_noise * xi; the heading turns at the yaw rate
  and the centre moves on the exact arc.

The true gap (:class:`punctured_planner.execution.Bodies`) is exact over each
holonomic step; a differential step's arc is within its sagitta,
|v| dt |omega| dt / 8, of its chord, and that is taken off the chord's gaps.
"""

from collections import deque
from dataclasses import dataclass
from dataclasses import field

import numpy as np

from ..core.pairs import PointPair
from ..execution.bodies import Bodies
from ..execution.execution import ExecutionSettings
from ..execution.execution import saturate
from ..execution.unicycle import forward_vectors
from ..execution.unicycle import headings
from ..execution.unicycle import wrap
from ..execution.unicycle import yaw_quaternions


@dataclass(frozen=True)
class FleetSettings:
    """
    The fleet's physics (the fleet_sim node's parameters of the same names).

    The defaults are the parameters' (ros/settings.py takes them from here).
    """

    bodies: Bodies = field(default_factory=Bodies)
    speed_limit: float = 0.5
    speed_factors: np.ndarray | None = None   # (k,), None: all 1
    latencies: np.ndarray | None = None       # (k,) seconds, None: all 0
    velocity_noise: float = 0.0
    command_timeout: float = 0.5
    seed: int = 0
    differential: np.ndarray | None = None    # (k,) bool, None: all holonomic
    yaw_rate_limit: float = ExecutionSettings.yaw_rate_limit  # rad/s, differential robots
    # m/s^2 on the commanded velocity: one value or (k,), one per robot; 0: unlimited
    max_acceleration: float | np.ndarray = 0.0
    max_yaw_acceleration: float = 0.0         # rad/s^2, differential robots; 0: unlimited


@dataclass(frozen=True)
class Contact:
    """Two bodies that started touching at time (s): kind, indices, gap (m)."""

    time: float
    kind: str
    first: int
    second: int
    gap: float


@dataclass(frozen=True)
class Command:
    """A robot's command as received: when it applies (after latency), linear and yaw rate."""

    applies_at: float     # s
    linear: np.ndarray    # (3,) body frame, m/s
    yaw_rate: float       # rad/s


@dataclass(frozen=True)
class Commanded:
    """The fleet's commands in force: (k, 3) linear velocities and (k,) yaw rates."""

    linear: np.ndarray
    yaw_rates: np.ndarray


class Fleet:
    """k robots at centres (k, 3); commands in, positions and the true gap out."""

    def __init__(self, positions: np.ndarray, settings: FleetSettings):
        """Place the robots at rest; no command yet."""
        self.positions = np.array(positions, dtype=float).reshape(-1, 3)
        k = len(self.positions)
        self.velocities = np.zeros((k, 3))
        self.headings = np.zeros(k)       # yaw (rad): differential robots turn, others not
        self.forward = np.zeros(k)        # executed forward speeds, differential robots
        self.yaw_rates = np.zeros(k)      # executed yaw rates, differential robots
        self._moves = np.zeros((k, 3))    # the last step's chords, differential robots
        self._ramped = np.zeros((k, 2))   # (forward, yaw rate) after the acceleration limits
        self._linear = np.zeros((k, 3))   # holonomic velocities after the acceleration limit
        self.differential = np.zeros(k, dtype=bool)  # configure sets the drives
        self._pending: list[deque[Command]] = [deque() for _ in range(k)]
        self._active = Commanded(np.zeros((k, 3)), np.zeros(k))
        self._active_since = np.full(k, -np.inf)
        self._rng = np.random.default_rng(settings.seed)
        self.configure(settings)
        self.min_gap = self._start_gap

    def configure(self, settings: FleetSettings) -> None:
        """
        Take new physics settings from the next command and step on (the robots stay).

        New obstacles bring new pairs: which of them touch now is measured afresh, so
        a contact is still reported once, when a pair starts touching (a new count of
        obstacles failed every later step on the old pairs' array).
        """
        k = len(self.positions)
        self.settings = settings
        gaps = settings.bodies.pair_gaps(self.positions).gaps
        self._touching = gaps < 0
        self._start_gap = float(gaps.min(initial=np.inf))  # the gap where they stand now
        self.speed_factors = (np.ones(k) if settings.speed_factors is None
                              else np.asarray(settings.speed_factors, dtype=float))
        self.latencies = (np.zeros(k) if settings.latencies is None
                          else np.asarray(settings.latencies, dtype=float))
        was_differential = self.differential
        self.differential = (np.zeros(k, dtype=bool) if settings.differential is None
                             else np.asarray(settings.differential, dtype=bool))
        # A robot made holonomic faces +x again, as its odometry's identity orientation
        # says: it kept its last heading, which the executor rotated its commands by, so a
        # command along +x drove it along -y.
        holonomic = ~self.differential
        # A robot whose drive changed ramps from the velocity it has, before its factor (0
        # for a factor 0: it stands): made holonomic, not from the ramp of its body-frame
        # commands (forward, 0, 0), which would slide it sideways; made differential
        # (facing +x, as a holonomic one does), its forward speed from its velocity along
        # +x, within its acceleration limit.
        factors = self.speed_factors[:, None]
        commanded = np.divide(self.velocities, factors, where=factors > 0,
                              out=np.zeros_like(self.velocities))
        made_holonomic = was_differential & holonomic
        self._linear[made_holonomic] = commanded[made_holonomic]
        made_differential = ~was_differential & self.differential
        self._ramped[made_differential, 0] = commanded[made_differential, 0]
        self.headings[holonomic] = self.yaw_rates[holonomic] = self.forward[holonomic] = 0.0
        self._ramped[holonomic] = 0.0
        self.accelerations = np.broadcast_to(
            np.asarray(settings.max_acceleration, dtype=float), k).copy()

    @property
    def orientations(self) -> np.ndarray:
        """Return each robot's heading about z as (k, 4) quaternions (x, y, z, w)."""
        return yaw_quaternions(self.headings)

    @property
    def body_velocities(self) -> np.ndarray:
        """
        Return the (k, 3) velocities in each robot's body frame, as its odometry's twist.

        A differential robot's is (forward, 0, 0); a holonomic robot faces +x, so
        its body frame is the world's.
        """
        return np.where(self.differential[:, None], forward_vectors(self.forward),
                        self.velocities)

    @property
    def robot_count(self) -> int:
        """Return k."""
        return len(self.positions)

    def command(self, robot: int, velocity: np.ndarray, now: float,
                yaw_rate: float = 0.0) -> None:
        """
        Queue a robot's command, received at now; it applies after the robot's latency.

        velocity (3,) is the linear velocity in the body frame, yaw_rate the
        angular z (a holonomic robot ignores it, a differential one uses only
        velocity[0] and it).
        """
        self._pending[robot].append(Command(now + self.latencies[robot],
                                            np.array(velocity, dtype=float), float(yaw_rate)))

    def _commanded(self, now: float) -> Commanded:
        """Return the commands in force at now (0 where the last one timed out)."""
        for robot, pending in enumerate(self._pending):
            while pending and pending[0].applies_at <= now:
                command = pending.popleft()
                self._active_since[robot] = command.applies_at
                self._active.linear[robot] = command.linear
                self._active.yaw_rates[robot] = command.yaw_rate
        timed_out = now - self._active_since > self.settings.command_timeout
        return Commanded(np.where(timed_out[:, None], 0.0, self._active.linear),
                         np.where(timed_out, 0.0, self._active.yaw_rates))

    def _unicycle_step(self, commanded: Commanded, dt: float) -> np.ndarray:
        """Turn and drive the differential robots for dt; return their arcs' sagittas (k,)."""
        s = self.settings
        wanted = np.c_[np.clip(commanded.linear[:, 0], -s.speed_limit, s.speed_limit),
                       np.clip(commanded.yaw_rates, -s.yaw_rate_limit, s.yaw_rate_limit)]
        limits = np.c_[self.accelerations, np.full(len(wanted), s.max_yaw_acceleration)] * dt
        change = wanted - self._ramped
        self._ramped = np.where(limits > 0, self._ramped + np.clip(change, -limits, limits),
                                wanted)
        noise = 1.0 + s.velocity_noise * self._rng.standard_normal((len(wanted), 2))
        executed = np.where(self.differential[:, None], self._ramped, 0.0)
        forward, yaw_rate = (self.speed_factors[:, None] * executed * noise).T
        turned = yaw_rate * dt
        # the exact arc: the chord has length 2 v sin(w dt / 2) / w, along the mid heading
        chord = forward * dt * np.sinc(turned / (2.0 * np.pi))
        middle = self.headings + 0.5 * turned
        self.forward, self.yaw_rates = forward, yaw_rate
        self._moves = chord[:, None] * headings(middle)
        self.headings = wrap(self.headings + turned)
        return np.abs(forward * dt * turned) / 8.0

    def _ramp(self, wanted: np.ndarray, dt: float) -> np.ndarray:
        """Return the (k, 3) holonomic velocities moved toward wanted within the limits."""
        change = wanted - self._linear
        limits = self.accelerations[:, None] * dt
        self._linear = np.where(self.accelerations[:, None] > 0,
                                self._linear + saturate(change, limits), wanted)
        return self._linear

    def step(self, now: float, dt: float) -> list:
        """Move every robot for dt seconds from time now; return the new Contacts."""
        s = self.settings
        commanded = self._commanded(now)
        linear = self._ramp(saturate(commanded.linear, s.speed_limit), dt)
        noise = 1.0 + s.velocity_noise * self._rng.standard_normal(linear.shape)
        holonomic = self.speed_factors[:, None] * linear * noise
        sagittas = np.zeros(self.robot_count)
        if self.differential.any():
            sagittas = np.where(self.differential, self._unicycle_step(commanded, dt), 0.0)
            self.velocities = np.where(self.differential[:, None], self._moves / max(dt, 1e-12),
                                       holonomic)
        else:
            self.velocities = holonomic
        start = self.positions
        self.positions = start + self.velocities * dt
        pairs = s.bodies.pair_gaps(start, self.positions)
        gaps = pairs.gaps
        if sagittas.any():
            # the arcs bow out of their chords by at most their sagittas: be conservative
            padded = np.concatenate([sagittas, np.zeros(len(s.bodies.obstacles))])
            gaps = gaps - padded[pairs.a] - padded[pairs.b]
        if gaps.size:
            self.min_gap = min(self.min_gap, float(gaps.min()))
        touching = gaps < 0
        contacts = []
        for i in np.flatnonzero(touching & ~self._touching):
            pair = PointPair.from_points(pairs.a[i], pairs.b[i], self.robot_count)
            contacts.append(Contact(now, pair.kind, pair.first, pair.second, float(gaps[i])))
        self._touching = touching
        return contacts
