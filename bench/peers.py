"""
Side by side with the planners people use today: OMPL and straight lines (issue 6).

Every planner gets the same seeded queries. OMPL plans on the composite
RealVectorStateSpace of all robots (k d dimensions), robots and obstacles
discs of radius RADIUS; a request through n configurations is n - 1 chained
queries. Every output, ours and theirs, is certified by the same exact
certificate (punctured_planner.core.certificate.certify): all of them are
piecewise-linear synchronous motions through their breakpoints.
Run alone: ``.venv/bin/python bench/peers.py [--quick]``.
"""

import argparse
from dataclasses import dataclass, field
from functools import partial
import itertools
import os
import sys
import time

from core_speed import format_table, median_time, random_obstacles
import numpy as np

from punctured_planner.core import plan as core_plan, Workspace
from punctured_planner.core.certificate import certify

# The construction's figures (the refinement's are bench/refinement.py's).
plan = partial(core_plan, refine=False)

RADIUS = 0.05
SEPARATION = 2 * RADIUS
PERTURBATION = 1e-6
QUERY_HALF_WIDTH = 2.0
BOUNDS_MARGIN = 1.0
# Composite-space step of OMPL's discrete motion check: a quarter of the separation.
MOTION_STEP = SEPARATION / 4

FULL_GRID = {'kind': ('random', 'adversarial'), 'd': (2, 3), 'k': (2, 4, 8, 16),
             'r': (0, 2, 5), 'n': (2, 5)}
OURS = ('ours paper', 'ours spread')
STRAIGHT = 'straight line'
RRT_CONNECT = 'OMPL RRTConnect'
RRT_CONNECT_SIMPLIFIED = 'OMPL RRTConnect + simplify'
OPTIMAL = 'OMPL AORRTC'
PLANNERS = OURS + (STRAIGHT, RRT_CONNECT, RRT_CONNECT_SIMPLIFIED, OPTIMAL)


@dataclass
class Query:
    """One seeded request: obstacles (r, d) and configurations (n, k, d)."""

    kind: str
    d: int
    k: int
    r: int
    n: int
    seed: int
    obstacles: np.ndarray
    configurations: np.ndarray

    @property
    def label(self):
        """Return a short name of the query."""
        return f'{self.kind} d={self.d} k={self.k} r={self.r} n={self.n} seed={self.seed}'


@dataclass
class Outcome:
    """What one planner did on one query."""

    planner: str
    query: Query
    solved: bool
    seconds: float
    times: np.ndarray = None
    positions: np.ndarray = None
    clearance: float = float('nan')
    length_ratio: float = float('nan')
    deterministic: bool = None
    stability: float = float('nan')
    checks: int = 0
    checker_seconds: float = float('nan')
    certificate: object = None
    notes: list = field(default_factory=list)


def separated(points, obstacles, gap):
    """Return True if robots (k, d) are pairwise and from every obstacle more than gap apart."""
    difference = points[:, None] - points[None]
    distance = np.sqrt(np.einsum('abi,abi->ab', difference, difference))
    np.fill_diagonal(distance, np.inf)
    if distance.min() <= gap:
        return False
    if len(obstacles):
        to_obstacles = np.linalg.norm(points[:, None] - obstacles[None], axis=2)
        return bool(to_obstacles.min() > gap)
    return True


def _random_configuration(rng, k, d, obstacles):
    """Return k robots uniform in the query box, valid for discs of RADIUS."""
    while True:
        points = rng.uniform(-QUERY_HALF_WIDTH, QUERY_HALF_WIDTH, (k, d))
        if separated(points, obstacles, 1.5 * SEPARATION):
            return points


