"""
The parameter table of each node: planner_node, plan_executor and fleet_sim.

Each node's settings are one frozen dataclass whose fields are its parameter
specs (:meth:`punctured_planner.ros.parameters.Spec.field`: the default is
the field's), read back by a :class:`~punctured_planner.ros.parameters.Table`
with the node's cross-parameter checks. msg_docs/parameters.md,
msg_docs/plan_executor.md and msg_docs/fleet_sim.md show these tables row for
row. No rclpy here (only the rcl_interfaces messages of the descriptors):
``punctured-planner plan`` reads a parameter file into the planner's settings
offline.
"""

from dataclasses import dataclass

import numpy as np

from .parameters import FRAME_ID
from .parameters import InvalidParameter
from .parameters import lengths
from .parameters import OBSTACLE_RADIUS
from .parameters import OBSTACLES
from .parameters import ROBOT_RADIUS
from .parameters import ros_names
from .parameters import Spec
from .parameters import Table
from .parameters import within
from .wording import WallNames
from ..core import VARIANTS
from ..core.errors import PlanningError
from ..core.errors import Wall
from ..core.walls import checked_bounds
from ..execution import Bodies
from ..execution import DRIVES
from ..execution import ExecutionSettings
from ..execution.execution import differential_mask
from ..execution.execution import one_or_each
from ..execution.execution import per_robot
from ..execution.execution import WrongCount
from ..sim import FleetSettings

# The variant parameter's default: 'discs' with a robot radius, else 'spread'.
AUTO = 'auto'
# Largest samples_per_leg a parameter or a request may ask for.
MAX_SAMPLES_PER_LEG = 1000
# The fastest max_speed (m/s), the parameter's and a request's: far beyond it the stamps,
# 1 ns apart at least, outlast the motion's duration.
MAX_SPEED = 1e6


