"""
The refinement (issue 18): refined against unrefined against OMPL RRTConnect + simplify.

Realistic fleets: k disc robots of radius R = 0.2 m (balls in 3-D) covering 6%
of a square hall (a cube in 3-D, at least 4 m wide), 3 to 10 pillars of radius
0.15 m at least 1 m apart, robot centres at least 4R apart and at least
2R + rho from every pillar, n = 3 configurations drawn independently; variant
'discs'. Figures per plan: path length / straight-line bound (the sum over
robots and segments of path length over the sum of straight-line distances
C_m -> C_{m+1}), excursion (how far the motion leaves the box of all
configurations and pillars, as a share of its longest side), min_gap against
the refinement's margin, planning time with the exact certificate (best of 2),
and continuity (a 1e-7 move of every coordinate inside the domain: the largest
change of the motion as a function of normalised time, over the move). OMPL
RRTConnect (2 s per segment) with path simplification (1 s) plans the same
fleets for small k (it does not solve larger ones in its budget), its discs
validity check in Python; its time is given with and without that checker.

Run alone: ``.venv/bin/python bench/refinement.py [--quick] [--k K ...]``;
``--k 40`` plans only fleets of 40 robots (in every dimension of the grid, with
its seeds), ``--quick --k 40`` with the smoke run's.
"""

import argparse
from dataclasses import dataclass, field, replace
import sys
import time

from core_speed import grid_main, grid_report
import numpy as np
import peers

from punctured_planner.core import plan, PlanningError, Workspace
from punctured_planner.core.certificate import certify
from punctured_planner.core.pairs import point_radii

RADIUS, PILLAR = 0.2, 0.15
COVERAGE = 0.06
MIN_HALL = 4.0
PERTURBATION = 1e-7
RAW, REFINED, RRT = 'construction', 'refined', 'OMPL RRTConnect + simplify'


@dataclass
class Fleet:
    """One request: pillars (r, d), configurations (n, k, d)."""

    k: int
    d: int
    seed: int
    pillars: np.ndarray
    configurations: np.ndarray


def _place(rng, count, hall, d, accept, tries=200000):
    """Return count points uniform in the hall, each accepted given those before, or None."""
    points = np.zeros((0, d))
    for _ in range(tries):
        point = rng.uniform(0.0, hall, d)
        if accept(point, points):
            points = np.vstack([points, point])
            if len(points) == count:
                return points
    return None


def realistic_fleet(k, d, seed, n=3):
    """Return a Fleet at the module's density, reproducible by seed (None if none fits)."""
    rng = np.random.default_rng(seed)
    body = np.pi * RADIUS ** 2 if d == 2 else 4 / 3 * np.pi * RADIUS ** 3
    hall = max(MIN_HALL, (k * body / COVERAGE) ** (1 / d))
    pillars = _place(rng, int(rng.integers(3, 11)), hall, d, lambda p, before: np.all(
        np.linalg.norm(before - p, axis=1) >= 1.0))

    def free(point, before):
        return bool(np.all(np.linalg.norm(before - point, axis=1) >= 4 * RADIUS)
                    and np.all(np.linalg.norm(pillars - point, axis=1) >= 2 * RADIUS + PILLAR))

    if pillars is None:
        return None
    configurations = [_place(rng, k, hall, d, free) for _ in range(n)]
    if any(c is None for c in configurations):
        return None
    return Fleet(k, d, seed, pillars, np.array(configurations))


def each_fleet(ks, seeds, seed_of, progress=None):
    """Yield the realistic fleets in the plane: seeds(k) per k, seeded by seed_of(k, seed)."""
    for k in ks:
        for seed in range(seeds(k)):
            fleet = realistic_fleet(k, 2, seed_of(k, seed))
            if fleet is None:
                continue
            if progress:
                progress(f'k={k} seed={seed}')
            yield fleet