def _columns_configuration(rng, k, d, obstacles):
    """Return k robots on a few lines x = const, some of them through obstacles."""
    columns = list(obstacles[:, 0]) + list(rng.uniform(-QUERY_HALF_WIDTH, QUERY_HALF_WIDTH,
                                                       max(1, k // 4)))
    while True:
        points = rng.uniform(-QUERY_HALF_WIDTH, QUERY_HALF_WIDTH, (k, d))
        points[:, 0] = rng.choice(columns, k)
        if separated(points, obstacles, 1.5 * SEPARATION):
            return points


def make_query(kind, d, k, r, n, seed):
    """
    Return the seeded query of that kind.

    random: every configuration uniform in a box. adversarial: C_1 has robots
    sharing projections with each other and with obstacles, and C_{m+1} is
    C_m mirrored through an obstacle (the origin when r = 0), so every
    straight line crosses that obstacle and all robots meet there at once.
    """
    rng = np.random.default_rng([seed, d, k, r, n, kind == 'adversarial'])
    obstacles = random_obstacles(rng, r, d)
    if kind == 'random':
        configurations = [_random_configuration(rng, k, d, obstacles) for _ in range(n)]
    else:
        while True:
            configurations = [_columns_configuration(rng, k, d, obstacles)]
            for m in range(n - 1):
                center = obstacles[m % r] if r else np.zeros(d)
                configurations.append(2 * center - configurations[-1])
            if all(separated(c, obstacles, 1.5 * SEPARATION) for c in configurations):
                break
    return Query(kind, d, k, r, n, seed, obstacles, np.array(configurations))


def make_queries(grid, seeds):
    """Return the queries of the grid (dict of tuples), `seeds` of each."""
    return [make_query(kind, d, k, r, n, seed)
            for kind, d, k, r, n in itertools.product(*(grid[key] for key in
                                                        ('kind', 'd', 'k', 'r', 'n')))
            for seed in range(seeds)]


def motion_length(positions):
    """Return the sum over robots of the length of their piecewise-linear paths."""
    steps = np.diff(positions, axis=0)
    return float(np.sqrt(np.einsum('vkd,vkd->vk', steps, steps)).sum())


def length_ratio(positions, configurations):
    """Return a motion's length over the straight-line bound: the same sum for C_1..C_n."""
    return motion_length(positions) / motion_length(configurations)


def perturbed(query, rng):
    """
    Return the query moved by at most PERTURBATION inside the same domain.

    Coordinates other than the first move freely. The first coordinate (the
    projection: the default frame is the coordinate axes here) moves by one
    shift per distinct value, none where it equals an obstacle's, so robots
    that share a projection keep sharing it and the projection pattern holds.
    """
    moved = query.configurations.copy()
    moved[..., 1:] += rng.uniform(-PERTURBATION, PERTURBATION, moved[..., 1:].shape)
    obstacle_x = set(query.obstacles[:, 0].tolist())
    for configuration in moved:
        values, inverse = np.unique(configuration[:, 0], return_inverse=True)
        shifts = rng.uniform(-PERTURBATION, PERTURBATION, values.size)
        shifts[[value in obstacle_x for value in values.tolist()]] = 0.0
        configuration[:, 0] = values[inverse] + shifts[inverse]
    return moved


def _finish(outcome):
    """Fill in clearance and path length relative to the straight-line bound."""
    query = outcome.query
    if outcome.positions is not None:
        outcome.certificate = certify(outcome.times, outcome.positions, query.obstacles)
        outcome.clearance = outcome.certificate.distance
        outcome.length_ratio = length_ratio(outcome.positions, query.configurations)
    return outcome


def run_ours(query, variant, timing_budget, check):
    """Plan with our planner (certified); time it warm; check determinism and stability."""
    workspace = Workspace(query.obstacles, dimension=query.d, variant=variant)
    result = plan(workspace, query.configurations)
    seconds, _ = median_time(lambda: plan(workspace, query.configurations), timing_budget,
                             min_repeats=5)
    outcome = Outcome(f'ours {variant}', query, True, seconds, result.times, result.positions)
    if check:
        again = plan(workspace, query.configurations)
        outcome.deterministic = (again.times.tobytes() == result.times.tobytes()
                                 and again.positions.tobytes() == result.positions.tobytes())
        moved = plan(workspace, perturbed(query, np.random.default_rng(query.seed)))
        if np.array_equal(moved.projection_counts, result.projection_counts):
            taus = np.union1d(np.linspace(0.0, 1.0, 4001), result.times)
            change = moved.position(taus) - result.position(taus)
            outcome.stability = float(np.sqrt(np.einsum('tkd,tkd->tk', change, change)).max())
        else:
            outcome.notes.append('perturbation changed the projection counts')
    return _finish(outcome)


def run_straight(query):
    """Return the straight-line interpolation through the configurations (no planning)."""
    n = query.n
    outcome = Outcome(STRAIGHT, query, True, 0.0, np.linspace(0.0, 1.0, n),
                      query.configurations.copy())
    outcome.deterministic = True
    outcome.stability = float(np.abs(perturbed(query, np.random.default_rng(query.seed))
                                     - query.configurations).max())
    return _finish(outcome)


class OmplPlanner:
    """
    OMPL on the composite space of k robots in R^d among r obstacles.

    A state is valid when every robot pair is more than pair_gap apart and
    robot and obstacle j more than obstacle_gaps[j] (by default discs of RADIUS:
    SEPARATION each); the motion check runs every motion_step.
    """

    def __init__(self, query, pair_gap=SEPARATION, obstacle_gaps=None, motion_step=MOTION_STEP):
        """Build the state space, its bounds and the validity checker for the query."""
        from ompl import base as ob, util as ou
        ou.setLogLevel(ou.LOG_NONE)
        self.ob = ob
        self.k, self.d = query.k, query.d
        self.dimension = query.k * query.d
        points = np.concatenate([query.configurations.reshape(-1, query.d),
                                 query.obstacles])
        low, high = points.min() - BOUNDS_MARGIN, points.max() + BOUNDS_MARGIN
        self.space = ob.RealVectorStateSpace(self.dimension)
        bounds = ob.RealVectorBounds(self.dimension)
        bounds.setLow(float(low))
        bounds.setHigh(float(high))
        self.space.setBounds(bounds)
        # OMPL's resolution is a fraction of the space's extent.
        extent = (high - low) * np.sqrt(self.dimension)
        self.resolution = float(motion_step / extent)
        self.obstacles = query.obstacles
        self.pair_gap2 = pair_gap ** 2
        self.obstacle_gaps2 = (np.full(len(query.obstacles), SEPARATION) if obstacle_gaps is None
                               else np.asarray(obstacle_gaps, float)) ** 2
        self.pairs = np.triu_indices(query.k, 1)
        self.checker = self._timed_valid
        self.calls, self.checker_seconds = 0, 0.0
        self.solve_calls = self.simplify_calls = 0
        self.solve_checker_seconds = self.simplify_checker_seconds = 0.0

    def _timed_valid(self, state):
        """Return _valid(state), counting the calls and the time spent in Python."""
        begin = time.perf_counter()
        valid = self._valid(state)
        self.checker_seconds += time.perf_counter() - begin
        self.calls += 1
        return valid

    def _valid(self, state):
        """Return True if every robot pair and robot-obstacle pair is farther than its gap."""
        x = np.fromiter((state[i] for i in range(self.dimension)), float,
                        self.dimension).reshape(self.k, self.d)
        a, b = self.pairs
        difference = x[a] - x[b]
        if a.size and np.einsum('pi,pi->p', difference, difference).min() <= self.pair_gap2:
            return False
        if len(self.obstacles):
            difference = x[:, None] - self.obstacles[None]
            return bool(np.all(np.einsum('koi,koi->ko', difference, difference)
                               > self.obstacle_gaps2[None]))
        return True

    def _state(self, values):
        """Return an OMPL state holding values (filled element by element)."""
        state = self.space.allocState()
        for i, value in enumerate(values.ravel().tolist()):
            state[i] = value
        return state

    def _states(self, path):
        """Return the (V, k, d) robot positions of an OMPL path's states."""
        return np.array([[path.getState(v)[i] for i in range(self.dimension)]
                         for v in range(path.getStateCount())]).reshape(-1, self.k, self.d)

    def solve(self, start, goal, planner_name, budget, simplify_budget=None):
        """
        Plan one query start -> goal within budget seconds.

        Returns (solved, seconds, raw positions, simplified positions,
        simplify seconds); simplification runs only when simplify_budget is set.
        """
        from ompl import geometric as og
        setup = og.SimpleSetup(self.space)
        setup.setStateValidityChecker(self.checker)
        information = setup.getSpaceInformation()
        information.setStateValidityCheckingResolution(self.resolution)
        setup.setStartAndGoalStates(self._state(start), self._state(goal))
        planner = getattr(og, planner_name)(information)
        setup.setPlanner(planner)
        if planner_name != 'RRTConnect':
            setup.setOptimizationObjective(
                self.ob.PathLengthOptimizationObjective(information))
        calls, checking = self.calls, self.checker_seconds
        begin = time.perf_counter()
        setup.solve(float(budget))
        seconds = time.perf_counter() - begin
        self.solve_calls += self.calls - calls
        self.solve_checker_seconds += self.checker_seconds - checking
        if not setup.haveExactSolutionPath():
            return False, seconds, None, None, 0.0
        raw = self._states(setup.getSolutionPath())
        simplified, simplify_seconds = None, 0.0
        if simplify_budget is not None:
            calls, checking = self.calls, self.checker_seconds
            begin = time.perf_counter()
            setup.simplifySolution(float(simplify_budget))
            simplify_seconds = time.perf_counter() - begin
            self.simplify_calls += self.calls - calls
            self.simplify_checker_seconds += self.checker_seconds - checking
            simplified = self._states(setup.getSolutionPath())
        return True, seconds, raw, simplified, simplify_seconds


def _chain(query, planner, planner_name, budget, simplify_budget, configurations=None):
    """Solve the n - 1 chained queries; return (solved, seconds, raw, simplified, simplify s)."""
    configurations = query.configurations if configurations is None else configurations
    seconds, simplify_seconds = 0.0, 0.0
    raw, simplified = [configurations[:1]], [configurations[:1]]
    for m in range(query.n - 1):
        ok, spent, path, short, spent_simplifying = planner.solve(
            configurations[m], configurations[m + 1], planner_name, budget, simplify_budget)
        seconds += spent
        simplify_seconds += spent_simplifying
        if not ok:
            return False, seconds, None, None, simplify_seconds
        # Pin the waypoints to the request exactly, then drop the repeated start.
        path[0], path[-1] = configurations[m], configurations[m + 1]
        raw.append(path[1:])
        if short is not None:
            short[0], short[-1] = configurations[m], configurations[m + 1]
            simplified.append(short[1:])
    return (True, seconds, np.concatenate(raw),
            np.concatenate(simplified) if simplify_budget is not None else None,
            simplify_seconds)


def arc_length_resample(positions, samples=1001):
    """Return positions (V, k, d) resampled at evenly spaced composite arc length."""
    flat = positions.reshape(len(positions), -1)
    cumulative = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(flat, axis=0),
                                                                 axis=1))])
    target = np.linspace(0.0, cumulative[-1], samples)
    columns = [np.interp(target, cumulative, flat[:, j]) for j in range(flat.shape[1])]
    return np.stack(columns, axis=1).reshape(samples, *positions.shape[1:])


