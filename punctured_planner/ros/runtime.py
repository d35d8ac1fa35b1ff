"""
The node runtime: start, spin and stop every node process of the package the same way.

``planner_node``, ``plan_executor`` and ``fleet_sim`` all run through
:func:`run_nodes`, so each starts, spins and stops alike: exit code 0, no
traceback, no thread left spinning, on Ctrl-C and on SIGTERM alike, also in
the middle of a callback (the callback finishes, a service response goes
out, then the process stops); exit code 2 with the reason for invalid
parameters; 1 when a callback raised.

Use::

    from punctured_planner.ros.runtime import NodeGroup, run_nodes

    def main(args=None):
        return run_nodes('my_node', lambda context: NodeGroup([MyNode(context=context)]),
                         args=args)

or, for a node with a parameter table (ros.parameters.Table), ``run_nodes(TABLE, ...)``:
the process is named after the table's node and checks its parameter files.

``make_nodes(context)`` returns the :class:`NodeGroup` to spin; each node gets its own
SingleThreadedExecutor in its own thread, so a slow callback on one node never
blocks another (give subscriptions their own node for that). In tests, or
wherever the process's signals belong to someone else, spin nodes with
:class:`ExecutorThreads` (``start()``, then ``close()``) in a Context of your own.

Why not rclpy's own idiom (``rclpy.spin`` inside ``except (KeyboardInterrupt,
ExternalShutdownException)``)? Its signal handler shuts the Context down under
executors still spinning in other threads: those threads die with an
ExternalShutdownException traceback, and rclpy 7.1's ``Executor.shutdown``
destroys the guard conditions a spinning thread may still be waiting on (it
does not wait for the work in flight). With daemon threads left in C code at
interpreter exit, the planner node printed a traceback on 9 of 10 Ctrl-C,
hung now and then, and segfaulted about once in 26 stops. Here instead:

1. SIGINT and SIGTERM get one Python handler, installed before ``rclpy.init``
   (which installs none of its own here). Whichever thread the kernel
   delivers a signal to, CPython's C handler writes its number into a pipe
   (:func:`signal.set_wakeup_fd`) that the main thread blocks on.
2. Each executor thread is a non-daemon thread that waits for work with a
   stop condition (``Executor.wait_for_ready_callbacks(condition=...)``), not
   ``Executor.spin``.
3. On the signal: the stop flag is set and every executor woken; each thread
   finishes its callback in flight and returns; the threads are joined. Only
   then are the executors shut down, the group's ``before_teardown`` hook run
   (plan_executor's last zero velocity), then the process lingers until
   ``REPLY_GRACE_SEC`` after the last reply it wrote (or until no client of
   the services that replied is left), and only then are the
   nodes destroyed (in reverse order) and the Context shut down. Every step
   between the stop and the destruction lives in one place,
   :meth:`ExecutorThreads.close`, which :func:`run_nodes` and the in-process
   tests share.

The stop, in the order of doc/design.md section 16: (1) no new work: the
threads leave their loop after the callback in flight, and the group's
``before_stop`` hook (run in the first node's thread) makes its node refuse
goals; (2) what is in flight finishes: the plan call in flight writes its
reply, each thread answers the service requests that had already arrived
(within ``STOP_PLANNING_SEC`` of the signal as the service would, later
quickly refused by the node, told of the stop by ``NodeGroup.on_stop``), and
the hook ends the goal
in flight while its thread spins on until the Future it returned is done (the
result sent), at most ``STOP_DRAIN_SEC``, and ``REQUEST_GRACE_SEC`` more for a
result request still on the wire;
(3) the participant stays until ``REPLY_GRACE_SEC`` after the last reply
written (a service's response or an action server's), so that the DDS writer
can still resend it at its next heartbeat to a client that missed part of it,
or until no client of the services that replied is left, answering what still
reaches its services meanwhile (at most ``LINGER_LIMIT_SEC``); (4) teardown. rclpy
offers no acknowledgement of a service reply, so the linger is a bounded time
after the write, not an observed delivery.

A callback that raises stops the process the same way, with the traceback
logged and exit code 1. A callback still running ``timeout_sec`` after the
signal cannot be stopped from Python: :func:`run_nodes` logs which nodes are
stuck and ends the process with ``os._exit(1)`` rather than destroy what a
thread still uses.
"""

