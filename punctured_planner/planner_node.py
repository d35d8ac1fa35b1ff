"""
Minimal planner node: serves ``plan_sequence`` and answers "not implemented yet".

This placeholder proves the foundation (interface package, install, DDS round
trip). The real planner node replaces :class:`PlannerNode`; the service name,
the entry point ``planner_node`` and the shutdown behaviour stay the same.
"""

import sys

from punctured_planner_interfaces.srv import PlanSequence
import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node

NOT_IMPLEMENTED_MSG = 'planner not implemented yet'


class PlannerNode(Node):
    """Serve PlanSequence; every request gets error_code UNKNOWN for now."""

    def __init__(self, **kwargs):
        """Create the node and its ``plan_sequence`` service (a relative name)."""
        super().__init__('planner_node', **kwargs)
        self._service = self.create_service(
            PlanSequence, 'plan_sequence', self._on_plan_sequence)
        self.get_logger().info(
            'serving %s (placeholder: %s)'
            % (self.resolve_service_name('plan_sequence'), NOT_IMPLEMENTED_MSG))

    def _on_plan_sequence(self, request, response):
        response.error_code = PlanSequence.Response.UNKNOWN
        response.error_msg = NOT_IMPLEMENTED_MSG
        return response


def main(args=None):
    """Run the node in the foreground until Ctrl-C or SIGTERM."""
    rclpy.init(args=args)
    node = None
    try:
        node = PlannerNode()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
