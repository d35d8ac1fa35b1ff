"""
The RViz markers of a plan (visualization_msgs/MarkerArray), as the planner publishes them.

Namespaces: a DELETEALL first (no stale markers), ``obstacles`` (black
spheres), ``axis`` (the e1 axis, grey), ``lanes`` (one thin line per robot
lane, a LINE_LIST), ``paths`` (one LINE_STRIP per robot through every
breakpoint, none twice, robot colours), ``waypoints`` (one SPHERE_LIST per
configuration C_m) and ``labels`` (robot names at C_1); with radii also
``pillars`` (one cylinder of its diameter per obstacle) and ``bodies`` (the
robots' discs at each C_m, translucent, of diameter 2 robot_radius); with
workspace_bounds ``walls`` (the edges of their box, a LINE_LIST).
"""

from collections.abc import Sequence
from dataclasses import dataclass

from geometry_msgs.msg import Vector3
import numpy as np
from std_msgs.msg import ColorRGBA
from std_msgs.msg import Header
from visualization_msgs.msg import Marker
from visualization_msgs.msg import MarkerArray

from .conversions import header
from .conversions import point_list
from .conversions import robot_names
from .conversions import to_xyz
from ..core import Plan
from ..core import Workspace
from ..core.walls import box_corners

# Height (m) of the cylinder drawn for a pillar with a radius.
PILLAR_HEIGHT = 1.0
# Colours of the robots in the markers (RGB, matplotlib's tab10).
PALETTE = (
    (0.122, 0.467, 0.706), (1.000, 0.498, 0.055), (0.173, 0.627, 0.173),
    (0.839, 0.153, 0.157), (0.580, 0.404, 0.741), (0.549, 0.337, 0.294),
    (0.890, 0.467, 0.761), (0.498, 0.498, 0.498), (0.737, 0.741, 0.133),
    (0.090, 0.745, 0.812),
)
_BLACK = (0.0, 0.0, 0.0, 1.0)


def _colour(index: int, alpha: float = 1.0) -> ColorRGBA:
    r, g, b = PALETTE[index % len(PALETTE)]
    return ColorRGBA(r=r, g=g, b=b, a=alpha)


def _rgba(r: float, g: float, b: float, a: float) -> ColorRGBA:
    return ColorRGBA(r=r, g=g, b=b, a=a)


@dataclass(frozen=True)
class _Drawing:
    """What every marker of one plan shares: header, plane, scale."""

    header: Header
    plane_z: float
    scale: float

    def marker(self, ns: str, marker_id: int, kind: int, colour: ColorRGBA, size: float,
               points: np.ndarray | Sequence[Sequence[float]] = ()) -> Marker:
        """Return one ADD marker of the plan's header, unit orientation, uniform scale."""
        item = Marker(header=self.header, ns=ns, id=marker_id, type=kind, action=Marker.ADD,
                      scale=Vector3(x=size, y=size, z=size), color=colour)
        item.pose.orientation.w = 1.0
        item.points = point_list(points) if len(points) else []
        return item


def plan_markers(plan: Plan, frame_id: str, stamp_ns: int, plane_z: float = 0.0,
                 names: Sequence[str] | None = None, max_speed: float = 1.0) -> MarkerArray:
    """Return a visualization_msgs/MarkerArray of the plan for RViz (module docstring)."""
    drawing = _Drawing(header(frame_id, stamp_ns), plane_z,
                       float(plan.workspace.lane_spacing))
    positions = to_xyz(plan.positions, plane_z)
    names = names or robot_names((), positions.shape[1])
    markers = [Marker(header=drawing.header, action=Marker.DELETEALL)]
    markers += _obstacle_markers(drawing, plan.workspace)
    markers += _wall_markers(drawing, plan.workspace)
    markers += _line_markers(drawing, plan, max_speed)
    markers += _waypoint_markers(drawing, plan, positions)
    markers += _label_markers(drawing, positions, names)
    return MarkerArray(markers=markers)


