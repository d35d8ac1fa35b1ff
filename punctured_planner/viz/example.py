"""
The example scenario of the pictures: 5 robots, 3 obstacles off one line, n = 3, spread.

The robots start in a row below the obstacles, meet in a ring around them
(one robot right above an obstacle, so C_2 lies in a lower stratum and D
moves) and end in a row above, in reverse order. For the 'discs' variant the
robots are discs of radius 0.3 and the pillars of radius 0.2.
"""

from typing import TypedDict

import numpy as np

from ..core import Plan, plan, Workspace

EXAMPLE_OBSTACLES = [[-3.0, 0.5], [0.0, -0.5], [2.5, 0.0]]
EXAMPLE_CONFIGURATIONS = [
    [[-4.0, -2.0], [-2.0, -2.5], [0.0, -2.0], [2.0, -2.5], [4.0, -2.0]],
    [[0.0, 2.5], [-2.4, 0.8], [-1.5, -2.0], [1.5, -2.0], [2.4, 0.8]],
    [[4.0, 3.0], [2.0, 3.5], [0.0, 3.0], [-2.0, 3.5], [-4.0, 3.0]],
]


EXAMPLE_ROBOT_RADIUS, EXAMPLE_OBSTACLE_RADIUS = 0.3, 0.2


class _Radii(TypedDict, total=False):
    """The radius keywords of Workspace that example_plan passes (both, or none)."""

    robot_radius: float
    obstacle_radius: float


def example_plan(variant: str = 'spread') -> Plan:
    """Return the plan of the example scenario (variant 'spread' unless told otherwise)."""
    radii: _Radii = (
        {'robot_radius': EXAMPLE_ROBOT_RADIUS, 'obstacle_radius': EXAMPLE_OBSTACLE_RADIUS}
        if variant == 'discs' else {})
    workspace = Workspace(EXAMPLE_OBSTACLES, variant=variant, **radii)
    return plan(workspace, np.array(EXAMPLE_CONFIGURATIONS))
