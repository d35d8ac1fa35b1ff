"""
render_animation: the synchronous motion as an animated GIF, all robots moving together.

Frames are evenly spaced in the plan's time (each leg lasts as long as its
fastest robot needs at max_speed, under max_acceleration when one is given),
fps x seconds of them, so the GIF lasts seconds; each robot leaves a trail
through every breakpoint it has passed, so a viewer sees the robots switch legs
together and never meet.
"""

import os
from typing import cast

from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.lines import Line2D
from matplotlib.patches import Circle
import numpy as np

from .canvas import frame_centiseconds, grab_frame, robot_colours, write_gif
from .geometry import plane_view
from .picture import plan_figure, plan_title
from ..core import Plan
from ..core.timing import leg_at


# A GIF frame lasts a whole number of centiseconds, and browsers show one shorter than 20 ms
# for 100 ms: fps above 50 played a GIF up to 10x slow. Every frame is held in memory, so
# an animation has at most MAX_FPS x MAX_SECONDS of them.
MAX_FPS = 50.0
MAX_SECONDS = 60.0
# One frame at most as long as the longest animation: a GIF frame's delay is 16 bits of
# centiseconds, and 0.001 fps overflowed it inside Pillow (a traceback, no picture).
MIN_FPS = 1.0 / MAX_SECONDS


