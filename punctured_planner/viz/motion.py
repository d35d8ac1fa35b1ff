"""
render_motion: an executed motion (odometry over time) as an animated GIF, top view.

Where :func:`render_animation` draws a plan as it is meant to run, this draws
what the robots did: each robot a disc of its radius at its recorded position,
with a trail, and its planned path faint underneath; the title gives the time
and the smallest gap so far. Headless (Agg, Pillow), like the other pictures.
"""

from matplotlib.patches import Circle
import numpy as np

from .canvas import frame_centiseconds, grab_frame, new_figure, robot_colours, write_gif


def render_motion(path: str, seconds: np.ndarray, positions: np.ndarray,
                  planned: np.ndarray, obstacles: np.ndarray, radius: float,
                  gaps: np.ndarray, title: str = '', fps: int = 8, dpi: int = 72) -> str:
    """
    Write the motion as an animated GIF at path; return path.

    seconds (T,), positions (T, k, 2) recorded; planned (M, k, 2) the plan's
    breakpoints; obstacles (r, 2); gaps (T,) the smallest gap so far at each frame.
    One frame per 1 / fps seconds of motion (the GIF plays in real time).
    """
    k = positions.shape[1]
    colours = robot_colours(k)
    figure = new_figure(6.4, 5.6, dpi=dpi)
    ax = figure.add_subplot()
    ax.set_aspect('equal')
    points = np.concatenate([positions.reshape(-1, 2), planned.reshape(-1, 2),
                             np.asarray(obstacles).reshape(-1, 2)])
    low, high = points.min(axis=0) - 0.5, points.max(axis=0) + 0.5
    ax.set_xlim(low[0], high[0])
    ax.set_ylim(low[1], high[1])
    ax.set_xlabel('x (m)')
    ax.set_ylabel('y (m)')
    for i in range(k):
        ax.plot(planned[:, i, 0], planned[:, i, 1], color=colours[i], lw=1, alpha=0.3)
    if len(obstacles):
        ax.plot(obstacles[:, 0], obstacles[:, 1], 'kx', ms=8, mew=2)
    trails = [ax.plot([], [], color=colours[i], lw=2)[0] for i in range(k)]
    discs = [Circle((0, 0), radius, color=colours[i], ec='black', zorder=5) for i in range(k)]
    for disc in discs:
        ax.add_patch(disc)
    heading = ax.set_title('')
    frames = []
    # one frame per GIF frame's length (whole centiseconds), so the GIF runs in real time
    every = frame_centiseconds(fps) / 100.0
    shown = np.unique(np.r_[np.searchsorted(seconds, np.arange(0.0, seconds[-1], every)),
                            len(seconds) - 1])
    for t in shown.tolist():
        for i in range(k):
            trails[i].set_data(positions[:t + 1, i, 0], positions[:t + 1, i, 1])
            discs[i].center = (float(positions[t, i, 0]), float(positions[t, i, 1]))
        heading.set_text('%s\nt = %.1f s, smallest gap so far %.3f m'
                         % (title, seconds[t], gaps[t]))
        figure.canvas.draw()
        frames.append(grab_frame(figure))
    write_gif(path, frames, fps)
    return path
