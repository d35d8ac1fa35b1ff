"""
Headless figures: a matplotlib Figure with an Agg canvas, never pyplot; GIFs of its frames.

A Figure built directly with an Agg canvas attached needs no backend choice,
touches no global pyplot state and can never open a window, so it renders on
machines without a display and inside a node's worker threads.
"""

import os
from typing import Literal

import matplotlib
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.layout_engine import LayoutEngine
import numpy as np
from PIL import Image

from ..outputs import replacing

# Colours of a GIF's one palette, taken from its first frame.
GIF_COLOURS = 96

# What Figure's layout argument takes.
_Layout = Literal['constrained', 'compressed', 'tight'] | LayoutEngine | None


def new_figure(width: float, height: float, dpi: float = 100,
               layout: _Layout = 'constrained') -> Figure:
    """Return a Figure of width x height inches drawn by the Agg renderer."""
    figure = Figure(figsize=(width, height), dpi=dpi, layout=layout)
    FigureCanvasAgg(figure)
    return figure


def robot_colours(count: int) -> list[tuple[float, float, float, float]]:
    """Return one distinct RGBA colour per robot (tab10, or turbo beyond ten robots)."""
    if count <= 10:
        palette = matplotlib.colormaps['tab10']
        return [palette(i) for i in range(count)]
    palette = matplotlib.colormaps['turbo']
    return [palette(i / (count - 1)) for i in range(count)]


def grab_frame(figure: Figure) -> Image.Image:
    """Return the figure's canvas as it is now, as an RGB Pillow image."""
    canvas = figure.canvas
    assert isinstance(canvas, FigureCanvasAgg)  # new_figure's
    return Image.fromarray(np.asarray(canvas.buffer_rgba())[..., :3].copy())


def frame_centiseconds(fps: float) -> int:
    """
    Return how long a GIF frame lasts at about fps frames a second, in centiseconds.

    GIF stores a frame's delay in whole centiseconds (at least 2 for every viewer):
    25 ms became 20, so a GIF of 40 fps for 8 s lasted 6.4 s. Frames are counted
    and spaced by this, so the GIF lasts as long as asked.
    """
    return max(2, int(round(100.0 / fps)))


def write_gif(path: str | os.PathLike[str], frames: list[Image.Image], fps: float) -> None:
    """
    Write frames as a looping GIF at path, each frame_centiseconds(fps) long.

    One palette for every frame (the first frame's colours, median cut) and no
    dithering: the figures are flat colours, which dithering would speckle and
    a palette per frame would make flicker.
    """
    palette = frames[0].convert('RGB').quantize(colors=GIF_COLOURS,
                                                method=Image.Quantize.MEDIANCUT)
    images = [image.quantize(palette=palette, dither=Image.Dither.NONE) for image in frames]
    with replacing(path) as part:
        images[0].save(part, format='GIF', save_all=True, append_images=images[1:],
                       duration=10 * frame_centiseconds(fps), loop=0)
