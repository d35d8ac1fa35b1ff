"""
The fleet_sim node: simulated holonomic disc robots over DDS, for tests, demos and users.

A thin adapter around :class:`punctured_planner.sim.Fleet`: ``<robot>/cmd_vel``
(geometry_msgs/Twist) in; ``<robot>/odom`` (nav_msgs/Odometry), ``robot_states``
(geometry_msgs/PoseArray) and ``~/min_gap`` (std_msgs/Float64, the true
smallest surface gap between bodies so far, latched) out, every step at
``rate``. Every new contact is logged with the bodies and the gap. Robots
named in ``muted_robots`` keep moving but publish no odometry (a dropped link),
settable at run time.
"""

import sys

from geometry_msgs.msg import PoseArray
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
import numpy as np
from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node
from std_msgs.msg import Float64
from std_msgs.msg import Header

from . import conversions
from .execution import Bodies
from .parameters import descriptor
from .parameters import node_values
from .parameters import parameter_value
from .parameters import Spec
from .planner_node import LATCHED
from .sim import Fleet
from .sim import FleetSettings
from .spin import spin_node

NODE_NAME = 'fleet_sim'
# Parameters that shape the fleet itself: fixed once it is built.
_FIXED = ('robot_names', 'initial_positions', 'robot_radius', 'obstacles',
          'obstacle_radius', 'rate', 'seed')

PARAMETERS = (
    Spec('frame_id', 'string', 'map',
         'Frame of the odometry and robot_states (the planning frame); settable at run time.',
         constraints='non-empty'),
    Spec('robot_names', 'string_array', [],
         "The robots: '<name>/cmd_vel' in, '<name>/odom' out, in robot order.",
         constraints='unique ROS names, one per initial position'),
    Spec('initial_positions', 'double_array', [],
         'Start positions as a flat list x0, y0, z0, x1, ... (one x, y, z per robot).',
         constraints='3 values per robot name, finite'),
    Spec('robot_radius', 'double', 0.0,
         'Radius R of every robot body (m): the gap of two robots is their centre '
         'distance - 2R.', low=0.0, high=1e3),
    Spec('obstacles', 'double_array', [],
         'Obstacle centres as a flat list x0, y0, z0, ... (for the true gap).',
         constraints='length a multiple of 3, finite values'),
    Spec('obstacle_radius', 'double_array', [],
         "Radius rho of the obstacles (m), as planner_node's: empty for 0, one value for "
         'all, or one per obstacle; a robot-obstacle gap is centre distance - R - rho.',
         constraints='empty, one value or one per obstacle; finite, >= 0'),
    Spec('speed_limit', 'double', 0.5,
         'Largest speed a robot executes (m/s); faster commands are scaled down.',
         low=0.0, high=1e3),
    Spec('speed_factors', 'double_array', [],
         'Per robot, the fraction of the commanded velocity it achieves (0.5: a slow '
         'robot); empty: all 1.', constraints='empty or one per robot, in [0, 10]'),
    Spec('latencies', 'double_array', [],
         'Per robot, the delay before a command takes effect (s); empty: all 0.',
         constraints='empty or one per robot, in [0, 10]'),
    Spec('velocity_noise', 'double', 0.0,
         'Relative velocity noise: each axis of the velocity is multiplied by 1 + '
         'velocity_noise x N(0, 1) every step.', low=0.0, high=10.0),
    Spec('command_timeout', 'double', 0.5,
         'A robot whose last command took effect longer ago than this stops (s).',
         low=1e-3, high=1e3),
    Spec('rate', 'double', 20.0,
         'Simulation and publishing rate (Hz).', low=1.0, high=1000.0),
    Spec('seed', 'integer', 0,
         'Seed of the velocity noise.', low=0, high=2 ** 31 - 1),
    Spec('muted_robots', 'string_array', [],
         'Robots whose odometry is not published (a dropped link); they keep moving. '
         'Settable at run time, like the physics parameters.',
         constraints='names among robot_names'),
)
SPECS = {spec.name: spec for spec in PARAMETERS}


def _per_robot(values, name, count):
    """Return a per-robot array parameter as (k,) (empty: None); raise ValueError."""
    if not values:
        return None
    if len(values) != count:
        raise ValueError('%s has %d values for %d robots' % (name, len(values), count))
    bad = [i for i, value in enumerate(values) if not 0.0 <= value <= 10.0]
    if bad:
        raise ValueError('%s[%d] = %r is outside [0, 10]' % (name, bad[0], values[bad[0]]))
    return np.asarray(values, dtype=float)