def excursion(positions, fleet):
    """Return how far positions (V, k, d) leave the box of configurations and pillars."""
    d = fleet.d
    points = np.concatenate([fleet.configurations.reshape(-1, d), fleet.pillars])
    low, high = points.min(axis=0), points.max(axis=0)
    flat = positions.reshape(-1, d)
    beyond = max(float((low - flat).max()), float((flat - high).max()), 0.0)
    return beyond / float((high - low).max())


@dataclass
class Result:
    """One planner on one fleet."""

    planner: str
    fleet: Fleet
    solved: bool
    length_ratio: float = float('nan')
    excursion: float = float('nan')
    gap: float = float('nan')
    margin: float = float('nan')
    seconds: float = float('nan')
    checker_seconds: float = float('nan')
    continuity: float = float('nan')
    extra: dict = field(default_factory=dict)


def _workspace(fleet):
    """Return the fleet's discs Workspace."""
    return Workspace(fleet.pillars, variant='discs', robot_radius=RADIUS,
                     obstacle_radius=PILLAR)


def _continuity(fleet, refine, base):
    """Return the motion change over a PERTURBATION move inside the domain (nan if it left)."""
    rng = np.random.default_rng(fleet.seed)
    moved = fleet.configurations + rng.uniform(-PERTURBATION, PERTURBATION,
                                               fleet.configurations.shape)
    other = plan(_workspace(fleet), moved, certify=False, refine=refine)
    if not np.array_equal(other.projection_counts, base.projection_counts):
        return float('nan')
    tau = np.linspace(0.0, 1.0, 3001)
    return float(np.abs(other.position(tau) - base.position(tau)).max() / PERTURBATION)


def run_ours(fleet, refine, measure_continuity, repeats=2):
    """Plan with the discs variant, refined or not; time includes the exact certificate."""
    workspace = _workspace(fleet)
    best = np.inf
    for _ in range(repeats):
        begin = time.perf_counter()
        result = plan(workspace, fleet.configurations, certify=False, refine=refine)
        gap = result.min_gap
        best = min(best, time.perf_counter() - begin)
    return Result(REFINED if refine else RAW, fleet, True,
                  peers.length_ratio(result.positions, fleet.configurations),
                  excursion(result.positions, fleet), gap,
                  result.margin if refine else gap, best,
                  continuity=_continuity(fleet, refine, result) if measure_continuity
                  else float('nan'))


def run_rrt(fleet, budget, simplify_budget):
    """Plan with OMPL RRTConnect and simplification; the discs check as its validity."""
    query = peers.Query('discs', fleet.d, fleet.k, len(fleet.pillars), 3, fleet.seed,
                        fleet.pillars, fleet.configurations)
    planner = peers.OmplPlanner(query, pair_gap=2 * RADIUS,
                                obstacle_gaps=np.full(len(fleet.pillars), RADIUS + PILLAR),
                                motion_step=RADIUS / 4)
    solved, seconds, _, short, simplify_seconds = peers._chain(
        query, planner, 'RRTConnect', budget, simplify_budget)
    total = seconds + simplify_seconds
    checking = planner.solve_checker_seconds + planner.simplify_checker_seconds
    if not solved:
        return Result(RRT, fleet, False, seconds=total, checker_seconds=checking)
    radii = point_radii(fleet.k, RADIUS, np.full(len(fleet.pillars), PILLAR))
    gap = certify(np.linspace(0, 1, len(short)), short, fleet.pillars, radii).distance
    return Result(RRT, fleet, True, peers.length_ratio(short, fleet.configurations),
                  excursion(short, fleet), gap, 0.0, total, checking)


@dataclass
class Settings:
    """What to run: fleet sizes per dimension, seeds, OMPL's fleets and budgets."""

    ks: dict = field(default_factory=lambda: {2: (3, 5, 8, 10, 20, 40, 100, 200),
                                              3: (3, 8, 20, 40)})
    seeds: int = 6
    large_seeds: int = 2
    continuity_seeds: int = 3
    rrt_ks: tuple = (3, 5, 8)
    rrt_seeds: int = 3
    rrt_budget: float = 2.0
    simplify_budget: float = 1.0


