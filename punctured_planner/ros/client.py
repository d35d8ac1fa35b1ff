"""
A client of the planner's graph, from a script or a command: one way to spin and to stop.

:func:`session` gives a node and its executor in a private rclpy Context (the
``punctured-planner`` command, ``make demo``); every wait spins that executor
with spin_once (:func:`spin_until`): in rclpy 7.1 repeated
spin_until_future_complete leaves stale tasks behind.
"""

from collections.abc import Callable
from collections.abc import Iterator
import contextlib
from dataclasses import dataclass
import time
from typing import Any

import rclpy
from rclpy.action.client import ClientGoalHandle
from rclpy.client import Client
from rclpy.executors import Executor
from rclpy.executors import SingleThreadedExecutor
from rclpy.node import Node

# How long one spin_once may block while waiting: short, so a deadline is kept to it.
SPIN_STEP_SEC = 0.05


def spin_until(executor: Executor, predicate: Callable[[], bool], timeout_sec: float) -> bool:
    """Spin ``executor`` (spin_once) until predicate() is true; return whether it became so."""
    deadline = time.monotonic() + timeout_sec
    while not predicate():
        remaining = deadline - time.monotonic()
        if remaining <= 0:
            return False
        executor.spin_once(timeout_sec=min(remaining, SPIN_STEP_SEC))
    return True


def call_service(executor: Executor, client: Client, request: Any,
                 timeout_sec: float) -> Any | None:
    """Call ``client`` once; return the response, or None on timeout."""
    future = client.call_async(request)
    if not spin_until(executor, future.done, timeout_sec):
        client.remove_pending_request(future)
        return None
    return future.result()


# Seconds without feedback after which a running goal's executor counts as gone:
# plan_executor sends feedback every control step (20 Hz by default, msg_docs/ExecutePlan.md),
# while DDS itself notices a killed process only when its lease ends (about 20 s).
FEEDBACK_SILENCE_SEC = 5.0


class GoalWatch:
    """When an ExecutePlan goal's feedback last came: pass :meth:`heard` as its callback."""

    def __init__(self) -> None:
        """No feedback yet."""
        self.last_feedback: float | None = None  # time.monotonic()

    def heard(self, feedback: Any) -> None:
        """Feedback callback of send_goal_async: the executor is alive now."""
        self.last_feedback = time.monotonic()

    def silent_for(self) -> float:
        """Return the seconds since the last feedback (0 before the first)."""
        if self.last_feedback is None:
            return 0.0
        return time.monotonic() - self.last_feedback


def wait_for_result(executor: Executor, handle: ClientGoalHandle, watch: GoalWatch,
                    timeout_sec: float) -> Any | None:
    """
    Spin until the goal's result; return it, or None when the executor went away.

    None once the goal's feedback, after it started, stopped for
    FEEDBACK_SILENCE_SEC (plan_executor died: no result will come) or
    ``timeout_sec`` passed.
    """
    future = handle.get_result_async()
    spin_until(executor, lambda: future.done() or watch.silent_for() > FEEDBACK_SILENCE_SEC,
               timeout_sec)
    if future.done():
        return future.result().result
    return None


@dataclass(frozen=True)
class Session:
    """A client's node and the executor that spins it (the node added to it)."""

    node: Node
    executor: Executor


@contextlib.contextmanager
def session(name: str, namespace: str | None = None) -> Iterator[Session]:
    """Yield a Session in a private rclpy Context; shut everything down after."""
    context = rclpy.context.Context()
    rclpy.init(context=context)
    executor = SingleThreadedExecutor(context=context)
    node = rclpy.create_node(name, namespace=namespace, context=context)
    executor.add_node(node)
    try:
        yield Session(node, executor)
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)
