"""
When a goal may start, and when a hold of the plan clock ends it (doc/design.md section 13).

A plan is certified from its start, at rest: a goal starts only with every robot at rest
(:func:`still_moving`) and within the tracking tolerance of its reference there
(:func:`off_start`). The plan clock holds
for stale odometry or for a robot that does not follow; one hold, whatever holds it,
may last ``hold_timeout`` (:class:`ClockHold`): then the goal ends, for lost odometry
if some robot's went stale during the hold, else for the robots the clock waits for
(:func:`waited_for`). A clock that measures errors too rarely for the plan's speed
holds too late (:func:`period_overrun`). The plan_executor node words and sends the
results.
"""

from dataclasses import dataclass

import numpy as np

from .reference import Reference
from .unicycle import Corners

# The clock counts as held below this rate. Near the hold threshold it slows in
# proportion to the room left, so a robot that cannot move makes the rate tend to 0
# without reaching it: the hold flickered and a goal with a stuck robot whose
# odometry stayed fresh ran on for good (a DDS test, 1 run in 3 under load).
HELD_RATE = 0.05


# A robot whose odometry reports at most this speed (m/s) is at rest: stopping from it
# takes millimetres. A goal that preempted a moving one started while its robots still
# braked from 0.3 - 0.6 m/s, ran ahead of the new reference (which starts at rest, and
# the clock does not wait for a robot ahead) and reached 1.2 delta (over DDS).
AT_REST_SPEED = 0.05


def still_moving(speeds: np.ndarray) -> np.ndarray:
    """Return the indices of the robots not at rest: speed above AT_REST_SPEED (or NaN)."""
    return np.flatnonzero(~(np.asarray(speeds) <= AT_REST_SPEED))


@dataclass(frozen=True)
class OffStart:
    """The robots (indices) farther than the tolerance from the plan's start, and how far."""

    robots: np.ndarray
    distances: np.ndarray


def off_start(reference: Reference, positions: np.ndarray, tolerance: float) -> OffStart:
    """Return the robots of positions (k, 3) beyond tolerance from the reference's start."""
    away = np.linalg.norm(positions - reference.position(0.0), axis=1)
    far = np.flatnonzero(away > tolerance)
    return OffStart(far, away[far])


@dataclass(frozen=True)
class Overrun:
    """
    Robots (indices) whose reference moves farther in one control period than the margin.

    distances: how far each moves in a period (m); margin: (1 - hold_fraction) x the
    tracking tolerance (m).
    """

    robots: np.ndarray
    distances: np.ndarray
    margin: float


def period_overrun(corners: Corners, tolerance: float, hold_fraction: float,
                   period: float) -> Overrun:
    """
    Return the robots whose reference moves farther in one period than the hold's margin.

    The clock holds once a control step measures an error of hold_fraction of the
    tolerance: a robot that stops following falls behind by up to what its reference
    moves in one period (and its command latency) before that, which the rest of
    the tolerance must cover (msg_docs/ExecutePlan.md). Speeds are each stamp
    interval's mean (corners: the reference's, Execution.corners), a profiled
    reference's peak higher: a lower bound.
    """
    travel = corners.speeds.max(axis=0, initial=0.0) * period
    margin = (1.0 - hold_fraction) * tolerance
    robots = np.flatnonzero(travel > margin)
    return Overrun(robots, travel[robots], margin)


@dataclass(frozen=True)
class HoldOver:
    """A hold that lasted its timeout: seconds held, and the robots stale during it."""

    seconds: float
    stale: tuple


@dataclass
class ClockHold:
    """
    The current hold of a goal's plan clock: since when, and who went stale during it.

    One hold, whatever holds the clock: two holds of their own let a robot whose
    odometry flapped reset each the other's and hold the fleet for good.
    """

    since: float | None = None   # seconds: the first control step of the current hold
    stale: tuple = ()            # names whose odometry went stale during it

    def update(self, allowed: float, stale: tuple, now: float, dt: float,
               timeout: float) -> HoldOver | None:
        """
        Follow one control step (the rate the robots allow, stale names, now and dt in s).

        Return the HoldOver once the hold lasted timeout (s), else None. The robots
        allowing the clock HELD_RATE at least with fresh odometry end a hold (the rate
        they allow, not the clock's: under an acceleration limit the clock rises slowly
        after a hold); the goal's first step (dt = 0) neither starts nor judges one.
        """
        if allowed >= HELD_RATE and not stale:
            self.since, self.stale = None, ()
            return None
        if dt <= 0.0:
            return None
        if self.since is None:
            self.since = now
        self.stale = tuple(dict.fromkeys(self.stale + tuple(stale)))
        held = now - self.since
        return HoldOver(held, self.stale) if held >= timeout else None


def waited_for(watched: np.ndarray, limit: float) -> np.ndarray:
    """
    Return the robots (indices) the clock waits for: watched errors (k,) at least limit.

    limit is hold_fraction x the tracking tolerance; a clock held by a turn's cap
    alone waits for the robot farthest behind.
    """
    waited = np.flatnonzero(watched >= limit)
    return waited if waited.size else np.array([int(np.argmax(watched))])
