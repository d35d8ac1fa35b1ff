"""
Differential-drive robots: the tracking law on a point ahead, turns in place, the clock's caps.

A differential (unicycle) robot with centre c and heading theta moves by
c' = v h, theta' = omega, h = (cos theta, sin theta): it takes only a forward
speed v and a yaw rate omega. The law (doc/design.md section 13) tracks the
point P = c + e h a lead e ahead of the centre: P' = v h + e omega h_perp.
(v, omega) = (u . h, u . h_perp / l), with a steering length l >= e, both
scaled by one factor lambda <= 1 to meet the speed and yaw-rate limits, give
P' = lambda D u, D = h h^T + (e / l) h_perp h_perp^T positive definite: P
moves within 90 degrees of u. With u = rate x reference' + gain x (reference - P),
the clock held (rate 0) gives d|reference - P|^2/dt = -2 lambda gain
(reference - P)^T D (reference - P) <= 0: the error of P never grows. The
centre is within e of P, so the clock watches E = |reference - P| + e, an upper
bound of the centre's error that never grows while the clock holds. l = e
would be exact feedback linearisation, but the heading would then answer
within e / v seconds, far faster than a base's command latency: it weaves.

Where its reference goes more than 90 degrees from its heading (a reversal, the
start facing away), the robot drives the other way round (heading theta + pi,
the lead point e behind), so it never follows more than 90 degrees off; the
clock is capped so that following stays within the yaw-rate limit
(:func:`creep_rate`) and slows before each corner of the reference, so the
robot reaches it slowly enough to turn (:func:`corner_caps`). A robot turns in
place (v = 0: the centre does not move) only while its own reference stands
still, towards its next move, and after the plan's end, to its final heading.
"""

from dataclasses import dataclass

import numpy as np

from ..core.timing import leg_at

# The lead e as a fraction of the tracking tolerance delta (capped by the clock's
# fractions, see lead()): small enough that the start (E = 2e) runs at full rate.
LEAD_FRACTION = 0.1
# Largest lead (m): a wider one moves the lead point far in a turn in place or a switch of
# driving direction (2e).
MAX_LEAD = 0.05
# The steering length (m): the heading turns toward the lead point's error within
# about STEERING / v seconds, slower than a base's latency (200 ms at 0.3 m/s: 6 cm).
STEERING = 0.1
# Misalignment (rad) beyond which a robot drives the other way round: it then never follows
# more than 90 degrees off. Turning in place at corners instead (beyond 45 degrees, with
# the fleet at rest) took the 20-robot bench 1.73x the holonomic run, this 1.24x
# (doc/design.md section 13).
REVERSE_ANGLE = np.pi / 2
# A robot whose reference stands still turns in place towards its next move when more
# than this (rad) off it, and ends the turn within ALIGNED: the gap between the two keeps
# it from switching between following and turning while it waits.
TURN_START = np.pi / 4
# A turn in place (while the reference stands still) ends this close (rad) to its heading.
ALIGNED = 0.1
# Fraction of the yaw-rate limit the clock leaves the lead point's sideways motion.
CREEP = 1.0
# Plan time (s) over which the clock slows into a corner ahead, from full rate.
LOOKAHEAD = 1.0
# The rate at which the reference passes a corner where the robot switches direction.
CORNER_RATE = 0.1
# Gain (1/s) of the turns in place, on the heading error: its braking, 4 x 1.9 rad/s^2,
# stays within a TurtleBot's yaw acceleration, and 4 x 200 ms latency does not ring.
HEADING_GAIN = 4.0
# A final heading within this (rad) of the requested one for execution.SETTLE seconds is
# reached: a late robot may still be turning when it passes the requested heading.
HEADING_TOLERANCE = 0.02
# Reference speeds below this (m/s) count as standing still.
STILL = 1e-9


@dataclass(frozen=True)
class UnicycleCommand:
    """Forward speeds (k,) in m/s and yaw rates (k,) in rad/s."""

    forward: np.ndarray
    yaw_rate: np.ndarray


def lead(tolerance: float, slow_fraction: float, hold_fraction: float) -> float:
    """
    Return the lead e (m) of the tracked point ahead of the centre.

    e <= (hold_fraction - slow_fraction) delta / 2: a turn in place or a switch
    of driving direction, begun with E <= hold_fraction delta - 2e, raises E by
    at most 2e (doc/design.md section 13), so it never passes the hold
    threshold. At most MAX_LEAD (an infinite tolerance: no bodies to meet).
    """
    fraction = min(LEAD_FRACTION, 0.5 * (hold_fraction - slow_fraction))
    return min(MAX_LEAD, fraction * float(tolerance))


def yaws(quaternions: np.ndarray) -> np.ndarray:
    """Return the (k,) yaw angles of (k, 4) quaternions (x, y, z, w)."""
    x, y, z, w = np.asarray(quaternions, dtype=float).T
    return np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def yaw_quaternions(angles: np.ndarray) -> np.ndarray:
    """Return the (k, 4) quaternions (x, y, z, w) of (k,) yaw angles about z: yaws' inverse."""
    half = 0.5 * np.asarray(angles, dtype=float).reshape(-1)
    return np.stack([np.zeros_like(half), np.zeros_like(half), np.sin(half), np.cos(half)],
                    axis=-1)


