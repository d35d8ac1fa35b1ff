"""
One control step of a plan's execution: the shared plan clock, then every robot's command.

Each step (doc/design.md section 13; msg_docs/ExecutePlan.md):

1. measure every robot's tracking error, |reference(s) - position|, at the
   current plan time s;
2. choose the clock rate: :func:`clock_rate` of the errors and the tracking
   tolerance, rising no faster than the plan's acceleration limit allows;
   while any robot's odometry is stale, falling to 0 (at once without the
   limit, else braking no faster than it rises) and no higher than the
   others' errors allow (with ``shared_clock`` off, 1: every robot follows
   the stamps on its own);
3. advance s by rate x dt (at most the plan's duration);
4. command each robot feed-forward plus feedback, saturated at its speed
   limit: v = sat(g (rate x reference'(s) + rate^2 dt x reference''(s))
   + gain x (reference(s) - position)), g the robot's learned feed-forward
   gain. A stale robot gets its feed-forward alone on the shared clock (0
   without it, or for a differential robot).

Differential robots (``drive``) track through :mod:`.unicycle` instead: the
clock sees the bound E = |reference - P| + e of each one's centre error, is
capped so each can follow its reference's direction and slows before the
corners ahead; a robot facing more than 90 degrees from where its reference
goes drives the other way round, and one whose reference stands still turns
in place towards its next move. After the end each parks its centre on
its last position, then turns in place to its last orientation (``final_heading``).

The execution is finished once s reached the plan's end and every robot has
been within ``goal_tolerance`` of its last configuration (and every
differential robot within unicycle.HEADING_TOLERANCE of its final heading)
for SETTLE seconds: a robot late behind the clock reaches its goal at speed,
and one control step inside the tolerance would stop it centimetres beyond.
"""

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from . import unicycle
from .bodies import Bodies
from .reference import Reference
from .tolerance import clock_rate

# Longest step the clock takes at once (s): a stalled control loop does not jump ahead.
MAX_STEP = 0.2
# Control steps of the clock kept to find the plan time at which an old position was taken
# (5 s at 20 Hz; odom_timeout declares older odometry stale).
HISTORY = 100
# Seconds every robot must stay at its goal (and final heading) before the run is finished.
SETTLE = 0.5
# Largest feed-forward gain: a robot that achieves a quarter of its commands is not helped.
MAX_FEEDFORWARD_GAIN = 4.0
# Share of each robot's acceleration limit its reference may use (the clock's reference is
# timed for it): the rest is the feedback's, to shed what a late robot gained in its
# latency where the reference brakes (doc/design.md section 13, "Room to correct").
ACCELERATION_SHARE = 0.6
# Reference speed (m/s) below which a robot's lag says nothing about its feed-forward
# (and the clock's rise counts the reference as moving this fast).
ADAPT_SPEED = 0.05
HOLONOMIC = 'holonomic'
DIFFERENTIAL = 'differential'
DRIVES = (HOLONOMIC, DIFFERENTIAL)


@dataclass(frozen=True)
class ExecutionSettings:
    """
    The tracking law's settings (the executor node's parameters of the same names).

    The defaults are the parameters' (ros/settings.py takes them from here).
    """

    gain: float = 2.0
    speed_limit: float = 0.5
    slow_fraction: float = 0.3
    hold_fraction: float = 0.6
    goal_tolerance: float = 0.01
    shared_clock: bool = True
    drive: tuple = (HOLONOMIC,)         # one value, or one per robot in plan order
    yaw_rate_limit: float = 1.0         # rad/s, differential robots
    final_heading: bool = True          # differential robots end facing their last pose
    # 1/s: how fast each robot's feed-forward gain learns its lag along its reference; 0: off
    feedforward_adaptation: float = 3.0
    # each robot's own speed (m/s) and acceleration (m/s^2) limits: one value, or one per
    # robot in plan order; empty: the plan's. The clock's reference is timed for them.
    max_speeds: tuple = ()
    max_accelerations: tuple = ()

    def differential(self, robot_count: int) -> np.ndarray:
        """Return the (k,) mask of differential robots; WrongCount if drive does not fit k."""
        return differential_mask(self.drive, robot_count)

    def limits(self, robot_count: int) -> tuple[np.ndarray | None, np.ndarray | None]:
        """Return (k,) max_speeds and max_accelerations (None: the plan's); WrongCount on k."""
        return (per_robot('max_speeds', self.max_speeds, robot_count),
                per_robot('max_accelerations', self.max_accelerations, robot_count))