@dataclass(frozen=True)
class PlannerSettings:
    """planner_node's parameters: a validated, immutable snapshot of the node's values."""

    frame_id: str = FRAME_ID.field()
    dimension: int = Spec(
        'dimension', 'integer', 2,
        'Dimension d of the planning space: 2 (planar, z fixed at plane_z) or 3.',
        low=2, high=3).field()
    plane_z: float = Spec(
        'plane_z', 'double', 0.0,
        'z of the plane in planar mode (dimension 2): every input z must equal it '
        '(within 1e-9).', low=-1e9, high=1e9).field()
    robot_names: tuple = Spec(
        'robot_names', 'string_array', [],
        "Robot names: '<name>/plan' topics and '<name>/odom' subscriptions, in robot "
        'order; empty: robot_0..robot_{k-1} and no odometry.', check=ros_names,
        prose='unique ROS names; robot_count must be 0 or their number').field()
    robot_count: int = Spec(
        'robot_count', 'integer', 0,
        'Number of robots every request must have; 0: any (taken from the request), '
        'or the number of robot_names when they are set.', low=0, high=1000000).field()
    obstacles: tuple = OBSTACLES.field()
    variant: str = Spec(
        'variant', 'string', AUTO,
        "Planner variant: 'discs' (disc robots and pillars: bodies never touch under "
        "the separation condition of doc/design.md section 6), 'spread' (clearance-aware "
        "spreading leg) or 'paper' (the paper's construction exactly); all give the "
        "same domain index. 'auto': 'discs' when robot_radius > 0, else 'spread'.",
        choices=(AUTO,) + VARIANTS).field()
    robot_radius: float = ROBOT_RADIUS.field()
    obstacle_radius: tuple = OBSTACLE_RADIUS.field()
    lane_spacing: float = Spec(
        'lane_spacing', 'double', 1.0,
        'Paper and spread variants: spacing of the lanes the robots slide along (m); 1 '
        'gives the paper heights. The discs variant spaces its lanes as its slots '
        '(min_spacing).',
        low=1e-6, high=1e6).field()
    min_spacing: float = Spec(
        'min_spacing', 'double', 0.5,
        'Spread variant: spacing g the spreading leg aims for between robots on the '
        'axis and from the obstacles (m). Discs variant: the pitch of its staging slots '
        'and lanes, at least 2.1 robot radii.', low=1e-6, high=1e6).field()
    required_clearance: float = Spec(
        'required_clearance', 'double', 0.0,
        'Refuse a plan whose certified smallest gap is below this (m): the surface gap '
        '(min_gap) where robots or obstacles have a radius, else the centre distance '
        '(min_clearance); 0 accepts every collision-free plan.',
        low=0.0, high=1e6, check=lengths).field()
    workspace_bounds: tuple = Spec(
        'workspace_bounds', 'double_array', [],
        'Walls of the workspace (m), in frame_id: [x_min, x_max, y_min, y_max] for '
        'dimension 2, then z_min, z_max for 3; every robot (its disc) and pillar must stay '
        'inside, inputs and plans outside are refused (OUTSIDE_WORKSPACE); empty: no walls.',
        prose='empty, or a min below its max for each of the dimension axes; finite').field()
    refine: bool = Spec(
        'refine', 'bool', True,
        "Refine the construction's motion (doc/design.md section 14): shorter, in the "
        "same domain, its gap never below the construction's; false: the construction's "
        'own motion.', prose='true or false').field()
    max_state_age: float = Spec(
        'max_state_age', 'double', 0.5,
        'Largest age (s, by arrival on the node clock) of the robot state a '
        'use_current_state request may start from; older is refused (NO_ROBOT_STATE). '
        '0 switches the check off: unsafe, a robot may be planned from where it was.',
        low=0.0, high=1e6).field()
    repeat_tolerance: float = Spec(
        'repeat_tolerance', 'double', 1e-3,
        'With use_current_state, leading request configurations whose every robot is '
        'within this distance (m) of the current state are dropped before planning '
        '(reported in dropped_configurations).', low=0.0, high=1e6).field()
    max_speed: float = Spec(
        'max_speed', 'double', 1.0,
        "Speed of the fastest robot on each leg (m/s) when a request's max_speed is "
        '<= 0.', low=1e-6, high=MAX_SPEED).field()
    max_acceleration: float = Spec(
        'max_acceleration', 'double', 0.0,
        "Acceleration limit of every robot (m/s^2) the stamps respect: each leg's speed "
        'rises and falls at most this fast, at rest at the start and the end, slowed into '
        'every corner (doc/design.md section 8); 0: unlimited, every leg at max_speed.',
        low=0.0, high=1e6).field()
    samples_per_leg: int = Spec(
        'samples_per_leg', 'integer', 0,
        "Extra poses between consecutive breakpoints when a request's samples_per_leg "
        'is < 0.', low=0, high=MAX_SAMPLES_PER_LEG).field()
    max_robots: int = Spec(
        'max_robots', 'integer', 10000,
        'Largest number of robots a request may have (REQUEST_OVER_LIMITS above).',
        low=1, high=1000000).field()
    max_configurations: int = Spec(
        'max_configurations', 'integer', 1000,
        'Largest number of configurations in a request, the current state included '
        '(REQUEST_OVER_LIMITS above).', low=2, high=1000000).field()
    max_poses: int = Spec(
        'max_poses', 'integer', 2000000,
        'Largest number of poses in all paths of one answer, robots x poses per path '
        '(REQUEST_OVER_LIMITS above).', low=1, high=1000000000).field()

    @property
    def core_variant(self) -> str:
        """Return the core variant to plan with: 'auto' resolved by robot_radius."""
        if self.variant != AUTO:
            return self.variant
        return 'discs' if self.robot_radius > 0 else 'spread'

    @property
    def core_obstacle_radius(self) -> float | tuple:
        """Return the core's obstacle_radius: a scalar (0 or the one value), or one each."""
        if len(self.obstacle_radius) <= 1:
            return self.obstacle_radius[0] if self.obstacle_radius else 0.0
        return self.obstacle_radius

    @property
    def core_bounds(self) -> np.ndarray | None:
        """
        Return workspace_bounds as the core's (d, 2) [min, max] per axis, or None.

        An odd count of values stays flat: the core's check then says which
        shape it expected and which it got.
        """
        if not self.workspace_bounds:
            return None
        values = np.asarray(self.workspace_bounds, dtype=float)
        return values.reshape(-1, 2) if values.size % 2 == 0 else values

    @property
    def expected_robot_count(self) -> int:
        """Return the robot count requests must have, or 0 when any count is fine."""
        return len(self.robot_names) or self.robot_count


