"""
Disc robots among pillars: how often each planner keeps the bodies apart (issue 11).

Fleets of k disc robots (radius R = 0.25 m) at realistic density: robots cover
about 6% of a square hall (at least 6 m wide, so small fleets get room for the
pillars), 3 to 10 pillars of radius 0.05-0.25 m at least 1 m apart, robot
centres at least 4R apart and at least 2R + rho from every pillar centre;
n configurations drawn independently. Every planner's output is judged by the
same exact certificate (Plan.min_gap; OMPL's paths through its states as
piecewise-linear synchronous motions); "gap >= 0" allows the rounding of the
coordinates (the certificate's resolution, 1e-12 of their scale), as bodies
that touch exactly come out a few ulps either side of 0. A second family meets the 'discs'
theorem's condition exactly (robots on a lattice of pitch S, pillars on
lattice cells, pillar pairs checked against condition (c)).

Run alone: ``.venv/bin/python bench/discs.py [--quick]``.
"""

from dataclasses import dataclass
import time

from core_speed import format_table, grid_main, progress_printer
import numpy as np
import peers

from punctured_planner.core import plan, PlanningError, Workspace
from punctured_planner.core.certificate import certify
from punctured_planner.core.discs import MARGIN
from punctured_planner.core.pairs import point_radii

RADIUS = 0.25
COVERAGE = 0.06
MIN_HALL = 6.0
PILLAR_SPACING = 1.0
VARIANTS = ('discs', 'spread', 'paper')
RRT = 'OMPL RRTConnect'
PERTURBATION = 1e-6


@dataclass
class Fleet:
    """One request: pillars (r, 2) of radii (r,), configurations (n, k, 2)."""

    k: int
    n: int
    seed: int
    pillars: np.ndarray
    radii: np.ndarray
    configurations: np.ndarray


def _place(rng, count, hall, accept, tries=200000):
    """Return count points uniform in the hall, each accepted given those before, or None."""
    points = []
    for _ in range(tries):
        point = rng.uniform(0.0, hall, 2)
        if accept(point, np.array(points).reshape(-1, 2)):
            points.append(point)
            if len(points) == count:
                return np.array(points)
    return None


def realistic_fleet(k, n, seed):
    """Return a Fleet at the benchmark's density (module docstring), reproducible by seed."""
    rng = np.random.default_rng(seed)
    hall = max(MIN_HALL, np.sqrt(k * np.pi * RADIUS ** 2 / COVERAGE))
    r = int(rng.integers(3, 11))
    radii = rng.uniform(0.05, 0.25, r)
    pillars = _place(rng, r, hall, lambda p, before: not len(before) or np.min(
        np.linalg.norm(before - p, axis=1)) >= PILLAR_SPACING)

    def free(point, before):
        if len(before) and np.min(np.linalg.norm(before - point, axis=1)) < 4 * RADIUS:
            return False
        return bool(np.all(np.linalg.norm(pillars - point, axis=1) >= 2 * RADIUS + radii))

    configurations = [_place(rng, k, hall, free) for _ in range(n)]
    if pillars is None or any(c is None for c in configurations):
        return None
    return Fleet(k, n, seed, pillars, radii, np.array(configurations))


def condition_fleet(k, n, seed):
    """Return a Fleet that meets the theorem's condition exactly (lattice of pitch S)."""
    rng = np.random.default_rng(seed)
    side = int(np.ceil(np.sqrt(1.5 * k + 10)))
    # S for the widest pillar drawn below (rho = R): 2R + nu + w (doc/design.md section 6).
    widest = Workspace([[0.0, 0.0]], variant='discs', robot_radius=RADIUS,
                       obstacle_radius=RADIUS).disc_layout.reach.max()
    pitch = max(4 * RADIUS, (2 + MARGIN) * RADIUS + widest)
    cells = np.array([(c, r) for c in range(side) for r in range(side)], float) * pitch
    for _ in range(100):
        pick = rng.permutation(len(cells))
        pillars = cells[pick[:int(rng.integers(3, 11))]]
        radii = rng.choice([0.0, 0.5, 1.0], len(pillars)) * RADIUS
        try:
            workspace = Workspace(pillars, variant='discs', robot_radius=RADIUS,
                                  obstacle_radius=radii)
        except PlanningError:
            continue
        if len(workspace.disc_layout.conflicting_pillars()):
            continue
        free = cells[pick[len(pillars):]]
        if len(free) < k:
            continue
        configurations = np.array([free[rng.permutation(len(free))[:k]] for _ in range(n)])
        return Fleet(k, n, seed, pillars, radii, configurations)
    return None