def path_change(first, second):
    """Return the largest robot displacement between two paths compared by arc length."""
    change = arc_length_resample(first) - arc_length_resample(second)
    return float(np.sqrt(np.einsum('skd,skd->sk', change, change)).max())


def _times(positions):
    """Return breakpoint parameters evenly spaced by breakpoint index."""
    return np.linspace(0.0, 1.0, len(positions))


def run_ompl(query, budget, optimal_budget, simplify_budget, check):
    """Return the OMPL outcomes (RRTConnect, RRTConnect + simplify, AORRTC) on a query."""
    planner = OmplPlanner(query)
    solved, seconds, raw, short, simplify_seconds = _chain(query, planner, 'RRTConnect',
                                                           budget, simplify_budget)
    connect = Outcome(RRT_CONNECT, query, solved, seconds)
    simplified = Outcome(RRT_CONNECT_SIMPLIFIED, query, solved, seconds + simplify_seconds)
    connect.checks = planner.solve_calls
    connect.checker_seconds = planner.solve_checker_seconds
    simplified.checks = planner.solve_calls + planner.simplify_calls
    simplified.checker_seconds = (planner.solve_checker_seconds
                                  + planner.simplify_checker_seconds)
    if solved:
        connect.times, connect.positions = _times(raw), raw
        simplified.times, simplified.positions = _times(short), short
    optimal_solved, optimal_seconds, optimal_raw, _, _ = _chain(
        query, planner, 'AORRTC', optimal_budget, None)
    optimal = Outcome(OPTIMAL, query, optimal_solved, optimal_seconds)
    if optimal_solved:
        optimal.times, optimal.positions = _times(optimal_raw), optimal_raw
    if check:
        _check_ompl(query, planner, budget, simplify_budget, connect, simplified)
    return [_finish(outcome) for outcome in (connect, simplified, optimal)]


