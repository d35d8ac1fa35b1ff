"""
Input checks: a request must be a sequence of points of F(R^d - Q_r, k).

Checks run in the priority order of ErrorCode: shape and counts first, then
non-finite values, then coincident robots, then robots on obstacles, then
robots outside the workspace bounds (OUTSIDE_WORKSPACE, whose value comes
after CLEARANCE_BELOW_REQUIRED's but which ranks here, core.errors). Every
message names the configuration (0-based m for C_{m+1}), the robots and the
obstacle at fault.
"""

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.spatial import cKDTree

from .errors import compared, ErrorCode, literal, PlanningError
from .limits import first_non_finite, first_out_of_range, MAX_COORDINATE
from .pairs import first_equal_pair, pair_difference_matrix, point_pairs, with_obstacles
from .walls import first_outside

# Up to this many robots, coincidences are found by comparing every pair.
_PAIRWISE_ROBOTS = 32


def real_array(item: object, what: str, configuration: int | None = None) -> np.ndarray:
    """
    Return item as a float array, or raise INVALID_REQUEST if it is not real numbers.

    what names it in the message ('{configuration}' with configuration m).
    """
    try:
        array = np.asarray(item)
        if array.dtype.kind not in 'biuf':
            raise TypeError(f'elements of type {array.dtype}')
        return array.astype(float)
    except (TypeError, ValueError, OverflowError) as error:
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            f'{what} is not an array of real numbers: {literal(error)}',
                            configuration=configuration) from None


def _reject_out_of_range(configurations, first=0):
    """
    Raise INVALID_REQUEST for a finite coordinate beyond +-MAX_COORDINATE.

    configurations is C_first as (k, d), or C_first.. as (n, k, d). Returns
    whether every coordinate is finite too (the usual case, found in one pass).
    """
    if (np.abs(configurations) <= MAX_COORDINATE).all():
        return True
    where = first_out_of_range(configurations)
    if where is None:
        return False
    m, robot, axis = (0, *where) if configurations.ndim == 2 else where
    raise PlanningError(ErrorCode.INVALID_REQUEST,
                        f'{{configuration}}, {{robot}}: coordinate {axis} is '
                        f'{configurations[where]:.6g}, beyond the supported range '
                        f'+-{MAX_COORDINATE:.0e}', configuration=first + m, robots=[robot],
                        coordinate=axis)


def _as_array(configurations, dimension):
    """
    Return (configurations as a float (n, k, d) array, all finite) or raise a shape error.

    The range (INVALID_REQUEST) is checked on each configuration before the
    robot counts are compared (ROBOT_COUNT_MISMATCH): the smaller code wins.
    """
    if isinstance(configurations, np.ndarray) and configurations.ndim == 3:
        configurations = real_array(configurations, 'the request')
        if configurations.shape[0] < 2:
            raise PlanningError(ErrorCode.NO_CONFIGURATIONS,
                                f'need at least 2 configurations, got {configurations.shape[0]}')
        if configurations.shape[2] == dimension and configurations.shape[1] > 0:
            return configurations, _reject_out_of_range(configurations)
    try:
        items = list(configurations)
    except TypeError:
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            'configurations must be a sequence of (k, d) arrays') from None
    if len(items) < 2:
        raise PlanningError(ErrorCode.NO_CONFIGURATIONS,
                            f'need at least 2 configurations, got {len(items)}')
    arrays = [real_array(item, '{configuration}', m) for m, item in enumerate(items)]
    for m, array in enumerate(arrays):
        if array.ndim != 2 or array.shape[1] != dimension:
            raise PlanningError(ErrorCode.INVALID_REQUEST,
                                f'{{configuration}} must have shape (k, {dimension}), '
                                f'got {array.shape}', configuration=m)
    robot_count = arrays[0].shape[0]
    if robot_count == 0:
        raise PlanningError(ErrorCode.INVALID_REQUEST, '{configuration} has no robots',
                            configuration=0)
    finite = True
    for m, array in enumerate(arrays):  # every one: a later range fault outranks NaN
        finite &= _reject_out_of_range(array, m)
    for m, array in enumerate(arrays):
        if array.shape[0] != robot_count:
            raise PlanningError(ErrorCode.ROBOT_COUNT_MISMATCH,
                                f'{{configuration}} has {array.shape[0]} robots, '
                                f'configuration 0 has {robot_count}', configuration=m)
    return np.stack(arrays), finite


