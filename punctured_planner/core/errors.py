"""
Planning errors: a machine-readable code plus the culprits as data, Nav2 style.

A :class:`PlanningError` carries its culprits (configuration, robots,
obstacle, coordinate, and for OUTSIDE_WORKSPACE the wall, the distance and the
leg) as numbers and its message as a template in which the
configuration, obstacles and wall are slots: ``{configuration}``,
``{obstacle}``, ``{obstacles}``, ``{waypoint}`` and ``{next_waypoint}``
(C_{m+1} and C_{m+2} of ``configuration`` m), ``{wall}``.
:meth:`PlanningError.describe` fills the slots with a :class:`Names`: the
core's own (``configuration 2``, ``obstacle 1 at [0.0, 1.0]``, ``the wall
x_max``) for ``str()``, the ROS layer's (the request's configuration labels,
the obstacles' positions and source, the wall's parameter entry) for a
service response. Free text put into a template goes through :func:`literal`.
"""

from collections.abc import Iterable
from dataclasses import dataclass
import enum
from typing import Any

import numpy as np


class ErrorCode(enum.IntEnum):
    """
    Why a request cannot be planned; names and values match PlanSequence.srv.

    The order of the values is the priority order of the checks: a request with
    several faults reports the one with the smallest value. OUTSIDE_WORKSPACE
    came last and is the one exception: it ranks with the input checks beside
    ROBOT_ON_OBSTACLE (a pillar outside the bounds with the obstacles' own
    check, right after OBSTACLES_DEGENERATE; a robot outside right after
    ROBOT_ON_OBSTACLE), before any plan exists to fall below the required
    clearance; a plan that leaves the bounds right after CLEARANCE_BELOW_REQUIRED.
    NODE_STOPPING is the node's, about no request's content: a request that
    waited past the stop's planning budget (doc/design.md section 16).
    """

    NONE = 0
    NO_CONFIGURATIONS = 1
    NO_ROBOT_STATE = 2
    REQUEST_OVER_LIMITS = 3
    INVALID_REQUEST = 4
    ROBOT_COUNT_MISMATCH = 5
    NON_FINITE_VALUE = 6
    FRAME_MISMATCH = 7
    OFF_PLANE = 8
    OBSTACLES_DEGENERATE = 9
    ROBOTS_COINCIDE = 10
    ROBOT_ON_OBSTACLE = 11
    CLEARANCE_BELOW_REQUIRED = 12
    OUTSIDE_WORKSPACE = 13
    NODE_STOPPING = 14
    UNKNOWN = 99


# The names of the first coordinate axes (a wall's culprit words).
_AXES = 'xyz'


def counted(count: int, noun: str) -> str:
    """Return '1 configuration', '3 configurations': count and noun, plural where it is."""
    return '%d %s%s' % (count, noun, '' if count == 1 else 's')


def axis_name(axis: int) -> str:
    """Return the name of coordinate axis: x, y, z, then x3, x4, ..."""
    return _AXES[axis] if axis < len(_AXES) else f'x{axis}'


@dataclass(frozen=True)
class Wall:
    """One wall of the box: the side min (high False) or max (high True) of an axis."""

    axis: int
    high: bool

    @property
    def name(self) -> str:
        """Return the wall's name: 'x_min', 'y_max', ... ('x3_min' beyond z)."""
        return f'{axis_name(self.axis)}_{"max" if self.high else "min"}'

    @property
    def index(self) -> int:
        """Return the wall's index in bounds.ravel(): x_min, x_max, y_min, ..."""
        return 2 * self.axis + int(self.high)

    def position(self, bounds: np.ndarray) -> float:
        """Return the wall's coordinate in bounds (d, 2)."""
        return float(bounds[self.axis, int(self.high)])


def compared(value: float, bound: float) -> tuple[str, str]:
    """
    Return value and bound as a message writes them: 6 digits, or all where those agree.

    A value refused against a bound it misses by an ulp must not read as equal to it:
    'centres 3.7 apart, less than 2 robot_radius = 3.7' was 3.6999999999999997.
    """
    value, bound = float(value), float(bound)  # repr of a numpy float names its type
    short = f'{value:.6g}', f'{bound:.6g}'
    return short if short[0] != short[1] or value == bound else (repr(value), repr(bound))


def literal(text: object) -> str:
    """Return text with its braces doubled: free text inside a message template."""
    return str(text).replace('{', '{{').replace('}', '}}')


