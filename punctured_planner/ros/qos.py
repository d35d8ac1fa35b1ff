"""
The QoS profiles of the package's topics, one place for every node and client.

``LATCHED``: the planner's plans, paths, markers and domain index, the
obstacles and the simulator's true gap; a late subscriber still gets the
latest message. ``STATE``: robot state streams (odometry, ``robot_states``);
best effort matches reliable and best-effort publishers alike.

``SERVER_QOS`` and ``CLIENT_QOS``: the ``plan_sequence`` service, the node's and
its clients' (doc/design.md section 15). rmw_fastrtps (Jazzy) carries a service
on two DDS topics. The server has one response writer, and the response reader
of every client of the service is matched with it: every reply reaches every
client, and each client takes and drops the replies meant for the others. A
reader keeps what it has not taken yet in a KEEP_LAST history of the QoS depth
(10 in rclpy's default service QoS), and a full history silently drops its
oldest sample. So a client that does not take for as long as the node answers 10
calls of other clients loses its own reply; the same depth bounds the requests
waiting in the node's request reader, and the replies its writer keeps for
repairs.

``FASTDDS_PROFILE``: what the node processes' reliable writers do beyond the
QoS above (their heartbeat period), loaded by :func:`load_fastdds_profile`.
"""

import os

from rclpy.qos import DurabilityPolicy
from rclpy.qos import HistoryPolicy
from rclpy.qos import QoSProfile
from rclpy.qos import ReliabilityPolicy


def latched(depth: int) -> QoSProfile:
    """
    Return the latched QoS (reliable, transient local, keep last) with ``depth``.

    A reader's depth is what it keeps of a burst until its callbacks take them:
    plan_executor reads ``plan`` with its plan store's, as the planner may publish
    plans back to back (those answered while one was being published), and with
    depth 1 it kept the first and the last of eight such plans.
    """
    return QoSProfile(depth=depth, history=HistoryPolicy.KEEP_LAST,
                      reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.TRANSIENT_LOCAL)


LATCHED = latched(1)
STATE = QoSProfile(depth=1, history=HistoryPolicy.KEEP_LAST,
                   reliability=ReliabilityPolicy.BEST_EFFORT,
                   durability=DurabilityPolicy.VOLATILE)
# Commands, references and the simulator's odometry and robot_states: a short queue,
# reliable (the rclpy default for a depth).
COMMANDS = 10

# The node: requests that may wait while it plans (one client's call each), and
# replies kept for repairs. Bounded: a reply stays until every matched client
# acknowledged it, so a crashed client holds this many replies until its lease ends.
SERVER_DEPTH = 100
# A client: replies to all clients that may arrive before it takes its own. A
# client process stalled for 1 s while the node answered 300 calls per second
# needs 300; the replies it holds are dropped as it takes them.
CLIENT_DEPTH = 1000


def _service_qos(depth: int) -> QoSProfile:
    """Return rclpy's service QoS (reliable, volatile, keep last) with ``depth``."""
    return QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=depth,
                      reliability=ReliabilityPolicy.RELIABLE,
                      durability=DurabilityPolicy.VOLATILE)


SERVER_QOS = _service_qos(SERVER_DEPTH)
CLIENT_QOS = _service_qos(CLIENT_DEPTH)

# The Fast DDS XML profile of the package's node processes: reliable writers send a
# heartbeat every 100 ms (Fast DDS: 3 s), so that a reader that missed part of a
# sample gets it resent as soon as it reads again (doc/design.md section 16).
FASTDDS_PROFILE = os.path.join(os.path.dirname(os.path.abspath(__file__)),
                               'fastdds_profile.xml')
# Where Fast DDS (Jazzy: 2.14) looks for a profile file; a user's choice is kept.
FASTDDS_PROFILE_VARIABLE = 'FASTRTPS_DEFAULT_PROFILES_FILE'
# The rmw implementations that read it; none is set means rmw_fastrtps_cpp (Jazzy).
FASTDDS_RMWS = ('', 'rmw_fastrtps_cpp', 'rmw_fastrtps_dynamic_cpp')


def load_fastdds_profile() -> None:
    """
    Point Fast DDS at FASTDDS_PROFILE for this process.

    Call before ``rclpy.init``. Nothing changes when the process runs another rmw,
    or when the user already set FASTDDS_PROFILE_VARIABLE.
    """
    if (not os.environ.get(FASTDDS_PROFILE_VARIABLE)
            and os.environ.get('RMW_IMPLEMENTATION', '') in FASTDDS_RMWS):
        os.environ[FASTDDS_PROFILE_VARIABLE] = FASTDDS_PROFILE