from dataclasses import dataclass
import math
import os
import signal
import sys
import threading
import time
import traceback
from typing import Any
from typing import Callable
from typing import Dict
from typing import List
from typing import Optional
from typing import Sequence

import rclpy
from rclpy._rclpy_pybind11 import RCLError
from rclpy.action import ActionServer
from rclpy.context import Context
from rclpy.exceptions import ParameterException
from rclpy.executors import ConditionReachedException
from rclpy.executors import ExternalShutdownException
from rclpy.executors import ShutdownException
from rclpy.executors import SingleThreadedExecutor
from rclpy.executors import TimeoutException
from rclpy.node import Node
from rclpy.service import Service
from rclpy.signals import SignalHandlerOptions
from rclpy.task import Future

from .early_signals import STOP_SIGNALS
from .early_signals import take_noted
from .parameters import rcl_reason
from .parameters import Table
from .qos import load_fastdds_profile
from .qos import SERVER_QOS

# Seconds a callback in flight may take to finish after the stop signal: the largest
# request max_poses allows (2,000,000 poses) held the planner's thread 18 s on an idle
# machine and more than 30 s at a load of 2 on 2 cores (doc/design.md section 16).
STOP_TIMEOUT_SEC = 60.0
# Seconds after the stop signal within which a node still does all its work: a request
# that waits is planned (later, refused at once), an answered plan published (later, only
# the reply goes out): Stop.planning_over, the node told by NodeGroup.on_stop. Five such
# requests waiting made the stop overrun 30 s, exit 1 and lose three replies.
STOP_PLANNING_SEC = 10.0
# Seconds the participant stays after the last reply it wrote (step 3 of the stop),
# unless no client of the services that replied is left: a reliable Fast DDS writer
# resends what a reader missed at its periodic heartbeat, every 3 s by default, and a
# reply larger than the writer's shared-memory segment (512 KB; a k = 512 plan is
# 565 KB) that its reader was not reading when it went out arrives only then
# (doc/design.md section 16).
REPLY_GRACE_SEC = 4.0
# Seconds between two looks at the graph and the services while the participant stays.
LINGER_POLL_SEC = 0.05
# Seconds the participant stays at most, however many requests reach it meanwhile (each
# answered, and its reply given REPLY_GRACE_SEC within this).
LINGER_LIMIT_SEC = 2 * REPLY_GRACE_SEC
# Seconds the first node's thread spins on after the goal in flight ended, for a
# result request still on the wire.
REQUEST_GRACE_SEC = 1.0
# Seconds the first node's thread spins on after the stop for before_stop's Future.
STOP_DRAIN_SEC = 2.0
# What writes a reply when its callback runs: a service, an action server.
REPLYING = (Service, ActionServer)
EXIT_OK = 0
EXIT_FAILED = 1
EXIT_BAD_PARAMETERS = 2
# What a node's constructor raises for invalid parameters: the package's own checks
# (ValueError with the reason) and rclpy's (a value outside a descriptor's range,
# a value of the wrong type).
BAD_PARAMETERS = (ValueError, ParameterException)
_WOKEN = 0  # the byte wake() writes: not a signal number


