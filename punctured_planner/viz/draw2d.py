"""
Draw a plan on 2-D axes through a PlaneView: the static picture and the animation background.

Layers, bottom to top: the walls (workspace bounds, in the plane), e1 axis, dashed
lanes, (optionally) the construction's
unrefined paths dashed, robot paths with direction
arrows, obstacles (and their discs), numbered waypoints C_1..C_n (and the
robots' discs there), the certified closest approach (smallest gap with radii).
"""

from collections.abc import Sequence
from typing import cast

from matplotlib.axes import Axes
from matplotlib.lines import Line2D
from matplotlib.patches import Circle, FancyArrowPatch
from matplotlib.typing import ColorType
import numpy as np

from .geometry import closest_approach, extent, moving_legs, PlaneView, waypoints
from ..core import Plan

AXIS_COLOUR = '0.35'
CLEARANCE_COLOUR = 'crimson'
WALL_COLOUR = 'saddlebrown'
ARROW_MIN_FRACTION = 0.03
# Robots the legend names one by one; a larger fleet's legend ran off the figure (k = 40).
LEGEND_ROBOTS = 12


def wall_outline(plan: Plan) -> np.ndarray | None:
    """Return the (5, 2) closed outline of the walls in the plane (None: none, or d != 2)."""
    bounds = plan.workspace.bounds
    if bounds is None or bounds.shape[0] != 2:
        return None
    (x0, x1), (y0, y1) = bounds
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]])


def draw_walls(ax: Axes, outline: np.ndarray) -> None:
    """Draw the walls' outline (wall_outline) as a thick closed line."""
    ax.plot(outline[:, 0], outline[:, 1], color=WALL_COLOUR, lw=2.4, zorder=1)


def draw_frame_lines(ax: Axes, plan: Plan, view: PlaneView,
                     colours: Sequence[ColorType]) -> None:
    """Draw the e1 axis (solid grey) and each robot's lane (dashed, in the robot's colour)."""
    axis = view(plan.axis_segment())
    ax.plot(axis[:, 0], axis[:, 1], color=AXIS_COLOUR, lw=1.2, zorder=1)
    for lane, colour in zip(view(plan.lane_segments()), colours):
        ax.plot(lane[:, 0], lane[:, 1], ls='--', lw=0.8, color=colour, alpha=0.55, zorder=1)


def draw_paths(ax: Axes, plan: Plan, view: PlaneView, colours: Sequence[ColorType],
               alpha: float = 1.0, arrows: bool = True) -> None:
    """Draw each robot's polyline through the breakpoints, with an arrow on every long leg."""
    paths = view(plan.positions)
    minimum = ARROW_MIN_FRACTION * extent(paths)
    for robot, colour in enumerate(colours):
        path = paths[:, robot]
        ax.plot(path[:, 0], path[:, 1], color=colour, lw=1.8, alpha=alpha, zorder=2,
                solid_capstyle='round')
        if not arrows:
            continue
        for start, end in zip(*moving_legs(path, minimum)):
            step = end - start
            ax.add_patch(FancyArrowPatch(start + 0.42 * step, start + 0.58 * step,
                                         arrowstyle='-|>', mutation_scale=12, color=colour,
                                         lw=0, shrinkA=0, shrinkB=0, zorder=3))


def draw_raw_paths(ax: Axes, plan: Plan, view: PlaneView, colours: Sequence[ColorType]) -> None:
    """Draw the construction's own motion of a refined plan (Plan.raw) dashed, under it."""
    paths = view(cast(Plan, plan.raw).positions)  # a refined plan: its raw is set
    for robot, colour in enumerate(colours):
        ax.plot(paths[:, robot, 0], paths[:, robot, 1], ls='--', lw=0.9, color=colour,
                alpha=0.6, zorder=1.5)


def draw_obstacles(ax: Axes, plan: Plan, view: PlaneView, size: float = 70) -> None:
    """Draw the obstacles as black crosses, and their discs where they have a radius."""
    obstacles = view(plan.workspace.obstacles)
    ax.scatter(obstacles[:, 0], obstacles[:, 1], marker='X', s=size, color='black', zorder=4)
    for (x, y), radius in zip(obstacles, plan.workspace.obstacle_radii):
        if radius > 0:
            ax.add_patch(Circle((x, y), radius, fc='0.25', ec='black', alpha=0.5, zorder=3))