class WrongCount(ValueError):
    """
    Values for all or for each item, of neither count: the setting, its count and the items'.

    name is the setting at fault (a parameter's name), given how many values it
    has, expected how many items there are (robots, obstacles).
    """

    def __init__(self, name: str, given: int, expected: int, items: str) -> None:
        """Keep the culprits; the message names them."""
        self.name = name
        self.given = given
        self.expected = expected
        self.items = items
        super().__init__('%s has %d values for %d %s (one, or one per %s)'
                         % (name, given, expected, items, items[:-1]))


def one_or_each(name: str, values: Sequence, count: int,
                items: str = 'robots') -> np.ndarray | None:
    """
    Return values, one for all or one per item, as a (count,) array; None for none.

    The rule of every parameter that gives one value for all robots (obstacles) or
    one each; WrongCount naming the parameter for any other count.
    """
    if not len(values):
        return None
    if len(values) not in (1, count):
        raise WrongCount(name, len(values), count, items)
    return np.broadcast_to(np.asarray(values), count).copy()


def per_robot(name: str, values: tuple, robot_count: int) -> np.ndarray | None:
    """Return values (one, or one per robot) as (k,) numbers, None for none (one_or_each)."""
    each = one_or_each(name, values, robot_count)
    return None if each is None else each.astype(float)


def differential_mask(drive: tuple, robot_count: int) -> np.ndarray:
    """Return the (k,) mask of drive's differential robots (one value, or one per robot)."""
    each = one_or_each('drive', drive, robot_count)
    return np.zeros(robot_count, dtype=bool) if each is None else each == DIFFERENTIAL


def leaving_their_plane(differential: np.ndarray, reference: Reference) -> np.ndarray:
    """Return the indices of the differential robots whose reference changes z: no unicycle can."""
    heights = reference.positions[..., 2]
    return np.flatnonzero(differential & (heights.max(axis=0) > heights.min(axis=0)))


@dataclass(frozen=True)
class Step:
    """What one control step decided: the clock, the references and the commands."""

    plan_time: float
    rate: float
    positions: np.ndarray       # (k, 3) references at plan_time
    orientations: np.ndarray    # (k, 4) references at plan_time
    velocities: np.ndarray      # (k, 3) commanded velocities, planning frame
    errors: np.ndarray          # (k,) tracking errors measured this step (m)
    watched: np.ndarray         # (k,) what the clock slows and holds for, per robot (m)
    finished: bool
    differential: np.ndarray    # (k,) robots commanded by forward speed and yaw rate
    forward: np.ndarray         # (k,) differential robots' forward speeds (m/s), else 0
    yaw_rates: np.ndarray       # (k,) differential robots' yaw rates (rad/s), else 0
    # the rate the robots allow (their errors, stale odometry: 0), before the acceleration
    # limit's rise: what a hold is judged on (execution.hold.ClockHold)
    allowed: float

    def body_commands(self, orientations: np.ndarray) -> np.ndarray:
        """
        Return the (k, 3) linear commands in each robot's body frame, from (k, 4) orientations.

        A holonomic robot's velocity rotated into its frame; a differential robot's
        (forward, 0, 0): never a sideways part. The yaw rates are yaw_rates.
        """
        rotated = Rotation.from_quat(orientations).apply(self.velocities, inverse=True)
        return np.where(self.differential[:, None], unicycle.forward_vectors(self.forward),
                        rotated)