class StopSignals:
    """
    SIGINT and SIGTERM as one wake-up the main thread waits for (a context manager).

    Inside ``with StopSignals() as signals:`` both signals only wake
    :meth:`wait`; on leaving, the previous handlers and wake-up fd come back, unless
    a stop signal came: then both stay ignored, as the process is on its way out (a
    second Ctrl-C or SIGTERM in its last 0.2 s of teardown killed it, exit -2 or -15).
    A stop signal noted while the process started (:mod:`.early_signals`) wakes
    :meth:`wait` at once; ``while_starting`` lists those signals. Enter it from the
    main thread (Python sets signal handlers only there).
    """

    def __init__(self) -> None:
        """Take over nothing before ``__enter__``."""
        self._previous: dict = {}
        self._previous_fd = -1
        self._read_fd = self._write_fd = -1
        self._stopped = False
        self.while_starting: list[int] = []

    def __enter__(self) -> 'StopSignals':
        """Install the handlers and the wake-up pipe."""
        self._read_fd, self._write_fd = os.pipe()
        os.set_blocking(self._write_fd, False)
        self._previous_fd = signal.set_wakeup_fd(self._write_fd, warn_on_full_buffer=False)
        for number in STOP_SIGNALS:
            self._previous[number] = signal.signal(number, _ignore)
        self.while_starting = take_noted()  # stop signals while the process started
        for noted in self.while_starting:
            os.write(self._write_fd, bytes([noted]))
        return self

    def __exit__(self, *exc_info) -> None:
        """Restore the previous handlers (ignore both after a stop) and wake-up fd."""
        for number, handler in self._previous.items():
            signal.signal(number, signal.SIG_IGN if self._stopped else handler)
        signal.set_wakeup_fd(self._previous_fd)
        os.close(self._read_fd)
        os.close(self._write_fd)

    def wait(self) -> int:
        """Block until a stop signal or :meth:`wake`; return the signal number, or 0 if woken."""
        while True:
            for number in os.read(self._read_fd, 64):
                if number in STOP_SIGNALS or number == _WOKEN:
                    self._stopped = self._stopped or number in STOP_SIGNALS
                    return number

    def wake(self) -> None:
        """Make :meth:`wait` return 0; callable from any thread."""
        try:
            os.write(self._write_fd, bytes([_WOKEN]))
        except BlockingIOError:
            pass  # the pipe is full of wake-ups already


def _with_traceback(words: str, error: BaseException) -> str:
    """Return a log line: words, then the error's traceback."""
    return words + ':\n' + ''.join(traceback.format_exception(error))


# The interface packages of the services rclpy gives every node.
_EVERY_NODES_INTERFACES = ('rcl_interfaces', 'type_description_interfaces')


def _everyones(service: Service) -> bool:
    """Return whether service is one rclpy gives every node (parameters, type description)."""
    return service.srv_type.__module__.split('.')[0] in _EVERY_NODES_INTERFACES


def _never() -> bool:
    """Return False: a condition that never ends a wait."""
    return False


def _ignore(number, frame):
    """Signal handler: nothing to do, the wake-up fd has woken StopSignals.wait."""


def companion(node: Node, role: str) -> Node:
    """
    Return the companion node ``<name>_<role>`` of node: same namespace and context.

    Spun in a thread of its own (NodeGroup), so what its callbacks take (a large
    message, a plan) never holds the node's own.
    """
    # A local __node remap outranks a global one (-r __node:=NAME, launch name=).
    name = '%s_%s' % (node.get_name(), role)
    return Node(name, context=node.context, namespace=node.get_namespace(),
                cli_args=['--ros-args', '-r', '__node:=' + name],
                start_parameter_services=False)


@dataclass
class NodeGroup:
    """
    The nodes of one process and what must happen before they are destroyed.

    ``before_stop`` runs in the first node's thread when the stop begins; it
    returns a Future (or None) that the thread spins on for, such as a goal's
    result going out. ``before_teardown`` runs once the executors stopped and
    before any node is destroyed: publishers still work, no callback runs any more.
    ``on_stop(stop)`` runs in the signal's thread as the stop begins, with its
    :class:`Stop`: a node may then cut short what only matters while it runs
    (Stop.planning_over), in the callback in flight and in those of the requests
    answered after it (the planner refuses them, NODE_STOPPING).
    """

    nodes: Sequence[Node]
    before_stop: Optional[Callable[[], Optional[Future]]] = None
    before_teardown: Optional[Callable[[], None]] = None
    on_stop: Optional[Callable[['Stop'], None]] = None


@dataclass
class Stop:
    """
    A stop under way: when the signal came (time.monotonic()) and whether it only lingers now.

    While lingering (step 3) nothing spins and no watchdog runs: a request
    answered then gets only a quick reply.
    """

    began: float
    lingering: bool = False

    def elapsed(self) -> float:
        """Return the seconds since the stop signal."""
        return time.monotonic() - self.began

    def planning_over(self) -> bool:
        """Return whether only replies go out now: STOP_PLANNING_SEC in, or lingering."""
        return self.lingering or self.elapsed() > STOP_PLANNING_SEC