def fleet_from_values(values: dict) -> tuple:
    """Return (names, initial positions (k, 3), FleetSettings, muted names); raise ValueError."""
    v = {name: parameter_value(SPECS[name], value) for name, value in values.items()}
    names = v['robot_names']
    positions = np.asarray(v['initial_positions'], dtype=float)
    if positions.size != 3 * len(names):
        raise ValueError('initial_positions has %d values for %d robot_names (3 per robot)'
                         % (positions.size, len(names)))
    bad = [i for i, value in enumerate(v['initial_positions']) if not np.isfinite(value)]
    if bad:
        raise ValueError('initial_positions[%d] is not finite' % bad[0])
    unknown = [name for name in v['muted_robots'] if name not in names]
    if unknown:
        raise ValueError('muted_robots names %s, not among robot_names' % ', '.join(unknown))
    obstacles = conversions.obstacles_from_parameter(v['obstacles'])
    radii = np.asarray(v['obstacle_radius'], dtype=float)
    if radii.size not in (0, 1, len(obstacles)):
        raise ValueError('obstacle_radius has %d values for %d obstacles (0, 1 or one each)'
                         % (radii.size, len(obstacles)))
    bodies = Bodies(v['robot_radius'], obstacles,
                    np.broadcast_to(radii if radii.size else 0.0, len(obstacles)).copy())
    settings = FleetSettings(
        bodies=bodies, speed_limit=v['speed_limit'],
        speed_factors=_per_robot(v['speed_factors'], 'speed_factors', len(names)),
        latencies=_per_robot(v['latencies'], 'latencies', len(names)),
        velocity_noise=v['velocity_noise'], command_timeout=v['command_timeout'],
        seed=v['seed'])
    return names, positions.reshape(-1, 3), settings, set(v['muted_robots'])


class FleetSim(Node):
    """Simulate the fleet at ``rate``: commands in, odometry, states and the true gap out."""

    def __init__(self, **kwargs):
        """Declare the parameters, build the fleet, subscribe and advertise per robot."""
        super().__init__(NODE_NAME, **kwargs)
        for spec in PARAMETERS:
            self.declare_parameter(spec.name, spec.default,
                                   descriptor(spec, read_only=spec.name in _FIXED))
        values = node_values(self, SPECS)
        self._names, positions, settings, self._muted = fleet_from_values(values)
        self._fleet = Fleet(positions, settings)
        self._frame_id = values['frame_id']
        self._period = 1.0 / values['rate']
        self._start_ns = self.get_clock().now().nanoseconds
        self._last_ns = self._start_ns
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self._odometry = []
        for i, name in enumerate(self._names):
            self.create_subscription(Twist, name + '/cmd_vel',
                                     lambda msg, i=i: self._on_command(i, msg), 10)
            self._odometry.append(self.create_publisher(Odometry, name + '/odom', 10))
        self._states = self.create_publisher(PoseArray, 'robot_states', 10)
        self._gap = self.create_publisher(Float64, '~/min_gap', LATCHED)
        self._timer = self.create_timer(self._period, self._step)
        self.get_logger().info('%d robots in frame %s at %g Hz; initial gap %.6g m'
                               % (len(self._names), self._frame_id, values['rate'],
                                  self._fleet.min_gap))

    def _seconds(self, now_ns):
        return (now_ns - self._start_ns) * 1e-9

    def _on_set_parameters(self, parameters):
        """Apply a change of the fleet's physics or muted robots at once, or refuse it."""
        values = node_values(self, SPECS, parameters)
        try:
            _, _, settings, muted = fleet_from_values(values)
        except ValueError as error:
            return SetParametersResult(successful=False, reason=str(error))
        self._fleet.configure(settings)
        self._muted = muted
        self._frame_id = values['frame_id']
        return SetParametersResult(successful=True)

    def _on_command(self, robot, msg):
        velocity = np.array([msg.linear.x, msg.linear.y, msg.linear.z])
        if not np.all(np.isfinite(velocity)):
            self.get_logger().warning('%s/cmd_vel: non-finite velocity ignored'
                                      % self._names[robot])
            return
        self._fleet.command(robot, velocity, self._seconds(self.get_clock().now().nanoseconds))

    def _step(self):
        """One simulation step and its messages (the timer); a bug is logged, not fatal."""
        try:
            self._step_and_publish()
        except Exception as error:  # noqa: B902 - the simulator keeps running
            self.get_logger().error('step failed: %s: %s' % (type(error).__name__, error))

    def _step_and_publish(self):
        now_ns = self.get_clock().now().nanoseconds
        dt = min((now_ns - self._last_ns) * 1e-9, 5 * self._period)
        self._last_ns = now_ns
        for contact in self._fleet.step(self._seconds(now_ns) - dt, dt):
            other = (self._names[contact.second] if contact.kind == 'robots'
                     else 'obstacle %d' % contact.second)
            self.get_logger().warning('contact at t = %.3f s: %s and %s, gap %.4f m'
                                      % (contact.time, self._names[contact.first], other,
                                         contact.gap))
        header = Header(frame_id=self._frame_id, stamp=conversions.time_from_ns(now_ns))
        states = PoseArray(header=header)
        for i, name in enumerate(self._names):
            odometry = Odometry(header=header, child_frame_id=name + '/base_link')
            pose = odometry.pose.pose
            pose.position.x, pose.position.y, pose.position.z = self._fleet.positions[i].tolist()
            pose.orientation.w = 1.0
            twist = odometry.twist.twist.linear
            twist.x, twist.y, twist.z = self._fleet.velocities[i].tolist()
            states.poses.append(pose)
            if name not in self._muted:
                self._odometry[i].publish(odometry)
        self._states.publish(states)
        self._gap.publish(Float64(data=float(self._fleet.min_gap)))

    def stop(self):
        """Nothing to leave safe: a simulated robot without commands stops by itself."""


def main(args=None):
    """Run fleet_sim until Ctrl-C or SIGTERM; return 0, or 2 for invalid parameters."""
    return spin_node(FleetSim, NODE_NAME, args)


if __name__ == '__main__':
    sys.exit(main())
