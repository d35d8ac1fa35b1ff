"""
The frame (o, e1, e2) the algorithm works in (doc/design.md section 4).

The paper normalises the obstacles onto the e1 axis and writes p(x) for the
first coordinate (Section 3). For arbitrary obstacles we pick a frame in which
the obstacles' e1 projections are pairwise distinct; robots project onto the
line o + R e1. The frame is fixed per workspace, never per query, so the
domains of continuity are well defined.
"""

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
from scipy.spatial import ConvexHull, QhullError

from .certificate import RELATIVE_RESOLUTION
from .errors import ErrorCode, literal, PlanningError
from .limits import MAX_COORDINATE
from .walls import box_corners

_ORTHONORMAL_TOLERANCE = 1e-9
# For bodies in the plane, the directions e2 may take: this many evenly spaced angles, the
# four axis directions among them (doc/design.md section 4).
_OBLIQUE_DIRECTIONS = 32
# Rooms (_room) within this share of the most are a tie, which the first frame wins: qhull
# rounds, and gave an oblique frame 200.00000000000003 against the axis frames' 200.0 in a
# 20 x 20 hall whose pillar every direction halves.
_ROOM_TIE = 1e-9


@dataclass(frozen=True, eq=False)
class Frame:
    """
    Origin o and orthonormal directions e1 (projection axis), e2 (lane direction).

    Compared by identity (eq=False): its fields are numpy arrays, whose == is
    elementwise; a workspace's frame is one object for all its plans.
    """

    origin: np.ndarray
    e1: np.ndarray
    e2: np.ndarray

    def project(self, points: npt.ArrayLike) -> np.ndarray:
        """Return p(x) = <x - o, e1> for points of shape (..., d)."""
        return (np.asarray(points, dtype=float) - self.origin) @ self.e1

    def offset(self, points: npt.ArrayLike) -> np.ndarray:
        """Return the e2 offset <x - o, e2> for points of shape (..., d)."""
        return (np.asarray(points, dtype=float) - self.origin) @ self.e2

    def axis_points(self, projections: npt.ArrayLike) -> np.ndarray:
        """Return o + p e1 for projections of shape (...,): the points of the axis."""
        return self.origin + np.asarray(projections, dtype=float)[..., None] * self.e1


def _complement_direction(e1):
    """Return a unit vector orthogonal to e1: the least aligned coordinate axis, orthogonalised."""
    axis = np.zeros_like(e1)
    axis[int(np.argmin(np.abs(e1)))] = 1.0
    e2 = axis - (axis @ e1) * e1
    return e2 / np.linalg.norm(e2)


def _moment_curve_directions(dimension, count):
    """
    Return `count` deterministic unit directions (1, s, s^2, ...) on the moment curve.

    Two distinct points share a projection on (1, s, ..., s^{d-1}) only for the at
    most d - 1 roots s of a nonzero polynomial, so among count > C(r, 2) (d - 1)
    distinct values of s at least one separates all r obstacles.
    """
    s = np.tan(np.pi * (np.arange(count) + 0.5) / count - np.pi / 2)
    directions = s[:, None] ** np.arange(dimension)[None, :]
    return directions / np.linalg.norm(directions, axis=1, keepdims=True)


def _axis_frames(d):
    """
    Yield the axis frames (a, b, s): e1 the axis a, e2 the axis b (b != a) times s = +-1.

    In a fixed order: a, then b from a + 1 on (cyclically), then + before -; the
    first is (0, 1, +1), the coordinate axes.
    """
    for a in range(d):
        for step in range(1, d):
            for sign in (1.0, -1.0):
                yield a, (a + step) % d, sign


def _frame_directions(d, oblique):
    """
    Yield the directions (e1, e2) a frame may take: the axis frames, then with oblique more.

    oblique (bodies, in the plane): e2 also takes the other _OBLIQUE_DIRECTIONS evenly
    spaced angles, e1 being e2 turned a quarter, towards the positive side of its
    larger coordinate.
    """
    for a, b, sign in _axis_frames(d):
        e1, e2 = np.zeros(d), np.zeros(d)
        e1[a], e2[b] = 1.0, sign
        yield e1, e2
    if not oblique or d != 2:
        return
    for angle in 2.0 * np.pi * np.arange(_OBLIQUE_DIRECTIONS) / _OBLIQUE_DIRECTIONS:
        e2 = np.array([np.cos(angle), np.sin(angle)])
        if np.all(np.abs(e2) > 1e-12):  # the axis directions came first
            e1 = np.array([e2[1], -e2[0]])
            yield e1 * np.sign(e1[int(np.argmax(np.abs(e1)))]), e2