def _planner_robot_count(settings: PlannerSettings) -> None:
    """Refuse a robot_count other than robot_names'; more robots than max_robots."""
    if settings.robot_names and settings.robot_count not in (0, len(settings.robot_names)):
        raise InvalidParameter(('robot_count', 'robot_names'),
                               'robot_count %d differs from the %d robot_names; set robot_count '
                               'to 0 or to their number' % (settings.robot_count,
                                                            len(settings.robot_names)))
    if settings.expected_robot_count > settings.max_robots:
        raise InvalidParameter(('max_robots', 'robot_count', 'robot_names'),
                               '%d robots configured but max_robots is %d'
                               % (settings.expected_robot_count, settings.max_robots))


def _planner_bounds(settings: PlannerSettings) -> None:
    """Refuse workspace_bounds the core refuses (its one rule), or a count not 2 per axis."""
    try:
        checked_bounds(settings.core_bounds, settings.dimension)
    except PlanningError as error:  # its reason without the code, the wall by its entry
        raise InvalidParameter(('workspace_bounds', 'dimension'),
                               'workspace_bounds %r for dimension %d (%s): %s'
                               % (list(settings.workspace_bounds), settings.dimension,
                                  ', '.join(Wall(axis, high).name
                                            for axis in range(settings.dimension)
                                            for high in (False, True)),
                                  error.describe(WallNames()))) from None


PLANNER = Table('planner_node', PlannerSettings,
                checks=(_planner_robot_count, _planner_bounds))


def _drives(name: str, value: tuple) -> None:
    """Refuse an empty drive list or an entry that is not a known drive."""
    if not value:
        raise InvalidParameter(name, '%s must hold one value or one per robot, got []' % name)
    bad = [i for i, item in enumerate(value) if item not in DRIVES]
    if bad:
        raise InvalidParameter(name, '%s[%d] = %r is not one of %s'
                               % (name, bad[0], value[bad[0]], ', '.join(DRIVES)), index=bad[0])


# The robots' drive, for the executor's tracking law and the simulator's kinematics alike.
DRIVE = Spec(
    'drive', 'string_array', ['holonomic'],
    "How the robots move: 'holonomic' (any planar velocity) or 'differential' (forward "
    'speed linear.x and yaw rate angular.z only: a unicycle); one value for all, or one '
    'per robot in robot order.', check=_drives,
    prose="'holonomic' or 'differential': one, or one per robot")
YAW_RATE_LIMIT = Spec(
    'yaw_rate_limit', 'double', ExecutionSettings.yaw_rate_limit,
    "Differential robots' yaw-rate limit (rad/s).", low=1e-6, high=1e3)


