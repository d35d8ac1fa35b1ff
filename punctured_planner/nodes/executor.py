"""
The plan_executor node: executes a published plan in lockstep over DDS.

A thin adapter around :class:`punctured_planner.execution.Execution`: it keeps
the plans it hears on ``plan`` (latched; :class:`punctured_planner.ros.goals.PlanStore`),
each robot's latest ``<robot>/odom``, and serves the ``execute_plan`` action
(ExecutePlan). A control timer at ``control_rate`` runs one Execution step for
the active goal and publishes ``<robot>/cmd_vel`` (mode ``velocity``;
geometry_msgs/Twist in the robot's body frame, rotated from the planning frame
by its odometry orientation; for a differential robot (``drive``) only
linear.x and angular.z, linear.y exactly 0) and ``<robot>/reference_pose``
(PoseStamped at the shared clock, both modes).

Goal life: the plan is looked up (``NO_PLAN`` once ``PLAN_WAIT_SEC`` passed
without it: the planner answers before it publishes, so a goal may name a plan
still on its way; at once, with the reason, if the message was no plan), its
tolerance checked (``UNSAFE_PLAN``), ``drive``, ``max_speeds`` and
``max_accelerations`` checked against its robots (``UNKNOWN_ROBOTS``: neither
one value nor one per robot); the executor then waits up to
``discovery_timeout`` for fresh odometry of every robot (``UNKNOWN_ROBOTS``) in
the plan's frame (``FRAME_MISMATCH``), each within the plan's tracking
tolerance of its start (``NOT_AT_START``: the certificate holds from there
only); then it runs until every robot has arrived (``NONE``), a cancel
(``CANCELED``: every robot is sent zero velocity from the cancel callback
itself, without waiting for the next tick), a newer goal (``PREEMPTED``),
odometry in another frame (``FRAME_MISMATCH``), odometry stale for longer than
``hold_timeout`` (``ODOMETRY_LOST``: the clock held that long, every robot is
sent zero velocity) or a clock held that long with every robot's odometry
fresh (``CLOCK_HELD``: a robot that cannot follow), one hold whatever its
cause. Odometry whose position is not finite or whose orientation is no
rotation is ignored (warned). From the first control step that finds a
robot's odometry older than ``odom_timeout`` the clock goes to a hold, braking
within the plan's acceleration limit with the stale robot on its feed-forward
alone (execution.Execution).
Plans are taken from ``plan`` (deserialised) and converted on a companion node,
``<name>_plans`` (same namespace), spun in its own thread, and handed to the node
through a guard condition: a plan of 42,000 poses a robot took 3.5 s to take and
convert, and the control loop sent no command that long. Everything else runs on
one single-threaded executor, so those callbacks never overlap.
A goal still waiting for its plan ends at once when canceled (``CANCELED``),
when a newer goal comes (``PREEMPTED``: the newest goal always wins) or at a
stop; the mode (``velocity`` or ``reference``) holds for a goal's whole run.
On Ctrl-C or SIGTERM new goals are rejected, the active goal's robots are
sent zero velocity, and every accepted goal (running, waiting, or not started
yet) ends with ``STOPPED`` (the runtime's ``before_stop`` hook, while the node
still spins, until every result is out); ``before_teardown`` sends zero
velocity once more before the node goes.
"""

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from dataclasses import field
import functools
import math
import sys
import time
from typing import Any

from geometry_msgs.msg import PoseStamped
from geometry_msgs.msg import Twist
from nav_msgs.msg import Odometry
from punctured_planner_interfaces.action import ExecutePlan
from punctured_planner_interfaces.msg import Plan
from rclpy.action import ActionServer
from rclpy.action import CancelResponse
from rclpy.action import GoalResponse
from rclpy.action.server import ServerGoalHandle
from rclpy.context import Context
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.subscription import Subscription
from rclpy.task import Future

