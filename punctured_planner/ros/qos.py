"""
The QoS profiles of the package's topics, one place for every node and client.

``LATCHED``: the planner's plans, paths, markers and domain index, the
obstacles and the simulator's true gap; a late subscriber still gets the
latest message. ``STATE``: robot state streams (odometry, ``robot_states``);
best effort matches reliable and best-effort publishers alike.
"""

from rclpy.qos import DurabilityPolicy
from rclpy.qos import HistoryPolicy
from rclpy.qos import QoSProfile
from rclpy.qos import ReliabilityPolicy

LATCHED = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST,
                     reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.TRANSIENT_LOCAL)
STATE = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST,
                   reliability=ReliabilityPolicy.BEST_EFFORT,
                   durability=DurabilityPolicy.VOLATILE)
# Commands and references: a short queue, reliable (the rclpy default for a depth).
COMMANDS = 10
