"""
Pictures of a plan: static PNG, animated GIF, and the domain picture for teaching.

Headless throughout: figures are drawn by matplotlib's Agg renderer without
pyplot, so nothing opens a window, no global backend is switched and the code
runs on machines without a display. Every function takes a Plan (or builds its
own small scenario) and output paths; nothing here needs ROS.
"""

from .animation import frame_parameters, render_animation
from .domain_picture import domain_picture
from .domains import domain_values, start_goal_grid, start_plane_grid
from .example import example_plan
from .picture import plan_title, render_png

__all__ = ['domain_picture', 'domain_values', 'example_plan', 'frame_parameters',
           'plan_title', 'render_animation', 'render_png', 'start_goal_grid',
           'start_plane_grid']
