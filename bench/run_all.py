"""
Run every benchmark, print the tables, write bench/results.md and bench/results.png.

``make bench`` runs this after installing bench/requirements.txt into .venv:
``.venv/bin/python bench/run_all.py [--quick] [--output FOLDER]``. All figures come
from this one run on the same seeded queries; the tables quote ratios, not seconds.
A smoke run (--quick) writes into a new temporary folder unless --output says where.
"""

import argparse
import datetime
from importlib import metadata
import os
import platform
import subprocess
import sys
import tempfile
import time

import core_speed
from core_speed import format_table
import discs
import hall
import numpy as np
import peers
import refinement

HERE = os.path.dirname(os.path.abspath(__file__))
RESULTS_MD = 'results.md'
RESULTS_PNG = 'results.png'


def machine():
    """Return a one-line description of this machine and the relevant versions."""
    cpu = platform.processor() or platform.machine()
    try:
        with open('/proc/cpuinfo') as cpuinfo:
            names = [line.split(':', 1)[1].strip() for line in cpuinfo
                     if line.startswith('model name')]
        cpu = f'{names[0]} x {len(names)}' if names else cpu
    except OSError:
        pass
    versions = ', '.join(f'{name} {_version(name)}' for name in ('numpy', 'scipy', 'ompl'))
    return f'{cpu}; Python {platform.python_version()}; {versions}'


def _version(name):
    """Return the installed version of a distribution, or '?'."""
    try:
        return metadata.version(name)
    except metadata.PackageNotFoundError:
        return '?'


def headline(figures, outcomes):
    """Return the lines that check the issue's targets against this run."""
    grouped = {}
    for outcome in outcomes:
        if outcome.query.k == 8:
            grouped.setdefault(outcome.planner, []).append(outcome)
    ours = np.median([o.seconds for o in grouped['ours paper']])
    connect = np.median([o.seconds for o in grouped[peers.RRT_CONNECT]])
    checker = np.median([o.seconds - o.checker_seconds for o in grouped[peers.RRT_CONNECT]])
    connect_success = np.mean([o.solved for o in grouped[peers.RRT_CONNECT]])
    ours_success = np.mean([o.clearance > 0 for o in grouped['ours paper']])
    small = figures['small'][('paper', True)][0]
    lines = [
        f'- k = 8 (all kinds, d, r, n): OMPL RRTConnect median / ours (paper, certified) = '
        f'**{connect / ours:.0f}x** (target >= 100x); {checker / ours:.0f}x with the time '
        f'spent in the Python validity checker removed. Success: ours '
        f'{100 * ours_success:.0f}% certified collision-free (point robots), RRTConnect '
        f'{100 * connect_success:.0f}% within the budget.',
        f'- One plan k=8 r=3 n=3 d=2, certified: {core_speed._seconds(small)} median, '
        f'{core_speed._verdict(small, core_speed.TARGET_SMALL)} (100 us).',
        f'- k = 10,000, n = 10, not certified: {core_speed._seconds(figures["large_plan"])}, '
        f'{core_speed._verdict(figures["large_plan"], core_speed.TARGET_LARGE)} (100 ms); '
        f'growth exponent in k {figures["plan_k_exponent"]:.2f}, in n '
        f'{figures["plan_n_exponent"]:.2f}.',
        f'- Certification k = 1000, n = 10: {core_speed._seconds(figures["certify_k1000"])}, '
        f'{core_speed._verdict(figures["certify_k1000"], core_speed.TARGET_CERTIFY)} (1 s).',
    ]
    return lines


def method_lines(settings, seconds):
    """Return the paragraph that says how the figures were measured."""
    grid = '; '.join(f'{key} in {", ".join(map(str, values))}'
                     for key, values in settings.grid.items())
    return [
        f'Queries: {grid}; {settings.seeds} seeds each, the same for every planner. '
        'random: every configuration uniform in a box; adversarial: robots sharing '
        'projections with each other and with obstacles, and each next configuration the '
        'mirror image through an obstacle (all straight lines cross it at once).',
        f'OMPL: composite RealVectorStateSpace of dimension k d, robots and obstacles discs of '
        f'radius {peers.RADIUS} (valid: every pair > {peers.SEPARATION} apart), motion check '
        f'every {peers.MOTION_STEP} in the composite space, n - 1 chained queries. RRTConnect '
        f'budget {settings.budget} s per query (+ simplifySolution, at most '
        f'{settings.simplify_budget} s); AORRTC runs its fixed budget of '
        f'{settings.optimal_budget} s per query and counts as solved when it has an exact '
        'solution by then. The validity checker is a Python callback, as OMPL users in Python '
        'write it; the column "Python checker time removed" subtracts the time measured '
        'inside that callback during the solve (about what OMPL would take with a free C++ '
        'checker; the C++-to-Python call overhead stays in).',
        'Ours: `plan(ws, C)` with certification, median of warm repeated calls per query; '
        'Workspace built once per obstacle set. Times are ratios to ours (paper) over the '
        'same queries. "certified": the exact clearance certificate run on every output '
        '(theirs too, as piecewise-linear synchronous motions through their states); '
        '"> 0" = point robots never meet, ">= 2 radius" = the discs OMPL plans for never '
        'overlap. Path length: sum over robots of their path length / the same for the '
        'straight lines through C_1..C_n.',
        f'Determinism: the same query twice in one process, bit for bit. Stability: the input '
        f'moved by at most {peers.PERTURBATION:g} keeping every projection pattern (ours: '
        'checked projection_counts unchanged), largest robot displacement between the two '
        'motions (ours: at equal tau over a dense grid and every breakpoint; OMPL: at equal '
        f'arc-length parameter). OMPL checks run on seed < {settings.check_seeds} and '
        f'k <= {settings.check_max_k} only (time). The straight line\'s "stability" is the '
        'perturbation itself.',
        f'Run time of the whole benchmark: {seconds / 60:.1f} min.',
    ]


