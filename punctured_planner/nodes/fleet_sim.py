"""
The fleet_sim node: simulated disc robots over DDS, holonomic or differential, for tests and demos.

A thin adapter around :class:`punctured_planner.sim.Fleet`: ``<robot>/cmd_vel``
(geometry_msgs/Twist) in; ``<robot>/odom`` (nav_msgs/Odometry), ``robot_states``
(geometry_msgs/PoseArray) and ``~/min_gap`` (std_msgs/Float64, the true
smallest surface gap between bodies so far, latched) out, every step at
``rate``. Every new contact is logged with the bodies and the gap. Robots
named in ``muted_robots`` keep moving but publish no odometry (a dropped link),
settable at run time. A differential robot (``drive``) takes only linear.x and
angular.z, like a real base: a non-zero linear.y is ignored, and logged once per
robot; its odometry carries its heading (yaw) and its body-frame twist.
Nothing to do before teardown: a simulated robot without commands stops by itself.
"""

import functools
import sys
from typing import Any

from geometry_msgs.msg import PoseArray
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
import numpy as np
from rclpy.context import Context
from rclpy.node import Node
from std_msgs.msg import Float64

from ..ros import conversions
from ..ros.parameters import NodeParameters
from ..ros.qos import COMMANDS
from ..ros.qos import LATCHED
from ..ros.runtime import NodeGroup
from ..ros.runtime import run_nodes
from ..ros.settings import FLEET_SIM
from ..ros.settings import FleetSimSettings
from ..ros.topics import CMD_VEL
from ..ros.topics import ODOM
from ..ros.topics import robot_topic
from ..sim import Fleet


class FleetSim(Node):
    """Simulate the fleet at ``rate``: commands in, odometry, states and the true gap out."""

    def __init__(self, **kwargs: Any) -> None:
        """Declare the parameters, build the fleet, subscribe and advertise per robot."""
        super().__init__(FLEET_SIM.node_name, **kwargs)
        self._node_parameters = NodeParameters(self, FLEET_SIM, self._apply_parameters)
        settings = self._node_parameters.settings
        self._names = settings.robot_names
        self._fleet = Fleet(settings.initial, settings.fleet())
        self._period = 1.0 / settings.rate
        self._start_ns = self.get_clock().now().nanoseconds
        self._last_ns = self._start_ns
        self._odometry = []
        self._sideways_logged: set[int] = set()
        for i, name in enumerate(self._names):
            self.create_subscription(Twist, robot_topic(name, CMD_VEL),
                                     functools.partial(self._on_command, i), COMMANDS)
            self._odometry.append(
                self.create_publisher(Odometry, robot_topic(name, ODOM), COMMANDS))
        self._states = self.create_publisher(PoseArray, 'robot_states', COMMANDS)
        self._gap = self.create_publisher(Float64, '~/min_gap', LATCHED)
        self._timer = self.create_timer(self._period, self._step)
        self.get_logger().info('%d robots in frame %s at %g Hz; initial gap %.6g m'
                               % (len(self._names), settings.frame_id, settings.rate,
                                  self._fleet.min_gap))

    def _seconds(self, now_ns: int) -> float:
        return (now_ns - self._start_ns) * 1e-9

    def _apply_parameters(self, settings: FleetSimSettings, changed: set[str]) -> None:
        """Post-set: the fleet's physics (frame and muted robots are read at every step)."""
        self._fleet.configure(settings.fleet())

    def _on_command(self, robot: int, msg: Twist) -> None:
        velocity = np.array([msg.linear.x, msg.linear.y, msg.linear.z])
        if not np.all(np.isfinite(velocity)) or not np.isfinite(msg.angular.z):
            self.get_logger().warning('%s/cmd_vel: non-finite velocity ignored'
                                      % self._names[robot])
            return
        if (self._fleet.differential[robot] and msg.linear.y != 0.0
                and robot not in self._sideways_logged):
            self._sideways_logged.add(robot)
            self.get_logger().warning('%s/cmd_vel: linear.y = %g ignored: a differential '
                                      'robot cannot move sideways (logged once)'
                                      % (self._names[robot], msg.linear.y))
        self._fleet.command(robot, velocity, self._seconds(self.get_clock().now().nanoseconds),
                            msg.angular.z)

    def _step(self) -> None:
        """One simulation step and its messages (the timer); a bug is logged, not fatal."""
        try:
            self._step_and_publish()
        except Exception as error:  # noqa: B902 - the simulator keeps running
            self.get_logger().error('step failed: %s: %s' % (type(error).__name__, error))

    def _step_and_publish(self) -> None:
        now_ns = self.get_clock().now().nanoseconds
        dt = min((now_ns - self._last_ns) * 1e-9, 5 * self._period)
        self._last_ns = now_ns
        for contact in self._fleet.step(self._seconds(now_ns) - dt, dt):
            other = (self._names[contact.second] if contact.kind == 'robots'
                     else 'obstacle %d' % contact.second)
            self.get_logger().warning('contact at t = %.3f s: %s and %s, gap %.4f m'
                                      % (contact.time, self._names[contact.first], other,
                                         contact.gap))
        settings = self._node_parameters.settings
        header = conversions.header(settings.frame_id, now_ns)
        states = PoseArray(header=header)
        fleet = self._fleet
        orientations, twists = fleet.orientations, fleet.body_velocities
        for i, name in enumerate(self._names):
            odometry = conversions.odometry(header, name + '/base_link', fleet.positions[i],
                                            twists[i], orientations[i], fleet.yaw_rates[i])
            states.poses.append(odometry.pose.pose)
            if name not in settings.muted_robots:
                self._odometry[i].publish(odometry)
        self._states.publish(states)
        self._gap.publish(Float64(data=float(self._fleet.min_gap)))


def fleet_sim_nodes(context: Context | None = None, **kwargs: Any) -> NodeGroup:
    """Return the simulator's node."""
    return NodeGroup([FleetSim(context=context, **kwargs)])


def main(args: list[str] | None = None) -> int:
    """Run fleet_sim until Ctrl-C or SIGTERM; return 0, or 2 for invalid parameters."""
    return run_nodes(FLEET_SIM, fleet_sim_nodes, args=args)


if __name__ == '__main__':
    sys.exit(main())