@dataclass(frozen=True)
class ExecutorSettings:
    """plan_executor's parameters."""

    mode: str = Spec(
        'mode', 'string', 'velocity',
        "'velocity': publish <robot>/cmd_vel (feed-forward + saturated feedback) and "
        "<robot>/reference_pose; 'reference': only <robot>/reference_pose, for robots "
        'with their own controller.', choices=('velocity', 'reference')).field()
    control_rate: float = Spec(
        'control_rate', 'double', 20.0,
        'Rate of the control loop: clock step, commands, references, feedback (Hz).',
        low=1.0, high=1000.0, read_only=True).field()
    gain: float = Spec(
        'gain', 'double', ExecutionSettings.gain,
        'Feedback gain on the position error (1/s).', low=0.0, high=100.0).field()
    speed_limit: float = Spec(
        'speed_limit', 'double', ExecutionSettings.speed_limit,
        "The robots' speed limit (m/s): commands are saturated at it.",
        low=1e-6, high=1e3).field()
    slow_fraction: float = Spec(
        'slow_fraction', 'double', ExecutionSettings.slow_fraction,
        'The clock runs at full rate while every tracking error is at most this fraction '
        'of the tolerance, slower above.', low=0.0, high=1.0).field()
    hold_fraction: float = Spec(
        'hold_fraction', 'double', ExecutionSettings.hold_fraction,
        'The clock holds while some tracking error is at least this fraction of the '
        'tolerance (above slow_fraction).', low=0.0, high=1.0).field()
    goal_tolerance: float = Spec(
        'goal_tolerance', 'double', ExecutionSettings.goal_tolerance,
        'A goal succeeds once the clock reached the end and every robot is this close to '
        'its last configuration (m).', low=1e-6, high=1e3).field()
    odom_timeout: float = Spec(
        'odom_timeout', 'double', 0.5,
        "A robot's odometry older than this (s, by arrival) is stale: the clock holds "
        "(braking within the plan's acceleration limit, the stale robot on its "
        'feed-forward alone) until it is back.', low=1e-3, high=1e3).field()
    discovery_timeout: float = Spec(
        'discovery_timeout', 'double', 5.0,
        'How long a new goal waits for odometry from every robot of the plan before it '
        'is refused with UNKNOWN_ROBOTS, and for every robot to be at rest before it is '
        'refused with NOT_AT_START (s).', low=0.0, high=1e3).field()
    hold_timeout: float = Spec(
        'hold_timeout', 'double', 5.0,
        'How long the plan clock may hold during a goal (s): then every robot gets zero '
        'velocity (mode velocity) and the goal aborts, with ODOMETRY_LOST for stale '
        'odometry, else with CLOCK_HELD (a robot that does not follow).',
        low=0.0, high=1e3).field()
    shared_clock: str = Spec(
        'shared_clock', 'string', 'on',
        "'on': one plan clock for all robots, slowed and held by their errors; 'off': "
        "every robot follows the plan's stamps on its own (for comparison).",
        choices=('on', 'off')).field()
    drive: tuple = DRIVE.field()
    yaw_rate_limit: float = YAW_RATE_LIMIT.field()
    final_heading: str = Spec(
        'final_heading', 'string', 'request',
        "'request': after the plan's end every differential robot turns in place to the "
        "orientation of its last pose (the request's; identity faces +x); 'none': it "
        'stops facing where it arrived.', choices=('request', 'none')).field()
    feedforward_adaptation: float = Spec(
        'feedforward_adaptation', 'double', ExecutionSettings.feedforward_adaptation,
        "How fast (1/s) each robot's feed-forward gain grows while it lags behind its "
        'moving reference by more than slow_fraction of the tolerance (and falls back '
        'toward 1 while it is ahead), up to 4: a robot that achieves a fraction f of its '
        'commands gets about 1/f of the feed-forward; 0: off.', low=0.0, high=100.0).field()
    max_speeds: tuple = Spec(
        'max_speeds', 'double_array', [],
        "Each robot's own top speed (m/s), one value for all or one per robot in plan "
        "order; empty: the plan's max_speed. The clock runs on the plan retimed so that no "
        "robot's reference is faster than its own (none faster than the plan).",
        check=within(1e-6, 1e3), prose='empty, one, or one per robot, in [1e-06, 1000]').field()
    max_accelerations: tuple = Spec(
        'max_accelerations', 'double_array', [],
        "Each robot's own acceleration limit (m/s^2), one value for all or one per robot; "
        "empty: the plan's max_acceleration. The plan is retimed for 0.6 of it (the rest is "
        "the feedback's), like max_speeds: one stamped without an acceleration limit too.",
        check=within(1e-6, 1e3),
        prose='empty, one, or one per robot, in [1e-06, 1000]').field()

    @property
    def execution(self) -> ExecutionSettings:
        """Return the tracking law's settings."""
        return ExecutionSettings(gain=self.gain, speed_limit=self.speed_limit,
                                 slow_fraction=self.slow_fraction,
                                 hold_fraction=self.hold_fraction,
                                 goal_tolerance=self.goal_tolerance,
                                 shared_clock=self.shared_clock == 'on', drive=self.drive,
                                 yaw_rate_limit=self.yaw_rate_limit,
                                 final_heading=self.final_heading == 'request',
                                 feedforward_adaptation=self.feedforward_adaptation,
                                 max_speeds=self.max_speeds,
                                 max_accelerations=self.max_accelerations)


