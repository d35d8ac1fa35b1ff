"""
Surface gaps between disc robots and disc obstacles, exact over straight moves.

A robot is a disc (a ball in 3-D) of radius R around its centre, obstacle j a
disc of radius rho_j. Their surface gap is centre distance - 2R for two robots
and centre distance - R - rho_j for a robot and an obstacle; negative means
contact (doc/design.md section 13). Over a step in which every robot moves on
a straight line at constant speed the relative position of a pair is linear
in time, so its smallest distance has the closed form of the clearance
certificate (:func:`punctured_planner.core.certificate.segment_minimum`).
"""

from dataclasses import dataclass
from dataclasses import field

import numpy as np

from ..core.certificate import segment_minimum
from ..core.pairs import point_pairs
from ..core.pairs import point_radii
from ..core.pairs import PointPair


@dataclass(frozen=True)
class Gap:
    """A surface gap (m) and where it is: kind 'robots' (a, b) or 'obstacle' (robot, obstacle)."""

    value: float
    kind: str = 'none'
    first: int = -1
    second: int = -1


@dataclass(frozen=True)
class PairGaps:
    """
    Every pair's surface gap (pairs,) and its points a, b (core.pairs.point_pairs).

    The pairs are the robot pairs, then every (robot, k + obstacle).
    """

    gaps: np.ndarray
    a: np.ndarray
    b: np.ndarray


@dataclass(frozen=True)
class Bodies:
    """The bodies' sizes: robot radius R, obstacle centres (r, 3) and radii (r,)."""

    robot_radius: float = 0.0
    obstacles: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))
    obstacle_radii: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def pair_gaps(self, start: np.ndarray, end: np.ndarray | None = None) -> PairGaps:
        """
        Return every pair's smallest surface gap while moving start -> end.

        start and end are (k, 3) centres (end None: the gaps at start).
        """
        k, r = len(start), len(self.obstacles)
        a, b = point_pairs(k, r)
        points = np.concatenate([start, self.obstacles])
        relative = points[a] - points[b]
        if end is None:
            squared = np.einsum('ij,ij->i', relative, relative)
        else:
            moved = np.concatenate([end, self.obstacles])
            # segment_minimum takes coordinate-first arrays (d, pairs)
            squared, _ = segment_minimum(np.ascontiguousarray(relative.T),
                                         np.ascontiguousarray((moved[a] - moved[b]
                                                               - relative).T))
        radii = point_radii(k, self.robot_radius, self.obstacle_radii)
        return PairGaps(np.sqrt(squared) - radii[a] - radii[b], a, b)

    def smallest_gap(self, start: np.ndarray, end: np.ndarray | None = None) -> Gap:
        """Return the smallest surface Gap while moving start -> end (inf: nothing to meet)."""
        pairs = self.pair_gaps(start, end)
        if pairs.gaps.size == 0:
            return Gap(np.inf)
        i = int(np.argmin(pairs.gaps))
        pair = PointPair.from_points(pairs.a[i], pairs.b[i], len(start))
        return Gap(float(pairs.gaps[i]), pair.kind, pair.first, pair.second)