def _room(obstacles, bounds, e2, clearance, robot_radius):
    """
    Return the measure (area, volume) of the robots' room beyond every obstacle along e2.

    The robots' centres keep robot_radius from the walls, and every construction
    stages beyond each obstacle's clearance (r,) along e2 (its centre's offset plus
    that much). The centres' box cut by the plane through the farthest of those is
    convex: its vertices are the corners beyond the plane and the points where the
    box's edges cross it, and their convex hull (qhull) is where every construction
    stages and runs its lanes. Counting the centres' offsets alone chose, for balls
    among pillars in a low hall, the room above them: the height the bodies fill.
    """
    inside = bounds + np.array([robot_radius, -robot_radius])
    if np.any(inside[:, 0] > inside[:, 1]):
        return 0.0
    corners = box_corners(inside)
    height = corners @ e2 - float((obstacles @ e2 + clearance).max())
    if height.max() <= 0.0:
        return 0.0
    # The box's edges: corners whose indices differ in one bit (box_corners).
    edges = [(i, i | 1 << bit) for i in range(corners.shape[0])
             for bit in range(bounds.shape[0]) if not i >> bit & 1]
    first, second = (np.array(ends) for ends in zip(*edges))
    crossing = height[first] * height[second] < 0.0
    first, second = first[crossing], second[crossing]
    share = (height[first] / (height[first] - height[second]))[:, None]
    points = np.concatenate([corners[height >= 0.0],
                             corners[first] + share * (corners[second] - corners[first])])
    try:
        return float(ConvexHull(points).volume)
    except QhullError:  # a sliver too thin for qhull: no room worth the name
        return 0.0


def _most_room(obstacles, bounds, directions, clearance, robot_radius):
    """
    Return the index of the direction e2 with the most room (_room) among directions.

    Rooms within _ROOM_TIE of the most are a tie, which the first of them wins.
    """
    rooms = np.array([_room(obstacles, bounds, e2, clearance, robot_radius)
                      for e2 in directions])
    return int(np.argmax(rooms >= rooms.max() * (1.0 - _ROOM_TIE)))


def _reach(obstacles, e2):
    """
    Return how far the farthest obstacle lies along e2 from the middle of the obstacles.

    The middle is the centre of their bounding box, which stands for the middle of the
    floor the robots share with them. Every construction takes the robots beyond the
    farthest obstacle along e2 and back, so a robot about the middle climbs about this
    far, twice a segment: without walls the bodies' frame makes it least.
    """
    middle = 0.5 * (obstacles.min(axis=0) + obstacles.max(axis=0))
    return float(((obstacles - middle) @ e2).max())


def _origin(obstacles, bounds, e1):
    """
    Return o: the obstacles' centroid (else the walls' centre, else 0) less its e1 part.

    The point variants carry every robot to the axis o + R e1 and the discs variant
    centres nothing on it, so the axis goes through the middle of the workspace: with
    o = 0, obstacles and robots near y = 100 made every robot travel to y = 0 and back.
    Dropping the e1 part leaves every projection p(x) = <x - o, e1> as it was (exactly,
    for an axis frame, whose o has a 0 in e1's coordinate).
    """
    if len(obstacles):
        centre = obstacles.mean(axis=0)
    elif bounds is not None:
        centre = bounds.mean(axis=1)
    else:
        return np.zeros_like(e1)
    return centre - (centre @ e1) * e1


def _is_axis(frame):
    """Return whether e2 is a coordinate axis (either way): an axis frame (_axis_frames)."""
    return int(np.count_nonzero(frame.e2)) == 1