def frame_parameters(plan: Plan, frame_count: int, max_speed: float = 1.0,
                     max_acceleration: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """
    Return (tau (F,), seconds (F,)) of frame_count frames evenly spaced in the plan's time.

    The first frame is the start (tau 0), the last the end (tau 1); a plan in which
    nothing moves has one frame. Each robot's trail runs through the breakpoints
    (render_animation), so no frame needs to fall on one.
    """
    stamps = plan.stamps(max_speed, max_acceleration)
    if not stamps[-1] > 0:
        return plan.times[:1].copy(), stamps[:1].copy()
    seconds = np.linspace(0.0, stamps[-1], max(2, frame_count))
    # stamps do not decrease; a leg in which nothing moves (no time) is one point of it
    tau = np.interp(seconds, stamps, plan.times)
    tau[0], tau[-1] = plan.times[0], plan.times[-1]
    return tau, seconds


def _leg_label(plan, tau):
    """Return 'C_m -> C_m+1: <leg name>' for the leg that contains tau."""
    leg = int(leg_at(plan.times, tau))
    segment = plan.segment_of(leg)
    return f'C_{segment + 1} -> C_{segment + 2}: {plan.leg_names[leg]}'


class _Movers:
    """
    The artists that move: one trail and one marker per robot, in one 2-D or 3-D axes.

    In 2-D a robot with a radius also gets its disc, to scale (``bodies``).
    """

    def __init__(self, ax, colours, three_d, radius=0.0):
        """Create empty trails and robot markers (and discs of radius) on ax."""
        self.three_d = three_d
        self.trails, self.robots, self.bodies = [], [], []
        if radius > 0 and not three_d:
            self.bodies = [ax.add_patch(Circle((0.0, 0.0), radius, fc=colour, ec='black',
                                               lw=0.6, alpha=0.45, zorder=8))
                           for colour in colours]
        for colour in colours:
            if three_d:
                trail, = ax.plot([], [], [], color=colour, lw=2.6)
                robot, = ax.plot([], [], [], 'o', color=colour, ms=9, mec='black', mew=0.8)
            else:
                trail = ax.add_line(Line2D([], [], color=colour, lw=2.6, zorder=8))
                robot = ax.add_line(Line2D([], [], ls='none', marker='o', color=colour, ms=10,
                                           mec='black', mew=0.8, zorder=9))
            self.trails.append(trail)
            self.robots.append(robot)

    def update(self, history: np.ndarray) -> None:
        """Show the robots at history[-1] and their trails over history (F, k, 2 or 3)."""
        for robot, (trail, marker) in enumerate(zip(self.trails, self.robots)):
            points = history[:, robot]
            if self.three_d:
                trail.set_data_3d(*points.T)
                marker.set_data_3d(*points[-1:].T)
            else:
                trail.set_data(*points.T)
                marker.set_data(*points[-1:].T)
        for robot, body in enumerate(self.bodies):
            body.set_center(tuple(history[-1, robot]))


def _static_background(figure, dynamic):
    """Return the figure drawn without its dynamic artists: what every frame starts from."""
    figure.canvas.draw()
    figure.set_layout_engine('none')
    for artist in dynamic:
        artist.set_visible(False)
    figure.canvas.draw()
    background = figure.canvas.copy_from_bbox(figure.bbox)
    for artist in dynamic:
        artist.set_visible(True)
    return background


def render_animation(plan: Plan, path: str | os.PathLike[str], fps: float = 20,
                     seconds: float = 8.0, dpi: float = 80, title: str | None = None,
                     max_speed: float = 1.0,
                     max_acceleration: float = 0.0) -> str | os.PathLike[str]:
    """
    Write the motion as an animated GIF at path, seconds long at about fps; return path.

    The static picture is drawn once; each frame redraws only the trails, the
    robots and the title over it (blitting), then Pillow, matplotlib's own GIF
    writer, encodes the frames with one shared palette.
    """
    if os.path.splitext(str(path))[1].lower() != '.gif':
        raise ValueError(f'render_animation writes GIF files; {path!r} does not end in .gif')
    if not (MIN_FPS <= fps <= MAX_FPS and 0 < seconds <= MAX_SECONDS):
        raise ValueError(f'fps must be in [{MIN_FPS:g}, {MAX_FPS:g}] (a GIF frame lasts at '
                         f'least {1000 / MAX_FPS:g} ms and at most {MAX_SECONDS:g} s) and '
                         f'seconds in (0, {MAX_SECONDS:g}]; got fps {fps:g}, seconds '
                         f'{seconds:g}')
    count = int(round(100.0 * seconds / frame_centiseconds(fps)))
    tau, stamps = frame_parameters(plan, count, max_speed,
                                   max_acceleration)
    # The trails: every breakpoint and every frame, in order; frame f ends at ends[f].
    trail_tau = np.union1d(tau, plan.times)
    ends = np.searchsorted(trail_tau, tau)
    positions = plan.position(trail_tau)
    colours = robot_colours(positions.shape[1])
    figure, axes = plan_figure(plan, dpi=dpi, title=title, path_alpha=0.25, arrows=False)
    heading = plan_title(plan, title)

    def caption(frame: int) -> str:
        """Return the title of one frame: the plan's title, the time and the leg."""
        limits = f'{max_speed:g} m/s'
        if max_acceleration:
            limits += f', {max_acceleration:g} m/s^2'
        return (f'{heading}\nt = {stamps[frame]:.2f} s at {limits} '
                f'(tau {tau[frame]:.3f}), {_leg_label(plan, tau[frame])}')

    heading_text = figure.suptitle(caption(0), fontsize=10)
    movers = []
    if len(axes) == 2:
        movers.append((_Movers(axes[0], colours, True), positions))
    movers.append((_Movers(axes[-1], colours, False, plan.workspace.robot_radius),
                   plane_view(plan)(positions)))
    dynamic = [heading_text] + [artist for mover, _ in movers
                                for artist in mover.trails + mover.robots + mover.bodies]
    background = _static_background(figure, dynamic)
    frames = []
    for frame in range(tau.size):
        cast(FigureCanvasAgg, figure.canvas).restore_region(background)  # new_figure's Agg canvas
        for mover, points in movers:
            mover.update(points[:ends[frame] + 1])
        heading_text.set_text(caption(frame))
        for artist in dynamic:
            figure.draw_artist(artist)
        frames.append(grab_frame(figure))
    write_gif(path, frames, fps)
    return path