def _slow_below_hold(settings: ExecutorSettings) -> None:
    """Refuse a slow_fraction not below hold_fraction: the clock slows before it holds."""
    if not settings.slow_fraction < settings.hold_fraction:
        raise InvalidParameter(('slow_fraction', 'hold_fraction'),
                               'slow_fraction %g must be below hold_fraction %g'
                               % (settings.slow_fraction, settings.hold_fraction))


EXECUTOR = Table('plan_executor', ExecutorSettings, checks=(_slow_below_hold,))


@dataclass(frozen=True)
class FleetSimSettings:
    """fleet_sim's parameters; those that shape the fleet itself are read-only."""

    frame_id: str = FRAME_ID.field()
    robot_names: tuple = Spec(
        'robot_names', 'string_array', [],
        "The robots: '<name>/cmd_vel' in, '<name>/odom' out, in robot order.",
        check=ros_names, prose='unique ROS names, one per initial position',
        read_only=True).field()
    initial_positions: tuple = Spec(
        'initial_positions', 'double_array', [],
        'Start positions as a flat list x0, y0, z0, x1, ... (one x, y, z per robot).',
        prose='3 values per robot name, finite', read_only=True).field()
    robot_radius: float = ROBOT_RADIUS.field()
    obstacles: tuple = OBSTACLES.field()
    obstacle_radius: tuple = OBSTACLE_RADIUS.field()
    speed_limit: float = Spec(
        'speed_limit', 'double', FleetSettings.speed_limit,
        'Largest speed a robot executes (m/s); faster commands are scaled down.',
        low=0.0, high=1e3).field()
    speed_factors: tuple = Spec(
        'speed_factors', 'double_array', [],
        'Per robot, the fraction of the commanded velocity it achieves (0.5: a slow '
        'robot); empty: all 1.', check=within(0.0, 10.0),
        prose='empty or one per robot, in [0, 10]').field()
    latencies: tuple = Spec(
        'latencies', 'double_array', [],
        'Per robot, the delay before a command takes effect (s); empty: all 0.',
        check=within(0.0, 10.0), prose='empty or one per robot, in [0, 10]').field()
    velocity_noise: float = Spec(
        'velocity_noise', 'double', FleetSettings.velocity_noise,
        'Relative velocity noise: each axis of the velocity is multiplied by 1 + '
        'velocity_noise x N(0, 1) every step.', low=0.0, high=10.0).field()
    command_timeout: float = Spec(
        'command_timeout', 'double', FleetSettings.command_timeout,
        'A robot whose last command took effect longer ago than this stops (s).',
        low=1e-3, high=1e3).field()
    rate: float = Spec(
        'rate', 'double', 20.0,
        'Simulation and publishing rate (Hz).', low=1.0, high=1000.0, read_only=True).field()
    seed: int = Spec(
        'seed', 'integer', FleetSettings.seed,
        'Seed of the velocity noise.', low=0, high=2 ** 31 - 1, read_only=True).field()
    muted_robots: tuple = Spec(
        'muted_robots', 'string_array', [],
        'Robots whose odometry is not published (a dropped link); they keep moving. '
        'Settable at run time, like the physics parameters.',
        prose='names among robot_names').field()
    drive: tuple = DRIVE.field()
    yaw_rate_limit: float = YAW_RATE_LIMIT.field()
    max_acceleration: tuple = Spec(
        'max_acceleration', 'double_array', [],
        "The robots' linear acceleration limit (m/s^2), one value for all or one per "
        'robot: the executed velocity (holonomic) or forward speed (differential) moves '
        'toward the command at most this fast; 0 or empty: at once.',
        check=within(0.0, 1e3), prose='empty, one, or one per robot, in [0, 1000]').field()
    max_yaw_acceleration: float = Spec(
        'max_yaw_acceleration', 'double', FleetSettings.max_yaw_acceleration,
        "Differential robots' yaw acceleration limit (rad/s^2); 0: at once.",
        low=0.0, high=1e4).field()

    @property
    def initial(self) -> np.ndarray:
        """Return the start positions as (k, 3)."""
        return np.asarray(self.initial_positions, dtype=float).reshape(-1, 3)

    def fleet(self) -> FleetSettings:
        """
        Return the fleet's physics: bodies, speed limit and factors, latencies, noise.

        Raises WrongCount for a one-or-each setting of another count (drive,
        max_acceleration, obstacle_radius): _fleet_counts refuses those settings by it.
        """
        obstacles = np.asarray(self.obstacles, dtype=float).reshape(-1, 3)
        radii = one_or_each('obstacle_radius', self.obstacle_radius, len(obstacles),
                            'obstacles')
        bodies = Bodies(self.robot_radius, obstacles,
                        np.zeros(len(obstacles)) if radii is None else radii.astype(float))
        accelerations = per_robot('max_acceleration', self.max_acceleration,
                                  len(self.robot_names))
        return FleetSettings(
            bodies=bodies, speed_limit=self.speed_limit,
            speed_factors=np.asarray(self.speed_factors) if self.speed_factors else None,
            latencies=np.asarray(self.latencies) if self.latencies else None,
            velocity_noise=self.velocity_noise, command_timeout=self.command_timeout,
            seed=self.seed, differential=differential_mask(self.drive, len(self.robot_names)),
            yaw_rate_limit=self.yaw_rate_limit,
            max_acceleration=(np.zeros(len(self.robot_names)) if accelerations is None
                              else accelerations),
            max_yaw_acceleration=self.max_yaw_acceleration)