@dataclass
class Result:
    """One planner on one fleet: the certified gap, path-length ratio and time."""

    planner: str
    fleet: Fleet
    gap: float
    length_ratio: float
    seconds: float
    domain_index: int = -1
    resolution: float = 0.0
    build_seconds: float = float('nan')

    @property
    def apart(self):
        """Return whether the bodies never touch: gap >= 0 up to the coordinates' rounding."""
        return self.gap >= -self.resolution


def run_ours(fleet, variant, repeats=3):
    """
    Plan with one of our variants.

    seconds is the best of repeats with the exact gap certificate, build_seconds
    without it (the plan's breakpoints only).
    """
    bodies = {'robot_radius': RADIUS, 'obstacle_radius': fleet.radii}
    frame = None
    if variant == 'paper':  # in the discs' frame, which may be oblique (design section 4)
        frame = Workspace(fleet.pillars, variant='discs', **bodies).frame
    workspace = Workspace(fleet.pillars, variant=variant, frame=frame, **bodies)
    best = build = np.inf
    for _ in range(repeats):
        begin = time.perf_counter()
        result = plan(workspace, fleet.configurations, certify=False, refine=False)
        built = time.perf_counter()
        gap = result.min_gap
        best = min(best, time.perf_counter() - begin)
        build = min(build, built - begin)
    return Result(variant, fleet, gap,
                  peers.length_ratio(result.positions, fleet.configurations), best,
                  result.domain_index, result.clearance.resolution, build)


def run_rrt(fleet, budget):
    """Plan with OMPL RRTConnect, discs as its validity check; unsolved counts as failed."""
    query = peers.Query('discs', 2, fleet.k, len(fleet.pillars), fleet.n, fleet.seed,
                        fleet.pillars, fleet.configurations)
    planner = peers.OmplPlanner(query, pair_gap=2 * RADIUS, obstacle_gaps=RADIUS + fleet.radii,
                                motion_step=RADIUS / 4)
    solved, seconds, raw, _, _ = peers._chain(query, planner, 'RRTConnect', budget, None)
    if not solved:
        return Result(RRT, fleet, -np.inf, np.nan, seconds)
    radii = point_radii(fleet.k, RADIUS, fleet.radii)
    certificate = certify(np.linspace(0, 1, len(raw)), raw, fleet.pillars, radii)
    return Result(RRT, fleet, certificate.distance,
                  peers.length_ratio(raw, fleet.configurations), seconds,
                  resolution=certificate.resolution)


def continuity(fleet, rng, trials=3):
    """Return the largest motion change / input change over small moves inside a domain."""
    workspace = Workspace(fleet.pillars, variant='discs', robot_radius=RADIUS,
                          obstacle_radius=fleet.radii)
    base = plan(workspace, fleet.configurations, certify=False, refine=False)
    tau = np.linspace(0.0, 1.0, 4001)
    worst = 0.0
    for _ in range(trials):
        moved = fleet.configurations + rng.uniform(-PERTURBATION, PERTURBATION,
                                                   fleet.configurations.shape)
        other = plan(workspace, moved, certify=False, refine=False)
        if not np.array_equal(other.projection_counts, base.projection_counts):
            continue
        change = np.abs(other.position(tau) - base.position(tau)).max()
        worst = max(worst, change / PERTURBATION)
    return worst


@dataclass
class Settings:
    """What to run: fleet sizes, configuration counts, seeds, OMPL's budget."""

    ks: tuple = (3, 5, 10, 20, 40, 100)
    ns: tuple = (2, 3, 5)
    seeds: int = 30
    rrt_ks: tuple = (3, 5, 10, 20, 40)
    rrt_seeds: int = 4
    rrt_budget: float = 2.0


def quick_settings():
    """Return a smoke-run grid."""
    return Settings(ks=(5, 20), ns=(3,), seeds=4, rrt_ks=(5,), rrt_seeds=1, rrt_budget=0.5)


