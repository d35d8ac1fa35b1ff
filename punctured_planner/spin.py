"""
Run one node until Ctrl-C or SIGTERM: the robots are left stopped, exit 0, no traceback.

Used by ``plan_executor`` and ``fleet_sim`` (``planner_node`` has two executors
and its own ``main``). rclpy's own signal handler would shut the context down
at once, and then no last message could go out; so SIGINT and SIGTERM only set
a flag here (raising KeyboardInterrupt from the handler could land inside
rclpy's C++ message conversion and surface as a RuntimeError traceback), the
spin loop sees it within _WAIT and ends, the node leaves things safe
(``node.stop()``: zero velocity to every robot it drives), and only then is
the node destroyed and the context shut down (the Jazzy idiom: executor
first, then ``rclpy.try_shutdown``). Invalid parameters: exit 2 with the reason.
"""

import signal
import sys
import threading

import rclpy
from rclpy.exceptions import ParameterException
from rclpy.executors import ExternalShutdownException
from rclpy.executors import SingleThreadedExecutor
from rclpy.signals import SignalHandlerOptions

# Longest wait for work (s): how soon a signal is noticed.
_WAIT = 0.1


def spin_node(factory, name: str, args=None) -> int:
    """Run factory() until Ctrl-C or SIGTERM; return 0, or 2 when its parameters are invalid."""
    rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    stopping = threading.Event()
    # Both explicitly: a process started in the background may inherit SIGINT ignored.
    previous = {signum: signal.signal(signum, lambda *_: stopping.set())
                for signum in (signal.SIGINT, signal.SIGTERM)}
    node = None
    executor = SingleThreadedExecutor()
    try:
        try:
            node = factory()
        except (ValueError, TypeError, ParameterException) as error:
            print('%s: invalid parameters: %s' % (name, error), file=sys.stderr)
            return 2
        executor.add_node(node)
        while rclpy.ok() and not stopping.is_set():
            executor.spin_once(timeout_sec=_WAIT)
    except ExternalShutdownException:
        pass
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        executor.shutdown()
        if node is not None:
            node.stop()
            node.destroy_node()
        rclpy.try_shutdown()
    return 0
