"""
How fast the feed-forward gain should learn: ``feedforward_adaptation`` side by side, no DDS.

Two closed loops of punctured_planner.execution against punctured_planner.sim,
run for each value of the executor's ``feedforward_adaptation`` (1/s):

1. ``make demo``'s scene without DDS: config/demo.yaml's planner, fleet_sim and
   plan_executor parameters (robot_0 at half speed and told to the executor
   through max_speeds, robot_1 100 ms late, 5% noise, 1 m/s^2), the plan from
   fleet_sim's initial positions to config/demo_request.yaml's configuration,
   answered as planner_node answers it (cli.offline_plan), on six noise seeds;
2. bench/execution.py's 20-robot sweep without DDS, every fourth robot the slow one.

For each value: the executed seconds (median and largest), the largest
tracking error over the tolerance delta and the smallest true gap. Run:
``.venv/bin/python bench/feedforward.py [--values 1 3 ...]``.
"""

import argparse
from dataclasses import replace
import os

import execution as twenty_robots
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
CONFIG = os.path.join(os.path.dirname(HERE), 'config')
SEEDS = range(3, 9)
STEP = 0.05  # the executor's control period (s); the fleet steps at half of it


def demo_scene():
    """Return (Reference, Bodies, tolerance, FleetSettings, ExecutionSettings) of make demo."""
    from punctured_planner.cli import build_request
    from punctured_planner.cli import load_request
    from punctured_planner.cli import offline_plan
    from punctured_planner.ros import conversions
    from punctured_planner.ros.parameters import load_parameter_file
    from punctured_planner.ros.settings import EXECUTOR
    from punctured_planner.ros.settings import FLEET_SIM
    from punctured_planner.ros.settings import PLANNER
    request = load_request(os.path.join(CONFIG, 'demo_request.yaml'))
    # each node's values as it reads the file (the shared section, then its own)
    planner, fleet, executor = (table.settings(load_parameter_file(
        os.path.join(CONFIG, 'demo.yaml'), table)) for table in (PLANNER, FLEET_SIM, EXECUTOR))
    start = np.reshape(fleet.initial_positions, (-1, 3))
    request['use_current_state'] = False
    request['configurations'].insert(0, {
        'header': request['configurations'][0]['header'],
        'poses': [{'position': dict(zip('xyz', map(float, p)))} for p in start]})
    outcome = offline_plan(build_request(request), planner)
    assert outcome.ok, outcome
    message = conversions.plan_message(outcome, planner)
    return (conversions.plan_reference(message), conversions.plan_bodies(message),
            message.tracking_tolerance, fleet.fleet(), executor.execution)


def demo_run(scene, adaptation: float, seed: int) -> dict:
    """Execute the demo's plan once; return seconds, error / delta and the true gap."""
    from punctured_planner.execution import Execution
    from punctured_planner.sim import Fleet
    reference, bodies, tolerance, fleet_settings, settings = scene
    k = reference.robot_count
    fleet = Fleet(reference.position(0.0), replace(fleet_settings, seed=seed))
    execution = Execution(reference, tolerance,
                          replace(settings, feedforward_adaptation=adaptation), bodies)
    now = 0.0
    while now < 20 * reference.duration:
        step = execution.step(STEP, fleet.positions, np.zeros(k, dtype=bool))
        for robot in range(k):
            fleet.command(robot, step.velocities[robot], now)
        for _ in range(2):
            fleet.step(now, STEP / 2)
            now += STEP / 2
        if step.finished:
            break
    return {'seconds': now, 'error': execution.max_errors.max() / tolerance,
            'gap': fleet.min_gap}


def line(name: str, runs: list) -> str:
    """Return one row of figures over runs (dicts of seconds, error, gap)."""
    seconds = [run['seconds'] for run in runs]
    return ('%-22s executed median %7.2f s, largest %7.2f s; largest error %.2f delta; '
            'smallest true gap %.3f m' % (name, np.median(seconds), max(seconds),
                                          max(run['error'] for run in runs),
                                          min(run['gap'] for run in runs)))


def main(argv=None):
    """Print both loops' figures for every value, side by side."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[1])
    parser.add_argument('--values', type=float, nargs='+', default=[1.0, 3.0],
                        help='feedforward_adaptation values (1/s; default 1 3)')
    args = parser.parse_args(argv)
    scene = demo_scene()
    the_plan = twenty_robots.core_plan()
    for value in args.values:
        print(line('demo, %g/s' % value, [demo_run(scene, value, seed) for seed in SEEDS]),
              flush=True)
        sweep = [twenty_robots.simulate(the_plan, slow, (slow + 1) % twenty_robots.K, True,
                                        feedforward_adaptation=value)
                 for slow in range(0, twenty_robots.K, 4)]
        print(line('20 robots, %g/s' % value, sweep), flush=True)
    return 0


if __name__ == '__main__':
    main()