def draw_waypoints(ax: Axes, plan: Plan, view: PlaneView, colours: Sequence[ColorType],
                   size: float = 12) -> None:
    """Draw C_1..C_n as circles in each robot's colour, numbered 1..n, and the robots' discs."""
    radius = plan.workspace.robot_radius
    for m, configuration in enumerate(view(waypoints(plan))):
        for (x, y), colour in zip(configuration, colours):
            if radius > 0:
                ax.add_patch(Circle((x, y), radius, fc=colour, ec=colour, alpha=0.25,
                                    zorder=4))
            ax.plot(x, y, 'o', ms=size, mfc='white', mec=colour, mew=1.6, zorder=5)
            ax.text(x, y, str(m + 1), ha='center', va='center', fontsize=0.6 * size,
                    color=colour, fontweight='bold', zorder=6)


def draw_closest_approach(ax: Axes, plan: Plan, view: PlaneView) -> None:
    """Draw the certified closest approach as a dotted crimson segment."""
    points = closest_approach(plan)
    if points is None:
        return
    points = view(points)
    ax.plot(points[:, 0], points[:, 1], ':', color=CLEARANCE_COLOUR, lw=1.6, zorder=7)
    ax.plot(points[:, 0], points[:, 1], 'o', color=CLEARANCE_COLOUR, ms=3.5, zorder=7)


def legend_handles(plan: Plan, colours: Sequence[ColorType],
                   waypoints_numbered: bool = True) -> list[Line2D]:
    """Return proxy artists naming the robots (the first LEGEND_ROBOTS) and every layer."""
    named = len(colours) if len(colours) <= LEGEND_ROBOTS else LEGEND_ROBOTS - 1
    handles = [Line2D([], [], color=colour, lw=2, label=f'robot {robot}')
               for robot, colour in enumerate(colours[:named])]
    if named < len(colours):
        handles.append(Line2D([], [], color='0.6', lw=2,
                              label=f'robots {named} - {len(colours) - 1}'))
    if plan.workspace.obstacle_count:
        handles.append(Line2D([], [], ls='none', marker='X', ms=8, color='black',
                              label='obstacle'))
    if wall_outline(plan) is not None:
        handles.append(Line2D([], [], color=WALL_COLOUR, lw=2.4, label='walls'))
    handles += [
        Line2D([], [], color=AXIS_COLOUR, lw=1.2, label='e1 axis'),
        Line2D([], [], color='0.5', ls='--', lw=0.8, label='lanes'),
    ]
    if waypoints_numbered:
        handles.append(Line2D([], [], ls='none', marker='o', ms=9, mfc='white', mec='0.3',
                              label='C_m (numbered m)'))
    if closest_approach(plan) is not None:
        label = (f'smallest gap: {plan.min_gap:.3g}' if plan.workspace.has_bodies
                 else f'closest: {plan.min_clearance:.3g}')
        handles.append(Line2D([], [], ls=':', color=CLEARANCE_COLOUR, lw=1.6, label=label))
    return handles


def draw_plan_2d(ax: Axes, plan: Plan, view: PlaneView, colours: Sequence[ColorType],
                 path_alpha: float = 1.0, arrows: bool = True, raw: bool = False) -> None:
    """Draw every layer of the plan on ax, axes labelled by the view (raw: Plan.raw dashed)."""
    outline = wall_outline(plan)  # in the plane, where the view is (x, y) itself
    if outline is not None:
        draw_walls(ax, outline)
    draw_frame_lines(ax, plan, view, colours)
    if raw and plan.raw is not None:
        draw_raw_paths(ax, plan, view, colours)
    draw_paths(ax, plan, view, colours, alpha=path_alpha, arrows=arrows)
    draw_obstacles(ax, plan, view)
    draw_waypoints(ax, plan, view, colours)
    draw_closest_approach(ax, plan, view)
    ax.set_xlabel(view.labels[0])
    ax.set_ylabel(view.labels[1])
    ax.set_aspect('equal', adjustable='box')
    ax.grid(True, lw=0.4, alpha=0.4)
    points = np.concatenate([view(plan.positions).reshape(-1, 2),
                             view(plan.workspace.obstacles).reshape(-1, 2)]
                            + ([] if outline is None else [outline]))
    low, high = points.min(axis=0), points.max(axis=0)
    pad = 0.06 * max(float((high - low).max()), 1.0)
    ax.set_xlim(low[0] - pad, high[0] + pad)
    ax.set_ylim(low[1] - pad, high[1] + pad)