class ExecutorThreads:
    """
    Each node spun by its own SingleThreadedExecutor in its own (non-daemon) thread.

    ``start()`` once, then ``close()`` (or ``stop()`` and destroy the nodes
    yourself). ``on_failure`` is called from the thread of a callback that
    raised; the exception is in :attr:`failure` and the logs. ``before_stop``
    and ``on_stop`` are the NodeGroup's.
    """

    def __init__(self, nodes: Sequence[Node], context: Optional[Context] = None,
                 on_failure: Optional[Callable[[], None]] = None,
                 before_stop: Optional[Callable[[], Optional[Future]]] = None,
                 on_stop: Optional[Callable[[Stop], None]] = None):
        """Make one executor per node (in ``context``); nothing spins yet."""
        self.nodes: List[Node] = list(nodes)
        self.failure: Optional[BaseException] = None
        self._on_failure = on_failure
        self._before_stop = before_stop
        self._on_stop = on_stop
        self._stopping = threading.Event()
        self._stop: Optional[Stop] = None
        self._last_reply: Optional[float] = None  # time.monotonic() after the last reply
        # Who the linger waits for: the services that replied (name -> their node), and
        # whether an action server replied (its clients are not counted: it waits the
        # whole grace).
        self._replied: Dict[str, Node] = {}
        self._action_replied = False
        self._executors = []
        for node in self.nodes:
            executor = SingleThreadedExecutor(context=context)
            executor.add_node(node)
            self._executors.append(executor)
        self._threads = [
            threading.Thread(target=self._spin, args=(node, executor, index == 0),
                             name='spin ' + node.get_fully_qualified_name())
            for index, (node, executor) in enumerate(zip(self.nodes, self._executors))]

    def start(self) -> None:
        """Start spinning every node in its thread."""
        for thread in self._threads:
            thread.start()

    def _spin(self, node: Node, executor: SingleThreadedExecutor, first: bool) -> None:
        """Run callbacks until stop(); a callback's exception ends the loop (and is logged)."""
        try:
            while self._run_one(executor, self._stopping.is_set):
                pass
            self._answer_waiting(node)
            if first and self._before_stop is not None:
                self._drain(node, executor, self._before_stop())
        except ExternalShutdownException:
            pass  # the Context was shut down by someone else: nothing left to spin
        except BaseException as error:  # noqa: B902 - logged, then the process stops
            self.failure = error
            node.get_logger().fatal(_with_traceback('callback raised, stopping', error))
            if self._on_failure is not None:
                self._on_failure()

    def _run_one(self, executor: SingleThreadedExecutor, condition: Callable[[], bool],
                 timeout_sec: Optional[float] = None) -> bool:
        """Run one ready callback; return False once ``condition()`` or the timeout came."""
        entity: object  # what the callback belongs to: a Service, a Timer, a waitable...
        try:
            handler, entity, node = executor.wait_for_ready_callbacks(
                timeout_sec=timeout_sec, condition=condition)
        except (ConditionReachedException, ShutdownException, TimeoutException):
            return False
        handler()
        if isinstance(entity, REPLYING):
            self._replied_by(entity if isinstance(entity, Service) else None, node)
        handler.result()  # raises the callback's exception
        return not condition()

    def _replied_by(self, service: Optional[Service], node: Node) -> float:
        """
        Note that ``service`` of ``node`` (None: an action server) replied; return when.

        Not the services every node has (parameters, type descriptions): their replies
        are small and quick, and a client polling them (rqt, a dashboard) held every
        stop for LINGER_LIMIT_SEC.
        """
        now = time.monotonic()
        if service is not None and _everyones(service):
            return now
        self._last_reply = now
        if service is not None:
            self._replied[service.srv_name] = node
        else:
            self._action_replied = True
        return now

    def _answer_waiting(self, node: Node, until: float = math.inf) -> None:
        """
        Answer the requests that reached the node's services and were not taken yet.

        A request the executor had not taken yet when the signal came is in flight
        for its client too: it is taken and answered here, in this thread, as the
        executor would (at most the server's queue depth per service); so is one
        that comes while the participant lingers. A node past the stop's planning
        budget, or lingering, answers them quickly (NodeGroup.on_stop, Stop), so
        that many large requests cannot hold the stop past STOP_TIMEOUT_SEC and
        every one is answered. None is taken after ``until`` (time.monotonic()):
        the linger's limit, which replies to callers that have gone (100 ms each)
        had held for 90 s.
        """
        for service in node.services:
            srv_type: Any = service.srv_type  # a generated type: Request, Response
            for _ in range(SERVER_QOS.depth):
                if time.monotonic() > until:
                    return
                with service.handle:
                    request, header = service.handle.service_take_request(srv_type.Request)
                if header is None:
                    break
                service.send_response(service.callback(request, srv_type.Response()), header)
                self._replied_by(service, node)

    def _drain(self, node: Node, executor: SingleThreadedExecutor,
               ended: Optional[Future]) -> None:
        """
        Spin on until ``ended`` is done (at most STOP_DRAIN_SEC), then REQUEST_GRACE_SEC more.

        The grace spin answers a request about what just ended that was still on
        the wire when it ended: a client that asked for a goal's result just
        before the stop gets it (``before_stop`` has made the node refuse new work).
        """
        if ended is None:
            return
        deadline = time.monotonic() + STOP_DRAIN_SEC
        while not ended.done():
            remaining = deadline - time.monotonic()
            if remaining <= 0.0 or not self._run_one(executor, ended.done, remaining):
                break
        # What ``ended`` set off (an action server sends the result in a task of its
        # own): run whatever is ready now, until nothing is.
        while time.monotonic() < deadline and self._run_one(executor, _never, 0.0):
            pass
        grace_end = self._replied_by(None, node) + REQUEST_GRACE_SEC  # after the goal's result
        while (remaining := grace_end - time.monotonic()) > 0.0:
            self._run_one(executor, _never, remaining)

    def stop(self, timeout_sec: float = STOP_TIMEOUT_SEC) -> bool:
        """
        Stop spinning: finish the callbacks in flight, join the threads, shut the executors down.

        Return False (and shut nothing down) if a thread is still running after
        ``timeout_sec``; :meth:`stuck` names its node.
        """
        if self._stop is None:
            self._stop = Stop(time.monotonic())
            if self._on_stop is not None:
                self._on_stop(self._stop)
        self._stopping.set()
        for executor in self._executors:
            executor.wake()
        for thread in self._threads:
            if thread.ident is not None:
                thread.join(timeout_sec)
        if self.stuck():
            return False
        for executor in self._executors:
            executor.shutdown()
        return True

    def stuck(self) -> List[str]:
        """Return the names of the nodes whose thread is still running."""
        return [node.get_fully_qualified_name()
                for node, thread in zip(self.nodes, self._threads) if thread.is_alive()]

    def linger(self) -> float:
        """
        Wait until REPLY_GRACE_SEC after the last reply written, if any; return the wait.

        The wait ends sooner once no client of the services that replied is left
        (a one-shot caller such as ``ros2 service call`` has its reply and is gone),
        unless an action server replied: its clients are not counted. The services
        stay advertised meanwhile, so a request that reaches one is answered
        (_answer_waiting) quickly, the stop lingering (Stop.planning_over), and
        its reply has its grace too, within LINGER_LIMIT_SEC in all: a caller
        that keeps calling cannot hold the stop.
        """
        started = time.monotonic()
        limit = started + LINGER_LIMIT_SEC
        if self._stop is not None:
            self._stop.lingering = True
        self._answer_all(limit)
        if self._last_reply is None:
            return 0.0
        while (remaining := min(self._last_reply + REPLY_GRACE_SEC, limit)
               - time.monotonic()) > 0.0 and self._awaited():
            time.sleep(min(remaining, LINGER_POLL_SEC))
            self._answer_all(limit)
        return time.monotonic() - started

    def _answer_all(self, until: float) -> None:
        """
        Answer what reached any node's services since its thread stopped, until ``until``.

        _answer_waiting, node after node. A callback that raises is logged and kept
        in :attr:`failure`, as in a spin thread, and the stop goes on: every other
        node is still answered and torn down.
        """
        for node in self.nodes:
            try:
                self._answer_waiting(node, until)
            except Exception as error:  # noqa: B902 - logged; the exit code says it
                self.failure = self.failure or error
                node.get_logger().error(_with_traceback('callback raised while stopping', error))

    def _awaited(self) -> bool:
        """Return whether a client may still be waiting for a reply written before the stop."""
        return self._action_replied or any(
            node.count_clients(name) > 0 for name, node in self._replied.items())

    def close(self, timeout_sec: float = STOP_TIMEOUT_SEC,
              before_teardown: Optional[Callable[[], None]] = None) -> bool:
        """
        stop(), before_teardown, linger(), destroy the nodes in reverse order.

        The whole stop (module docstring). Return False (and leave everything
        as it is) if stop() failed.
        """
        if not self.stop(timeout_sec):
            return False
        if before_teardown is not None:
            before_teardown()
        lingered = self.linger()
        if lingered > 0.0:
            self.nodes[0].get_logger().debug(
                'stopping: kept the participant %.3f s for the last reply' % lingered)
        for node in reversed(self.nodes):
            node.destroy_node()
        return True


