"""
The section Gamma on axis configurations and the sequential composition (Remark 2.3).

Gamma(L, L') (paper, equation (3.1)): robot with paper index i lifts to height
i along e2, slides to L'_i + i e2, and drops; a third of the time each. The
n-th sequential section concatenates Gamma(L_m, L_{m+1}) and, by Remark 2.3,
wraps each segment in the deformations H(C_m) forward and H(C_{m+1}) backward
(doc/design.md section 3).
"""

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

# Breakpoint fractions of one segment [tau_m, tau_{m+1}]: the first third is
# H(C_m) forward with its legs of equal length, the middle third is Gamma
# (lift, slide, drop: a ninth each), the last third is H(C_{m+1}) backward.
PAPER_FRACTIONS = (0.0, 1 / 6, 1 / 3, 4 / 9, 5 / 9, 2 / 3, 5 / 6, 1.0)
SPREAD_FRACTIONS = (0.0, 1 / 9, 2 / 9, 1 / 3, 4 / 9, 5 / 9, 2 / 3, 7 / 9, 8 / 9, 1.0)

PAPER_LEGS = ('D', 'phi', 'lift', 'slide', 'drop', 'phi^-1', 'D^-1')
SPREAD_LEGS = ('D', 'S', 'phi', 'lift', 'slide', 'drop', 'phi^-1', 'S^-1', 'D^-1')


@dataclass(frozen=True)
class Schedule:
    """The legs of one segment C_m -> C_{m+1} of a variant and their breakpoint fractions."""

    legs: tuple[str, ...]
    fractions: tuple[float, ...]


# The one table from variant to legs: Workspace and plan read it.
SCHEDULES = {
    'paper': Schedule(PAPER_LEGS, PAPER_FRACTIONS),
    'spread': Schedule(SPREAD_LEGS, SPREAD_FRACTIONS),
}
# 'discs' has no fixed schedule: its legs depend on the pillars each robot passes
# (core.discs); its breakpoints come with the plan.
VARIANTS = (*SCHEDULES, 'discs')


@lru_cache(maxsize=64)
def lane_heights(robot_count: int, obstacle_count: int, lane_spacing: float, lane_base: float,
                 variant: str) -> np.ndarray:
    """
    Return the (k,) e2 heights of the lanes above the axis (read-only: cached, as every plan's).

    Paper: robot i (1-based) has paper index r + i and lane height
    (r + i) lane_spacing, exactly the paper's heights for lane_spacing 1 and
    obstacles on the axis. Spread: lanes lane_spacing apart starting
    lane_spacing beyond the highest obstacle. Either way above `lane_base`,
    the highest obstacle e2 offset, so the slides never meet an obstacle.
    """
    first = obstacle_count + 1 if variant == 'paper' else 1
    lanes = lane_base + (first + np.arange(robot_count)) * lane_spacing
    lanes.flags.writeable = False
    return lanes


@lru_cache(maxsize=64)
def segment_times(configuration_count: int, fractions: tuple[float, ...]) -> np.ndarray:
    """
    Return breakpoint parameters: tau_m + (tau_{m+1} - tau_m) f for each segment.

    Waypoints sit at tau_m = (m - 1) / (n - 1) (paper, equation (2.1)); the
    segments share their end points, so there are (n - 1) (len(f) - 1) + 1 times.
    """
    tau = np.arange(configuration_count) / (configuration_count - 1)
    times = tau[:-1, None] + np.diff(tau)[:, None] * np.asarray(fractions)[None, :]
    times = np.concatenate([times[:, :-1].ravel(), tau[-1:]])
    times.flags.writeable = False
    return times


def compose(deformation_stages: list[np.ndarray], lanes: np.ndarray,
            e2: np.ndarray) -> np.ndarray:
    """
    Return the (V, k, d) breakpoint positions of the sequential section.

    deformation_stages lists (n, k, d) arrays H_0 = C, H_1, ..., H_s = L (the
    configurations after each deformation leg, ending on the axis). Segment m
    runs H(C_m) forward, Gamma(L_m, L_{m+1}), then H(C_{m+1}) backward.
    """
    axis = deformation_stages[-1]
    lifted = axis + lanes[:, None] * e2
    forward = deformation_stages
    backward = deformation_stages[::-1]
    segment = ([stage[:-1] for stage in forward]
               + [lifted[:-1], lifted[1:]]
               + [stage[1:] for stage in backward[:-1]])
    n, k, d = deformation_stages[0].shape
    positions = np.empty(((n - 1) * len(segment) + 1, k, d))
    by_segment = positions[:-1].reshape(n - 1, len(segment), k, d)
    for leg, stage in enumerate(segment):
        by_segment[:, leg] = stage
    positions[-1] = deformation_stages[0][-1]
    return positions