# The parameter whose length counts the items a one-or-each setting must fit.
_COUNTED_BY = {'robots': 'robot_names', 'obstacles': 'obstacles'}


def _fleet_counts(settings: FleetSimSettings) -> None:
    """Refuse other than 3 coordinates, one factor, latency and drive per robot; unknown muted."""
    count = len(settings.robot_names)
    if len(settings.initial_positions) != 3 * count:
        raise InvalidParameter(('initial_positions', 'robot_names'),
                               'initial_positions has %d values for %d robot_names (3 per '
                               'robot)' % (len(settings.initial_positions), count))
    for name in ('speed_factors', 'latencies'):
        values = getattr(settings, name)
        if values and len(values) != count:
            raise InvalidParameter((name, 'robot_names'), '%s has %d values for %d robots'
                                   % (name, len(values), count))
    try:  # the one-or-each settings, read where the simulator reads them
        settings.fleet()
    except WrongCount as error:  # the setting, and the parameter it must fit
        raise InvalidParameter((error.name, _COUNTED_BY[error.items]), str(error)) from error
    unknown = [(index, name) for index, name in enumerate(settings.muted_robots)
               if name not in settings.robot_names]
    if unknown:
        raise InvalidParameter(('muted_robots', 'robot_names'),
                               'muted_robots names %s, not among robot_names'
                               % ', '.join(name for _, name in unknown), index=unknown[0][0])


FLEET_SIM = Table('fleet_sim', FleetSimSettings, checks=(_fleet_counts,))
