"""Planning errors: a machine-readable code plus the culprit, Nav2 style."""

from collections.abc import Iterable
import enum
from typing import Any


class ErrorCode(enum.IntEnum):
    """
    Why a request cannot be planned; names and values match PlanSequence.srv.

    The order of the values is the priority order of the checks: a request with
    several faults reports the one with the smallest value.
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
    UNKNOWN = 99


class PlanningError(ValueError):
    """
    A request the planner refuses, with the configuration, robots and obstacle at fault.

    Indices are 0-based: ``configuration`` is m for C_{m+1}, ``robots`` the robot
    indices involved, ``obstacle`` the obstacle index (or None).
    """

    def __init__(self, code: int, message: str, configuration: int | None = None,
                 robots: Iterable[int] = (), obstacle: int | None = None,
                 clearance: Any = None, gap: Any = None) -> None:
        """Store the code and the culprit; the message is the human-readable reason."""
        super().__init__(message)
        self.code = ErrorCode(code)
        self.configuration = configuration
        self.robots = tuple(int(i) for i in robots)
        self.obstacle = obstacle
        # The refused plan's Clearance certificates, centre distance and surface gap
        # (CLEARANCE_BELOW_REQUIRED only; gap None where rounding left it untrusted).
        self.clearance = clearance
        self.gap = gap

    def __str__(self) -> str:
        """Return the message prefixed by the code name."""
        return f'{self.code.name}: {self.args[0]}'
