"""
Headless figures: a matplotlib Figure with an Agg canvas, never pyplot.

A Figure built directly with an Agg canvas attached needs no backend choice,
touches no global pyplot state and can never open a window, so it renders on
machines without a display and inside a node's worker threads.
"""

from typing import Literal

import matplotlib
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.layout_engine import LayoutEngine

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
