"""
What the node publishes for a plan: the RViz markers and the list of latched messages.

The node and the MCAP recording both take :func:`plan_messages`, so a plan
looks the same on the topics and in a recording. Conversions of single
messages are in :mod:`punctured_planner.conversions`.
"""

from dataclasses import dataclass

from geometry_msgs.msg import Point
from geometry_msgs.msg import Vector3
from nav_msgs.msg import Path
import numpy as np
from std_msgs.msg import ColorRGBA
from std_msgs.msg import Header
from std_msgs.msg import UInt32
from visualization_msgs.msg import Marker
from visualization_msgs.msg import MarkerArray

from .conversions import domain_index_message
from .conversions import plan_message
from .conversions import robot_names
from .conversions import time_from_ns
from .conversions import to_xyz

# Height (m) of the cylinder drawn for a pillar with a radius.
PILLAR_HEIGHT = 1.0
# Colours of the robots in the markers (RGB, matplotlib's tab10).
PALETTE = (
    (0.122, 0.467, 0.706), (1.000, 0.498, 0.055), (0.173, 0.627, 0.173),
    (0.839, 0.153, 0.157), (0.580, 0.404, 0.741), (0.549, 0.337, 0.294),
    (0.890, 0.467, 0.761), (0.498, 0.498, 0.498), (0.737, 0.741, 0.133),
    (0.090, 0.745, 0.812),
)


def _colour(index, alpha=1.0):
    r, g, b = PALETTE[index % len(PALETTE)]
    return ColorRGBA(r=r, g=g, b=b, a=alpha)


def _points(xyz):
    points = []
    for x, y, z in np.asarray(xyz, dtype=float).tolist():
        point = Point()
        point.x, point.y, point.z = x, y, z
        points.append(point)
    return points


def plan_markers(plan, frame_id, stamp_ns, plane_z=0.0, names=None, max_speed=1.0):
    """
    Return a visualization_msgs/MarkerArray of the plan for RViz.

    Namespaces: a DELETEALL first (no stale markers), ``obstacles`` (black
    spheres), ``axis`` (the e1 axis, grey), ``lanes`` (one thin line per
    robot lane, a LINE_LIST), ``paths`` (one LINE_STRIP per robot through
    every breakpoint, none twice, robot colours), ``waypoints`` (one SPHERE_LIST per
    configuration C_m) and ``labels`` (robot names at C_1); with radii also
    ``pillars`` (one cylinder of its diameter per obstacle) and ``bodies`` (the
    robots' discs at each C_m, translucent, of diameter 2 robot_radius).
    """
    header = Header(frame_id=frame_id, stamp=time_from_ns(stamp_ns))
    positions = to_xyz(plan.positions, plane_z)
    k = positions.shape[1]
    names = names or robot_names((), k)
    scale = float(plan.workspace.lane_spacing)
    width = 0.05 * scale
    markers = [Marker(header=header, action=Marker.DELETEALL)]

    def marker(ns, marker_id, kind, colour, size, points=()):
        item = Marker(header=header, ns=ns, id=marker_id, type=kind, action=Marker.ADD,
                      scale=Vector3(x=size, y=size, z=size), color=colour)
        item.pose.orientation.w = 1.0
        item.points = _points(points) if len(points) else []
        return item

    obstacles = to_xyz(plan.workspace.obstacles, plane_z).reshape(-1, 3)
    if len(obstacles):
        markers.append(marker('obstacles', 0, Marker.SPHERE_LIST,
                              ColorRGBA(r=0.0, g=0.0, b=0.0, a=1.0), 0.25 * scale, obstacles))
    for j, radius in enumerate(plan.workspace.obstacle_radii.tolist()):
        if radius > 0:  # the pillar's body: a cylinder of its diameter
            pillar = marker('pillars', j, Marker.CYLINDER,
                            ColorRGBA(r=0.3, g=0.3, b=0.3, a=0.6), 2 * radius)
            pillar.scale.z = PILLAR_HEIGHT
            pillar.pose.position.x, pillar.pose.position.y = obstacles[j, :2].tolist()
            pillar.pose.position.z = float(obstacles[j, 2]) + 0.5 * PILLAR_HEIGHT
            markers.append(pillar)
    axis = to_xyz(plan.axis_segment(), plane_z)
    markers.append(marker('axis', 0, Marker.LINE_STRIP,
                          ColorRGBA(r=0.5, g=0.5, b=0.5, a=0.8), width, axis))
    lanes = to_xyz(plan.lane_segments(), plane_z).reshape(-1, 3)
    markers.append(marker('lanes', 0, Marker.LINE_LIST,
                          ColorRGBA(r=0.6, g=0.6, b=0.6, a=0.5), 0.5 * width, lanes))
    moving = to_xyz(plan.sample(0, max_speed).positions, plane_z)
    for i in range(k):
        markers.append(marker('paths', i, Marker.LINE_STRIP, _colour(i), width,
                              moving[:, i]))
    radius = plan.workspace.robot_radius
    for m, index in enumerate(np.asarray(plan.waypoint_indices).tolist()):
        item = marker('waypoints', m, Marker.SPHERE_LIST,
                      ColorRGBA(r=1.0, g=1.0, b=1.0, a=1.0), 0.2 * scale, positions[index])
        item.colors = [_colour(i) for i in range(k)]
        markers.append(item)
        if radius > 0:  # the robots' bodies at C_m: discs of their diameter
            bodies = marker('bodies', m, Marker.SPHERE_LIST, ColorRGBA(), 2 * radius,
                            positions[index])
            bodies.colors = [_colour(i, 0.35) for i in range(k)]
            markers.append(bodies)
    for i in range(k):
        label = marker('labels', i, Marker.TEXT_VIEW_FACING,
                       ColorRGBA(r=0.0, g=0.0, b=0.0, a=1.0), 0.3 * scale)
        x, y, z = positions[0, i].tolist()
        label.pose.position.x, label.pose.position.y = x, y
        label.pose.position.z = z + 0.3 * scale
        label.text = names[i]
        markers.append(label)
    return MarkerArray(markers=markers)


@dataclass(frozen=True)
class Publication:
    """One message to publish: relative topic, message type, the message or its CDR bytes."""

    topic: str
    msg_type: type
    data: object

    def serialized(self):
        """Return the message as CDR bytes (as published)."""
        if isinstance(self.data, bytes):
            return self.data
        from rclpy.serialization import serialize_message
        return serialize_message(self.data)


def plan_messages(outcome, settings):
    """
    Return the Publications of a successful planning Outcome, as the node publishes them.

    Topics are relative: ``<robot>/plan`` per robot (the bytes built with the
    response's Paths, :func:`punctured_planner.conversions.plan_to_paths`),
    ``plan_markers``, ``domain_index``, then ``plan`` (the Plan message, last: an
    executor never sees a plan whose paths are not out).
    """
    messages = [Publication('%s/plan' % name.strip('/'), Path, data)
                for name, data in zip(outcome.names, outcome.paths.serialized)]
    messages.append(Publication('plan_markers', MarkerArray, plan_markers(
        outcome.plan, settings.frame_id, outcome.start_ns, settings.plane_z, outcome.names,
        outcome.max_speed)))
    messages.append(Publication('domain_index', UInt32, domain_index_message(outcome.plan)))
    plan = plan_message(outcome, settings)
    messages.append(Publication('plan', type(plan), plan))
    return messages