def service_sweep(quick):
    """Return the table bench/service_roundtrip.py prints: round trips over DDS against k."""
    script = os.path.join(HERE, 'service_roundtrip.py')
    args = [sys.executable, script] + (['--calls', '50'] if quick else ['--sweep'])
    result = subprocess.run(args, capture_output=True, text=True, timeout=1800)
    return result.stdout.strip() or 'failed:\n' + result.stderr.strip()[-2000:]


def write_markdown(folder, figures, outcomes, settings, seconds, stages, profiles, service,
                   disc_lines, refinement_lines, hall_lines):
    """Write results.md into folder."""
    by = {
        'k': lambda q: q.k, 'kind': lambda q: q.kind, 'd': lambda q: q.d,
        'r': lambda q: q.r, 'n': lambda q: q.n,
    }
    parts = [
        '# Benchmarks', '',
        f'Generated by `bench/run_all.py` ({" ".join(sys.argv[1:]) or "full run"}) on '
        f'{datetime.date.today().isoformat()}: {machine()}.', '',
        '## Targets', '', *headline(figures, outcomes), '',
        '## Against OMPL and straight lines', '',
        format_table(peers.summary_rows(outcomes)), '',
    ]
    for label, key in by.items():
        parts += [format_table(peers.breakdown_rows(outcomes, key, label)), '']
    flagged = peers.flagged_rows(outcomes)
    marginal = sum(1 for o in outcomes if o.planner not in peers.OURS + (peers.STRAIGHT,)
                   and o.solved and 0.9 * peers.SEPARATION <= o.clearance < peers.SEPARATION)
    parts += ['### OMPL outputs the exact certificate puts clearly below 2 radius', '',
              f'{marginal} OMPL outputs dip below 2 radius by less than 10% between the '
              'states its motion check samples (expected at that resolution). Below 90%:', '',
              format_table(flagged) if len(flagged) > 1 else 'none in this run.', '']
    parts += ['### How', '']
    parts += [f'- {line}' for line in method_lines(settings, seconds)]
    parts += [
        '', '## The core alone', '',
        format_table([('figure', 'value', 'target')] + core_speed.summary_rows(figures)), '',
        format_table(core_speed.scaling_rows(figures)), '',
        '### Where the time goes (k=8 r=3 n=3 d=2)', '',
        format_table([('stage', 'median')]
                     + [(name, core_speed._seconds(value)) for name, value in stages]), '',
    ]
    for name, text in profiles.items():
        parts += [f'cProfile, {name}:', '', '```', text, '```', '']
    parts += ['## Disc robots among pillars', '', discs.__doc__.strip().split('\n\n')[1], '',
              *disc_lines, '']
    parts += ['## The refinement (issue 18)', '',
              refinement.__doc__.strip().split('\n\n')[1], '', *refinement_lines, '']
    parts += ['## Workspace bounds: fleets in a hall (issue 19)', '',
              hall.__doc__.strip().split('\n\n')[1], '', *hall_lines, '']
    parts += ['## Service round trip over DDS against k', '',
              'planner_node in its own process, one client, Fast DDS on this machine '
              '(`bench/service_roundtrip.py --sweep`); most of the time at large k is '
              'building and (de)serialising the Path messages, not planning:', '',
              '```', service, '```', '']
    parts += ['![planning time against k](results.png)', '']
    with open(os.path.join(folder, RESULTS_MD), 'w') as out:
        out.write('\n'.join(parts))


