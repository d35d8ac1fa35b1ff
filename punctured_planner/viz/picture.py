"""
render_png: one static picture of a plan, with its domain and clearance in the title.

Planar plans (d = 2) are drawn as they are; d = 3 as a 3-D view beside a top
view (x, y); d > 3 projected on the frame plane (e1, e2).
"""

import os

from matplotlib.axes import Axes
from matplotlib.figure import Figure

from .canvas import new_figure, robot_colours
from .draw2d import draw_plan_2d, legend_handles
from .draw3d import draw_plan_3d
from .geometry import plane_view
from ..core import Plan
from ..outputs import replacing


def clearance_text(plan: Plan) -> str:
    """
    Return one line naming the certified clearance and where it is reached.

    With robot or obstacle radii it is the surface gap (negative: the bodies touch).
    """
    bodies = plan.workspace.has_bodies
    clearance = plan.gap if bodies else plan.clearance
    what = 'gap' if bodies else 'clearance'
    if clearance.kind == 'none':
        return f'certified {what}: nothing to collide with'
    a, b = clearance.indices
    who = f'robots {a}, {b}' if clearance.kind == 'robots' else f'robot {a}, obstacle {b}'
    return (f'certified {what} {clearance.distance:.4g} ({who}; '
            f'{plan.leg_names[clearance.leg]} leg, tau {clearance.tau:.3f})')


def domain_text(plan: Plan) -> str:
    """Return one line with the domain l, its range, its index and TC_n."""
    low, high = plan.domain_range
    complexity = plan.sequential_complexity
    tc = 'n/a' if complexity is None else str(complexity)
    optimal = ', optimal' if plan.optimal else ''
    return (f'domain l = {plan.domain} in [{low}, {high}]: index {plan.domain_index} '
            f'of {plan.domain_count} domains (TC_n = {tc}{optimal})')


def plan_title(plan: Plan, title: str | None = None) -> str:
    """Return the title: optional first line, sizes and variant, domain, clearance."""
    n, k, d = plan.configurations.shape
    r = plan.workspace.obstacle_count
    lines = [] if title is None else [str(title)]
    robots = '1 robot' if k == 1 else f'{k} robots'
    obstacles = '1 obstacle' if r == 1 else f'{r} obstacles'
    lines.append(f'{robots}, {obstacles} in R^{d}, n = {n} configurations, '
                 f'variant {plan.variant!r}')
    lines.append(domain_text(plan))
    lines.append(clearance_text(plan))
    return '\n'.join(lines)


def plan_figure(plan: Plan, dpi: float = 100, title: str | None = None, path_alpha: float = 1.0,
                arrows: bool = True, raw: bool = False) -> tuple[Figure, list[Axes]]:
    """
    Return (figure, axes list) with the whole plan drawn; the caller saves or animates it.

    raw also draws a refined plan's unrefined motion (Plan.raw), dashed, on the 2-D views.
    """
    d = plan.positions.shape[2]
    colours = robot_colours(plan.positions.shape[1])
    view = plane_view(plan)
    if d == 3:
        figure = new_figure(13.5, 6.5, dpi)
        space = figure.add_subplot(1, 2, 1, projection='3d')
        draw_plan_3d(space, plan, colours, path_alpha=path_alpha, arrows=arrows)
        space.set_title('3-D view')
        top = figure.add_subplot(1, 2, 2)
        draw_plan_2d(top, plan, view, colours, path_alpha=path_alpha, arrows=arrows, raw=raw)
        top.set_title('top view (x, y)')
        axes = [space, top]
    else:
        figure = new_figure(9.5, 6.8, dpi)
        plane = figure.add_subplot(1, 1, 1)
        draw_plan_2d(plane, plan, view, colours, path_alpha=path_alpha, arrows=arrows,
                     raw=raw)
        if d > 3:
            plane.set_title('projection on the frame plane (e1, e2)')
        axes = [plane]
    figure.suptitle(plan_title(plan, title), fontsize=10)
    figure.legend(handles=legend_handles(plan, colours), loc='outside right upper',
                  fontsize=8, frameon=False)
    return figure, axes


def render_png(plan: Plan, path: str | os.PathLike[str], title: str | None = None,
               dpi: float = 100, raw: bool = False) -> str | os.PathLike[str]:
    """Draw the plan into a PNG file at path and return the path (raw: see plan_figure)."""
    figure, _ = plan_figure(plan, dpi=dpi, title=title, raw=raw)
    with replacing(path) as part:
        figure.savefig(part, dpi=dpi, format='png')
    return path