def quick_settings():
    """Return a smoke-run grid."""
    return Settings(ks={2: (5, 20), 3: (5,)}, seeds=2, large_seeds=1, continuity_seeds=1,
                    rrt_ks=(5,), rrt_seeds=1, rrt_budget=0.5, simplify_budget=0.2)


def run(settings, progress=None):
    """Return every Result of the grid."""
    results = []
    for d, ks in settings.ks.items():
        for k in ks:
            seeds = settings.seeds if k <= 40 else settings.large_seeds
            for seed in range(seeds):
                fleet = realistic_fleet(k, d, 100 * k + 10 * d + seed)
                if fleet is None:
                    continue
                if progress:
                    progress(f'd={d} k={k} seed={seed}')
                try:
                    for refine in (False, True):
                        results.append(run_ours(fleet, refine,
                                                seed < settings.continuity_seeds))
                except PlanningError as error:  # reported, not hidden
                    print(f'd={d} k={k} seed={seed}: {error}', file=sys.stderr)
                if d == 2 and k in settings.rrt_ks and seed < settings.rrt_seeds:
                    results.append(run_rrt(fleet, settings.rrt_budget,
                                           settings.simplify_budget))
    return results


def _median(values, digits=2, scale=1.0):
    """Return the median of the finite values, formatted, or '-'."""
    values = np.asarray(values, float) * scale
    values = values[np.isfinite(values)]
    return f'{np.median(values):.{digits}f}' if values.size else '-'


def _select(results, planner, d, ks):
    """Return the solved results of planner at dimension d for fleet sizes in ks."""
    return [r for r in results if r.planner == planner and r.fleet.d == d
            and r.fleet.k in ks and r.solved]


def _apart(results):
    """Return 'a/b': how many of the plans keep every pair of bodies apart (min_gap >= 0)."""
    return f'{sum(r.gap >= 0 for r in results)}/{len(results)}'


def table(results):
    """Return the rows per (d, k): medians of every figure for the three planners."""
    rows = [('d', 'k', 'plans', 'length ratio: construction, refined, OMPL',
             'excursion: construction, refined, OMPL', 'refined min_gap >= margin',
             'bodies apart (min_gap >= 0): construction, refined',
             'time ms: construction, refined, OMPL (without its checker)',
             'continuity: construction, refined (max)')]
    for d in sorted({r.fleet.d for r in results}):
        for k in sorted({r.fleet.k for r in results if r.fleet.d == d}):
            raw, refined = _select(results, RAW, d, (k,)), _select(results, REFINED, d, (k,))
            rrt = [r for r in results if r.planner == RRT and r.fleet.d == d and r.fleet.k == k]
            solved = [r for r in rrt if r.solved]
            ompl = (f'{_median([r.seconds for r in rrt], 0, 1e3)} '
                    f'({_median([r.seconds - r.checker_seconds for r in rrt], 0, 1e3)}), '
                    f'{len(solved)}/{len(rrt)} solved' if rrt else '-')
            kept = sum(r.gap >= r.margin for r in refined)
            rows.append((
                str(d), str(k), str(len(refined)),
                ', '.join([_median([r.length_ratio for r in raw]),
                           _median([r.length_ratio for r in refined]),
                           _median([r.length_ratio for r in solved])]),
                ', '.join([_median([r.excursion for r in group], 0, 100) + '%'
                           for group in (raw, refined, solved)]),
                f'{kept}/{len(refined)}',
                ', '.join(_apart(group) for group in (raw, refined)),
                ', '.join([_median([r.seconds for r in raw], 1, 1e3),
                           _median([r.seconds for r in refined], 1, 1e3), ompl]),
                ', '.join(f'{np.nanmax([r.continuity for r in group] + [np.nan]):.1f}'
                          if any(np.isfinite(r.continuity) for r in group) else '-'
                          for group in (raw, refined))))
    return rows


