"""
The planner node: topics and parameters in, PlanSequence service, a Path per robot out.

A thin adapter: it keeps the latest obstacles, robot state and parameters under
one lock, takes one snapshot of them per request (logged with its stamps),
hands request and snapshot to :class:`punctured_planner.ros.planning.PlanSequenceHandler`
(the checks and the core) and publishes the result. No math here; every message
conversion is in :mod:`punctured_planner.ros.conversions`.

Obstacle rule: the latest of the two sources is the obstacle set. At start it
is the ``obstacles`` parameter; a message on the ``obstacles`` topic replaces
it; setting the parameter again replaces the topic's set, and so on.

Robot state rule (``use_current_state``): the newer of the last ``robot_states``
message and, when ``robot_names`` is set, the state assembled from every
robot's ``<name>/odom`` (complete once each robot has reported; as old as its
oldest message).

Concurrency: the subscriptions live on a companion node, ``<name>_inputs``
(``planner_node_inputs`` by default; same namespace and context), spun by its
own single-threaded executor in its own thread; the service (one plan at a
time) lives on ``<name>_server``, spun by another, and the node itself keeps
only its parameter services, on a thread of their own. Planning therefore
never blocks the subscriptions nor ``ros2 param``: a 2,000,000-pose request
held the service's thread 18 s, and a parameter get waited 16 s behind it when
both shared one. Not rclpy's MultiThreadedExecutor: in rclpy 7.1 it busy-
loops on subscription traffic (ros2/rclpy#1223, #1452), and measured here, with
obstacles and robot states at 50 Hz, service round trips went from 4 ms to 80
ms median with stalls of 2-6 s (two single-threaded executors: 3.4 ms, worst 6
ms). The publishers live on a third companion, ``<name>_outputs``, spun by a
fourth thread, which wakes only when a plan is to be published or one of their QoS
events fires (rclpy's default handlers log a subscriber with incompatible QoS or
type, two per publisher).
rclpy 7.1's executor looks each waitable of its nodes up in a plain list after
every wake-up: with one latched Path per robot, 1,026 waitables cost 7.7 ms per
wake-up against 0.07 ms for 2 (measured), about 6 ms per request at k = 512 on
the service's executor; on the inputs node, which wakes with every message of
its 50 Hz streams, that would be most of a core. A plan is answered first;
then the request's outcome is logged and the plan handed to the outputs' thread,
which publishes the answered plans in the order they were answered, each complete
and in the order of topics msg_docs/topics.md gives, while the service's thread
takes the next request (publishing a 1.99 M-pose plan had held it 20 s). Start
and stop (Ctrl-C and SIGTERM alike, threads joined before anything is destroyed):
:func:`punctured_planner.ros.runtime.run_nodes`.
"""

from collections import deque
from dataclasses import dataclass
import functools
import gc
import sys
import threading
import traceback
from typing import Any
import warnings

from geometry_msgs.msg import PoseArray
from nav_msgs.msg import Odometry
from nav_msgs.msg import Path
from punctured_planner_interfaces.msg import Plan
from punctured_planner_interfaces.srv import PlanSequence
from rclpy.context import Context
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.subscription import Subscription
from std_msgs.msg import UInt32
from visualization_msgs.msg import MarkerArray

from ..core import PlanningError
from ..core.errors import counted
from ..ros import conversions
from ..ros import publications
from ..ros.goals import PLAN_HISTORY
from ..ros.parameters import NodeParameters
from ..ros.planning import PlanSequenceHandler
from ..ros.planning import refuse_stopping
from ..ros.qos import LATCHED
from ..ros.qos import latched
from ..ros.qos import SERVER_QOS
from ..ros.qos import STATE
from ..ros.runtime import companion
from ..ros.runtime import NodeGroup
from ..ros.runtime import run_nodes
from ..ros.runtime import Stop
from ..ros.settings import PLANNER
from ..ros.settings import PlannerSettings
from ..ros.snapshot import ObstacleSet
from ..ros.snapshot import Outcome
from ..ros.snapshot import RobotOdometry
from ..ros.snapshot import RobotState
from ..ros.snapshot import Snapshot
from ..ros.snapshot import take_snapshot
from ..ros.topics import ODOM
from ..ros.topics import PLAN
from ..ros.topics import robot_topic
from ..ros.wording import ObstacleNames
# rmw_fastrtps waits up to 100 ms for the client's response reader to be matched,
# then drops the reply; rclpy reports that with this warning (doc/design.md section 15).
SEND_TIMEOUT_WARNING = 'failed to send response (timeout)'
# Attempts at sending one reply: up to 1 s for a new client's reader to be matched.
SEND_ATTEMPTS = 10