def write_plot(folder, figures, outcomes):
    """Write results.png into folder: time vs k against OMPL, and the core's scaling."""
    import matplotlib
    matplotlib.use('Agg')
    from matplotlib import pyplot

    figure, (left, right) = pyplot.subplots(1, 2, figsize=(12, 4.8))
    styles = {'ours paper': 'o-', 'ours spread': 's-', peers.RRT_CONNECT: '^--',
              peers.RRT_CONNECT_SIMPLIFIED: 'v--', peers.OPTIMAL: 'd:'}
    for planner, series in peers.time_by_k(outcomes).items():
        if planner in styles and series:
            ks, seconds = zip(*series)
            left.plot(ks, seconds, styles[planner], label=planner)
    left.set_xscale('log', base=2)
    ks = sorted({outcome.query.k for outcome in outcomes})
    left.set_xticks(ks, [str(k) for k in ks])
    left.set_yscale('log')
    left.set_xlabel('robots k')
    left.set_ylabel('median planning time per request [s]')
    left.set_title('Same seeded queries (d 2-3, r 0-5, n 2-5)')
    left.grid(True, which='both', alpha=0.3)
    left.legend(fontsize=8)
    for key, label, style in (('plan_by_k', 'plan, not certified (n=10)', 'o-'),
                              ('certify_by_k', 'certification alone (n=10)', 's-')):
        ks, seconds = zip(*figures[key])
        right.plot(ks, seconds, style, label=label)
    ks = np.array([k for k, _ in figures['plan_by_k']], float)
    anchor = dict(figures['plan_by_k'])[1000]
    right.plot(ks, anchor * (ks / 1000), 'k:', alpha=0.5, label='slope 1 (linear in k)')
    right.axhline(core_speed.TARGET_LARGE, color='r', alpha=0.4, lw=1)
    right.annotate('100 ms target at k = 10,000', (2, core_speed.TARGET_LARGE * 1.2),
                   color='r', fontsize=8)
    right.set_xscale('log')
    right.set_yscale('log')
    right.set_xlabel('robots k')
    right.set_ylabel('median time [s]')
    right.set_title(f'Our core: plan time ~ k^{figures["plan_k_exponent"]:.2f}, '
                    f'certification ~ k^{figures["certify_k_exponent"]:.2f}')
    right.grid(True, which='both', alpha=0.3)
    right.legend(fontsize=8)
    figure.tight_layout()
    figure.savefig(os.path.join(folder, RESULTS_PNG), dpi=110)


def main(argv=None):
    """Run everything; print the tables; write results.md and results.png."""
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--quick', action='store_true',
                        help='a small grid and short timing budgets (smoke run)')
    parser.add_argument('--output', metavar='FOLDER',
                        help='where results.md and results.png go (default: bench/, and '
                        'for --quick a new temporary folder: a smoke run never replaces '
                        'the published figures)')
    args = parser.parse_args(argv)
    folder = args.output or (tempfile.mkdtemp(prefix='pp_bench_quick_') if args.quick
                             else HERE)
    os.makedirs(folder, exist_ok=True)  # before the run, not after its 14 minutes
    start = time.perf_counter()
    settings = peers.quick_settings() if args.quick else peers.Settings(peers.FULL_GRID)

    def progress(index, total, query):
        print(f'{time.perf_counter() - start:7.1f} s  [{index}/{total}] {query.label}',
              file=sys.stderr, flush=True)

    print('==> the core alone', file=sys.stderr, flush=True)
    figures = core_speed.run(budget=0.1 if args.quick else 0.5, quick=args.quick)
    stages = core_speed.stage_breakdown()
    profiles = core_speed.profiles()
    print('==> against OMPL and straight lines', file=sys.stderr, flush=True)
    outcomes = peers.run(settings, progress)
    print('==> disc robots among pillars', file=sys.stderr, flush=True)
    disc_lines = discs.report(discs.quick_settings() if args.quick else discs.Settings())
    print('==> the refinement against the construction and OMPL', file=sys.stderr, flush=True)
    refinement_lines = refinement.report(refinement.quick_settings() if args.quick
                                         else refinement.Settings())
    print('==> workspace bounds: fleets in a hall', file=sys.stderr, flush=True)
    hall_lines = hall.report(hall.quick_settings() if args.quick else hall.Settings())
    print('==> service round trip over DDS', file=sys.stderr, flush=True)
    service = service_sweep(args.quick)
    seconds = time.perf_counter() - start
    write_markdown(folder, figures, outcomes, settings, seconds, stages, profiles, service,
                   disc_lines, refinement_lines, hall_lines)
    write_plot(folder, figures, outcomes)
    print('\n'.join(headline(figures, outcomes)))
    print()
    print(format_table(peers.summary_rows(outcomes)))
    print()
    print(format_table(peers.breakdown_rows(outcomes, lambda q: q.k, 'k')))
    print()
    print(format_table([('figure', 'value', 'target')] + core_speed.summary_rows(figures)))
    print()
    print('\n'.join(disc_lines))
    print()
    print('\n'.join(refinement_lines))
    print()
    print('\n'.join(hall_lines))
    print()
    print(service)
    print(f'\nwrote {RESULTS_MD} and {RESULTS_PNG} into {folder} in {seconds / 60:.1f} min')
    sys.stdout.flush()
    sys.stderr.flush()
    # nanobind reports OMPL's Python wrappers as leaked at interpreter exit: skip teardown.
    os._exit(0)


if __name__ == '__main__':
    main()
