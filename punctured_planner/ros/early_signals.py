"""
Stop signals that come while a node process still starts: noted, then acted on.

A node's module imports rclpy, numpy and scipy, 0.2 - 0.6 s before
:func:`punctured_planner.ros.runtime.run_nodes` takes SIGINT and SIGTERM over
(``runtime.StopSignals``). Python's default handlers would end the process there:
a KeyboardInterrupt traceback, or exit -15. The console scripts
(:mod:`punctured_planner.nodes.start`) call :func:`note_from_now` before those
imports, with only the standard library loaded; ``StopSignals`` then takes what was
noted as a signal of its own, and the process stops as from any other: exit 0
(doc/design.md section 16). Nothing here imports ROS.
"""

import signal
from types import FrameType

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
_noted: list[int] = []  # the stop signals noted and not taken yet, in order


def _note(number: int, frame: FrameType | None) -> None:
    """Signal handler: note the signal for StopSignals."""
    _noted.append(number)


def note_from_now() -> None:
    """Note SIGINT and SIGTERM from now on instead of acting on them (call it first)."""
    for number in STOP_SIGNALS:
        signal.signal(number, _note)


def take_noted() -> list[int]:
    """Return the stop signals noted so far, oldest first, and forget them."""
    taken = []
    while _noted:
        taken.append(_noted.pop(0))
    return taken