def forward_vectors(forward: np.ndarray) -> np.ndarray:
    """Return the (k, 3) body-frame vectors (forward, 0, 0) of (k,) forward speeds."""
    forward = np.asarray(forward, dtype=float)
    return np.stack([forward, np.zeros_like(forward), np.zeros_like(forward)], axis=-1)


def headings(angles: np.ndarray) -> np.ndarray:
    """Return the (k, 3) unit headings of (k,) yaw angles, in the plane z = const."""
    angles = np.asarray(angles, dtype=float)
    return np.stack([np.cos(angles), np.sin(angles), np.zeros_like(angles)], axis=-1)


def wrap(angles: np.ndarray) -> np.ndarray:
    """Return angles wrapped into [-pi, pi)."""
    return (np.asarray(angles, dtype=float) + np.pi) % (2.0 * np.pi) - np.pi


def misalignment(angles: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Return the signed angles (k,) from headings to (k, 3) directions (0 where none)."""
    directions = np.asarray(directions, dtype=float)
    wanted = np.arctan2(directions[:, 1], directions[:, 0])
    moving = np.hypot(directions[:, 0], directions[:, 1]) > STILL
    return np.where(moving, wrap(wanted - angles), 0.0)


def lead_points(positions: np.ndarray, angles: np.ndarray, lead_distance: float) -> np.ndarray:
    """Return the (k, 3) points P = c + e h tracked in place of the centres."""
    return np.asarray(positions, dtype=float) + lead_distance * headings(angles)


def steering(lead_distance: float) -> float:
    """Return the steering length l >= e of the lead e: STEERING, or e if that is longer."""
    return max(STEERING, lead_distance)


def follow(desired: np.ndarray, angles: np.ndarray, steering_length: float,
           speed_limit: float, yaw_rate_limit: float) -> UnicycleCommand:
    """
    Return the command that moves the lead points with velocity lambda D desired (k, 3).

    v = u . h and omega = u . h_perp / l, both scaled by the largest
    lambda <= 1 within |v| <= speed_limit and |omega| <= yaw_rate_limit; a
    lead point e ahead then moves at lambda (u . h) h + lambda (e / l) (u . h_perp) h_perp.
    """
    h = headings(angles)
    perpendicular = np.stack([-h[:, 1], h[:, 0], np.zeros(len(h))], axis=-1)
    forward = np.einsum('ij,ij->i', desired, h)
    yaw_rate = np.einsum('ij,ij->i', desired, perpendicular) / steering_length
    tiny = np.finfo(float).tiny
    scale = np.minimum(1.0, np.minimum(speed_limit / np.maximum(np.abs(forward), tiny),
                                       yaw_rate_limit / np.maximum(np.abs(yaw_rate), tiny)))
    return UnicycleCommand(forward * scale, yaw_rate * scale)


def turn(errors: np.ndarray, yaw_rate_limit: float) -> np.ndarray:
    """Return the (k,) yaw rates of turns in place toward heading errors (rad), saturated."""
    return np.clip(HEADING_GAIN * np.asarray(errors, dtype=float), -yaw_rate_limit,
                   yaw_rate_limit)


def park(positions: np.ndarray, angles: np.ndarray, goals: np.ndarray, gain: float,
         speed_limit: float, yaw_rate_limit: float) -> UnicycleCommand:
    """
    Return the command that brings the centres (k, 3) straight to goals (k, 3).

    v = gain (goal - c) . h, forward or backward, while the heading turns to the
    line through the goal: d|goal - c|/dt = -gain ((goal - c) . h)^2 / |goal - c| <= 0,
    so the distance to the goal never grows.
    """
    offsets = np.asarray(goals, dtype=float) - positions
    h = headings(angles)
    forward = np.clip(gain * np.einsum('ij,ij->i', offsets, h), -speed_limit, speed_limit)
    # the line through the goal, driven forward or backward, whichever needs less turning
    error = wrap(2.0 * misalignment(angles, offsets)) / 2.0
    return UnicycleCommand(forward, turn(error, yaw_rate_limit))


def creep_rate(angles: np.ndarray, speeds: np.ndarray, steering_length: float,
               yaw_rate_limit: float) -> np.ndarray:
    """
    Return the (k,) largest clock rates at which lead points can follow references.

    A reference moving at speed |r'| in a direction at angle alpha from the
    heading asks for the yaw rate rate |r'| |sin alpha| / l; the clock leaves
    it CREEP times the limit. Beyond REVERSE_ANGLE the robot must switch its
    driving direction first: 0.
    """
    sideways = np.asarray(speeds, dtype=float) * np.abs(np.sin(angles))
    allowed = CREEP * steering_length * yaw_rate_limit
    rates = np.minimum(1.0, allowed / np.maximum(sideways, np.finfo(float).tiny))
    return np.where(np.abs(angles) > REVERSE_ANGLE, 0.0, rates)


@dataclass(frozen=True)
class Upcoming:
    """Where each reference moves next: directions (k, 3), and when, still_until (k,)."""

    directions: np.ndarray
    still_until: np.ndarray


class Corners:
    """A reference's moving intervals per robot, for the turns ahead of the clock."""

    def __init__(self, seconds: np.ndarray, positions: np.ndarray,
                 rests: np.ndarray | None = None):
        """
        Precompute each interval's velocity and each robot's next moving interval.

        rests (M,): the poses at which a reference timed under acceleration
        limits stands still (Reference.at_rest); None: a plan without the limit,
        whose velocities jump at every corner.
        """
        self.seconds = np.asarray(seconds, dtype=float)
        self.rests = rests
        lengths = np.diff(self.seconds)
        steps = np.diff(positions, axis=0)
        with np.errstate(divide='ignore', invalid='ignore'):
            velocities = np.where(lengths[:, None, None] > 0,
                                  steps / lengths[:, None, None], 0.0)
        self.velocities = velocities                           # (M - 1, k, 3)
        self.speeds = np.linalg.norm(velocities, axis=-1)      # (M - 1, k)
        moving = self.speeds > STILL
        count = len(lengths)
        # next_moving[j, i]: first interval >= j in which robot i moves (count: none)
        index = np.where(moving, np.arange(count)[:, None], count)
        self.next_moving = np.minimum.accumulate(index[::-1], axis=0)[::-1] if count else index

    def turns(self, robots: np.ndarray) -> np.ndarray:
        """
        Return the (M,) poses at which one of robots (k,) turns by more than REVERSE_ANGLE.

        Between two consecutive moves of a robot (the intervals between them
        may stand still), at the start of the second one: there it switches
        its driving direction.
        """
        result = np.zeros(self.seconds.size, dtype=bool)
        for robot in np.flatnonzero(robots):
            moves = np.flatnonzero(self.speeds[:, robot] > STILL)
            directions = self.velocities[moves, robot]
            beta = wrap(np.diff(np.arctan2(directions[:, 1], directions[:, 0])))
            result[moves[1:][np.abs(beta) > REVERSE_ANGLE]] = True
        return result

    def upcoming(self, s: float) -> Upcoming:
        """
        Return where each reference moves next, and when.

        Where robot i's reference moves at s, still_until is s and the direction
        its current one; where it stands still, the direction of its next move
        (0 if none) and the plan time that move starts (inf if none).
        """
        k = self.speeds.shape[1]  # (M - 1, k), also (0, k) for a reference of one pose
        if self.speeds.size == 0 or s >= self.seconds[-1]:
            return Upcoming(np.zeros((k, 3)), np.full(k, np.inf))
        j = int(leg_at(self.seconds, s))
        nxt = self.next_moving[j]
        has = nxt < len(self.speeds)
        rows = np.minimum(nxt, len(self.speeds) - 1)
        directions = self.velocities[rows, np.arange(k)]
        directions = np.where(has[:, None], directions, 0.0)
        starts = np.where(has, np.maximum(self.seconds[rows], s), np.inf)
        return Upcoming(directions, starts)

    def corner_caps(self, s: float, steering_length: float,
                    yaw_rate_limit: float) -> np.ndarray:
        """
        Return the (k,) clock rates that slow each robot into the corners ahead.

        A corner is a breakpoint at plan time t in (s, s + LOOKAHEAD] where robot i's
        reference moves before and turns by beta, or stops (the plan's end too):
        a base with an acceleration limit cannot stop at once either. It must be
        passed at most at creep_rate(beta) (CORNER_RATE if beta needs a switch
        of direction or the reference stops), and the cap rises linearly to 1 over
        LOOKAHEAD plan seconds before it. A reference timed under acceleration
        limits (rests) brakes into its stops at those limits, and its turns
        beyond REVERSE_ANGLE are stops (Execution): there only the creep corners
        are left to slow into.
        """
        k = self.speeds.shape[1]  # (M - 1, k), also (0, k) for a reference of one pose
        caps = np.ones(k)
        first = int(np.searchsorted(self.seconds, s, side='right'))
        last = int(np.searchsorted(self.seconds, s + LOOKAHEAD, side='right'))
        for b in range(max(first, 1), min(last, len(self.speeds) + 1)):
            before = self.velocities[b - 1]
            after = self.velocities[b] if b < len(self.speeds) else np.zeros_like(before)
            speeds_after = np.linalg.norm(after, axis=-1)
            corner = self.speeds[b - 1] > STILL
            if self.rests is not None:
                corner &= (speeds_after > STILL) & ~self.rests[b]
            if not corner.any():
                continue
            beta = wrap(np.arctan2(after[:, 1], after[:, 0])
                        - np.arctan2(before[:, 1], before[:, 0]))
            at_corner = np.maximum(CORNER_RATE, creep_rate(beta, speeds_after,
                                                           steering_length, yaw_rate_limit))
            at_corner = np.where(speeds_after > STILL, at_corner, CORNER_RATE)
            ramp = at_corner + (1.0 - at_corner) * (self.seconds[b] - s) / LOOKAHEAD
            caps = np.where(corner, np.minimum(caps, ramp), caps)
        return caps
