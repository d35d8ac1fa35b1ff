"""
The node processes' console scripts: a stop signal from their first instruction on is clean.

Each notes SIGINT and SIGTERM (:mod:`punctured_planner.ros.early_signals`) before it
imports its node, whose imports take 0.2 - 0.6 s, and then runs the node's ``main``;
a stop signal in between stops the node as soon as it runs, exit 0. ``python -m
punctured_planner.nodes.<node>`` runs the same ``main`` without that first note.
"""

import importlib

from ..ros import early_signals


def _run(node: str) -> int:
    """Note the stop signals, then import the node's module and run its main."""
    early_signals.note_from_now()
    return importlib.import_module('.' + node, __package__).main()


def planner_node() -> int:
    """Run the planner node of punctured_planner.nodes.planner."""
    return _run('planner')


def plan_executor() -> int:
    """Run the plan executor of punctured_planner.nodes.executor."""
    return _run('executor')


def fleet_sim() -> int:
    """Run the simulated fleet of punctured_planner.nodes.fleet_sim."""
    return _run('fleet_sim')