def _check_ompl(query, planner, budget, simplify_budget, connect, simplified):
    """Fill determinism (same query again) and stability (perturbed query) for RRTConnect."""
    if not connect.solved:
        return
    again = _chain(query, planner, 'RRTConnect', budget, simplify_budget)
    if again[0]:
        connect.deterministic = (again[2].shape == connect.positions.shape
                                 and again[2].tobytes() == connect.positions.tobytes())
        simplified.deterministic = (again[3].shape == simplified.positions.shape
                                    and again[3].tobytes() == simplified.positions.tobytes())
    moved = perturbed(query, np.random.default_rng(query.seed))
    other = _chain(query, planner, 'RRTConnect', budget, simplify_budget, moved)
    if other[0]:
        connect.stability = path_change(connect.positions, other[2])
        simplified.stability = path_change(simplified.positions, other[3])


@dataclass
class Settings:
    """Grid, seeds and budgets of one run."""

    grid: dict
    seeds: int = 3
    budget: float = 5.0
    optimal_budget: float = 0.25
    simplify_budget: float = 0.5
    timing_budget: float = 0.02
    check_seeds: int = 1
    check_max_k: int = 8


def run(settings, progress=None):
    """Return every Outcome of every planner on every query of settings."""
    outcomes = []
    queries = make_queries(settings.grid, settings.seeds)
    for index, query in enumerate(queries):
        check = query.seed < settings.check_seeds and query.k <= settings.check_max_k
        for variant in ('paper', 'spread'):
            outcomes.append(run_ours(query, variant, settings.timing_budget, True))
        outcomes.append(run_straight(query))
        outcomes.extend(run_ompl(query, settings.budget, settings.optimal_budget,
                                 settings.simplify_budget, check))
        if progress:
            progress(index + 1, len(queries), query)
    return outcomes