def _obstacle_markers(drawing: _Drawing, workspace: Workspace) -> list[Marker]:
    """
    Return the obstacles' spheres and, for those with a radius, their bodies.

    In the plane an obstacle with a radius is a pillar, drawn as a cylinder
    PILLAR_HEIGHT high standing on the plane; in space a ball, drawn as itself.
    """
    obstacles = to_xyz(workspace.obstacles, drawing.plane_z).reshape(-1, 3)
    markers = []
    if len(obstacles):
        markers.append(drawing.marker('obstacles', 0, Marker.SPHERE_LIST, _rgba(*_BLACK),
                                      0.25 * drawing.scale, obstacles))
    ball = workspace.dimension >= 3
    for j, radius in enumerate(workspace.obstacle_radii.tolist()):
        if radius > 0:  # the body: a ball, or a pillar's cylinder, of its diameter
            pillar = drawing.marker('pillars', j, Marker.SPHERE if ball else Marker.CYLINDER,
                                    _rgba(0.3, 0.3, 0.3, 0.6), 2 * radius)
            pillar.pose.position.x, pillar.pose.position.y, pillar.pose.position.z = (
                obstacles[j].tolist())
            if not ball:
                pillar.scale.z = PILLAR_HEIGHT
                pillar.pose.position.z += 0.5 * PILLAR_HEIGHT
            markers.append(pillar)
    return markers


def _wall_markers(drawing: _Drawing, workspace: Workspace) -> list[Marker]:
    """Return the edges of the walls' box (none without workspace_bounds)."""
    if workspace.bounds is None:
        return []
    corners = box_corners(workspace.bounds)
    # an edge joins two corners whose indices differ in one bit (box_corners)
    index = np.arange(len(corners))
    ends = [(i, i | bit) for bit in (1 << np.arange(corners.shape[1])).tolist()
            for i in index[(index & bit) == 0].tolist()]
    edges = to_xyz(corners[np.array(ends)], drawing.plane_z).reshape(-1, 3)
    return [drawing.marker('walls', 0, Marker.LINE_LIST, _rgba(0.545, 0.271, 0.075, 1.0),
                           0.08 * drawing.scale, edges)]


def _line_markers(drawing: _Drawing, plan: Plan, max_speed: float) -> list[Marker]:
    """Return the frame axis, the lanes and every robot's path through its breakpoints."""
    width = 0.05 * drawing.scale
    axis = to_xyz(plan.axis_segment(), drawing.plane_z)
    lanes = to_xyz(plan.lane_segments(), drawing.plane_z).reshape(-1, 3)
    markers = [drawing.marker('axis', 0, Marker.LINE_STRIP, _rgba(0.5, 0.5, 0.5, 0.8), width,
                              axis),
               drawing.marker('lanes', 0, Marker.LINE_LIST, _rgba(0.6, 0.6, 0.6, 0.5),
                              0.5 * width, lanes)]
    moving = to_xyz(plan.sample(0, max_speed).positions, drawing.plane_z)
    for i in range(moving.shape[1]):
        markers.append(drawing.marker('paths', i, Marker.LINE_STRIP, _colour(i), width,
                                      moving[:, i]))
    return markers


def _waypoint_markers(drawing: _Drawing, plan: Plan, positions: np.ndarray) -> list[Marker]:
    """Return every C_m in the robots' colours and, with a radius, their bodies."""
    k = positions.shape[1]
    radius = plan.workspace.robot_radius
    markers = []
    for m, index in enumerate(np.asarray(plan.waypoint_indices).tolist()):
        item = drawing.marker('waypoints', m, Marker.SPHERE_LIST, _rgba(1.0, 1.0, 1.0, 1.0),
                              0.2 * drawing.scale, positions[index])
        item.colors = [_colour(i) for i in range(k)]
        markers.append(item)
        if radius > 0:  # the robots' bodies at C_m: discs of their diameter
            bodies = drawing.marker('bodies', m, Marker.SPHERE_LIST, ColorRGBA(), 2 * radius,
                                    positions[index])
            bodies.colors = [_colour(i, 0.35) for i in range(k)]
            markers.append(bodies)
    return markers


def _label_markers(drawing: _Drawing, positions: np.ndarray,
                   names: Sequence[str]) -> list[Marker]:
    """Return every robot's name above its place in C_1."""
    markers = []
    for i, name in enumerate(names[:positions.shape[1]]):
        label = drawing.marker('labels', i, Marker.TEXT_VIEW_FACING, _rgba(*_BLACK),
                               0.3 * drawing.scale)
        x, y, z = positions[0, i].tolist()
        label.pose.position.x, label.pose.position.y = x, y
        label.pose.position.z = z + 0.3 * drawing.scale
        label.text = name
        markers.append(label)
    return markers
