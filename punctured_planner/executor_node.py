"""
The plan_executor node: executes a published plan in lockstep over DDS.

A thin adapter around :class:`punctured_planner.execution.Execution`: it keeps
the plans it hears on ``plan`` (latched), each robot's latest ``<robot>/odom``,
and serves the ``execute_plan`` action (ExecutePlan). A control timer at
``control_rate`` runs one Execution step for the active goal and publishes
``<robot>/cmd_vel`` (mode ``velocity``; geometry_msgs/Twist in the robot's body
frame, rotated from the planning frame by its odometry orientation) and
``<robot>/reference_pose`` (PoseStamped at the shared clock, both modes).

Goal life: the plan is looked up (``NO_PLAN``), its tolerance checked
(``UNSAFE_PLAN``); the executor then waits up to ``discovery_timeout`` for
fresh odometry of every robot (``UNKNOWN_ROBOTS``) in the plan's frame
(``FRAME_MISMATCH``); then it runs until every robot has arrived (``NONE``),
a cancel (``CANCELED``: every robot is sent zero velocity from the cancel
callback itself, without waiting for the next tick), a newer goal
(``PREEMPTED``) or odometry in another frame (``FRAME_MISMATCH``). Stale
odometry never ends a goal: the clock holds until the robot is back.
Everything runs on one single-threaded executor, so callbacks never overlap.
"""

from collections import OrderedDict
from dataclasses import dataclass
from dataclasses import field
import sys

from geometry_msgs.msg import PoseStamped
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
import numpy as np
from punctured_planner_interfaces.action import ExecutePlan
from punctured_planner_interfaces.msg import Plan
from rcl_interfaces.msg import SetParametersResult
from rclpy.action import ActionServer
from rclpy.action import CancelResponse
from rclpy.action import GoalResponse
from rclpy.node import Node
from rclpy.task import Future
from scipy.spatial.transform import Rotation
from std_msgs.msg import Header

from . import conversions
from .execution import Execution
from .execution import ExecutionSettings
from .parameters import descriptor
from .parameters import node_values
from .parameters import parameter_value
from .parameters import Spec
from .planner_node import LATCHED
from .planner_node import STATE
from .spin import spin_node

NODE_NAME = 'plan_executor'
# Plans kept for goals that name an older one.
PLAN_HISTORY = 16
Result = ExecutePlan.Result

PARAMETERS = (
    Spec('mode', 'string', 'velocity',
         "'velocity': publish <robot>/cmd_vel (feed-forward + saturated feedback) and "
         "<robot>/reference_pose; 'reference': only <robot>/reference_pose, for robots "
         'with their own controller.', constraints="'velocity' or 'reference'"),
    Spec('control_rate', 'double', 20.0,
         'Rate of the control loop: clock step, commands, references, feedback (Hz).',
         low=1.0, high=1000.0),
    Spec('gain', 'double', 2.0,
         'Feedback gain on the position error (1/s).', low=0.0, high=100.0),
    Spec('speed_limit', 'double', 0.5,
         "The robots' speed limit (m/s): commands are saturated at it.", low=1e-6, high=1e3),
    Spec('slow_fraction', 'double', 0.3,
         'The clock runs at full rate while every tracking error is at most this fraction '
         'of the tolerance, slower above.', low=0.0, high=1.0),
    Spec('hold_fraction', 'double', 0.6,
         'The clock holds while some tracking error is at least this fraction of the '
         'tolerance (above slow_fraction).', low=0.0, high=1.0),
    Spec('goal_tolerance', 'double', 0.01,
         'A goal succeeds once the clock reached the end and every robot is this close to '
         'its last configuration (m).', low=1e-6, high=1e3),
    Spec('odom_timeout', 'double', 0.5,
         "A robot's odometry older than this (s, by arrival) is stale: the clock holds "
         'and the robot gets zero velocity until it is back.', low=1e-3, high=1e3),
    Spec('discovery_timeout', 'double', 5.0,
         'How long a new goal waits for odometry from every robot of the plan before it '
         'is refused with UNKNOWN_ROBOTS (s).', low=0.0, high=1e3),
    Spec('shared_clock', 'string', 'on',
         "'on': one plan clock for all robots, slowed and held by their errors; 'off': "
         "every robot follows the plan's stamps on its own (for comparison).",
         constraints="'on' or 'off'"),
)
SPECS = {spec.name: spec for spec in PARAMETERS}
_CHOICES = {'mode': ('velocity', 'reference'), 'shared_clock': ('on', 'off')}