class Names:
    """How a message names configurations and obstacles: the core's words, 0-based."""

    def configuration(self, m: int) -> str:
        """Return the name of configuration m (C_{m+1})."""
        return f'configuration {m}'

    def waypoint(self, m: int) -> str:
        """Return the name of configuration m as a waypoint of the plan: C_{m+1}."""
        return f'C_{m + 1}'

    def robot_label(self, i: int) -> str:
        """Return what follows 'robot' in robot i's name: its index."""
        return str(i)

    def robot(self, i: int) -> str:
        """Return the name of robot i: 'robot 3'."""
        return 'robot ' + self.robot_label(i)

    def robots(self, indices: tuple[int, ...]) -> str:
        """Return the name of several robots: 'robots 0 and 3'."""
        return 'robots ' + ' and '.join(self.robot_label(i) for i in indices)

    def obstacle(self, j: int, point: Any = None) -> str:
        """Return the name of obstacle j, with its position when the error carries it."""
        return f'obstacle {j}' + ('' if point is None else f' at {point}')

    def obstacles(self, indices: tuple[int, ...]) -> str:
        """Return the name of several obstacles: 'obstacles 0 and 3'."""
        return 'obstacles ' + ' and '.join(str(j) for j in indices)

    def wall(self, wall: Wall) -> str:
        """Return the name of a wall of the workspace bounds: 'the wall x_max'."""
        return f'the wall {wall.name}'


class _Slots(dict):
    """The slot values of one error's template, each computed when the template asks."""

    def __init__(self, error: 'PlanningError', names: Names) -> None:
        super().__init__()
        self._error = error
        self._names = names

    def __missing__(self, slot: str) -> str:
        error, names = self._error, self._names
        if slot == 'configuration':
            return names.configuration(int(error.configuration))  # type: ignore[arg-type]
        if slot in ('waypoint', 'next_waypoint'):
            m = int(error.configuration)  # type: ignore[arg-type]
            return names.waypoint(m if slot == 'waypoint' else m + 1)
        if slot == 'robot':
            return names.robot(int(error.robots[0]))
        if slot == 'robots':
            return names.robots(tuple(int(i) for i in error.robots))
        if slot == 'obstacle':
            return names.obstacle(int(error.obstacle), error.point)  # type: ignore[arg-type]
        if slot == 'obstacles':
            return names.obstacles(error.obstacles)
        if slot == 'wall':
            return names.wall(error.wall)  # type: ignore[arg-type]
        raise KeyError(slot)


class PlanningError(ValueError):
    """
    A request the planner refuses, with the configuration, robots and obstacle at fault.

    Indices are 0-based: ``configuration`` is m for C_{m+1} (for
    CLEARANCE_BELOW_REQUIRED the segment C_{m+1} -> C_{m+2}), ``robots`` the
    robot indices involved, ``obstacle`` the obstacle index (or None) and
    ``obstacles`` every obstacle involved, ``coordinate`` the axis (0 for x) of
    a faulty coordinate; ``point`` is the obstacle's position as the core
    words it. For OUTSIDE_WORKSPACE ``wall`` is the wall crossed (axis and
    side), ``distance`` how far the body reaches beyond it (> 0) and ``leg``
    the plan's leg (None for an input outside the bounds); for a plan that
    leaves the bounds ``configuration`` is that leg's segment. ``option`` is the
    Workspace option at fault, where one is: a value refused (a length, the
    dimension, the variant) or one that does not fit the others (obstacle_radius
    whose count is not the obstacles'). ``message`` is
    the template (module docstring); ``args[0]`` and ``str()`` are worded with
    the core's :class:`Names`.
    """

    def __init__(self, code: int, message: str, configuration: int | None = None,
                 robots: Iterable[int] = (), obstacle: int | None = None,
                 obstacles: Iterable[int] = (), coordinate: int | None = None,
                 point: Any = None, clearance: Any = None, gap: Any = None,
                 wall: Wall | None = None, distance: float | None = None,
                 leg: int | None = None, option: str | None = None) -> None:
        """Store the code and the culprits; message is the reason's template."""
        self.code = ErrorCode(code)
        self.template = message
        self.configuration = configuration
        self.robots = tuple(int(i) for i in robots)
        self.obstacle = obstacle
        self.obstacles = tuple(int(j) for j in obstacles) or (
            (int(obstacle),) if obstacle is not None else ())
        self.coordinate = coordinate
        self.point = point
        # The refused plan's Clearance certificates, centre distance and surface gap
        # (CLEARANCE_BELOW_REQUIRED only; as found, also where the clearance is below the
        # coordinates' resolution).
        self.clearance = clearance
        self.gap = gap
        self.wall = wall
        self.distance = distance
        self.leg = leg
        self.option = option
        super().__init__(self.describe(Names()))

    def describe(self, names: Names) -> str:
        """Return the reason with the configuration and obstacles named by names."""
        return self.template.format_map(_Slots(self, names))

    def __str__(self) -> str:
        """Return the message prefixed by the code name."""
        return f'{self.code.name}: {self.args[0]}'
