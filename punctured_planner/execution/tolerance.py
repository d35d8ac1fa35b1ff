"""
The tracking tolerance of a plan and the rate of the shared plan clock.

Certificate (doc/design.md section 13): let g be the plan's exact smallest
surface gap over the whole motion (centre distance - 2R for two robots, centre
distance - R - rho for a robot and an obstacle). If at plan time s every robot
is within delta of its reference position, each centre distance differs from
the reference one by at most 2 delta (triangle inequality; an obstacle does not
move, so at most delta there), so every gap is at least g - 2 delta. With
delta = g / 2 the bodies cannot touch: that delta is the tracking tolerance
(core.timing.tracking_tolerance, less where a wall is nearer).
The shared clock keeps every robot inside it: full speed while the largest
error is at most ``slow_fraction`` delta, slower in between, held from
``hold_fraction`` delta on; the margin (1 - hold_fraction) delta covers what a
robot can move in one control step and its command latency.
"""

import numpy as np


def clock_rate(errors: np.ndarray, tolerance: float, slow_fraction: float,
               hold_fraction: float) -> float:
    """
    Return the plan clock's rate in [0, 1] for the robots' tracking errors (m).

    1 while max(errors) <= slow_fraction * tolerance, 0 from hold_fraction *
    tolerance on, linear in between (0 < slow_fraction < hold_fraction <= 1).
    No robot (empty errors) or an infinite tolerance gives 1.
    """
    worst = float(np.max(errors, initial=0.0))
    if not np.isfinite(tolerance):
        return 1.0
    low, high = slow_fraction * tolerance, hold_fraction * tolerance
    if worst <= low:
        return 1.0
    if worst >= high:
        return 0.0
    return (high - worst) / (high - low)
