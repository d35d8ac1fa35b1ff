"""
The points of a configuration and their pairs: robots 0 .. k - 1, then obstacle j as k + j.

Index arrays of point pairs are built once per size (they sit on every hot path): the
certificate's (doc/design.md section 9), the refinement's and the executor's gaps.
"""

from dataclasses import dataclass
from functools import lru_cache

import numpy as np


@lru_cache(maxsize=32)
def point_pairs(robot_count: int, obstacle_count: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """
    Return read-only index arrays (a, b) into the k + r points of a configuration.

    First every robot pair a < b, then every (robot, obstacle) pair with the
    obstacle numbered k + its index.
    """
    a, b = np.triu_indices(robot_count, 1)
    robot = np.repeat(np.arange(robot_count), obstacle_count)
    obstacle = robot_count + np.tile(np.arange(obstacle_count), robot_count)
    first, second = np.concatenate([a, robot]), np.concatenate([b, obstacle])
    first.flags.writeable = second.flags.writeable = False
    return first, second


@lru_cache(maxsize=32)
def pair_difference_matrix(robot_count: int, obstacle_count: int = 0) -> np.ndarray:
    """
    Return the (pairs, k + r) matrix with rows e_a - e_b for the pairs of point_pairs.

    Every row has one +1 and one -1, so each product is a single exact
    subtraction: M @ points gives every pair's relative position at once,
    faster than two fancy-index gathers for a few dozen points.
    """
    a, b = point_pairs(robot_count, obstacle_count)
    matrix = np.zeros((a.size, robot_count + obstacle_count))
    matrix[np.arange(a.size), a] = 1.0
    matrix[np.arange(a.size), b] = -1.0
    matrix.flags.writeable = False
    return matrix


def point_radii(robot_count: int, robot_radius: float,
                obstacle_radii: np.ndarray) -> np.ndarray:
    """Return the (k + r,) radii of the points: each robot's robot_radius, then the obstacles'."""
    return np.concatenate([np.full(robot_count, float(robot_radius)),
                           np.asarray(obstacle_radii, dtype=float)])


@dataclass(frozen=True)
class PointPair:
    """A pair of points as its culprits: kind 'robots' (two robots) or 'obstacle' (robot, j)."""

    kind: str
    first: int
    second: int

    @classmethod
    def from_points(cls, first: int, second: int, robot_count: int) -> 'PointPair':
        """Return the pair of points first < second, the second k + j for obstacle j."""
        if second >= robot_count:
            return cls('obstacle', int(first), int(second) - robot_count)
        return cls('robots', int(first), int(second))


def first_equal_pair(points: np.ndarray,
                     groups: np.ndarray | None = None) -> tuple[int, int] | None:
    """
    Return indices a < b of two equal points (N, d) or values (N,), or None: sorting, not pairs.

    With groups (N,) only points of one group count (one configuration's robots).
    The pair is the first one in sorted order, so the same input names the same pair.
    """
    points = np.asarray(points)
    if len(points) < 2:
        return None
    columns = points.reshape(len(points), -1)
    keys = tuple(columns.T[::-1]) + (() if groups is None else (groups,))
    order = np.lexsort(keys)
    ordered = columns[order]
    same = np.all(ordered[1:] == ordered[:-1], axis=1)
    if groups is not None:
        grouped = groups[order]
        same &= grouped[1:] == grouped[:-1]
    hits = np.flatnonzero(same)
    if hits.size == 0:
        return None
    a, b = sorted((int(order[hits[0]]), int(order[hits[0] + 1])))
    return a, b


def with_obstacles(configurations: np.ndarray, obstacles: np.ndarray) -> np.ndarray:
    """Return (n, k + r, d): every configuration's robots followed by the fixed obstacles."""
    n, k, d = configurations.shape
    points = np.empty((n, k + len(obstacles), d))
    points[:, :k] = configurations
    points[:, k:] = obstacles
    return points