def run_nodes(process: Table | str, make_nodes: Callable[[Context], NodeGroup],
              args: Optional[List[str]] = None,
              timeout_sec: float = STOP_TIMEOUT_SEC) -> int:
    """
    Run a process's nodes until SIGINT or SIGTERM, stop them cleanly; return the exit code.

    The whole ``main()`` of a node process (see the module docstring). ``process``
    is the node's parameter Table, which names the process and checks the
    parameter files of ``args`` (sys.argv when None; Table.check_files), or the
    name of a process whose nodes have no table. Then: initialise a Context with
    the arguments, call ``make_nodes(context)``, spin each node in its thread,
    wait for a stop signal, stop. Returns 0 after a signal, 1 when a callback
    raised, 2 (with the reason on stderr) for a parameter file the node cannot
    use or parameters ``make_nodes`` refused (``name: invalid parameters:``), or
    arguments rcl refuses (``name: cannot start:``). Call it from the main thread.
    """
    name, parameters = ((process.node_name, process) if isinstance(process, Table)
                        else (process, None))
    with StopSignals() as signals:
        load_fastdds_profile()
        context = Context()
        try:
            if parameters is not None:
                parameters.check_files(sys.argv if args is None else args)
            rclpy.init(args=args, context=context,
                       signal_handler_options=SignalHandlerOptions.NO)
        except ValueError as error:
            print('%s: invalid parameters: %s' % (name, error), file=sys.stderr)
            return EXIT_BAD_PARAMETERS
        except RCLError as error:  # arguments rcl refuses
            print('%s: cannot start: %s' % (name, rcl_reason(error)),
                  file=sys.stderr)
            return EXIT_BAD_PARAMETERS
        try:
            try:
                group = make_nodes(context)
            except BAD_PARAMETERS as error:
                print('%s: invalid parameters: %s' % (name, error), file=sys.stderr)
                return EXIT_BAD_PARAMETERS
            threads = ExecutorThreads(group.nodes, context, on_failure=signals.wake,
                                      before_stop=group.before_stop,
                                      on_stop=group.on_stop)
            threads.start()
            if signals.while_starting:  # why a node that just started stops at once
                group.nodes[0].get_logger().info('%s came while the process started: '
                                                 'stopping' % signal.Signals(
                                                     signals.while_starting[0]).name)
            signals.wait()
            _teardown(threads, group, timeout_sec)
        finally:
            rclpy.try_shutdown(context=context)
    return EXIT_FAILED if threads.failure is not None else EXIT_OK


def _teardown(threads: ExecutorThreads, group: NodeGroup, timeout_sec: float) -> None:
    """
    Tear the nodes down after the stop signal (ExecutorThreads.close), or exit if stuck.

    A callback still running ``timeout_sec`` after the signal cannot be
    stopped from Python: the stuck nodes are logged and the process ends with
    ``os._exit(1)`` rather than destroy what a thread still uses.
    """
    if not threads.close(timeout_sec, group.before_teardown):
        threads.nodes[0].get_logger().fatal(
            'callbacks of %s still running %.0f s after the stop signal; exiting '
            'without cleanup' % (', '.join(threads.stuck()), timeout_sec))
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(EXIT_FAILED)