def run(settings, progress=None):
    """Return (results, condition results, continuity ratios, timing rows)."""
    results, condition, ratios = [], [], []
    rng = np.random.default_rng(0)
    for k in settings.ks:
        for n in settings.ns:
            for seed in range(settings.seeds):
                fleet = realistic_fleet(k, n, 1000 * k + 10 * n + seed)
                if fleet is None:
                    continue
                if progress:
                    progress(f'k={k} n={n} seed={seed}')
                results += [run_ours(fleet, variant) for variant in VARIANTS]
                if k in settings.rrt_ks and seed < settings.rrt_seeds and n == 3:
                    results.append(run_rrt(fleet, settings.rrt_budget))
                if seed < 3:
                    ratios.append(continuity(fleet, rng))
                exact = condition_fleet(k, n, seed)
                if exact is not None:
                    condition.append(run_ours(exact, 'discs', repeats=1))
    return results, condition, ratios


def _share(results):
    """Return the share of results whose bodies never touch, as a percentage string."""
    return f'{100 * np.mean([r.apart for r in results]):.1f}%' if len(results) else '-'


def _median(values):
    """Return the median of the finite values, formatted."""
    values = np.asarray(values, float)
    values = values[np.isfinite(values)]
    return f'{np.median(values):.2f}' if values.size else '-'


def share_rows(results):
    """Return table rows: per k, the share of plans with min_gap >= 0 for each planner."""
    planners = VARIANTS + (RRT,)
    rows = [('k', 'requests') + tuple(f'{p} gap >= 0' for p in planners)
            + tuple(f'{p} length ratio' for p in ('discs', 'spread'))]
    for k in sorted({r.fleet.k for r in results}):
        by = {p: [r for r in results if r.fleet.k == k and r.planner == p] for p in planners}
        rows.append((str(k), str(len(by['discs'])))
                    + tuple(_share(by[p]) for p in planners)
                    + tuple(_median([r.length_ratio for r in by[p]]) for p in ('discs', 'spread')))
    return rows


def summary(results, condition, ratios):
    """Return the headline lines: the issue's targets against this run."""
    discs = [r for r in results if r.planner == 'discs']
    dense = [r for r in discs if r.fleet.k <= 40]
    paper = {(r.fleet.k, r.fleet.n, r.fleet.seed): r.domain_index
             for r in results if r.planner == 'paper'}
    mismatches = sum(r.domain_index != paper[(r.fleet.k, r.fleet.n, r.fleet.seed)]
                     for r in discs)
    k40 = [r for r in discs if r.fleet.k == 40 and r.fleet.n == 3]
    spread40 = [r for r in results
                if r.planner == 'spread' and r.fleet.k == 40 and r.fleet.n == 3]
    lengths = {p: _median([r.length_ratio for r in results if r.planner == p])
               for p in ('discs', 'spread')}
    lines = [
        f'- Fleets meeting the stated condition: {_share(condition)} of '
        f'{len(condition)} plans have min_gap >= 0 (target 100%).',
        f'- Realistic fleets, k <= 40: {_share(dense)} of {len(dense)} plans '
        f'have min_gap >= 0 (target 99%); all k: {_share(discs)}.',
        f'- Median path length / straight-line travel: discs {lengths["discs"]}, spread '
        f'{lengths["spread"]} (target: discs no worse).',
        f"- Domain index equal to the paper variant's: {len(discs) - mismatches} of "
        f'{len(discs)} requests.',
        f'- Continuity: a {PERTURBATION:g} move inside a domain moved the motion by at most '
        f'{max(ratios, default=float("nan")):.2f}x that (target <= 10x; {len(ratios)} fleets).',
    ]
    if k40:
        def milliseconds(rows, field):
            return 1e3 * np.median([getattr(row, field) for row in rows])
        lines.append(f'- Planning k = 40, n = 3: {milliseconds(k40, "build_seconds"):.2f} ms '
                     f'median for the breakpoints (target 2 ms), '
                     f'{milliseconds(k40, "seconds"):.2f} ms with the exact gap certificate; '
                     f'spread {milliseconds(spread40, "build_seconds"):.2f} and '
                     f'{milliseconds(spread40, "seconds"):.2f} ms on the same fleets.')
    return lines


def report(settings):
    """Run the benchmark; return its Markdown lines: the targets, then the table per k."""
    results, condition, ratios = run(settings, progress_printer())
    return summary(results, condition, ratios) + ['', format_table(share_rows(results))]


def main(argv=None):
    """Run the benchmark and print its tables."""
    grid_main(__doc__, report, quick_settings, Settings, argv)


if __name__ == '__main__':
    main()