@dataclass(frozen=True)
class Meeting:
    """
    Two bodies of C_m too close: robots first < second, or robot first and obstacle second.

    distance is their centres' (0 where they are at one point).
    """

    configuration: int
    first: int
    second: int
    distance: float = 0.0


def _sorted_coincidence(configurations):
    """Return the Meeting of two robots at one point in some C_m, sorting the points; or None."""
    n, k, d = configurations.shape
    pair = first_equal_pair(configurations.reshape(n * k, d), np.repeat(np.arange(n), k))
    if pair is None:
        return None
    return Meeting(pair[0] // k, pair[0] % k, pair[1] % k)


def _coincidences(configurations, obstacles):
    """
    Return (robots at one point, a robot on an obstacle's point): each a Meeting or None.

    Few robots: one product with the pair difference matrix gives every
    robot-robot and robot-obstacle difference; many: sort, and compare each
    robot with each obstacle.
    """
    n, k, d = configurations.shape
    r = len(obstacles)
    if k <= _PAIRWISE_ROBOTS:
        points = with_obstacles(configurations, obstacles)
        zero = ~(pair_difference_matrix(k, r) @ points).any(axis=2)
        if not zero.any():
            return None, None
        a, b = point_pairs(k, r)
        robot_pairs = k * (k - 1) // 2
        hits = np.argwhere(zero[:, :robot_pairs])
        robots = (Meeting(int(hits[0][0]), int(a[hits[0][1]]), int(b[hits[0][1]]))
                  if hits.size else None)
        hits = np.argwhere(zero[:, robot_pairs:])
        on = None
        if hits.size:
            m, pair = int(hits[0][0]), robot_pairs + int(hits[0][1])
            on = Meeting(m, int(a[pair]), int(b[pair]) - k)
        return robots, on
    if r:
        hits = np.argwhere(np.all(configurations[:, :, None, :] == obstacles[None, None], axis=3))
        if hits.size:
            m, robot, obstacle = (int(v) for v in hits[0])
            return _sorted_coincidence(configurations), Meeting(m, robot, obstacle)
    return _sorted_coincidence(configurations), None


def _first_overlap(configurations, obstacles, robot_radius, obstacle_radii):
    """
    Return (overlapping robot discs, a robot disc overlapping an obstacle's): Meetings.

    Either is None when there is none; the first configuration with one wins.
    Touching bodies (distance equal to the sum of the radii) do not overlap.
    """
    robots = None
    if robot_radius > 0:
        for m, configuration in enumerate(configurations):
            pairs = cKDTree(configuration).query_pairs(2 * robot_radius, output_type='ndarray')
            if pairs.size:
                gaps = np.linalg.norm(configuration[pairs[:, 0]] - configuration[pairs[:, 1]],
                                      axis=1)
                inside = np.flatnonzero(gaps < 2 * robot_radius)
                if inside.size:
                    a, b = sorted(int(i) for i in pairs[inside[0]])
                    robots = Meeting(m, a, b, float(gaps[inside[0]]))
                    break
    on = None
    if len(obstacles) and (robot_radius > 0 or (obstacle_radii > 0).any()):
        reach = robot_radius + obstacle_radii
        for m, configuration in enumerate(configurations):
            distance = np.linalg.norm(configuration[:, None] - obstacles[None], axis=2)
            hits = np.argwhere(distance < reach[None])
            if hits.size:
                robot, obstacle = (int(v) for v in hits[0])
                on = Meeting(m, robot, obstacle, float(distance[robot, obstacle]))
                break
    return robots, on


def validate_configurations(configurations: npt.ArrayLike, obstacles: np.ndarray,
                            robot_radius: float = 0.0,
                            obstacle_radii: np.ndarray | None = None,
                            bounds: np.ndarray | None = None) -> np.ndarray:
    """
    Return the request as a float (n, k, d) array after every check, or raise PlanningError.

    With radii, robot discs that overlap (ROBOTS_COINCIDE) and a robot disc that
    overlaps an obstacle's (ROBOT_ON_OBSTACLE) are refused too. With bounds
    (checked, core.walls), a robot whose centre is closer than robot_radius to
    a wall, or beyond it, is refused (OUTSIDE_WORKSPACE).
    """
    checked, all_finite = _as_array(configurations, obstacles.shape[1])
    bad = None if all_finite else first_non_finite(checked)
    if bad is not None:
        m, robot, axis = bad
        raise PlanningError(ErrorCode.NON_FINITE_VALUE,
                            f'{{configuration}}, {{robot}}: coordinate {axis} is '
                            f'{checked[m, robot, axis]}', configuration=m, robots=[robot],
                            coordinate=axis)
    coincident, on_point = _coincidences(checked, obstacles)
    if obstacle_radii is None:
        obstacle_radii = np.zeros(len(obstacles))
    overlap, on_obstacle = _first_overlap(checked, obstacles, robot_radius,
                                          obstacle_radii)
    # The smallest code first (robots before obstacles), and within it the first
    # configuration, an exact meeting before an overlap there: an exact robot on an
    # obstacle outranked overlapping discs, a meeting in C_3 an overlap in C_1.
    robots = _first_of(coincident, overlap)
    if robots is not None and robots is coincident:
        both = [coincident.first, coincident.second]
        raise PlanningError(ErrorCode.ROBOTS_COINCIDE,
                            f'{{configuration}}: {{robots}} are at the same '
                            f'point {checked[coincident.configuration, both[0]].tolist()}',
                            configuration=coincident.configuration, robots=both)
    if robots is not None:  # the overlap
        apart, least = compared(robots.distance, 2 * robot_radius)
        raise PlanningError(ErrorCode.ROBOTS_COINCIDE,
                            f'{{configuration}}: the discs of {{robots}} overlap: centres '
                            f'{apart} apart, less than 2 '
                            f'robot_radius = {least}', configuration=robots.configuration,
                            robots=[robots.first, robots.second])
    touching = _first_of(on_point, on_obstacle)
    if touching is not None and touching is on_point:
        raise PlanningError(ErrorCode.ROBOT_ON_OBSTACLE,
                            '{configuration}: {robot} is on {obstacle}',
                            configuration=on_point.configuration, robots=[on_point.first],
                            obstacle=on_point.second, point=obstacles[on_point.second].tolist())
    if touching is not None:  # the overlap
        obstacle = touching.second
        apart, least = compared(touching.distance, robot_radius + obstacle_radii[obstacle])
        raise PlanningError(ErrorCode.ROBOT_ON_OBSTACLE,
                            f'{{configuration}}: {{robot}} overlaps '
                            f'{{obstacle}}: centres {apart} apart, less than robot_radius + '
                            f'obstacle_radius = {least}',
                            configuration=touching.configuration, robots=[touching.first],
                            obstacle=obstacle, point=obstacles[obstacle].tolist())
    if bounds is not None:
        _reject_outside(checked, bounds, robot_radius)
    return checked


def _first_of(exact: Meeting | None, overlap: Meeting | None) -> Meeting | None:
    """Return the meeting in the earlier configuration, exact on a tie; None for none."""
    if exact is None or (overlap is not None
                         and overlap.configuration < exact.configuration):
        return overlap
    return exact


def _reject_outside(configurations, bounds, robot_radius):
    """Raise OUTSIDE_WORKSPACE for the worst robot of the first C_m with one outside."""
    outside = first_outside(configurations, bounds, robot_radius)
    if outside is None:
        return
    m, robot, axis = outside.index, outside.body, outside.wall.axis
    raise PlanningError(ErrorCode.OUTSIDE_WORKSPACE,
                        '{configuration}: {robot} is '
                        + outside.words(bounds, configurations[m, robot, axis], robot_radius,
                                        'robot_radius'),
                        configuration=m, robots=[robot], wall=outside.wall,
                        distance=outside.beyond)