def choose_frame(obstacles: np.ndarray, bounds: np.ndarray | None = None,
                 oblique: bool = False, robot_radius: float = 0.0,
                 clearance: np.ndarray | float = 0.0) -> Frame:
    """
    Return the default frame for obstacles (r, d): deterministic, fixed per workspace.

    The origin o is the obstacles' centroid (else the walls' centre, else 0) less its e1
    part (_origin). The candidates are the frames that separate the obstacles: the axis
    frames, and with oblique (bodies, whose margins are far above the rounding an
    oblique frame brings into every projection; not point robots) in the plane e2 at
    _OBLIQUE_DIRECTIONS angles. Every construction stages and runs its lanes beyond the
    farthest obstacle along e2 (beyond its clearance, (r,) or one for all: the discs'
    PillarClearance), so with walls (bounds (d, 2)) the frame is the one with the most
    room there (_room: the area, or volume, of the robots' centres' box, robot_radius
    inside the walls, beyond that); without walls, for bodies, the one whose farthest
    obstacle is nearest the middle of the obstacles (_reach), an oblique frame only where
    it saves more than robot_radius of that climb over every axis frame; otherwise the
    first, the coordinate
    axes when they separate the obstacles (e1 = x, e2 = y). Ties go to the first, the
    axis frames first. With no axis frame separating the obstacles, the moment-curve
    direction that maximises the smallest gap between their projections, e2 across it
    (with walls, the way with the more room) (doc/design.md sections 4 and 17).
    """
    r, d = obstacles.shape
    frames = [Frame(_origin(obstacles, bounds, e1), e1, e2)
              for e1, e2 in _frame_directions(d, oblique=oblique and r > 0)]
    # Distinct projections, taken as the workspace takes them (Frame.project): exact in an
    # axis frame, and in an oblique one farther apart than their rounding (an e1 across the
    # line of two pillars once told them apart by 4e-16).
    resolution = RELATIVE_RESOLUTION * float(np.abs(obstacles).max(initial=0.0))
    frames = [frame for frame in frames
              if r < 2 or np.all(np.diff(np.sort(frame.project(obstacles)))
                                 > (0.0 if _is_axis(frame) else resolution))]
    if frames and r > 0 and bounds is not None:
        return frames[_most_room(obstacles, bounds, [frame.e2 for frame in frames],
                                 clearance, robot_radius)]
    if frames and r > 0 and oblique:
        # The axis frames keep the request's own coordinates (lanes along the building's
        # walls, exact projections): an oblique one must pay for itself (design section 4).
        return frames[int(np.argmin([_reach(obstacles, frame.e2)
                                     - (robot_radius if _is_axis(frame) else 0.0)
                                     for frame in frames]))]
    if frames:
        return frames[0]
    count = max(16, (r * (r - 1) // 2) * (d - 1) + 1)
    directions = _moment_curve_directions(d, count)
    gaps = np.diff(np.sort(obstacles @ directions.T, axis=0), axis=0).min(axis=0)
    e1 = directions[int(np.argmax(gaps))]
    e2 = _complement_direction(e1)
    if bounds is not None:  # towards the more room, as every other frame with walls
        e2 = (e2, -e2)[_most_room(obstacles, bounds, (e2, -e2), clearance, robot_radius)]
    return Frame(_origin(obstacles, bounds, e1), e1, e2)


def checked_frame(frame: Frame | tuple, dimension: int) -> Frame:
    """Return a Frame or (origin, e1, e2) as a Frame, dimension and orthonormality checked."""
    if isinstance(frame, Frame):
        frame = (frame.origin, frame.e1, frame.e2)
    try:
        origin, e1, e2 = (np.asarray(v, dtype=float).reshape(-1) for v in frame)
    except (TypeError, ValueError):
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            f'frame must be a Frame or (origin, e1, e2), three '
                            f'{dimension}-vectors of real numbers; got {literal(repr(frame))}',
                            option='frame') from None
    if not (origin.size == e1.size == e2.size == dimension):
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            f'frame vectors must have dimension {dimension}', option='frame')
    # an origin beyond the coordinates' range (1e308) made every projection inf and the
    # motion NaN, which the certificate took for an infinite gap
    if not np.all(np.abs(origin) <= MAX_COORDINATE):
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            f'frame origin {origin.tolist()} must be finite and within the '
                            f'supported range +-{MAX_COORDINATE:.0e}', option='frame')
    gram = np.array([[e1 @ e1, e1 @ e2], [e2 @ e1, e2 @ e2]])
    if not (np.all(np.isfinite(gram))
            and np.allclose(gram, np.eye(2), atol=_ORTHONORMAL_TOLERANCE)):
        raise PlanningError(ErrorCode.INVALID_REQUEST, 'frame e1, e2 must be orthonormal',
                            option='frame')
    return Frame(origin, e1, e2)