def _median(values):
    """Return the median of values, nan for none."""
    values = [v for v in values if v == v]
    return float(np.median(values)) if values else float('nan')


def _percent(flags):
    """Return the percentage of True among flags (None ignored) as text."""
    flags = [flag for flag in flags if flag is not None]
    return f'{100 * np.mean(flags):.0f}%' if flags else '-'


def _number(value, digits=3):
    """Return value with `digits` significant digits, '-' for nan."""
    return '-' if value != value else f'{value:.{digits}g}'


def _by_planner(outcomes):
    """Return {planner: [outcomes]} in PLANNERS order."""
    grouped = {name: [] for name in PLANNERS}
    for outcome in outcomes:
        grouped[outcome.planner].append(outcome)
    return grouped


def reference_median(outcomes, variant='ours paper'):
    """Return our median planning time (certification included) over the same queries."""
    return _median([o.seconds for o in outcomes if o.planner == variant])


def summary_rows(outcomes):
    """Return the table of figures per planner (header first)."""
    rows = [('planner', 'solved in budget', 'certified > 0', 'certified >= 2 radius',
             'median time / ours', 'p95 time / ours', 'path length / straight (median)',
             'certified clearance (min / median)', 'deterministic', 'stability (max change)')]
    ours = reference_median(outcomes)
    for planner, group in _by_planner(outcomes).items():
        if not group:
            continue
        seconds = [o.seconds for o in group]
        solved = [o for o in group if o.solved]
        clearances = [o.clearance for o in solved]
        timed = planner != STRAIGHT
        stability = [o.stability for o in group if o.stability == o.stability]
        rows.append((
            planner,
            _percent([o.solved for o in group]),
            _percent([o.solved and o.clearance > 0 for o in group]),
            _percent([o.solved and o.clearance >= SEPARATION for o in group]),
            _number(_median(seconds) / ours) if timed else '-',
            _number(float(np.percentile(seconds, 95)) / ours) if timed else '-',
            _number(_median([o.length_ratio for o in solved])),
            (f'{_number(min(clearances))} / {_number(_median(clearances))}'
             if clearances else '-'),
            _percent([o.deterministic for o in group]),
            (f'{_number(max(stability))} (n={len(stability)})' if stability else '-'),
        ))
    return rows