@dataclass(frozen=True)
class ExecutorSettings:
    """The node's validated parameters."""

    mode: str
    control_rate: float
    odom_timeout: float
    discovery_timeout: float
    execution: ExecutionSettings


def settings_from_values(values: dict) -> ExecutorSettings:
    """Return ExecutorSettings from parameter values; raise ValueError with the reason."""
    v = {name: parameter_value(SPECS[name], value) for name, value in values.items()}
    for name, choices in _CHOICES.items():
        if v[name] not in choices:
            raise ValueError('%s must be one of %s, got %r'
                             % (name, ', '.join(choices), v[name]))
    if not v['slow_fraction'] < v['hold_fraction']:
        raise ValueError('slow_fraction %g must be below hold_fraction %g'
                         % (v['slow_fraction'], v['hold_fraction']))
    execution = ExecutionSettings(gain=v['gain'], speed_limit=v['speed_limit'],
                                  slow_fraction=v['slow_fraction'],
                                  hold_fraction=v['hold_fraction'],
                                  goal_tolerance=v['goal_tolerance'],
                                  shared_clock=v['shared_clock'] == 'on')
    return ExecutorSettings(v['mode'], v['control_rate'], v['odom_timeout'],
                            v['discovery_timeout'], execution)


@dataclass(frozen=True)
class KnownPlan:
    """A plan heard on ``plan``, ready to execute."""

    plan_id: int
    names: tuple
    frame_id: str
    reference: object   # execution.Reference
    bodies: object      # execution.Bodies
    min_gap: float
    tolerance: float


@dataclass(frozen=True)
class RobotOdometry:
    """The latest odometry of one robot."""

    position: np.ndarray
    orientation: np.ndarray
    frame_id: str
    received_ns: int


@dataclass
class Run:
    """The active goal: its plan, its Execution once started, and how it ended."""

    goal: object
    plan: KnownPlan
    requested_ns: int
    done: Future = field(default_factory=Future)
    execution: Execution = None
    started_ns: int = 0
    last_ns: int = 0
    stale: tuple = ()


