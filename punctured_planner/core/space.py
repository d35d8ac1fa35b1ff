"""
The punctured space R^d - Q_r: the obstacles, their frame (core.frame) and the options.

The lanes lie beyond every obstacle's e2 offset (doc/design.md section 4).
"""

from functools import cached_property
import numbers

import numpy as np
import numpy.typing as npt

from .discs import DiscLayout, PillarClearance
from .errors import ErrorCode, literal, PlanningError
from .frame import checked_frame, choose_frame, Frame
from .limits import checked_length, first_non_finite, first_out_of_range, length_range
from .limits import lengths_in_range
from .limits import MAX_COORDINATE
from .pairs import first_equal_pair
from .sections import VARIANTS
from .validation import real_array
from .walls import checked_bounds, first_outside


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
    frame is chosen from the obstacles and the walls (choose_frame).
    ``bounds`` (d, 2), [low, high] per axis in the configurations' own
    coordinates (core.walls), are the walls of the room: every robot and
    pillar must stay inside, a disc keeping its radius from every wall
    (OUTSIDE_WORKSPACE); None for no walls.
    """

    def __init__(self, obstacles: npt.ArrayLike, dimension: int | None = None,
                 frame: Frame | tuple | None = None, lane_spacing: float = 1.0,
                 variant: str = 'paper', min_spacing: float = 0.5,
                 required_clearance: float = 0.0, robot_radius: float = 0.0,
                 obstacle_radius: npt.ArrayLike = 0.0,
                 bounds: npt.ArrayLike | None = None) -> None:
        """Validate the obstacles and options and fix the frame."""
        if dimension is not None and (isinstance(dimension, bool)
                                      or not isinstance(dimension, numbers.Integral)
                                      or dimension < 2):
            raise PlanningError(ErrorCode.INVALID_REQUEST,
                                f'dimension must be an integer >= 2 or None, got '
                                f'{literal(repr(dimension))}', option='dimension')
        obstacles = real_array(obstacles, 'the obstacle array')
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
            raise PlanningError(ErrorCode.INVALID_REQUEST,
                                f'obstacles of shape {obstacles.shape}: the dimension d must '
                                f'be at least 2')
        bad = first_non_finite(obstacles)
        if bad is not None:
            raise PlanningError(ErrorCode.NON_FINITE_VALUE,
                                '{obstacle} has a non-finite coordinate',
                                obstacle=bad[0], coordinate=bad[1])
        far = first_out_of_range(obstacles)
        if far is not None:
            raise PlanningError(ErrorCode.INVALID_REQUEST,
                                f'{{obstacle}} is beyond the supported range '
                                f'+-{MAX_COORDINATE:.0e}', obstacle=far[0], coordinate=far[1])
        self._check_variant(variant)
        self.lane_spacing = checked_length(lane_spacing, 'lane_spacing', zero=False)
        self.min_spacing = checked_length(min_spacing, 'min_spacing', zero=False)
        self.required_clearance = checked_length(required_clearance, 'required_clearance',
                                                 zero=True)
        self.bounds = checked_bounds(bounds, self.dimension)
        self.obstacles = obstacles
        self.variant = variant
        self.robot_radius, self.obstacle_radii = _checked_radii(robot_radius, obstacle_radius,
                                                                len(obstacles))
        self._reject_coincident_obstacles()
        self.frame = self._default_frame() if frame is None else checked_frame(frame,
                                                                               self.dimension)
        self.obstacle_projections = self.frame.project(obstacles)
        same = first_equal_pair(self.obstacle_projections)
        if same is not None:
            raise PlanningError(ErrorCode.OBSTACLES_DEGENERATE,
                                '{obstacles} share one projection on '
                                'the frame axis e1; choose a frame that separates them',
                                obstacle=same[0], obstacles=same)
        self._reject_obstacles_outside()
        self.sorted_obstacle_projections = np.sort(self.obstacle_projections)
        # Lanes must clear every obstacle: start above the highest e2 offset.
        self.lane_base = max(0.0, float(self.frame.offset(obstacles).max(initial=0.0)))

    def _reject_coincident_obstacles(self):
        """Raise OBSTACLES_DEGENERATE if two obstacles are the same point."""
        same = first_equal_pair(self.obstacles)
        if same is not None:
            raise PlanningError(ErrorCode.OBSTACLES_DEGENERATE,
                                '{obstacles} are at the same point', obstacle=same[0],
                                obstacles=same)

    def _reject_obstacles_outside(self):
        """Raise OUTSIDE_WORKSPACE for a pillar whose centre is closer than rho to a wall."""
        if self.bounds is None:
            return
        outside = first_outside(self.obstacles[None], self.bounds, self.obstacle_radii)
        if outside is not None:
            j = outside.body
            raise PlanningError(ErrorCode.OUTSIDE_WORKSPACE,
                                '{obstacle} is ' + outside.words(
                                    self.bounds, self.obstacles[j, outside.wall.axis],
                                    self.obstacle_radii[j], 'its obstacle_radius'),
                                obstacle=j, point=self.obstacles[j].tolist(),
                                wall=outside.wall, distance=outside.beyond)

    @staticmethod
    def _check_variant(variant):
        """Raise INVALID_REQUEST for an unknown variant."""
        if variant not in VARIANTS:
            raise PlanningError(ErrorCode.INVALID_REQUEST,
                                f'variant must be one of {VARIANTS}, got {literal(repr(variant))}',
                                option='variant')

    @property
    def obstacle_count(self) -> int:
        """Return r, the number of obstacles."""
        return len(self.obstacles)

    @cached_property
    def has_bodies(self) -> bool:
        """Return whether robots or obstacles have a radius (then gaps, not distances, count)."""
        # Cached: read several times by every plan, and the radii are fixed per workspace.
        return self.robot_radius > 0 or bool(np.any(self.obstacle_radii > 0))

    @cached_property
    def disc_layout(self) -> DiscLayout:
        """
        Return the pillars, reaches and pitches of the 'discs' construction.

        With bodies, a required gap c is planned for by inflating every body by
        c / 2: a gap >= 0 between the inflated bodies is a gap >= c between the real ones.
        """
        return DiscLayout.from_sizes(self.frame, self.obstacles, self._pillar_clearance,
                                     self.bounds)

    @cached_property
    def _pillar_clearance(self) -> PillarClearance:
        """Return the pillars' reaches, pitches and clearances for the bodies as planned."""
        inflation = self._inflation()
        return PillarClearance.from_radii(self.robot_radius + inflation,
                                          self.obstacle_radii + inflation, self.min_spacing)

    def _inflation(self) -> float:
        """Return what every body's radius is planned with more: half the required gap c."""
        return 0.5 * self.required_clearance if self.has_bodies else 0.0

    def _default_frame(self):
        """
        Return choose_frame's frame for the obstacles and walls.

        Oblique frames round every projection: only the discs' margins are far above
        that. With walls the discs stage beyond each pillar's clearance
        (PillarClearance), their centres R inside the walls (R as planned, inflated by
        required_clearance), which is the room the frame is chosen by; without walls
        an oblique frame must save R of the climb.
        """
        if self.variant != 'discs':
            return choose_frame(self.obstacles, self.bounds)
        if self.bounds is None:
            return choose_frame(self.obstacles, oblique=True, robot_radius=self.robot_radius)
        return choose_frame(self.obstacles, self.bounds, oblique=True,
                            robot_radius=self._pillar_clearance.robot_radius,
                            clearance=self._pillar_clearance.clear)


def _checked_radii(robot_radius, obstacle_radius, obstacle_count):
    """Return (R, rho (r,)) after checking they are lengths (limits) and rho has r values."""
    radius = checked_length(robot_radius, 'robot_radius', zero=True)
    radii = real_array(obstacle_radius, 'obstacle_radius')
    if radii.ndim == 0:
        radii = np.full(obstacle_count, float(radii))
    if radii.shape != (obstacle_count,):
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            f'obstacle_radius must be a scalar or one value per obstacle '
                            f'(shape ({obstacle_count},)), got shape {radii.shape}',
                            option='obstacle_radius')
    bad = np.flatnonzero(~lengths_in_range(radii, zero=True))
    if bad.size:
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            '{obstacle}: obstacle_radius must be '
                            f'{length_range(zero=True)}, got {radii[bad[0]]}',
                            obstacle=int(bad[0]))
    return radius, radii