def flagged_rows(outcomes):
    """
    Return the OMPL outputs the exact certificate puts below 0.9 x 2 radius.

    OMPL accepted them; between its motion-check samples (MOTION_STEP apart)
    a pair may dip slightly below 2 radius, but not by 10%. For each: the
    certified pair, how far that pair is apart at the two states of the leg
    (OMPL checked those) and the leg's composite length (OMPL's motion check
    samples it every MOTION_STEP).
    """
    rows = [('query', 'planner', 'certified', 'pair', "at the leg's two states",
             'leg length (composite)')]
    for outcome in outcomes:
        if (outcome.planner in OURS + (STRAIGHT,) or not outcome.solved
                or outcome.clearance >= 0.9 * SEPARATION):
            continue
        found = outcome.certificate
        leg = outcome.positions[found.leg:found.leg + 2]
        first = leg[:, found.indices[0]]
        second = (leg[:, found.indices[1]] if found.kind == 'robots'
                  else outcome.query.obstacles[found.indices[1]][None])
        ends = np.linalg.norm(first - second, axis=-1)
        rows.append((outcome.query.label, outcome.planner, _number(found.distance),
                     f'{found.kind} {found.indices}', ', '.join(_number(e) for e in ends),
                     _number(float(np.linalg.norm(leg[1] - leg[0])))))
    return rows


def breakdown_rows(outcomes, key, label):
    """Return per-`key` success and median-time ratios of OMPL RRTConnect against ours."""
    rows = [(label, 'queries', 'ours paper: certified > 0', 'straight line collides',
             'RRTConnect solved', 'AORRTC solved', 'RRTConnect median / ours',
             'same, Python checker time removed', 'RRTConnect checks (median)',
             'AORRTC median / ours')]
    values = sorted({key(o.query) for o in outcomes})
    for value in values:
        group = _by_planner([o for o in outcomes if key(o.query) == value])
        ours = _median([o.seconds for o in group['ours paper']])
        rows.append((
            str(value), str(len(group['ours paper'])),
            _percent([o.clearance > 0 for o in group['ours paper']]),
            _percent([o.clearance < SEPARATION for o in group[STRAIGHT]]),
            _percent([o.solved for o in group[RRT_CONNECT]]),
            _percent([o.solved for o in group[OPTIMAL]]),
            _number(_median([o.seconds for o in group[RRT_CONNECT]]) / ours),
            _number(_median([o.seconds - o.checker_seconds for o in group[RRT_CONNECT]])
                    / ours),
            _number(_median([o.checks for o in group[RRT_CONNECT]])),
            _number(_median([o.seconds for o in group[OPTIMAL]]) / ours),
        ))
    return rows


def time_by_k(outcomes):
    """Return {planner: [(k, median seconds)]} for the plot."""
    series = {}
    for planner, group in _by_planner(outcomes).items():
        ks = sorted({o.query.k for o in group})
        series[planner] = [(k, _median([o.seconds for o in group if o.query.k == k]))
                           for k in ks]
    return series


def quick_settings():
    """Return a small grid for a smoke run."""
    return Settings({'kind': ('random', 'adversarial'), 'd': (2,), 'k': (2, 8), 'r': (2,),
                     'n': (2,)}, seeds=1, budget=2.0, optimal_budget=0.1)


def main(argv=None):
    """Print the peer comparison table."""
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--quick', action='store_true', help='a small grid only')
    args = parser.parse_args(argv)
    settings = quick_settings() if args.quick else Settings(FULL_GRID)
    outcomes = run(settings, lambda i, total, q: print(f'[{i}/{total}] {q.label}',
                                                       file=sys.stderr, flush=True))
    print(format_table(summary_rows(outcomes)))
    print()
    print(format_table(breakdown_rows(outcomes, lambda q: q.k, 'k')))
    sys.stdout.flush()
    # nanobind reports OMPL's Python wrappers as leaked at interpreter exit: skip teardown.
    os._exit(0)


if __name__ == '__main__':
    main()