def summary(results):
    """Return the headline lines: issue 18's targets against this run."""
    def ratio(ks, d=2):
        return _median([r.length_ratio for r in _select(results, REFINED, d, ks)])

    def share(ks, d=2):
        return _median([r.excursion for r in _select(results, REFINED, d, ks)], 0, 100)

    def milliseconds(planner, k):
        return _median([r.seconds for r in _select(results, planner, 2, (k,))], 1, 1e3)

    refined = [r for r in results if r.planner == REFINED]
    rrt8 = [r for r in results if r.planner == RRT and r.fleet.k == 8]
    small, middle, large = range(3, 11), range(20, 41), range(100, 201)
    return [
        f'- Median path length / straight-line bound, refined (d = 2): k <= 10 '
        f'{ratio(small)} (target <= 1.7), k = 20 - 40 {ratio(middle)} (target <= 2.0), '
        f'k = 100 - 200 {ratio(large)} (target <= 2.5); d = 3: k <= 10 {ratio(small, 3)}, '
        f'k = 20 - 40 {ratio(middle, 3)}.',
        f'- Median excursion beyond the box, refined (d = 2): k <= 40 '
        f'{share(range(3, 41))}% (target <= 15%), k = 100 - 200 {share(large)}%.',
        f'- Refined plans with min_gap >= their margin: '
        f'{sum(r.gap >= r.margin for r in refined)} of {len(refined)} (target all).',
        '- Bodies apart (min_gap >= 0), construction and refined: '
        + ', '.join(f'{bodies} (d = {d}) ' + ' and '.join(
            _apart([r for r in results if r.planner == planner and r.fleet.d == d])
            for planner in (RAW, REFINED)) for d, bodies in ((2, 'discs'), (3, 'balls')))
        + ' (doc/design.md section 6: each ball meets a pillar with its own reach).',
        f'- Planning time with the certificate, k = 40 n = 3: refined '
        f'{milliseconds(REFINED, 40)} ms (target < 50 ms), construction '
        f'{milliseconds(RAW, 40)} ms; k = 200: refined {milliseconds(REFINED, 200)} ms '
        f'(target < 1000 ms), construction {milliseconds(RAW, 200)} ms.',
        f'- k = 8: refined {milliseconds(REFINED, 8)} ms against OMPL RRTConnect + simplify '
        f'{_median([r.seconds for r in rrt8], 1, 1e3)} ms, '
        f'{_median([r.seconds - r.checker_seconds for r in rrt8], 1, 1e3)} ms without its '
        f'Python checker (target: refined faster than both).',
        f'- Continuity: a {PERTURBATION:g} move inside a domain moved the refined motion by '
        f'at most {np.nanmax([r.continuity for r in refined] + [np.nan]):.1f}x that '
        f'(target <= 100x).',
    ]


def report(settings):
    """Run the benchmark; return its Markdown lines: the targets, then the table."""
    return grid_report(settings, run, summary, table)


def main(argv=None):
    """Run the benchmark and print its figures (--k: only those fleet sizes)."""
    parser = argparse.ArgumentParser(add_help=False)
    parser.add_argument('--k', type=int, nargs='+', help='fleet sizes to run (default: all)')
    chosen, rest = parser.parse_known_args(argv)

    def only(settings):
        if not chosen.k:
            return settings
        return replace(settings, ks={d: tuple(chosen.k) for d in settings.ks},
                       rrt_ks=tuple(k for k in settings.rrt_ks if k in chosen.k))

    grid_main(__doc__, report, lambda: only(quick_settings()), lambda: only(Settings()), rest)


if __name__ == '__main__':
    main()