def behind(lags: np.ndarray, motion: np.ndarray) -> np.ndarray:
    """
    Return the (k,) parts of lags (reference - position, (k, 3)) that a slower clock reduces.

    A robot behind its reference moving along motion (k, 3), or beside it, is
    helped by the clock waiting: its whole lag counts. A robot ahead of it is
    not (the reference catches up only while the clock runs, and a hold makes
    a robot at speed overshoot further): only its sideways part counts. A
    reference standing still: the whole lag.
    """
    speeds = np.linalg.norm(motion, axis=1)
    along = np.einsum('kd,kd->k', lags, motion) / np.maximum(speeds, np.finfo(float).tiny)
    distance = np.linalg.norm(lags, axis=1)
    sideways = np.sqrt(np.maximum(distance ** 2 - along ** 2, 0.0))
    return np.where((speeds > 0) & (along < 0), sideways, distance)


def saturate(velocities: np.ndarray, limit: float | np.ndarray) -> np.ndarray:
    """Return (k, 3) velocities scaled down to speed at most limit, direction kept."""
    speeds = np.linalg.norm(velocities, axis=-1, keepdims=True)
    scale = np.minimum(1.0, limit / np.maximum(speeds, np.finfo(float).tiny))
    return velocities * scale


class Execution:
    """The state of one plan's execution: its clock, the largest errors and the smallest gap."""

    def __init__(self, reference: Reference, tolerance: float, settings: ExecutionSettings,
                 bodies: Bodies | None = None):
        """
        Start at plan time 0 with no error measured yet; WrongCount if drive does not fit.

        The clock runs on the plan retimed (Reference.retimed) for robots slower
        than the plan (settings.max_speeds), and, for a plan timed under an
        acceleration limit or robots given one (max_accelerations), for
        ACCELERATION_SHARE of each robot's acceleration (its own, at most the
        plan's): its plan time is then that timing's.
        """
        self.tolerance = float(tolerance)
        k = reference.robot_count
        speeds, accelerations = settings.limits(k)
        profile = reference.profile
        plan_acceleration = np.full(k, profile.max_acceleration if profile else np.inf)
        # (k,) the acceleration each robot's reference (and the clock's rise) may use
        self.accelerations = ACCELERATION_SHARE * (
            plan_acceleration if accelerations is None
            else np.minimum(accelerations, plan_acceleration))
        self.differential = settings.differential(k)
        # a timed plan stops where a differential robot switches its driving direction
        # (it passes through rest there anyway, doc/design.md section 13)
        # timed under an acceleration limit: the plan's, or the robots' own on a plan
        # stamped without one (which they could not follow at its corners)
        timed = profile is not None or accelerations is not None
        stops = (unicycle.Corners(reference.seconds, reference.positions).turns(
            self.differential) if timed else np.zeros(0, dtype=bool))
        if speeds is not None or timed:
            reference = reference.retimed(
                np.full(k, np.inf) if speeds is None else speeds,
                self.accelerations, self.tolerance, stops if stops.any() else None)
        self.reference = reference
        self.settings = settings
        self.bodies = bodies if bodies is not None else Bodies()
        self.plan_time = 0.0
        self.max_errors = np.zeros(reference.robot_count)
        self.min_gap = np.inf
        self.lead = unicycle.lead(self.tolerance, settings.slow_fraction,
                                  settings.hold_fraction)
        self.steering = unicycle.steering(self.lead)
        self.corners = unicycle.Corners(reference.seconds, reference.positions,
                                        reference.at_rest() if timed else None)
        self.final_yaws = unicycle.yaws(reference.orientation(reference.duration))
        self.turning = np.zeros(reference.robot_count, dtype=bool)
        # robots driving backward: their lead point is e behind, their 'heading' theta + pi
        self.reverse = np.zeros(reference.robot_count, dtype=bool)
        self.settled = 0.0     # seconds every robot has been at its goal for
        # (k,) what each robot's feed-forward is multiplied by: 1 until it lags (_feedforward)
        self.feedforward_gains = np.ones(reference.robot_count)
        self.rate = 0.0        # the clock's last rate
        self.commanded_speeds = np.zeros(reference.robot_count)  # (k,) the last commands' m/s
        self.elapsed = 0.0     # seconds of control steps so far
        # (elapsed, plan time read) at each of the last HISTORY steps, for old positions
        self.clock_history: deque = deque(maxlen=HISTORY)

    def beyond_tolerance(self) -> np.ndarray:
        """Return the robots (indices) whose largest tracking error so far passed the tolerance."""
        return np.flatnonzero(self.max_errors > self.tolerance)

    def step(self, dt: float, positions: np.ndarray, stale: np.ndarray,
             orientations: np.ndarray | None = None, ages: np.ndarray | None = None) -> Step:
        """
        Advance by dt seconds for robot positions (k, 3) and stale flags (k,); return the Step.

        orientations (k, 4) are the robots' quaternions (None: identity); the
        differential robots' headings are their yaws. The positions of stale
        robots are not used (their errors count as 0 this step). ages (k,) are
        how old the positions are (s; None: fresh): each is compared with its
        reference at the plan time of that instant (:meth:`_measured`), and
        the clock counts what a robot may have moved since, beyond one control
        step, as error (:meth:`_late`).
        """
        s = self.settings
        stale = np.asarray(stale, dtype=bool)
        k = self.reference.robot_count
        angles = (np.zeros(k) if orientations is None else unicycle.yaws(orientations))
        self.elapsed += max(dt, 0.0)
        self.clock_history.append((self.elapsed, self.plan_time))
        measured_reference = self._measured(ages)
        lags = measured_reference - positions
        errors = np.linalg.norm(lags, axis=1)
        errors[stale] = 0.0
        self.max_errors = np.maximum(self.max_errors, errors)
        if not stale.any():
            self.min_gap = min(self.min_gap, self.bodies.smallest_gap(positions).value)
        differential = self.differential & ~stale
        dt = min(max(dt, 0.0), MAX_STEP)
        # An all-holonomic fleet (the default) needs none of the unicycle's work.
        unicycles = bool(self.differential.any())
        motion = self.reference.velocity(self.plan_time)
        watched, alpha = behind(lags, motion), np.zeros(k)
        if unicycles:
            # a turn may start only while the whole bound E of a robot's centre error is
            # small; the clock then watches only E's part that waiting reduces (behind)
            lead_points = unicycle.lead_points(positions, self._driving(angles), self.lead)
            bound = np.linalg.norm(measured_reference - lead_points, axis=1) + self.lead
            alpha = self._update_turns(angles, np.where(differential, bound, errors), dt)
            watched = np.where(differential,
                               behind(measured_reference - lead_points, motion) + self.lead,
                               watched)
        driving = self._driving(angles)
        late = self._late(ages, dt)
        # the stale robots' positions say nothing: the others' errors still slow the clock
        shown = np.where(stale, 0.0, watched)
        watched = watched + late * self.commanded_speeds  # what the robots may have moved
        if not s.shared_clock:
            rate = allowed = 1.0
        else:
            seen = min(clock_rate(shown, self.tolerance, s.slow_fraction, s.hold_fraction),
                       self._differential_cap(alpha))
            allowed = 0.0 if stale.any() else min(seen, clock_rate(
                watched, self.tolerance, s.slow_fraction, s.hold_fraction))
            if self.reference.profile is None:  # no acceleration limit: the rate at once
                rate = min(seen, allowed)
            else:
                # what stale or old odometry may hide brakes the clock (a rate below the
                # one before, so no rise is left); what it shows may hold it
                change = self._rate_change(motion)
                rate = self._rate_rise(min(seen, self._braked(allowed, dt, change)), dt,
                                       change)
        self.rate = rate
        duration = self.reference.duration
        self.plan_time = min(duration, self.plan_time + rate * dt)
        target = self.reference.position(self.plan_time)
        feedforward = self._feedforward(rate, dt, lags, stale)
        # A position older than a control step is where the robot was: its error is its
        # lag then (it has moved on since, as its reference did), not its distance to the
        # reference now, which drove a robot whose odometry stopped ever harder ahead.
        error = np.where(late[:, None] > 0.0, lags, target - positions)
        command = feedforward + s.gain * error
        velocities = saturate(command, s.speed_limit)
        forward, yaw_rates = np.zeros(k), np.zeros(k)
        if unicycles:
            unicycle_command = self._unicycle(feedforward, target, positions, angles, driving,
                                              alpha)
            forward = np.where(differential, unicycle_command.forward, 0.0)
            yaw_rates = np.where(differential, unicycle_command.yaw_rate, 0.0)
            velocities = np.where(differential[:, None],
                                  forward[:, None] * unicycle.headings(angles), velocities)
        # A stale robot's position is unknown: it follows the shared clock's braking
        # reference on its feed-forward alone; a differential one stops (its heading is
        # unknown too), and without the shared clock every stale robot does.
        fed = s.shared_clock & ~self.differential[stale]
        velocities[stale] = np.where(fed[:, None], saturate(feedforward[stale], s.speed_limit),
                                     0.0)
        self.commanded_speeds = np.where(differential, np.abs(forward),
                                         np.linalg.norm(velocities, axis=1))
        arrived = bool(self.plan_time >= duration and not stale.any() and np.all(
            np.linalg.norm(target - positions, axis=1) <= s.goal_tolerance))
        finished = self._settled(arrived, angles, dt) and arrived
        return Step(self.plan_time, rate, target, self.reference.orientation(self.plan_time),
                    velocities, errors, watched, finished, self.differential.copy(), forward,
                    yaw_rates, allowed)

    def _measured(self, ages: np.ndarray | None) -> np.ndarray:
        """
        Return the (k, 3) references at the plan times the robots' positions were taken at.

        A position ages (k,) seconds old (by arrival: an upper bound of its age)
        is compared with its reference at the clock of that instant, from the
        clock's last HISTORY steps (older: the oldest kept): a robot exactly on
        its reference 0.3 s ago is not 0.3 s x v behind it. The certificate
        needs every robot within delta of its reference at one and the same
        plan time, which is what this compares; without ages (or 0) it is the
        current plan time.
        """
        if ages is None or not np.any(np.asarray(ages) > 0):
            return self.reference.position(self.plan_time)
        times, plan_times = np.array(self.clock_history).T
        then = np.interp(self.elapsed - np.asarray(ages, dtype=float), times, plan_times)
        result = np.empty((self.reference.robot_count, 3))
        for s_then in np.unique(then):
            robots = then == s_then
            result[robots] = self.reference.position(float(s_then))[robots]
        return result

    def _late(self, ages: np.ndarray | None, dt: float) -> np.ndarray:
        """
        Return the (k,) seconds by which the robots' odometry is older than a control step.

        A robot whose odometry is that late has moved about that x its speed
        since (its last command's speed): at 0.5 m/s a stalled simulator's
        0.5 s is 0.25 m, more than delta. One control step of age is the
        sampling the margin (1 - hold_fraction) delta covers already; the rest
        counts as tracking error, so the clock slows and holds while the
        positions it sees are old, braking within the acceleration limit
        (_braked; doc/design.md section 13), and the feedback of a late
        position acts on its lag when measured.
        """
        if ages is None:
            return np.zeros(self.reference.robot_count)
        return np.maximum(np.asarray(ages, dtype=float) - dt, 0.0)

    def _rate_change(self, motion: np.ndarray) -> float:
        """
        Return how fast (1/s^2) the clock's rate may change under the acceleration limits.

        The rate change that moves every reference's velocity rate x r_i'(s) by
        at most its robot's a_i (the plan's share, or the robot's own) per second;
        motion (k, 3) is the references' velocity now (r_i'(s)).
        """
        speeds = np.linalg.norm(motion, axis=1)
        return float(np.min(self.accelerations / np.maximum(speeds, ADAPT_SPEED)))

    def _rate_rise(self, wanted: float, dt: float, change: float) -> float:
        """
        Return wanted, or less where the clock would speed up faster than the plan allows.

        Under acceleration limits the clock rises no faster than change (_rate_change):
        released from a hold at once, a robot limited to a_i would lag its
        reference's jump by up to v^2 / (2 a_i) and hold the clock again. It
        still slows and holds at once for the robots' errors. (A plan without the
        limit takes its rate at once: step.)
        """
        return min(wanted, self.rate + change * dt)

    def _braked(self, wanted: float, dt: float, change: float) -> float:
        """
        Return wanted, or more where the clock would slow down faster than the robots can.

        For what odometry does not show: a robot's stale odometry (wanted 0), and
        what a robot may have moved since its odometry (_late), which grows as
        fast as the robot goes once its odometry stops and had held the clock
        within 0.25 s, before the robot even counted as stale. Under the plan's
        acceleration limit (without one the clock follows wanted at once: step) it brakes
        no faster than change (_rate_change), every robot following its braking reference,
        a stale one on its feed-forward alone (step): held at once, each robot at
        v overran its stopped reference by v^2 / (2 a_i) (a probe over DDS: 0.26 m
        against a tolerance of 0.15 m at 0.75 m/s and 1 m/s^2).
        """
        return max(wanted, self.rate - change * dt)

    def _feedforward(self, rate: float, dt: float, lags: np.ndarray,
                     stale: np.ndarray) -> np.ndarray:
        """
        Return the (k, 3) feed-forward velocities at the clock's new plan time.

        The reference's velocity plus its acceleration over one control step
        (an acceleration-limited base answers a command about a step late),
        times the clock rate, times each robot's feed-forward gain. A gain
        grows while its robot lags behind a moving reference by more than
        slow_fraction delta, so far that the clock waits for it (lags (k, 3)
        are reference - position when measured; a lag below that, from latency,
        odometry age or a corner, is left to the feedback), and shrinks back
        toward 1 while it is ahead: a robot that achieves only a fraction f of
        its commands gets about 1 / f of the feed-forward and keeps the pace
        the clock sets instead of the much lower K e of its feedback alone.
        A gain does not grow while its feed-forward alone reaches the speed
        limit (anti-windup: the robot cannot go faster).
        With the clock held (rate 0) there is no feed-forward, so the hold's
        argument (doc/design.md section 13) is unchanged.
        """
        s_now = self.plan_time
        velocity = self.reference.velocity(s_now)
        feedforward = rate * velocity + rate * rate * dt * self.reference.acceleration(s_now)
        speeds = np.linalg.norm(velocity, axis=1)
        moving = (rate * speeds > ADAPT_SPEED) & ~stale
        along = np.einsum('kd,kd->k', lags, velocity) / np.maximum(speeds, ADAPT_SPEED)
        waited = self.settings.slow_fraction * self.tolerance
        excess = np.where(along > waited, along - waited, np.minimum(along, 0.0))
        # no growth while the feed-forward alone is at the speed limit: a larger gain would
        # not move the robot faster, only wind up (and overshoot once the reference slows)
        saturated = (self.feedforward_gains * np.linalg.norm(feedforward, axis=1)
                     >= self.settings.speed_limit)
        excess = np.where(saturated, np.minimum(excess, 0.0), excess)
        change = self.settings.feedforward_adaptation * dt * excess / self.tolerance
        self.feedforward_gains = np.clip(
            np.where(moving, self.feedforward_gains + change, self.feedforward_gains),
            1.0, MAX_FEEDFORWARD_GAIN)
        return self.feedforward_gains[:, None] * feedforward

    def _settled(self, arrived: bool, angles: np.ndarray, dt: float) -> bool:
        """Return whether every robot has been at its goal (and final heading) for SETTLE s."""
        facing = True
        if self.settings.final_heading and self.differential.any():
            facing = bool(np.all(np.abs(unicycle.wrap(self.final_yaws - angles))[
                self.differential] <= unicycle.HEADING_TOLERANCE))
        self.settled = self.settled + dt if arrived and facing else 0.0
        return self.settled >= SETTLE

    def _update_turns(self, angles: np.ndarray, watched: np.ndarray,
                      dt: float) -> np.ndarray:
        """
        Switch the differential robots' driving directions and turns; return misalignments.

        Where the driving heading is more than REVERSE_ANGLE (90 degrees) from
        the direction the reference moves in (or moves next), driving the other
        way round needs less turning: the robot switches direction once
        E <= hold delta - 2e (its lead point jumps by 2e, so E stays below hold
        delta). So no robot is ever more than 90 degrees from where it goes,
        and it follows at the creep rate instead of turning in place with the
        fleet waiting. A robot whose reference stands still for the whole step
        and that is more than TURN_START off its next move turns in place towards
        it (the centre stands, E grows by at most 2e) until within ALIGNED of it:
        that costs the clock nothing.
        """
        s = self.settings
        upcoming = self.corners.upcoming(self.plan_time)
        still_until = upcoming.still_until
        alpha = unicycle.misalignment(self._driving(angles), upcoming.directions)
        may_turn = watched <= s.hold_fraction * self.tolerance - 2.0 * self.lead
        flip = self.differential & may_turn & (np.abs(alpha) > unicycle.REVERSE_ANGLE)
        self.reverse ^= flip
        alpha = np.where(flip, unicycle.wrap(alpha + np.pi), alpha)
        # still for the whole step; a reference moving now never waits, even for dt = 0
        waiting = (still_until > self.plan_time) & (still_until - self.plan_time >= dt)
        start = may_turn & (np.abs(alpha) > unicycle.TURN_START)
        self.turning = (self.differential & waiting & (self.turning | start)
                        & (np.abs(alpha) > unicycle.ALIGNED))
        return alpha

    def _driving(self, angles: np.ndarray) -> np.ndarray:
        """Return the driving headings: the yaw, or yaw + pi for robots driving backward."""
        return angles + np.pi * self.reverse

    def _differential_cap(self, alpha: np.ndarray) -> float:
        """
        Return the largest clock rate the differential robots allow this step.

        Each caps it so its lead point can follow its reference's direction
        (creep_rate: 0 beyond REVERSE_ANGLE, until it has switched direction;
        1 while its reference stands still, where it may turn in place), and
        slows into its corners.
        """
        if not self.differential.any():
            return 1.0
        s_now, limit = self.plan_time, self.settings.yaw_rate_limit
        speeds = np.linalg.norm(self.reference.velocity(s_now), axis=1)
        caps = np.minimum(unicycle.creep_rate(alpha, speeds, self.steering, limit),
                          self.corners.corner_caps(s_now, self.steering, limit))
        return float(np.min(caps[self.differential], initial=1.0))

    def _unicycle(self, feedforward: np.ndarray, target: np.ndarray, positions: np.ndarray,
                  angles: np.ndarray, driving: np.ndarray,
                  alpha: np.ndarray) -> unicycle.UnicycleCommand:
        """
        Return every robot's unicycle command: follow, turn, park or face the final pose.

        feedforward (k, 3) is :meth:`_feedforward`'s, angles are the yaws,
        driving the driving headings (yaw + pi backward), alpha the misalignments.
        """
        s = self.settings
        if self.plan_time >= self.reference.duration:
            command = unicycle.park(positions, angles, target, s.gain, s.speed_limit,
                                    s.yaw_rate_limit)
            parked = np.linalg.norm(target - positions, axis=1) <= 0.5 * s.goal_tolerance
            final = (unicycle.turn(unicycle.wrap(self.final_yaws - angles), s.yaw_rate_limit)
                     if s.final_heading else np.zeros(len(angles)))
            return unicycle.UnicycleCommand(np.where(parked, 0.0, command.forward),
                                            np.where(parked, final, command.yaw_rate))
        lead_points = unicycle.lead_points(positions, driving, self.lead)
        desired = feedforward + s.gain * (target - lead_points)
        command = unicycle.follow(desired, driving, self.steering, s.speed_limit,
                                  s.yaw_rate_limit)
        forward = np.where(self.reverse, -command.forward, command.forward)
        return unicycle.UnicycleCommand(
            np.where(self.turning, 0.0, forward),
            np.where(self.turning, unicycle.turn(alpha, s.yaw_rate_limit), command.yaw_rate))
