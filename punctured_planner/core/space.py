"""
The punctured space R^d - Q_r and the frame (o, e1, e2) the algorithm works in.

The paper normalises the obstacles onto the e1 axis and writes p(x) for the
first coordinate (Section 3). For arbitrary obstacles we pick a frame in which
the obstacles' e1 projections are pairwise distinct; robots project onto the
line o + R e1 and the lanes lie beyond every obstacle's e2 offset
(doc/design.md section 4). The frame is fixed per workspace, never per query, so
the domains of continuity are well defined.
"""

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import numpy.typing as npt

from .discs import DiscLayout
from .errors import ErrorCode, literal, PlanningError
from .sections import VARIANTS
from .validation import first_out_of_range, MAX_COORDINATE

_ORTHONORMAL_TOLERANCE = 1e-9


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


def _coincident_pair(values):
    """Return indices (a, b), a < b, of two equal entries of a 1-D array, or None."""
    order = np.argsort(values, kind='stable')
    equal = np.flatnonzero(np.diff(values[order]) == 0)
    if equal.size == 0:
        return None
    a, b = sorted((int(order[equal[0]]), int(order[equal[0] + 1])))
    return a, b


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


def choose_frame(obstacles: np.ndarray) -> Frame:
    """
    Return the default frame for obstacles (r, d): deterministic, fixed per obstacle set.

    The coordinate axes (o = 0, e1 = x, e2 = y) whenever the obstacles' x
    coordinates are distinct; otherwise the next coordinate axis that works;
    otherwise the moment-curve direction that maximises the smallest gap between
    obstacle projections.
    """
    r, d = obstacles.shape
    origin = np.zeros(d)
    for a in range(d):
        if r < 2 or np.all(np.diff(np.sort(obstacles[:, a])) > 0):
            e1 = np.zeros(d)
            e1[a] = 1.0
            e2 = np.zeros(d)
            e2[(a + 1) % d] = 1.0
            return Frame(origin, e1, e2)
    count = max(16, (r * (r - 1) // 2) * (d - 1) + 1)
    directions = _moment_curve_directions(d, count)
    gaps = np.diff(np.sort(obstacles @ directions.T, axis=0), axis=0).min(axis=0)
    e1 = directions[int(np.argmax(gaps))]
    return Frame(origin, e1, _complement_direction(e1))


def _checked_frame(frame, dimension):
    """Return a Frame or (origin, e1, e2) as a Frame, dimension and orthonormality checked."""
    if isinstance(frame, Frame):
        frame = (frame.origin, frame.e1, frame.e2)
    origin, e1, e2 = (np.asarray(v, dtype=float).reshape(-1) for v in frame)
    if not (origin.size == e1.size == e2.size == dimension):
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            f'frame vectors must have dimension {dimension}')
    gram = np.array([[e1 @ e1, e1 @ e2], [e2 @ e1, e2 @ e2]])
    if not (np.all(np.isfinite(gram)) and np.all(np.isfinite(origin))
            and np.allclose(gram, np.eye(2), atol=_ORTHONORMAL_TOLERANCE)):
        raise PlanningError(ErrorCode.INVALID_REQUEST, 'frame e1, e2 must be orthonormal')
    return Frame(origin, e1, e2)


class Workspace:
    """
    The obstacles Q_r in R^d, the frame, and the planner's options.

    ``variant`` is 'paper' (the paper's construction, exact), 'spread' (adds
    the spreading leg S and lanes `lane_spacing` apart beyond the obstacles) or
    'discs' (robots and obstacles with radii; doc/design.md section 6).
    ``robot_radius`` R and ``obstacle_radius`` rho (a scalar, or one per
    obstacle) make robots and obstacles discs (balls for d >= 3); then a
    configuration whose bodies overlap is refused.
    ``required_clearance`` refuses plans whose certified clearance is below it:
    the centre distance for point robots and obstacles, the surface gap
    (Plan.min_gap) as soon as a radius is set.
    ``frame`` is the core's own Frame or (origin, e1, e2); by default the
    frame is chosen from the obstacles (choose_frame).
    """

    def __init__(self, obstacles: npt.ArrayLike, dimension: int | None = None,
                 frame: Frame | tuple | None = None, lane_spacing: float = 1.0,
                 variant: str = 'paper', min_spacing: float = 0.5,
                 required_clearance: float = 0.0, robot_radius: float = 0.0,
                 obstacle_radius: npt.ArrayLike = 0.0) -> None:
        """Validate the obstacles and options and fix the frame."""
        obstacles = np.asarray(obstacles, dtype=float)
        if obstacles.size == 0:
            if obstacles.ndim == 2 and obstacles.shape[1] > 0:
                dimension = obstacles.shape[1] if dimension is None else dimension
            elif dimension is None:
                raise PlanningError(ErrorCode.INVALID_REQUEST,
                                    f'obstacles of shape {obstacles.shape} do not give the '
                                    f'dimension d: pass dimension=d or a (0, d) array')
            obstacles = obstacles.reshape(0, dimension)
        if obstacles.ndim != 2 or (dimension is not None and obstacles.shape[1] != dimension):
            raise PlanningError(ErrorCode.INVALID_REQUEST,
                                f'obstacles must have shape (r, d), got {obstacles.shape}')
        self.dimension = int(obstacles.shape[1])
        if self.dimension < 2:
            raise PlanningError(ErrorCode.INVALID_REQUEST, 'the dimension d must be at least 2')
        bad = np.argwhere(~np.isfinite(obstacles))
        if bad.size:
            raise PlanningError(ErrorCode.NON_FINITE_VALUE,
                                '{obstacle} has a non-finite coordinate',
                                obstacle=int(bad[0][0]), coordinate=int(bad[0][1]))
        far = first_out_of_range(obstacles)
        if far is not None:
            raise PlanningError(ErrorCode.INVALID_REQUEST,
                                f'{{obstacle}} is beyond the supported range '
                                f'+-{MAX_COORDINATE:.0e}', obstacle=far[0], coordinate=far[1])
        self._check_options(variant, lane_spacing, min_spacing, required_clearance)
        self.obstacles = obstacles
        self.variant = variant
        self.lane_spacing = float(lane_spacing)
        self.min_spacing = float(min_spacing)
        self.required_clearance = float(required_clearance)
        self.robot_radius, self.obstacle_radii = _checked_radii(robot_radius, obstacle_radius,
                                                                len(obstacles))
        self._reject_coincident_obstacles()
        self.frame = (choose_frame(obstacles) if frame is None
                      else _checked_frame(frame, self.dimension))
        self.obstacle_projections = self.frame.project(obstacles)
        same = _coincident_pair(self.obstacle_projections)
        if same is not None:
            raise PlanningError(ErrorCode.OBSTACLES_DEGENERATE,
                                '{obstacles} share one projection on '
                                'the frame axis e1; choose a frame that separates them',
                                obstacle=same[0], obstacles=same)
        self.sorted_obstacle_projections = np.sort(self.obstacle_projections)
        # Lanes must clear every obstacle: start above the highest e2 offset.
        self.lane_base = max(0.0, float(self.frame.offset(obstacles).max(initial=0.0)))

    def _reject_coincident_obstacles(self):
        """Raise OBSTACLES_DEGENERATE if two obstacles are the same point."""
        obstacles = self.obstacles
        if len(obstacles) < 2:
            return
        order = np.lexsort(obstacles.T[::-1])
        same = np.flatnonzero(np.all(np.diff(obstacles[order], axis=0) == 0, axis=1))
        if same.size:
            a, b = sorted((int(order[same[0]]), int(order[same[0] + 1])))
            raise PlanningError(ErrorCode.OBSTACLES_DEGENERATE,
                                '{obstacles} are at the same point', obstacle=a,
                                obstacles=(a, b))

    @staticmethod
    def _check_options(variant, lane_spacing, min_spacing, required_clearance):
        """Raise INVALID_REQUEST for an unknown variant or a non-positive spacing."""
        if variant not in VARIANTS:
            raise PlanningError(ErrorCode.INVALID_REQUEST,
                                f'variant must be one of {VARIANTS}, got {literal(repr(variant))}')
        if not (np.isfinite(lane_spacing) and lane_spacing > 0):
            raise PlanningError(ErrorCode.INVALID_REQUEST, 'lane_spacing must be positive')
        if not (np.isfinite(min_spacing) and min_spacing > 0):
            raise PlanningError(ErrorCode.INVALID_REQUEST, 'min_spacing must be positive')
        if not (np.isfinite(required_clearance) and required_clearance >= 0):
            raise PlanningError(ErrorCode.INVALID_REQUEST,
                                'required_clearance must be non-negative')

    @property
    def obstacle_count(self) -> int:
        """Return r, the number of obstacles."""
        return len(self.obstacles)

    @property
    def has_bodies(self) -> bool:
        """Return whether robots or obstacles have a radius (then gaps, not distances, count)."""
        return self.robot_radius > 0 or bool(np.any(self.obstacle_radii > 0))

    @cached_property
    def disc_layout(self) -> DiscLayout:
        """
        Return the pillars, reaches and pitches of the 'discs' construction.

        With bodies, a required gap c is planned for by inflating every body by
        c / 2: a gap >= 0 between the inflated bodies is a gap >= c between the real ones.
        """
        inflation = 0.5 * self.required_clearance if self.has_bodies else 0.0
        return DiscLayout.from_radii(self.frame, self.obstacles,
                                     self.robot_radius + inflation,
                                     self.obstacle_radii + inflation, self.lane_spacing,
                                     self.min_spacing)


def _checked_radii(robot_radius, obstacle_radius, obstacle_count):
    """Return (R, rho (r,)) after checking they are finite, non-negative and rho has r values."""
    try:
        radius = float(robot_radius)
        radii = np.asarray(obstacle_radius, dtype=float)
    except (TypeError, ValueError):
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            'robot_radius and obstacle_radius must be real numbers') from None
    if not (np.isfinite(radius) and radius >= 0):
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            f'robot_radius must be finite and non-negative, got {radius}')
    if radii.ndim == 0:
        radii = np.full(obstacle_count, float(radii))
    if radii.shape != (obstacle_count,):
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            f'obstacle_radius must be a scalar or one value per obstacle '
                            f'(shape ({obstacle_count},)), got shape {radii.shape}')
    bad = np.flatnonzero(~(np.isfinite(radii) & (radii >= 0)))
    if bad.size:
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            '{obstacle}: obstacle_radius must be finite and '
                            f'non-negative, got {radii[bad[0]]}', obstacle=int(bad[0]))
    return radius, radii
