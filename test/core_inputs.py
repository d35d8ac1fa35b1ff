"""Input generators shared by the core tests: random and degenerate requests."""

import numpy as np


def configuration_with_count(rng, obstacles, robot_count, target_count, frame_axis=0):
    """
    Return a (k, d) configuration whose projection count cp equals target_count.

    Obstacles must have distinct coordinates on frame_axis. target_count - r new
    projection values go to as many robots; the others share an existing value
    (an obstacle's or a new one), with distinct offsets so no robot coincides.
    """
    r, d = obstacles.shape
    new_count = target_count - r
    existing = list(obstacles[:, frame_axis])
    fresh = []
    while len(fresh) < new_count:
        value = float(rng.integers(-20, 21)) / 4
        if value not in existing and value not in fresh:
            fresh.append(value)
    robots = rng.permutation(robot_count)
    projections = np.empty(robot_count)
    projections[robots[:new_count]] = fresh
    pool = existing + fresh
    projections[robots[new_count:]] = rng.choice(pool, robot_count - new_count)
    configuration = rng.normal(size=(robot_count, d)).round(3)
    configuration[:, frame_axis] = projections
    # Distinct offsets away from every obstacle offset: no coincidence at all.
    other = (frame_axis + 1) % d
    offsets = (rng.permutation(robot_count) + 1) * rng.choice([-1.0, 1.0]) * 0.5
    configuration[:, other] = obstacles[:, other].max(initial=0.0) + offsets + 0.25
    return configuration


def axis_obstacles(rng, obstacle_count, dimension):
    """Return obstacles with distinct x coordinates on a coarse grid (many shared values)."""
    xs = rng.choice(np.arange(-8, 9) / 2, size=obstacle_count, replace=False)
    obstacles = rng.integers(-2, 3, size=(obstacle_count, dimension)).astype(float)
    obstacles[:, 0] = xs
    return obstacles