@dataclass(frozen=True)
class AfterReply:
    """A request's outcome to log (and publish, if planned) once its reply is sent."""

    number: int
    outcome: Outcome
    settings: PlannerSettings


class PlannerNode(Node):
    """Serve ``plan_sequence``; publish each robot's Path, the domain index and markers."""

    def __init__(self, **kwargs: Any) -> None:
        """Declare the parameters, subscribe, advertise; raise ValueError for bad parameters."""
        super().__init__(PLANNER.node_name, **kwargs)
        self._lock = threading.Lock()
        self._handler = PlanSequenceHandler()
        self._request_count = 0
        self._plan_count = 0
        self._robot_states: RobotState | None = None
        self._odometry: dict[str, RobotOdometry] = {}
        self._obstacles: ObstacleSet  # from the parameters, two lines below
        self._node_parameters = NodeParameters(self, PLANNER, self._apply_parameters,
                                               self._check_obstacles_fit)
        self._settings: PlannerSettings = self._node_parameters.settings
        self._obstacles = self._parameter_obstacles(self._settings)

        # The service's, the subscriptions' and the publishers' own nodes: each spun
        # apart, and apart from the parameter services (module docstring).
        self.server = companion(self, 'server')
        self.inputs = companion(self, 'inputs')
        self.outputs = companion(self, 'outputs')
        self.inputs.create_subscription(PoseArray, 'obstacles', self._on_obstacles, LATCHED)
        self.inputs.create_subscription(PoseArray, 'robot_states', self._on_robot_states,
                                        STATE)
        self._odometry_subscriptions: dict[str, Subscription] = {}
        self._update_odometry_subscriptions()
        # A robot_names change re-subscribes in the inputs' own thread: destroying a
        # subscription from the parameters' thread while that thread's executor built its
        # wait set raised InvalidHandle there and stopped the node (exit 1; 1,000 names
        # set back to 4, 2 of 2 times).
        self._robot_names_changed = self.inputs.create_guard_condition(
            self._update_odometry_subscriptions)
        self._latched_publishers: dict[str, Publisher] = {}  # relative topic -> publisher
        self._latched_names: list[str] = []
        for topic, msg_type in (('domain_index', UInt32), ('plan_markers', MarkerArray),
                                ('plan', Plan)):
            self._publisher(topic, msg_type)
        self._service = self.server.create_service(PlanSequence, 'plan_sequence',
                                                   self._on_plan_sequence,
                                                   qos_profile=SERVER_QOS)
        # The executor sends the callback's reply through this attribute: through
        # _send_response, so that no reply is dropped without an error in the log.
        self._send = self._service.send_response
        self._service.send_response = self._send_response  # type: ignore[method-assign]
        self._answering = 0  # the number of the request whose reply is being sent
        # Whether the last reply failed every attempt: its caller had gone (_send_attempts).
        self._caller_gone = False
        self._stop: Stop | None = None  # the stop under way (NodeGroup.on_stop)
        self._collecting = True  # whether the cyclic collector ran when it was taken
        self._after_reply: AfterReply | None = None  # what to publish once it is sent
        # Answered plans the outputs' thread has still to publish, oldest first: appended
        # by the service's thread, taken by the outputs' (a deque's append and popleft
        # are atomic), and at teardown by before_teardown (publish_answered).
        self._answered: deque[AfterReply] = deque()
        self._plans_answered = self.outputs.create_guard_condition(self.publish_answered)
        s = self._settings
        self.get_logger().info(
            'serving %s: frame %s, dimension %d, variant %s, robot radius %g, %s, robots %s'
            % (self.resolve_service_name('plan_sequence'), s.frame_id, s.dimension,
               s.core_variant, s.robot_radius, self._obstacles.describe(),
               ', '.join(s.robot_names) or (str(s.robot_count) if s.robot_count else 'any')))

    # ------------------------------------------------------------ parameters

    def _apply_parameters(self, settings: PlannerSettings, changed: set[str]) -> None:
        """Post-set: the settings, and obstacles and odometry where their parameters changed."""
        with self._lock:
            self._settings = settings
            if 'obstacles' in changed:
                self._obstacles = self._parameter_obstacles(settings)
            if 'robot_names' in changed:
                self._odometry = {name: value for name, value in self._odometry.items()
                                  if name in settings.robot_names}
        if 'robot_names' in changed:
            self._robot_names_changed.trigger()

    def _check_obstacles_fit(self, settings: PlannerSettings, changed: set[str]) -> None:
        """On-set and at start-up: refuse settings the obstacles cannot be planned in."""
        obstacles = (self._parameter_obstacles(settings) if 'obstacles' in changed
                     else self._obstacles)
        self._handler.check_parameter_obstacles(settings, obstacles, changed)

    def _parameter_obstacles(self, settings: PlannerSettings) -> ObstacleSet:
        return ObstacleSet(conversions.obstacles_from_parameter(settings.obstacles),
                           stamp_ns=self.get_clock().now().nanoseconds)

    # ------------------------------------------------------------ subscriptions

    def _update_odometry_subscriptions(self) -> None:
        """Subscribe to the odometry of every robot of robot_names, and of no other."""
        with self._lock:
            names = self._settings.robot_names
        for name in list(self._odometry_subscriptions):
            if name not in names:
                self.inputs.destroy_subscription(self._odometry_subscriptions.pop(name))
        for name in names:
            if name not in self._odometry_subscriptions:
                self._odometry_subscriptions[name] = self.inputs.create_subscription(
                    Odometry, robot_topic(name, ODOM), functools.partial(self._on_odometry, name),
                    STATE)

    def _on_obstacles(self, msg: PoseArray) -> None:
        """Take a new obstacle set if it can be planned in; else warn and keep the old one."""
        obstacles = ObstacleSet(conversions.obstacles_from_pose_array(msg),
                                frame_id=msg.header.frame_id,
                                source=self.resolve_topic_name('obstacles'),
                                stamp_ns=conversions.stamp_to_ns(msg.header.stamp))
        with self._lock:
            settings, previous = self._settings, self._obstacles
        try:
            self._handler.check_obstacles(settings, obstacles)
        except PlanningError as error:
            self.get_logger().warning('refused %s: %s: %s; keeping %s' % (
                obstacles.describe(), error.code.name,
                error.describe(ObstacleNames(obstacles.name)), previous.describe()))
            return
        with self._lock:
            self._obstacles = obstacles
        self.get_logger().debug('obstacles: %s' % obstacles.describe())

    def _on_robot_states(self, msg: PoseArray) -> None:
        positions, orientations = conversions.pose_array_poses(msg)
        state = RobotState(positions, orientations, msg.header.frame_id,
                           conversions.stamp_to_ns(msg.header.stamp), 'robot_states',
                           self.get_clock().now().nanoseconds)
        with self._lock:
            self._robot_states = state

    def _on_odometry(self, name: str, msg: Odometry) -> None:
        entry = conversions.robot_odometry(msg, self.get_clock().now().nanoseconds)
        with self._lock:
            # A late message for a robot just removed from robot_names is dropped.
            if name in self._settings.robot_names:
                self._odometry[name] = entry

    def snapshot(self) -> Snapshot:
        """Return one consistent Snapshot of parameters, obstacles and robot state."""
        with self._lock:
            return take_snapshot(self._settings, self._obstacles, self._robot_states,
                                 dict(self._odometry))

    # ------------------------------------------------------------ the service

    def _on_plan_sequence(self, request: PlanSequence.Request,
                          response: PlanSequence.Response) -> PlanSequence.Response:
        # Answer first, collect after: the cyclic collector stays off until the reply is
        # sent (_send_response). A plan's messages are many objects (k x M poses), and a
        # full collection scanning them took 24-40 ms inside the reply of one call in
        # three at k = 512 (doc/design.md section 11); reference counting still frees.
        # A host process that runs with the collector off keeps it off.
        self._collecting = gc.isenabled()
        gc.disable()
        try:
            return self._plan_request(request, response)
        except BaseException:
            self._resume_collection()
            raise

    def note_stop(self, stop: Stop) -> None:
        """Take the stop under way (NodeGroup.on_stop): once its planning is over, replies only."""
        self._stop = stop

    def _resume_collection(self) -> None:
        """Turn the cyclic collector back on if it was on when the call was taken."""
        if self._collecting:
            gc.enable()

    def _past_planning(self) -> Stop | None:
        """Return the stop under way once only replies go out (runtime.Stop), else None."""
        stop = self._stop
        return stop if stop is not None and stop.planning_over() else None

    def _plan_request(self, request: PlanSequence.Request,
                      response: PlanSequence.Response) -> PlanSequence.Response:
        """Plan one request against a snapshot; keep what to log and publish after the reply."""
        self._request_count += 1
        number = self._answering = self._request_count
        if (stop := self._past_planning()) is not None:
            refuse_stopping(response, self.get_name(), number, len(request.configurations),
                            stop.elapsed())
            self.get_logger().warning('plan_sequence #%d: %s' % (number, response.error_msg))
            return response
        now_ns = self.get_clock().now().nanoseconds
        snapshot = self.snapshot()
        logger = self.get_logger()
        logger.info('plan_sequence #%d: %s%s; snapshot: %s'
                    % (number, counted(len(request.configurations), 'configuration'),
                       ' + current state' if request.use_current_state else '',
                       snapshot.describe()))
        outcome = self._handler.handle(request, response, snapshot, now_ns)
        if outcome.ok:
            self._plan_count += 1
            outcome.plan_id = response.plan_id = self._plan_count
        # Logged, and published if planned, by _send_response once the reply is out
        # (answer first): each rclpy log line looks up its caller's source file
        # through inspect, a cost the reply need not wait for.
        self._after_reply = AfterReply(number, outcome, snapshot.settings)
        return response

    def _log_outcome(self, after: AfterReply) -> None:
        """Log how a request ended: planned, refused, or an internal error with its traceback."""
        number, outcome, response = after.number, after.outcome, after.outcome.response
        logger = self.get_logger()
        if outcome.ok:
            p = outcome.planned().plan
            logger.info('plan_sequence #%d: planned k=%d n=%d, domain %d of %d, clearance '
                        '%.6g, %.3f ms' % (number, p.positions.shape[1],
                                           len(p.waypoint_indices), p.domain_index,
                                           p.domain_count, p.min_clearance,
                                           1e3 * conversions.duration_to_seconds(
                                               response.planning_time)))
        elif outcome.exception is not None:
            logger.error('plan_sequence #%d: %s' % (number, response.error_msg))
            logger.error(''.join(traceback.format_exception(outcome.exception)))
        else:
            logger.warning('plan_sequence #%d: error %d: %s'
                           % (number, response.error_code, response.error_msg))

    def _send_response(self, response, header):
        """
        Send the reply to request #self._answering; log each failed attempt, retry a bounded time.

        rclpy turns the rmw's "client will not receive response" into a RuntimeWarning
        that Python shows once; here every one is an error naming the request.
        warnings.catch_warnings is process-wide: a warning of another thread in this
        short window is shown again below, not lost.
        """
        try:
            number, sequence = self._answering, header.request_id.sequence_number
            self._send_attempts(response, header, number, sequence)
        finally:
            self._resume_collection()
            after, self._after_reply = self._after_reply, None
            if after is not None:
                self._log_outcome(after)
                if after.outcome.ok:
                    self._answered.append(after)
                    self._plans_answered.trigger()

    def _send_attempts(self, response, header, number, sequence):
        """
        Send one reply, up to SEND_ATTEMPTS times while rmw reports the timeout.

        Each failed attempt holds the service's thread 100 ms (rmw_fastrtps's wait for
        the client's reader). The retries are for a new client whose reader is not
        matched yet; a caller that has gone never will be, and callers that left
        after sending held the thread 1.1 s each: 90 of them delayed a live call
        29 s, and made a stop overrun 60 s, exit 1 and lose a call sent before it
        (a review's runs over DDS, 2026-12-05). So a reply gets one attempt once
        the reply before it failed every attempt (its caller had gone: a reply that
        goes out ends that), and once the stop only replies (runtime.Stop).
        """
        attempts = (1 if self._caller_gone or self._past_planning() is not None
                    else SEND_ATTEMPTS)
        for attempt in range(1, attempts + 1):
            with warnings.catch_warnings(record=True) as caught:
                warnings.simplefilter('always')
                self._send(response, header)
            failed = [w for w in caught if SEND_TIMEOUT_WARNING in str(w.message)]
            for other in caught:
                if other not in failed:
                    warnings.showwarning(other.message, other.category, other.filename,
                                         other.lineno)
            if not failed:
                self._caller_gone = False
                self.get_logger().debug('plan_sequence #%d: reply sent (client sequence '
                                        'number %d, attempt %d)' % (number, sequence, attempt))
                return
            self.get_logger().error(
                'plan_sequence #%d: reply (error code %d) not sent to the client (sequence '
                'number %d), attempt %d of %d: %s'
                % (number, response.error_code, sequence, attempt, attempts,
                   failed[0].message))
        self._caller_gone = True

    def publish_answered(self) -> None:
        """
        Publish every answered plan not published yet, oldest first.

        The outputs' thread runs it once a reply is out; the stop runs it when no
        thread spins any more (NodeGroup.before_teardown), for plans answered as it
        began.
        """
        while self._answered:
            after = self._answered.popleft()
            if (stop := self._past_planning()) is not None:
                # Publishing the largest plan took 10 s more: the stop must end, and
                # the caller has its plan in the reply.
                self.get_logger().warning(
                    'plan_sequence #%d: plan %d answered, %.0f s into the stop: not '
                    'published' % (after.number, after.outcome.plan_id, stop.elapsed()))
            else:
                self._publish_after_reply(after)

    def _publish_after_reply(self, after: AfterReply) -> None:
        """
        Publish an answered plan; a failure is logged and the robots' paths retracted.

        The caller already holds a success with the plan id: the plan is then
        not on ``plan``, so an ``execute_plan`` of it ends NO_PLAN (msg_docs/topics.md).
        """
        try:
            self._publish(after.outcome, after.settings)
        except Exception as error:  # never crash the service
            self.get_logger().error(
                'plan_sequence #%d: plan %d answered, but publishing it failed: %r; its '
                'paths are retracted and it is not on plan' % (
                    after.number, after.outcome.plan_id, error))
            self._retract(after.outcome.names or [], after.settings)

    def _publish(self, outcome: Outcome, settings: PlannerSettings) -> None:
        """
        Publish the complete plan in the order of msg_docs/topics.md.

        Every robot's Path, robots no longer planned emptied, then markers,
        domain index and Plan last: a subscriber to ``plan`` finds the paths out.
        """
        messages = publications.plan_messages(outcome, settings)
        publishers = [self._publisher(m.topic, m.msg_type) for m in messages]
        names = outcome.planned().names
        stale = [name for name in self._latched_names if name not in names]
        paths = len(names)
        for publisher, message in zip(publishers[:paths], messages[:paths]):
            publisher.publish(message.data)
        for name in stale:
            self._publisher(robot_topic(name, PLAN), Path).publish(
                conversions.empty_path(settings.frame_id, outcome.start_ns))
        for publisher, message in zip(publishers[paths:], messages[paths:]):
            publisher.publish(message.data)
        self._latched_names = list(names)

    def _retract(self, names: list[str], settings: PlannerSettings) -> None:
        """After a failed publish, latch empty paths so no robot keeps a partial plan."""
        try:
            for name in names:
                self._publisher(robot_topic(name, PLAN), Path).publish(
                    conversions.empty_path(settings.frame_id, self.get_clock().now().nanoseconds))
        except Exception as error:  # the reply is out already
            self.get_logger().error('could not retract the partial plan: %r' % error)

    def _publisher(self, topic: str, msg_type: type) -> Publisher:
        """Return the latched publisher of a relative topic (on the outputs node), made once."""
        publisher = self._latched_publishers.get(topic)
        if publisher is None:
            # plan keeps as many plans as plan_executor does: a writer that kept one dropped
            # a large plan still going out when the next was written, and no reader got it
            # (4 of 10 answered plans in a burst; the rest, each robot's latest, keep one).
            publisher = self.outputs.create_publisher(
                msg_type, topic, latched(PLAN_HISTORY) if msg_type is Plan else LATCHED)
            self._latched_publishers[topic] = publisher
        return publisher


def planner_nodes(context: Context | None = None, **kwargs: Any) -> NodeGroup:
    """Return the PlannerNode and its server, inputs and outputs nodes: each in its own thread."""
    node = PlannerNode(context=context, **kwargs)
    return NodeGroup([node, node.server, node.inputs, node.outputs], on_stop=node.note_stop,
                     before_teardown=node.publish_answered)


def main(args: list[str] | None = None) -> int:
    """Run the node until Ctrl-C or SIGTERM; return 0, or 2 for invalid parameters."""
    return run_nodes(PLANNER, planner_nodes, args=args)


if __name__ == '__main__':
    sys.exit(main())
