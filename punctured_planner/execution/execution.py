"""
One control step of a plan's execution: the shared plan clock, then every robot's command.

Each step (doc/design.md section 13; msg_docs/ExecutePlan.md):

1. measure every robot's tracking error, |reference(s) - position|, at the
   current plan time s;
2. choose the clock rate: 0 while any robot's odometry is stale, else
   :func:`clock_rate` of the errors and the tracking tolerance (with
   ``shared_clock`` off, 1: every robot follows the stamps on its own);
3. advance s by rate x dt (at most the plan's duration);
4. command each robot feed-forward plus feedback, saturated at its speed
   limit: v = sat(rate x reference'(s) + gain x (reference(s) - position)).
   A stale robot gets 0.

The execution is finished once s reached the plan's end and every robot is
within ``goal_tolerance`` of its last configuration.
"""

from dataclasses import dataclass

import numpy as np

from .bodies import Bodies
from .reference import Reference
from .tolerance import clock_rate

# Longest step the clock takes at once (s): a stalled control loop does not jump ahead.
MAX_STEP = 0.2


@dataclass(frozen=True)
class ExecutionSettings:
    """The tracking law's settings (the executor node's parameters of the same names)."""

    gain: float = 2.0
    speed_limit: float = 1.0
    slow_fraction: float = 0.3
    hold_fraction: float = 0.6
    goal_tolerance: float = 0.01
    shared_clock: bool = True


@dataclass(frozen=True)
class Step:
    """What one control step decided: the clock, the references and the commands."""

    plan_time: float
    rate: float
    positions: np.ndarray       # (k, 3) references at plan_time
    orientations: np.ndarray    # (k, 4) references at plan_time
    velocities: np.ndarray      # (k, 3) commanded velocities, planning frame
    errors: np.ndarray          # (k,) tracking errors measured this step (m)
    finished: bool


def saturate(velocities: np.ndarray, limit: float) -> np.ndarray:
    """Return (k, 3) velocities scaled down to speed at most limit, direction kept."""
    speeds = np.linalg.norm(velocities, axis=-1, keepdims=True)
    scale = np.minimum(1.0, limit / np.maximum(speeds, np.finfo(float).tiny))
    return velocities * scale


class Execution:
    """The state of one plan's execution: its clock, the largest errors and the smallest gap."""

    def __init__(self, reference: Reference, tolerance: float, settings: ExecutionSettings,
                 bodies: Bodies | None = None):
        """Start at plan time 0 with no error measured yet."""
        self.reference = reference
        self.tolerance = float(tolerance)
        self.settings = settings
        self.bodies = bodies if bodies is not None else Bodies()
        self.plan_time = 0.0
        self.max_errors = np.zeros(reference.robot_count)
        self.min_gap = np.inf

    def step(self, dt: float, positions: np.ndarray, stale: np.ndarray) -> Step:
        """
        Advance by dt seconds for robot positions (k, 3) and stale flags (k,); return the Step.

        The positions of stale robots are not used (their errors count as 0 this step).
        """
        s = self.settings
        stale = np.asarray(stale, dtype=bool)
        errors = np.linalg.norm(self.reference.position(self.plan_time) - positions, axis=1)
        errors[stale] = 0.0
        self.max_errors = np.maximum(self.max_errors, errors)
        if not stale.any():
            self.min_gap = min(self.min_gap, self.bodies.smallest_gap(positions).value)
        if not s.shared_clock:
            rate = 1.0
        elif stale.any():
            rate = 0.0
        else:
            rate = clock_rate(errors, self.tolerance, s.slow_fraction, s.hold_fraction)
        duration = self.reference.duration
        self.plan_time = min(duration, self.plan_time + rate * min(max(dt, 0.0), MAX_STEP))
        target = self.reference.position(self.plan_time)
        command = rate * self.reference.velocity(self.plan_time) + s.gain * (target - positions)
        velocities = saturate(command, s.speed_limit)
        velocities[stale] = 0.0
        finished = bool(self.plan_time >= duration and not stale.any()
                        and np.all(np.linalg.norm(target - positions, axis=1)
                                   <= s.goal_tolerance))
        return Step(self.plan_time, rate, target, self.reference.orientation(self.plan_time),
                    velocities, errors, finished)
