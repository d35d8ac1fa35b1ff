"""Draw a plan in a 3-D view (d = 3): the same layers as in the plane, on Axes3D."""

from collections.abc import Sequence

from matplotlib.typing import ColorType
from mpl_toolkits.mplot3d import Axes3D
import numpy as np

from .draw2d import AXIS_COLOUR, CLEARANCE_COLOUR
from .geometry import closest_approach, extent, moving_legs, waypoints
from ..core import Plan

ARROW_MIN_FRACTION = 0.04


def draw_paths_3d(ax: Axes3D, plan: Plan, colours: Sequence[ColorType], alpha: float = 1.0,
                  arrows: bool = True) -> None:
    """Draw each robot's polyline and, on every long leg, a direction arrow (quiver)."""
    minimum = ARROW_MIN_FRACTION * extent(plan.positions)
    for robot, colour in enumerate(colours):
        path = plan.positions[:, robot]
        ax.plot(path[:, 0], path[:, 1], path[:, 2], color=colour, lw=1.6, alpha=alpha)
        if not arrows:
            continue
        starts, ends = moving_legs(path, minimum)
        if len(starts):
            tails = starts + 0.4 * (ends - starts)
            vectors = 0.2 * (ends - starts)
            ax.quiver(*tails.T, *vectors.T, color=colour, arrow_length_ratio=0.9, lw=1.4)


def draw_plan_3d(ax: Axes3D, plan: Plan, colours: Sequence[ColorType], path_alpha: float = 1.0,
                 arrows: bool = True) -> None:
    """Draw axis, lanes, paths, obstacles, numbered waypoints and the closest approach."""
    axis = plan.axis_segment()
    ax.plot(*axis.T, color=AXIS_COLOUR, lw=1.2)
    for lane, colour in zip(plan.lane_segments(), colours):
        ax.plot(*lane.T, ls='--', lw=0.8, color=colour, alpha=0.55)
    draw_paths_3d(ax, plan, colours, alpha=path_alpha, arrows=arrows)
    obstacles = plan.workspace.obstacles
    ax.scatter(*obstacles.T, marker='X', s=60, color='black', depthshade=False)
    for m, configuration in enumerate(waypoints(plan)):
        for point, colour in zip(configuration, colours):
            ax.scatter(*point, s=110, facecolor='white', edgecolor=colour, lw=1.4,
                       depthshade=False)
            ax.text(*point, str(m + 1), ha='center', va='center', fontsize=7, color=colour,
                    fontweight='bold')
    points = closest_approach(plan)
    if points is not None:
        ax.plot(*points.T, ':', color=CLEARANCE_COLOUR, lw=1.6)
    ax.set_xlabel('x')
    ax.set_ylabel('y')
    ax.set_zlabel('z')
    everything = np.concatenate([plan.positions.reshape(-1, 3), obstacles])
    ax.set_box_aspect(np.maximum(np.ptp(everything, axis=0), 0.2 * extent(everything)))
