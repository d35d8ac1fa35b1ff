"""Input checks: a request must be a sequence of points of F(R^d - Q_r, k).

Checks run in the priority order of ErrorCode: shape and counts first, then
non-finite values, then coincident robots, then robots on obstacles. Every
message names the configuration (0-based m for C_{m+1}), the robots and the
obstacle at fault.
"""

import numpy as np

from .errors import ErrorCode, PlanningError


def _as_array(configurations, dimension):
    """Return configurations as a float (n, k, d) array or raise a shape error."""
    if isinstance(configurations, np.ndarray):
        items = list(configurations) if configurations.ndim >= 1 else [configurations]
    else:
        items = list(configurations)
    if len(items) < 2:
        raise PlanningError(ErrorCode.NO_CONFIGURATIONS,
                            f'need at least 2 configurations, got {len(items)}')
    arrays = [np.asarray(item, dtype=float) for item in items]
    for m, array in enumerate(arrays):
        if array.ndim != 2 or array.shape[1] != dimension:
            raise PlanningError(ErrorCode.INVALID_REQUEST,
                                f'configuration {m} must have shape (k, {dimension}), '
                                f'got {array.shape}', configuration=m)
    robot_count = arrays[0].shape[0]
    if robot_count == 0:
        raise PlanningError(ErrorCode.INVALID_REQUEST, 'configuration 0 has no robots',
                            configuration=0)
    for m, array in enumerate(arrays):
        if array.shape[0] != robot_count:
            raise PlanningError(ErrorCode.ROBOT_COUNT_MISMATCH,
                                f'configuration {m} has {array.shape[0]} robots, '
                                f'configuration 0 has {robot_count}', configuration=m)
    return np.stack(arrays)


def _coincident_robots(configurations):
    """Return (m, a, b) for two robots at the same point in C_m, or None."""
    n, k, d = configurations.shape
    flat = configurations.reshape(n * k, d)
    config = np.repeat(np.arange(n), k)
    order = np.lexsort(tuple(flat.T[::-1]) + (config,))
    same = np.all(flat[order][1:] == flat[order][:-1], axis=1)
    same &= config[order][1:] == config[order][:-1]
    hits = np.flatnonzero(same)
    if hits.size == 0:
        return None
    first, second = order[hits[0]], order[hits[0] + 1]
    a, b = sorted((int(first % k), int(second % k)))
    return int(first // k), a, b


def validate_configurations(configurations, obstacles):
    """Return the request as a float (n, k, d) array after every check, or raise PlanningError."""
    configurations = _as_array(configurations, obstacles.shape[1])
    bad = np.argwhere(~np.isfinite(configurations))
    if bad.size:
        m, robot, axis = (int(v) for v in bad[0])
        raise PlanningError(ErrorCode.NON_FINITE_VALUE,
                            f'configuration {m}, robot {robot}: coordinate {axis} is '
                            f'{configurations[m, robot, axis]}', configuration=m, robots=[robot])
    coincident = _coincident_robots(configurations)
    if coincident is not None:
        m, a, b = coincident
        raise PlanningError(ErrorCode.ROBOTS_COINCIDE,
                            f'configuration {m}: robots {a} and {b} are at the same point '
                            f'{configurations[m, a].tolist()}', configuration=m, robots=[a, b])
    if len(obstacles):
        on = np.argwhere(np.all(configurations[:, :, None, :] == obstacles[None, None], axis=3))
        if on.size:
            m, robot, obstacle = (int(v) for v in on[0])
            raise PlanningError(ErrorCode.ROBOT_ON_OBSTACLE,
                                f'configuration {m}: robot {robot} is on obstacle {obstacle} '
                                f'at {obstacles[obstacle].tolist()}', configuration=m,
                                robots=[robot], obstacle=obstacle)
    return configurations