class PlanExecutor(Node):
    """Serve ``execute_plan``; track the shared plan clock with every robot of the plan."""

    def __init__(self, **kwargs):
        """Declare the parameters, subscribe to ``plan``, serve the action, start the timer."""
        super().__init__(NODE_NAME, **kwargs)
        for spec in PARAMETERS:
            self.declare_parameter(spec.name, spec.default, descriptor(spec, read_only=(
                spec.name == 'control_rate')))
        self._settings = settings_from_values(node_values(self, SPECS))
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self._plans = OrderedDict()        # plan id -> KnownPlan
        self._odometry = {}                # robot name -> RobotOdometry
        self._links = {}                   # robot name -> (subscription, cmd_vel, reference)
        self._run = None
        self.create_subscription(Plan, 'plan', self._on_plan, LATCHED)
        self._server = ActionServer(self, ExecutePlan, 'execute_plan', self._execute,
                                    goal_callback=lambda goal: GoalResponse.ACCEPT,
                                    cancel_callback=self._on_cancel)
        self._timer = self.create_timer(1.0 / self._settings.control_rate, self._control)
        self.get_logger().info('serving %s, mode %s, control at %g Hz'
                               % (self.resolve_service_name('execute_plan'),
                                  self._settings.mode, self._settings.control_rate))

    # ------------------------------------------------------------ parameters

    def _on_set_parameters(self, parameters):
        """Refuse a change that makes the settings invalid; apply it at the next goal."""
        try:
            settings = settings_from_values(node_values(self, SPECS, parameters))
        except ValueError as error:
            return SetParametersResult(successful=False, reason=str(error))
        self._settings = settings
        return SetParametersResult(successful=True)

    # ------------------------------------------------------------ inputs

    def _on_plan(self, msg):
        """Keep a published plan (the last PLAN_HISTORY); subscribe to its robots' odometry."""
        try:
            reference = conversions.plan_reference(msg)
        except ValueError as error:
            self.get_logger().error('plan %d ignored: %s' % (msg.plan_id, error))
            return
        frame = msg.paths[0].header.frame_id
        plan = KnownPlan(int(msg.plan_id), tuple(msg.robot_names), frame, reference,
                         conversions.plan_bodies(msg), float(msg.min_gap),
                         float(msg.tracking_tolerance))
        self._plans.pop(plan.plan_id, None)
        self._plans[plan.plan_id] = plan
        while len(self._plans) > PLAN_HISTORY:
            self._plans.popitem(last=False)
        for name in plan.names:
            self._link(name)
        self.get_logger().info('plan %d: %d robots, %.3f s, min gap %.6g m, tolerance %.6g m'
                               % (plan.plan_id, len(plan.names), reference.duration,
                                  plan.min_gap, plan.tolerance))

    def _link(self, name):
        """Create the odometry subscription and command publishers of a robot (once)."""
        if name in self._links:
            return
        subscription = self.create_subscription(
            Odometry, name + '/odom', lambda msg, name=name: self._on_odometry(name, msg),
            STATE)
        self._links[name] = (subscription, self.create_publisher(Twist, name + '/cmd_vel', 10),
                             self.create_publisher(PoseStamped, name + '/reference_pose', 10))

    def _on_odometry(self, name, msg):
        position, orientation = conversions.odometry_pose(msg)
        self._odometry[name] = RobotOdometry(position, orientation, msg.header.frame_id,
                                             self.get_clock().now().nanoseconds)

    # ------------------------------------------------------------ the action

    def _on_cancel(self, goal):
        """Accept a cancel of the active goal and stop every robot at once."""
        run = self._run
        if run is not None and run.goal is goal:
            self._stop_robots(run.plan.names)
            self._finish(run, Result.CANCELED, 'canceled at plan time %.3f s'
                         % (run.execution.plan_time if run.execution else 0.0))
        return CancelResponse.ACCEPT

    async def _execute(self, goal):
        """Run one goal to its end; return its ExecutePlan result."""
        previous = self._run
        if previous is not None:
            self._stop_robots(previous.plan.names)
            self._finish(previous, Result.PREEMPTED, 'preempted by a newer goal')
        plan, code, message = self._lookup(goal.request.plan_id)
        if code == Result.NONE:
            run = Run(goal, plan, self.get_clock().now().nanoseconds)
            self._run = run
            result = await run.done
        else:
            result = Result(error_code=code, error_msg=message,
                            plan_id=plan.plan_id if plan else goal.request.plan_id)
        if result.error_code == Result.NONE:
            goal.succeed()
        elif result.error_code == Result.CANCELED and goal.is_cancel_requested:
            goal.canceled()
        else:
            goal.abort()
        line = 'goal for plan %d: error %d: %s' % (result.plan_id, result.error_code,
                                                   result.error_msg)
        if result.error_code == Result.NONE:
            self.get_logger().info(line)
        else:
            self.get_logger().warning(line)
        return result

    def _lookup(self, plan_id):
        """Return (KnownPlan or None, code, message) for a goal's plan id (0: the latest)."""
        if not self._plans:
            return None, Result.NO_PLAN, 'no plan received yet on %s' % (
                self.resolve_topic_name('plan'))
        if plan_id == 0:
            plan = next(reversed(self._plans.values()))
        elif plan_id in self._plans:
            plan = self._plans[plan_id]
        else:
            return None, Result.NO_PLAN, 'plan %d is not there (known plans: %s)' % (
                plan_id, ', '.join(str(i) for i in self._plans))
        if not plan.tolerance > 0:
            return plan, Result.UNSAFE_PLAN, (
                'plan %d has min_gap %.6g m, tracking tolerance %.6g m: its bodies touch '
                'even when executed exactly' % (plan.plan_id, plan.min_gap, plan.tolerance))
        return plan, Result.NONE, ''

    def _finish(self, run, code, message):
        """End a run with a result (once); the goal's coroutine resumes with it."""
        if run.done.done():
            return
        if self._run is run:
            self._run = None
        execution = run.execution
        now = self.get_clock().now().nanoseconds
        result = Result(error_code=code, error_msg=message, plan_id=run.plan.plan_id,
                        executed_duration=conversions.duration_from_seconds(
                            (now - run.started_ns) * 1e-9 if run.started_ns else 0.0))
        if execution is not None:
            result.max_tracking_errors = execution.max_errors.tolist()
            result.min_gap = float(execution.min_gap)
        run.done.set_result(result)

    # ------------------------------------------------------------ the control loop

    def _states(self, plan, now_ns):
        """Return (positions (k, 3), orientations (k, 4), stale names, wrong-frame message)."""
        k = len(plan.names)
        positions = plan.reference.position(0.0).copy()
        orientations = np.tile([0.0, 0.0, 0.0, 1.0], (k, 1))
        stale = []
        timeout_ns = self._settings.odom_timeout * 1e9
        for i, name in enumerate(plan.names):
            odometry = self._odometry.get(name)
            if odometry is None or now_ns - odometry.received_ns > timeout_ns:
                stale.append(name)
                continue
            if odometry.frame_id and odometry.frame_id != plan.frame_id:
                return None, None, stale, ('odometry of %s is in frame %r, the plan in %r'
                                           % (name, odometry.frame_id, plan.frame_id))
            positions[i] = odometry.position
            orientations[i] = odometry.orientation
        return positions, orientations, stale, ''

    def _control(self):
        """One control step of the active goal (the timer)."""
        run = self._run
        if run is None:
            return
        try:
            self._control_run(run)
        except Exception as error:  # noqa: B902 - a bug ends the goal, not the node
            self._stop_robots(run.plan.names)
            self._finish(run, Result.UNKNOWN, 'internal error: %s: %s'
                         % (type(error).__name__, error))

    def _control_run(self, run):
        now = self.get_clock().now().nanoseconds
        plan = run.plan
        positions, orientations, stale, wrong_frame = self._states(plan, now)
        if wrong_frame:
            self._stop_robots(plan.names)
            self._finish(run, Result.FRAME_MISMATCH, wrong_frame)
            return
        if run.execution is None:
            if stale:
                if now - run.requested_ns > self._settings.discovery_timeout * 1e9:
                    self._finish(run, Result.UNKNOWN_ROBOTS, 'no odometry within %g s from '
                                 '%s (topics %s)' % (
                                     self._settings.discovery_timeout, ', '.join(stale),
                                     ', '.join(self.resolve_topic_name(n + '/odom')
                                               for n in stale)))
                return
            run.execution = Execution(plan.reference, plan.tolerance,
                                      self._settings.execution, plan.bodies)
            run.started_ns = run.last_ns = now
            self.get_logger().info('executing plan %d: %d robots, %.3f s'
                                   % (plan.plan_id, len(plan.names), plan.reference.duration))
        stale_mask = np.array([name in stale for name in plan.names])
        step = run.execution.step((now - run.last_ns) * 1e-9, positions, stale_mask)
        run.last_ns = now
        if tuple(stale) != run.stale:
            if stale:
                self.get_logger().warning('plan clock held at %.3f s: odometry of %s is '
                                          'older than %g s' % (step.plan_time, ', '.join(stale),
                                                               self._settings.odom_timeout))
            else:
                self.get_logger().info('odometry back; plan clock resumes at %.3f s'
                                       % step.plan_time)
            run.stale = tuple(stale)
        self._publish_step(plan, step, orientations, now)
        feedback = ExecutePlan.Feedback(
            plan_time=step.plan_time, plan_duration=plan.reference.duration,
            clock_rate=step.rate, max_tracking_errors=run.execution.max_errors.tolist(),
            min_gap=float(run.execution.min_gap), stale_robots=list(stale))
        run.goal.publish_feedback(feedback)
        if step.finished:
            self._stop_robots(plan.names)
            self._finish(run, Result.NONE, 'plan %d executed' % plan.plan_id)

    def _publish_step(self, plan, step, orientations, now_ns):
        """Publish every robot's reference pose and, in mode velocity, its body-frame command."""
        header = Header(frame_id=plan.frame_id, stamp=conversions.time_from_ns(now_ns))
        body = Rotation.from_quat(orientations).apply(step.velocities, inverse=True)
        velocity_mode = self._settings.mode == 'velocity'
        for i, name in enumerate(plan.names):
            _, cmd_vel, reference = self._links[name]
            pose = PoseStamped(header=header)
            x, y, z = step.positions[i].tolist()
            pose.pose.position.x, pose.pose.position.y, pose.pose.position.z = x, y, z
            qx, qy, qz, qw = step.orientations[i].tolist()
            o = pose.pose.orientation
            o.x, o.y, o.z, o.w = qx, qy, qz, qw
            reference.publish(pose)
            if velocity_mode:
                twist = Twist()
                twist.linear.x, twist.linear.y, twist.linear.z = body[i].tolist()
                cmd_vel.publish(twist)

    def _stop_robots(self, names):
        """Send zero velocity to every named robot (mode velocity)."""
        if self._settings.mode != 'velocity':
            return
        for name in names:
            self._links[name][1].publish(Twist())

    def stop(self):
        """Stop the robots of the active goal (on shutdown)."""
        run = self._run
        if run is not None:
            self._stop_robots(run.plan.names)


def main(args=None):
    """Run plan_executor until Ctrl-C or SIGTERM; return 0, or 2 for invalid parameters."""
    return spin_node(PlanExecutor, NODE_NAME, args)


if __name__ == '__main__':
    sys.exit(main())