from ..execution import Execution
from ..execution import Step
from ..execution.execution import differential_mask
from ..execution.execution import leaving_their_plane
from ..execution.execution import WrongCount
from ..execution.hold import ClockHold
from ..execution.hold import off_start
from ..execution.hold import period_overrun
from ..execution.hold import still_moving
from ..execution.hold import waited_for
from ..ros import conversions
from ..ros.goals import fleet_state
from ..ros.goals import FleetState
from ..ros.goals import InvalidPlan
from ..ros.goals import KnownPlan
from ..ros.goals import Lookup
from ..ros.goals import PLAN_HISTORY
from ..ros.goals import PlanStore
from ..ros.parameters import NodeParameters
from ..ros.parameters import robot_topics_refused
from ..ros.qos import COMMANDS
from ..ros.qos import latched
from ..ros.qos import STATE
from ..ros.runtime import companion
from ..ros.runtime import NodeGroup
from ..ros.runtime import REQUEST_GRACE_SEC
from ..ros.runtime import run_nodes
from ..ros.settings import EXECUTOR
from ..ros.settings import ExecutorSettings
from ..ros.snapshot import RobotOdometry
from ..ros.topics import CMD_VEL
from ..ros.topics import ODOM
from ..ros.topics import REFERENCE_POSE
from ..ros.topics import robot_topic

Result = ExecutePlan.Result
# Seconds a goal waits for a plan it names that was not heard yet (msg_docs/topics.md).
PLAN_WAIT_SEC = 5.0


@dataclass
class Run:
    """The active goal: its plan, its Execution once started, and how it ended."""

    goal: Any
    plan: KnownPlan
    requested_ns: int
    mode: str  # the mode parameter as the goal started: it holds to the end
    done: Future = field(default_factory=Future)
    execution: Execution | None = None
    started_ns: int = 0
    last_ns: int = 0
    stale: tuple = ()
    hold: ClockHold = field(default_factory=ClockHold)  # the plan clock's current hold


@dataclass(eq=False)
class PlanWait:
    """A goal waiting for its plan: the plan id (0: any), and a Future for the wait's end."""

    plan_id: int
    goal: Any
    heard: Future = field(default_factory=Future)  # done when the wait ends, for any reason

    def wake(self) -> None:
        """End the wait (its plan came, the time ran out, a cancel, a newer goal, a stop)."""
        if not self.heard.done():
            self.heard.set_result(True)


@dataclass(frozen=True)
class HeardPlan:
    """A message heard on ``plan``: its id, and the plan, or why it is none."""

    plan_id: int
    plan: KnownPlan | None
    problem: str = ''


@dataclass(frozen=True)
class RobotLink:
    """One robot's topics: its odometry subscription, command and reference publishers."""

    odometry: Subscription
    cmd_vel: Publisher
    reference: Publisher


