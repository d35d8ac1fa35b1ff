"""
How the ROS layer names configurations, obstacles and walls in an error message: here.

A :class:`~punctured_planner.core.errors.PlanningError` carries its culprits
as numbers and its message as a template (see core/errors.py); the service
response words it with :class:`RequestNames`: a configuration by its label in
the request (the current state first, with use_current_state), an obstacle by
its index, position and source, and a wall of the workspace bounds by its
entry in the workspace_bounds parameter. The core numbers only the
configurations it plans; ``planned`` maps them back to the request's.
"""

from typing import Callable
from typing import Sequence

from ..core.errors import Names
from ..core.errors import Wall


class WallNames(Names):
    """Walls by the entry of the workspace_bounds parameter that sets them."""

    def wall(self, wall: Wall) -> str:
        """Return 'the wall x_max (workspace_bounds[1])': the parameter entry that sets it."""
        return 'the wall %s (workspace_bounds[%d])' % (wall.name, wall.index)


class ObstacleNames(WallNames):
    """
    Obstacles by index, position and source (the node's obstacle set); walls by entry.

    name(j) words obstacle j: the node's :meth:`ObstacleSet.name
    <punctured_planner.ros.snapshot.ObstacleSet.name>`.
    """

    def __init__(self, name: Callable[[int], str]) -> None:
        """Name each obstacle j as name(j)."""
        self._name = name

    def obstacle(self, j: int, point: object = None) -> str:
        """Return 'obstacle j at (x, y, z) (from <source>)'."""
        return self._name(j)

    def obstacles(self, indices: tuple[int, ...]) -> str:
        """Return the names of several obstacles, joined by 'and'."""
        return ' and '.join(self._name(j) for j in indices)


class RequestNames(ObstacleNames):
    """
    Configurations by their label in the request, obstacles as :class:`ObstacleNames`.

    Robots by their index and, with robot_names, their name: 'robot 3 (ghost)'.
    """

    def __init__(self, name: Callable[[int], str], label: Callable[[int], str],
                 planned: Sequence[int] | None = None, robots: Sequence[str] = ()) -> None:
        """
        Name configurations, obstacles and robots.

        label(m) names request configuration m; planned[i] is the i-th planned one's m;
        robots[i] is robot i's name (robot_names; empty: none).
        """
        super().__init__(name)
        self._label = label
        self._planned = planned
        self._robot_names = tuple(robots)

    def robot_label(self, i: int) -> str:
        """Return '3 (ghost)' for robot 3 named ghost, or '3' without robot_names."""
        return '%d (%s)' % (i, self._robot_names[i]) if i < len(self._robot_names) else str(i)

    def _request_index(self, m: int) -> int:
        return m if self._planned is None else self._planned[m]

    def configuration(self, m: int) -> str:
        """Return the label of the request configuration the core's m is."""
        return self._label(self._request_index(m))

    def waypoint(self, m: int) -> str:
        """Return C_{i+1} for the request configuration i the core's m is."""
        return 'C_%d' % (self._request_index(m) + 1)
