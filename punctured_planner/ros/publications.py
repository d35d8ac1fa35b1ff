"""
What the planner publishes for a plan: the list of latched messages.

The node and the MCAP recording both take :func:`plan_messages`, so a plan
looks the same on the topics and in a recording. Conversions of single
messages are in :mod:`punctured_planner.ros.conversions`, the markers in
:mod:`punctured_planner.ros.markers`.
"""

from dataclasses import dataclass

from nav_msgs.msg import Path
from rclpy.serialization import serialize_message
from std_msgs.msg import UInt32
from visualization_msgs.msg import MarkerArray

from .conversions import domain_index_message
from .conversions import plan_message
from .markers import plan_markers
from .settings import PlannerSettings
from .snapshot import Outcome
from .topics import PLAN
from .topics import robot_topic


@dataclass(frozen=True)
class Publication:
    """One message to publish: relative topic, message type, the message or its CDR bytes."""

    topic: str
    msg_type: type
    data: object

    def serialized(self) -> bytes:
        """Return the message as CDR bytes (as published)."""
        if isinstance(self.data, bytes):
            return self.data
        return serialize_message(self.data)


def plan_messages(outcome: Outcome, settings: PlannerSettings) -> list[Publication]:
    """
    Return the Publications of a successful planning Outcome, as the node publishes them.

    Topics are relative: ``<robot>/plan`` per robot (the bytes built with the
    response's Paths, :func:`punctured_planner.ros.conversions.plan_to_paths`),
    ``plan_markers``, ``domain_index``, then ``plan`` (the Plan message, last: an
    executor never sees a plan whose paths are not out).
    """
    planned = outcome.planned()
    messages = [Publication(robot_topic(name, PLAN), Path, data)
                for name, data in zip(planned.names, planned.paths.serialized)]
    messages.append(Publication('plan_markers', MarkerArray, plan_markers(
        planned.plan, settings.frame_id, outcome.start_ns, settings.plane_z, planned.names,
        outcome.max_speed)))
    messages.append(Publication('domain_index', UInt32, domain_index_message(planned.plan)))
    plan = plan_message(outcome, settings)
    messages.append(Publication('plan', type(plan), plan))
    return messages
