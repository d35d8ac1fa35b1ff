"""
domain_picture: the domains of continuity, drawn for one or two robots in the plane.

Three obstacles on the x axis, n = 2 (start C_1, goal C_2). Left: every start
position of robot 0 in the plane, goal (and robot 1's start) fixed; the domain
drops on the vertical lines through the obstacles (and robot 1). Right: the
start x against the goal x (robot 1 rides at a fixed offset equal to the
obstacle gap), where all n k + 1 domains appear: open cells, lines, crossings.
The lower strata are lines and points; they are drawn thickened to be seen.
"""

from dataclasses import dataclass
import os

import matplotlib
from matplotlib.cm import ScalarMappable
from matplotlib.colors import BoundaryNorm, Colormap, ListedColormap
import numpy as np
from scipy.ndimage import binary_dilation

from .canvas import new_figure, robot_colours
from .domains import snapped_axis, start_goal_grid, start_goal_specials, start_plane_grid
from ..core import Workspace
from ..core.complexity import domain_range, sequential_complexity
from ..outputs import replacing

TEACHING_OBSTACLES = [[-2.0, 0.0], [0.0, 0.0], [2.0, 0.0]]
LIMIT = 4.5
# C_1 and C_2 of the left panel; robot 0's start is what varies.
PLANE_REQUEST = [[[-3.3, 1.0], [1.2, -1.4]], [[1.0, 2.0], [3.0, -2.0]]]
# C_1 and C_2 of the right panel: robot 1 rides 2 (the obstacle gap) right of robot 0.
SLICE_REQUEST = [[[0.0, 1.0], [2.0, -1.0]], [[0.0, 1.5], [2.0, -1.5]]]


@dataclass(frozen=True)
class TeachingScene:
    """The picture's workspace and its two requests (n, k, 2): the left panel's, the right's."""

    workspace: Workspace
    plane: np.ndarray
    sliced: np.ndarray


def teaching_scene(robot_count: int) -> TeachingScene:
    """Return the workspace and the two panels' requests for 1 or 2 robots."""
    if robot_count not in (1, 2):
        raise ValueError('the domain picture is drawn for 1 or 2 robots')
    return TeachingScene(Workspace(TEACHING_OBSTACLES),
                         np.array(PLANE_REQUEST)[:, :robot_count],
                         np.array(SLICE_REQUEST)[:, :robot_count])


def thicken(values: np.ndarray, width: int = 2) -> np.ndarray:
    """
    Return a copy of a domain image where each lower value is dilated to be visible.

    Values below the largest one grow by width pixels per step below it, lowest
    drawn last, so lines stay lines and their crossings stand out as squares.
    """
    shown = values.copy()
    present = np.unique(values[np.isfinite(values)])
    square = np.ones((3, 3), dtype=bool)
    for value in present[::-1][1:]:
        steps = int(present[-1] - value)
        shown[binary_dilation(values == value, square, iterations=width * steps)] = value
    return shown


def domain_colours(low: int, high: int) -> tuple[Colormap, BoundaryNorm]:
    """Return (colormap, norm) with one discrete colour per domain value low..high."""
    palette = matplotlib.colormaps['viridis'].resampled(high - low + 1)
    colours = ListedColormap(palette(np.arange(high - low + 1))).with_extremes(bad='white')
    return colours, BoundaryNorm(np.arange(low - 0.5, high + 1.5), high - low + 1)


def _show(ax, values, xs, ys, colours, norm):
    """Draw a thickened domain image on ax over the grid xs, ys."""
    image = np.ma.masked_invalid(thicken(values))
    return ax.imshow(image, origin='lower', extent=(xs[0], xs[-1], ys[0], ys[-1]),
                     cmap=colours, norm=norm, interpolation='nearest')


def _plane_panel(ax, workspace, request, resolution, colours, norm):
    """Draw the left panel: robot 0's start over the plane."""
    xs = snapped_axis(-LIMIT, LIMIT, resolution,
                      np.concatenate([workspace.obstacles[:, 0], request[0, 1:, 0]]))
    ys = snapped_axis(-LIMIT, LIMIT, resolution, workspace.obstacles[:, 1])
    _show(ax, start_plane_grid(workspace, request, xs, ys), xs, ys, colours, norm)
    robots = robot_colours(request.shape[1])
    ax.scatter(*workspace.obstacles.T, marker='X', s=70, color='black', label='obstacle')
    for robot, colour in enumerate(robots):
        if robot:
            ax.plot(*request[0, robot], 's', ms=9, color=colour, mec='black',
                    label=f'start of robot {robot}')
        ax.plot(*request[1, robot], '*', ms=14, color=colour, mec='black',
                label=f'goal of robot {robot}')
    ax.set_title('start of robot 0 anywhere in the plane', fontsize=10)
    ax.set_xlabel('x of robot 0 in C_1')
    ax.set_ylabel('y of robot 0 in C_1')
    ax.legend(loc='lower left', fontsize=7, framealpha=0.85)


def _slice_panel(ax, workspace, request, resolution, colours, norm):
    """Draw the right panel: start x against goal x, every domain present."""
    start_special, goal_special = start_goal_specials(workspace, request)
    starts = snapped_axis(-LIMIT, LIMIT, resolution, start_special)
    goals = snapped_axis(-LIMIT, LIMIT, resolution, goal_special)
    _show(ax, start_goal_grid(workspace, request, starts, goals), starts, goals, colours,
          norm)
    rider = ' (robot 1 two to its right)' if request.shape[1] > 1 else ''
    ax.set_title('start x against goal x' + rider, fontsize=10)
    ax.set_xlabel('x of robot 0 in C_1')
    ax.set_ylabel('x of robot 0 in C_2')


def domain_picture(path: str | os.PathLike[str], robot_count: int = 1, resolution: int = 361,
                   dpi: float = 100) -> str | os.PathLike[str]:
    """Draw the domain picture for robot_count (1 or 2) robots into a PNG at path; return path."""
    scene = teaching_scene(robot_count)
    workspace = scene.workspace
    r = workspace.obstacle_count
    low, high = domain_range(2, robot_count, r)
    colours, norm = domain_colours(low, high)
    figure = new_figure(11.5, 5.6, dpi)
    left, right = figure.subplots(1, 2)
    _plane_panel(left, workspace, scene.plane, resolution, colours, norm)
    _slice_panel(right, workspace, scene.sliced, resolution, colours, norm)
    mappable = ScalarMappable(norm=norm, cmap=colours)
    bar = figure.colorbar(mappable, ax=[left, right], ticks=np.arange(low, high + 1),
                          shrink=0.85)
    bar.set_ticklabels([f'l = {value} (index {value - low})' for value in
                        range(low, high + 1)])
    bar.set_label('domain l = cp(C_1) + cp(C_2)')
    tc = sequential_complexity(2, robot_count, r, 2)
    robots = '1 robot' if robot_count == 1 else f'{robot_count} robots'
    figure.suptitle(f'Domains of continuity: {robots}, {r} obstacles on the x axis, n = 2: '
                    f'{high - low + 1} domains = TC_2 = {tc}; lower strata (lines, points) '
                    'drawn thickened', fontsize=10)
    with replacing(path) as part:
        figure.savefig(part, dpi=dpi, format='png')
    return path