class PlanExecutor(Node):
    """Serve ``execute_plan``; track the shared plan clock with every robot of the plan."""

    def __init__(self, **kwargs: Any) -> None:
        """Declare the parameters, subscribe to ``plan``, serve the action, start the timer."""
        super().__init__(EXECUTOR.node_name, **kwargs)
        self._node_parameters = NodeParameters(self, EXECUTOR)
        self._plans = PlanStore()
        self._odometry: dict[str, RobotOdometry] = {}
        self._links: dict[str, RobotLink] = {}
        self._run: Run | None = None
        self._waits: list[PlanWait] = []  # the goals waiting for their plan
        self._newest: ServerGoalHandle | None = None  # the goal that came last
        self._stopping = False  # the process is stopping: no new goal
        self._halted: Run | None = None  # the goal ended by the stop
        # The ids of the accepted goals whose result is not out yet (goal handles compare by
        # value and are not hashable), and, once a stop began, the Future done when none is.
        self._unfinished: set[bytes] = set()
        self._all_out: Future | None = None
        self._last_result = -math.inf  # time.monotonic() when the last result went out
        # Plans heard and converted in the plans' thread, oldest first: appended there,
        # taken in the node's (a deque's append and popleft are atomic).
        self._heard: deque[HeardPlan] = deque()
        self._plans_heard = self.create_guard_condition(self._take_plans)
        self.plans = companion(self, 'plans')
        self.plans.create_subscription(Plan, 'plan', self._on_plan, latched(PLAN_HISTORY))
        self._server = ActionServer(self, ExecutePlan, 'execute_plan', self._execute,
                                    goal_callback=self._on_goal,
                                    handle_accepted_callback=self._on_accepted,
                                    cancel_callback=self._on_cancel)
        self._timer = self.create_timer(1.0 / self._settings.control_rate, self._control)
        self.get_logger().info('serving %s, mode %s, control at %g Hz'
                               % (self.resolve_service_name('execute_plan'),
                                  self._settings.mode, self._settings.control_rate))

    @property
    def _settings(self) -> ExecutorSettings:
        """
        Return the accepted parameters.

        The mode holds for a goal's whole run, and the execution settings (gain, limits,
        fractions, goal_tolerance, drive) from its first control step with every robot
        heard; the timeouts (odom, hold, discovery) apply from the next step.
        """
        return self._node_parameters.settings

    # ------------------------------------------------------------ inputs

    def _on_plan(self, msg: Plan) -> None:
        """
        In the plans' thread: convert a published plan and hand it to the node.

        A plan whose robot topics rcl refuses in this namespace is no plan: subscribing
        to them raised, which ended the node.
        """
        try:
            plan = conversions.known_plan(msg)
        except InvalidPlan as error:
            heard = HeardPlan(msg.plan_id, None, str(error))
        else:
            refused = next(filter(None, (robot_topics_refused(self.plans, name)
                                         for name in plan.names)), '')
            heard = (HeardPlan(msg.plan_id, None, 'plan %d: %s' % (msg.plan_id, refused))
                     if refused else HeardPlan(msg.plan_id, plan))
        self._heard.append(heard)
        self._plans_heard.trigger()

    def _take_plans(self) -> None:
        """
        Keep the plans heard (the last PLAN_HISTORY); subscribe to their robots' odometry.

        A message that is not a plan is kept as ignored, with the reason, for the goals
        that name it (or the latest plan): they end NO_PLAN saying why.
        """
        while self._heard:
            heard = self._heard.popleft()
            plan = heard.plan
            if plan is None:
                self.get_logger().error('plan %d ignored: %s' % (heard.plan_id, heard.problem))
                self._plans.ignore(heard.plan_id, heard.problem)
                self._wake_waits(heard.plan_id)
                continue
            self._plans.add(plan)
            self._wake_waits(plan.plan_id)
            for name in plan.names:
                self._link(name)
            self.get_logger().info(
                'plan %d: %d robots, %.3f s, min gap %.6g m, tolerance %.6g m'
                % (plan.plan_id, len(plan.names), plan.reference.duration, plan.min_gap,
                   plan.tolerance))

    def _wake_waits(self, plan_id: int) -> None:
        """End the waits of the goals for plan_id or for the latest plan: it was heard."""
        for wait in self._waits:
            if wait.plan_id in (0, plan_id):
                wait.wake()

    def _odometry_topics(self, names: Sequence[str]) -> str:
        """Return the robots' odometry topics, resolved, for a message."""
        return ', '.join(self.resolve_topic_name(robot_topic(name, ODOM)) for name in names)

    def _link(self, name: str) -> None:
        """Create the odometry subscription and command publishers of a robot (once)."""
        if name in self._links:
            return
        self._links[name] = RobotLink(
            self.create_subscription(Odometry, robot_topic(name, ODOM),
                                     functools.partial(self._on_odometry, name), STATE),
            self.create_publisher(Twist, robot_topic(name, CMD_VEL), COMMANDS),
            self.create_publisher(PoseStamped, robot_topic(name, REFERENCE_POSE), COMMANDS))

    def _on_odometry(self, name: str, msg: Odometry) -> None:
        """
        Keep a robot's latest odometry; ignore one whose pose is no pose (warned).

        A NaN position made the clock jump to the plan's end and every robot get NaN
        velocities for good; ignored, it leaves the robot's last good odometry to age
        (stale after odom_timeout, the goal ODOMETRY_LOST after hold_timeout).
        """
        odometry = conversions.robot_odometry(msg, self.get_clock().now().nanoseconds)
        problem = odometry.problem()
        if problem:
            self.get_logger().warning('odometry of %s ignored: %s' % (name, problem),
                                      throttle_duration_sec=1.0)
            return
        self._odometry[name] = odometry

    # ------------------------------------------------------------ the action

    def _on_goal(self, goal: ExecutePlan.Goal) -> GoalResponse:
        """Accept every goal, unless the process is stopping."""
        return GoalResponse.REJECT if self._stopping else GoalResponse.ACCEPT

    def _on_accepted(self, goal: ServerGoalHandle) -> None:
        """Note an accepted goal until its result is out, then execute it."""
        self._unfinished.add(bytes(goal.goal_id.uuid))
        goal.execute()

    def _on_cancel(self, goal: ServerGoalHandle) -> CancelResponse:
        """Accept a cancel: of the active goal, its robots stopped at once; of a waiting one."""
        run = self._run
        if run is not None and run.goal is goal:
            self._end(run, Result.CANCELED, 'canceled at plan time %.3f s'
                      % (run.execution.plan_time if run.execution else 0.0))
        for wait in self._waits:
            if wait.goal is goal:
                wait.wake()
        return CancelResponse.ACCEPT

    async def _execute(self, goal: ServerGoalHandle) -> ExecutePlan.Result:
        """Run one goal to its end; return its ExecutePlan result."""
        try:
            return await self._goal_result(goal)
        finally:
            # The action server sends the result as this coroutine returns, in the same step.
            self._unfinished.discard(bytes(goal.goal_id.uuid))
            self._last_result = time.monotonic()
            if self._all_out is not None and not self._unfinished:
                self._all_out.set_result(True)

    async def _goal_result(self, goal: ServerGoalHandle) -> ExecutePlan.Result:
        """Return a goal's result, its goal handle ended (succeed, canceled or abort)."""
        # A cancel or a stop that came before the goal started.
        if goal.is_cancel_requested:
            return self._ended(goal, Lookup(None, Result.CANCELED, 'canceled before it started'))
        if self._stopping:
            return self._ended(goal, Lookup(None, Result.STOPPED,
                                            'plan_executor stopped before the goal started'))
        previous = self._run
        if previous is not None:
            self._end(previous, Result.PREEMPTED, 'preempted by a newer goal')
        self._newest = goal
        for waiting in self._waits:  # superseded: they end PREEMPTED (_waited)
            waiting.wake()
        found = self._plans.lookup(goal.request.plan_id, self.resolve_topic_name('plan'))
        if not self._plans.heard(goal.request.plan_id):  # it may be on its way
            found = await self._wait_for_plan(PlanWait(goal.request.plan_id, goal))
        if found.runnable is not None:
            found = self._check_per_robot(found.runnable)
        if found.runnable is None:
            return self._ended(goal, found)
        run = Run(goal, found.runnable, self.get_clock().now().nanoseconds,
                  mode=self._settings.mode)
        self._run = run
        return self._finished(goal, await run.done)

    def _ended(self, goal: ServerGoalHandle, found: Lookup) -> ExecutePlan.Result:
        """End a goal that does not run with its Lookup's code and message."""
        return self._finished(goal, Result(
            error_code=found.code, error_msg=found.message,
            plan_id=found.plan.plan_id if found.plan else goal.request.plan_id))

    def _finished(self, goal: ServerGoalHandle,
                  result: ExecutePlan.Result) -> ExecutePlan.Result:
        """End the goal handle as its result says (succeed, canceled or abort); log it."""
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

    async def _wait_for_plan(self, wait: PlanWait) -> Lookup:
        """
        Wait up to PLAN_WAIT_SEC for the goal's plan (0: any) on ``plan``; look it up.

        The wait ends early when the goal is canceled, a newer goal comes or the
        process stops: then the goal ends CANCELED, PREEMPTED or STOPPED.
        """
        self._waits.append(wait)
        timer = self.create_timer(PLAN_WAIT_SEC, wait.wake)
        try:
            await wait.heard
        finally:
            self.destroy_timer(timer)
            self._waits.remove(wait)
        plan_id = wait.plan_id
        if wait.goal.is_cancel_requested:
            return Lookup(None, Result.CANCELED, 'canceled while waiting for plan %d' % plan_id)
        if self._stopping:
            return Lookup(None, Result.STOPPED, 'plan_executor stopped while waiting for '
                          'plan %d' % plan_id)
        if self._newest is not wait.goal:
            return Lookup(None, Result.PREEMPTED, 'preempted by a newer goal while waiting for '
                          'plan %d' % plan_id)
        return self._plans.lookup(plan_id, self.resolve_topic_name('plan'))

    def _check_per_robot(self, plan: KnownPlan) -> Lookup:
        """
        Return plan with NONE, or UNKNOWN_ROBOTS if drive has not one value or one per robot.

        The same for max_speeds and max_accelerations (which may also be empty), and for
        a differential robot whose path leaves its plane (z): it was accepted, and never
        arrived.
        """
        settings, count = self._settings.execution, len(plan.names)
        try:
            differential = differential_mask(settings.drive, count)
            settings.limits(count)
        except WrongCount as error:
            reason = str(error)
        else:
            climbing = leaving_their_plane(differential, plan.reference)
            if not climbing.size:
                return Lookup(plan, Result.NONE)
            reason = ('drive makes %s differential, and a differential robot moves in its '
                      'plane only: its path changes z'
                      % ', '.join(plan.names[i] for i in climbing))
        return Lookup(plan, Result.UNKNOWN_ROBOTS, 'plan %d has robots %s: %s'
                      % (plan.plan_id, ', '.join(plan.names), reason))

    def _end(self, run: Run, code: int, message: str) -> None:
        """Stop the run's robots, then end its goal with code and message."""
        self._stop_robots(run)
        self._finish(run, code, message)

    def _finish(self, run: Run, code: int, message: str) -> None:
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
            self._warn_beyond_tolerance(run.plan, execution)
        run.done.set_result(result)

    def _warn_beyond_tolerance(self, plan: KnownPlan, execution: Execution) -> None:
        """Log the robots whose tracking error passed the tolerance: the gap was not kept."""
        beyond = execution.beyond_tolerance()
        if beyond.size:
            self.get_logger().warning(
                'plan %d: tracking errors beyond the tolerance %.4g m: %s; its bodies were '
                'kept only min_gap - 2 x the largest, %.4g m, apart' % (
                    plan.plan_id, plan.tolerance, ', '.join(
                        '%s %.4g m' % (plan.names[i], execution.max_errors[i])
                        for i in beyond),
                    plan.min_gap - 2.0 * float(execution.max_errors.max())))

    # ------------------------------------------------------------ the control loop

    def _control(self) -> None:
        """One control step of the active goal (the timer)."""
        run = self._run
        if run is None:
            return
        try:
            self._control_run(run)
        except Exception as error:  # noqa: B902 - a bug ends the goal, not the node
            self._end(run, Result.UNKNOWN, 'internal error: %s: %s'
                      % (type(error).__name__, error))

    def _control_run(self, run: Run) -> None:
        """Start the goal's Execution once every robot reported, then step and publish it."""
        now = self.get_clock().now().nanoseconds
        plan, settings = run.plan, self._settings
        state = fleet_state(plan, self._odometry, now, settings.odom_timeout)
        if state.wrong_frame is not None:
            self._stop_robots(run)
            self._finish(run, Result.FRAME_MISMATCH, state.wrong_frame.describe())
            return
        execution = run.execution if run.execution is not None else self._start(run, state, now)
        if execution is None:
            return
        dt = (now - run.last_ns) * 1e-9
        step = execution.step(dt, state.positions, state.stale_mask, state.orientations,
                              state.ages)
        run.last_ns = now
        if self._hold_expired(run, step, state, now, dt):
            return
        self._log_stale(run, state, step.plan_time)
        self._publish_step(run, step, state, now)
        run.goal.publish_feedback(ExecutePlan.Feedback(
            plan_time=step.plan_time, plan_duration=execution.reference.duration,
            clock_rate=step.rate, max_tracking_errors=execution.max_errors.tolist(),
            min_gap=float(execution.min_gap), stale_robots=list(state.stale)))
        if step.finished:
            self._stop_robots(run)
            self._finish(run, Result.NONE, 'plan %d executed' % plan.plan_id)

    def _start(self, run: Run, state: FleetState, now: int) -> Execution | None:
        """
        Start the run's Execution once every robot reported and is at rest.

        UNKNOWN_ROBOTS, or NOT_AT_START for a robot still moving, after discovery_timeout;
        the per-robot settings are checked again (they may have changed while it waited).
        Return the started Execution, or None while waiting (or once refused).
        """
        settings, plan = self._settings, run.plan
        waited = now - run.requested_ns > settings.discovery_timeout * 1e9
        if state.stale:
            if waited:
                self._finish(run, Result.UNKNOWN_ROBOTS, 'no odometry within %g s from %s '
                             '(topics %s)' % (settings.discovery_timeout, ', '.join(state.stale),
                                              self._odometry_topics(state.stale)))
            return None
        # a goal that preempts a moving one waits for the robots to stop: its plan starts
        # at rest
        moving = still_moving(state.speeds)
        if moving.size:
            if waited:
                self._finish(run, Result.NOT_AT_START, 'still moving %g s after the goal '
                             'came: %s; plan %d starts at rest' % (
                                 settings.discovery_timeout, ', '.join(
                                     '%s at %.3f m/s' % (plan.names[i], state.speeds[i])
                                     for i in moving), plan.plan_id))
            return None
        per_robot = self._check_per_robot(plan)
        if per_robot.code != Result.NONE:  # drive, max_speeds or max_accelerations changed
            self._finish(run, per_robot.code, per_robot.message)
            return None
        far = off_start(plan.reference, state.positions, plan.tolerance)
        if far.robots.size:
            self._finish(run, Result.NOT_AT_START, '%s farther than the tracking tolerance '
                         '%.6g m from the start of plan %d (%s): the plan is certified from '
                         'its start only; plan again from where they are (use_current_state)'
                         % ('robot' if far.robots.size == 1 else 'robots', plan.tolerance,
                            plan.plan_id, ', '.join(
                                '%s %.3f m' % (plan.names[i], distance)
                                for i, distance in zip(far.robots, far.distances))))
            return None
        execution = Execution(plan.reference, plan.tolerance, settings.execution, plan.bodies)
        run.execution = execution
        run.started_ns = run.last_ns = now
        self.get_logger().info('executing plan %d: %d robots, %.3f s (%.3f s as timed for '
                               'the robots)' % (plan.plan_id, len(plan.names),
                                                plan.reference.duration,
                                                execution.reference.duration))
        overrun = period_overrun(execution.corners, plan.tolerance, settings.hold_fraction,
                                 1.0 / settings.control_rate)
        if overrun.robots.size:
            self.get_logger().warning(
                'plan %d: in one control period (%g Hz) the reference of %s moves farther '
                'than the %.4g m that (1 - hold_fraction) of the tracking tolerance %.4g m '
                'leaves: a robot that stops following can pass the tolerance before the '
                'clock holds; lower max_speeds or raise control_rate' % (
                    plan.plan_id, settings.control_rate, ', '.join(
                        '%s (%.4g m)' % (plan.names[i], distance)
                        for i, distance in zip(overrun.robots, overrun.distances)),
                    overrun.margin, plan.tolerance))
        return execution

    def _hold_expired(self, run: Run, step: Step, state: FleetState, now: int,
                      dt: float) -> bool:
        """
        End the goal once the clock held hold_timeout, every robot sent zero velocity.

        One hold, whatever holds the clock (execution.hold.ClockHold):
        ODOMETRY_LOST if some robot's odometry went stale during it, else
        CLOCK_HELD, naming the robots the clock waits for.
        """
        timeout = self._settings.hold_timeout
        over = run.hold.update(step.allowed, state.stale, now * 1e-9, dt, timeout)
        if over is None:
            return False
        held_at = 'the plan clock held %.3f s at plan time %.3f s, hold_timeout %g s' % (
            over.seconds, step.plan_time, timeout)
        if over.stale:
            self._end(run, Result.ODOMETRY_LOST, 'odometry of %s stale (older than %g s; '
                      'topics %s): %s; every robot was sent zero velocity'
                      % (', '.join(over.stale), self._settings.odom_timeout,
                         self._odometry_topics(over.stale), held_at))
            return True
        plan, limit = run.plan, run.plan.tolerance * self._settings.execution.hold_fraction
        waited = waited_for(step.watched, limit)
        self._end(run, Result.CLOCK_HELD, '%s, the odometry fresh: the clock waits for %s '
                  '(hold_fraction x the tracking tolerance: %.6g m); every robot was sent '
                  'zero velocity' % (held_at, ', '.join(
                      '%s %.3f m behind' % (plan.names[i], step.watched[i]) for i in waited),
                      limit))
        return True

    def _log_stale(self, run: Run, state: FleetState, plan_time: float) -> None:
        """Say when the plan clock holds for stale odometry, and when it resumes."""
        if state.stale == run.stale:
            return
        if state.stale:
            self.get_logger().warning('plan clock holding from %.3f s: odometry of %s is '
                                      'older than %g s' % (plan_time, ', '.join(state.stale),
                                                           self._settings.odom_timeout))
        else:
            self.get_logger().info('odometry back; plan clock resumes at %.3f s' % plan_time)
        run.stale = state.stale

    def _publish_step(self, run: Run, step: Step, state: FleetState, now_ns: int) -> None:
        """
        Publish every robot's reference pose and, in mode velocity, its body-frame command.

        A differential robot gets (forward, 0, 0) and its yaw rate: never a sideways part.
        """
        plan = run.plan
        header = conversions.header(plan.frame_id, now_ns)
        commands = step.body_commands(state.orientations) if run.mode == 'velocity' else None
        for i, name in enumerate(plan.names):
            link = self._links[name]
            link.reference.publish(conversions.pose_stamped(header, step.positions[i],
                                                            step.orientations[i]))
            if commands is not None:
                link.cmd_vel.publish(conversions.twist(commands[i], step.yaw_rates[i]))

    def _stop_robots(self, run: Run) -> None:
        """Send zero velocity to every robot of the run (mode velocity, as it started)."""
        if run.mode != 'velocity':
            return
        for name in run.plan.names:
            self._links[name].cmd_vel.publish(conversions.twist())

    def end_goals(self) -> Future | None:
        """
        Refuse new goals; end every goal STOPPED, the active one's robots stopped (before_stop).

        Every accepted goal: running, waiting for its plan, or not started yet (it ends
        as it starts). Return the Future that is done once every result is out: done
        already when none is pending but a result went out within REQUEST_GRACE_SEC
        (the stop's grace spin then answers a client asking for it a moment late: one
        that asked after its cancel's reply, at a stop, got nothing in 1 of 3 runs);
        None otherwise.
        """
        self._stopping = True
        for wait in self._waits:
            wait.wake()
        run = self._run
        if run is not None:
            self._halted = run
            self._end(run, Result.STOPPED, 'plan_executor stopped at plan time %.3f s; its '
                      'robots were sent zero velocity'
                      % (run.execution.plan_time if run.execution else 0.0))
        if self._unfinished:
            self._all_out = Future()
            return self._all_out
        if time.monotonic() - self._last_result > REQUEST_GRACE_SEC:
            return None
        just_out = Future()
        just_out.set_result(True)
        return just_out

    def stop_halted_robots(self) -> None:
        """Send zero velocity again to the robots end_goals stopped: the last command they get."""
        if self._halted is not None:
            self._stop_robots(self._halted)


def executor_nodes(context: Context | None = None, **kwargs: Any) -> NodeGroup:
    """Return the executor and its plans' node: at a stop its goal ends STOPPED."""
    node = PlanExecutor(context=context, **kwargs)
    return NodeGroup([node, node.plans], before_stop=node.end_goals,
                     before_teardown=node.stop_halted_robots)


def main(args: list[str] | None = None) -> int:
    """Run plan_executor until Ctrl-C or SIGTERM; return 0, or 2 for invalid parameters."""
    return run_nodes(EXECUTOR, executor_nodes, args=args)


if __name__ == '__main__':
    sys.exit(main())
