"""
The math core's own speed figures (issue 3), measured warm and in process.

Every figure is the median of many timed calls (time.perf_counter); a call
that takes microseconds is timed in batches and divided by the batch size.
Run alone: ``.venv/bin/python bench/core_speed.py [--quick] [--profile]``.
"""

import argparse
import cProfile
from functools import partial
import io
import os
import pstats
import sys
import time
import tracemalloc

import numpy as np

from punctured_planner.core import plan as core_plan, Workspace
from punctured_planner.core.certificate import certify

# The construction's figures (the refinement's are bench/refinement.py's).
plan = partial(core_plan, refine=False)

# Issue 3's targets, in seconds.
TARGET_SMALL = 100e-6
TARGET_LARGE = 0.1
TARGET_CERTIFY = 1.0

SCALING_KS = (2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10000)
SCALING_NS = (2, 3, 5, 10, 20, 50)
CERTIFY_KS = (2, 5, 10, 20, 50, 100, 200, 500, 1000)
FIT_FROM_K = 100
FIT_FROM_N = 5


def random_obstacles(rng, r, d, scale=1.0):
    """Return (r, d) obstacles with distinct first coordinates (the default frame works)."""
    obstacles = rng.uniform(-scale, scale, (r, d))
    obstacles[:, 0] = np.sort(rng.permutation(np.linspace(-scale, scale, max(r, 1)))[:r])
    return obstacles


def random_query(rng, n, k, d, obstacles, density=1.0):
    """Return (n, k, d) configurations uniform in a box that holds k robots at `density`."""
    half = 0.5 * (k / density) ** (1.0 / d) + 1.0
    configurations = rng.uniform(-half, half, (n, k, d))
    if len(obstacles) and np.any(np.all(configurations[:, :, None] == obstacles, axis=3)):
        raise RuntimeError('a random robot landed on an obstacle')
    return configurations


def workspace_and_query(seed, n, k, r, d, variant='paper'):
    """Return a seeded (Workspace, configurations) pair."""
    rng = np.random.default_rng(seed)
    obstacles = random_obstacles(rng, r, d)
    workspace = Workspace(obstacles, dimension=d, variant=variant)
    return workspace, random_query(rng, n, k, d, obstacles)


def median_time(call, budget=0.5, min_repeats=7, max_repeats=201):
    """
    Return (median seconds per call, repeats) over timed batches of call().

    The batch size is chosen so one batch takes about a millisecond; batches
    repeat until `budget` seconds pass (at least min_repeats of them).
    """
    call()
    start = time.perf_counter()
    call()
    once = max(time.perf_counter() - start, 1e-7)
    number = max(1, int(1e-3 / once))
    samples = []
    deadline = time.perf_counter() + budget
    while len(samples) < min_repeats or (time.perf_counter() < deadline
                                         and len(samples) < max_repeats):
        start = time.perf_counter()
        for _ in range(number):
            call()
        samples.append((time.perf_counter() - start) / number)
    return float(np.median(samples)), len(samples) * number


def peak_memory(call):
    """Return the peak bytes traced by tracemalloc during one call()."""
    tracemalloc.start()
    try:
        tracemalloc.reset_peak()
        call()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def fitted_exponent(sizes, seconds, from_size):
    """Return b of seconds ~ a size^b by least squares in log-log over sizes >= from_size."""
    sizes, seconds = np.asarray(sizes, float), np.asarray(seconds, float)
    keep = sizes >= from_size
    return float(np.polyfit(np.log(sizes[keep]), np.log(seconds[keep]), 1)[0])


def small_plan_figures(budget):
    """Return the k = 8, r = 3, n = 3, d = 2 figures, with and without certification."""
    figures = {}
    for variant in ('paper', 'spread'):
        workspace, query = workspace_and_query(3, 3, 8, 3, 2, variant)
        for certified in (True, False):
            seconds, calls = median_time(lambda: plan(workspace, query, certify=certified),
                                         budget)
            figures[(variant, certified)] = (seconds, calls)
    return figures


def scaling_figures(budget, quick=False):
    """Return plan time vs k (n = 10) and vs n (k = 1000), with and without certification."""
    ks = [k for k in SCALING_KS if not quick or k <= 1000] + ([] if not quick else [10000])
    by_k = []
    for k in ks:
        workspace, query = workspace_and_query(10, 10, k, 3, 2)
        seconds, _ = median_time(lambda: plan(workspace, query, certify=False), budget,
                                 min_repeats=5 if k < 5000 else 3)
        by_k.append((k, seconds))
    by_n = []
    for n in SCALING_NS:
        workspace, query = workspace_and_query(11, n, 1000, 3, 2)
        seconds, _ = median_time(lambda: plan(workspace, query, certify=False), budget,
                                 min_repeats=5)
        by_n.append((n, seconds))
    certify_by_k = []
    for k in CERTIFY_KS:
        workspace, query = workspace_and_query(12, 10, k, 3, 2)
        motion = plan(workspace, query, certify=False)
        seconds, _ = median_time(
            lambda: certify(motion.times, motion.positions, workspace.obstacles),
            budget, min_repeats=3 if k >= 500 else 5)
        certify_by_k.append((k, seconds))
    certify_by_n = []
    for n in SCALING_NS:
        workspace, query = workspace_and_query(13, n, 100, 3, 2)
        motion = plan(workspace, query, certify=False)
        seconds, _ = median_time(
            lambda: certify(motion.times, motion.positions, workspace.obstacles),
            budget, min_repeats=5)
        certify_by_n.append((n, seconds))
    return {
        'plan_by_k': by_k, 'plan_by_n': by_n,
        'certify_by_k': certify_by_k, 'certify_by_n': certify_by_n,
        'plan_k_exponent': fitted_exponent(*zip(*by_k), FIT_FROM_K),
        'plan_n_exponent': fitted_exponent(*zip(*by_n), FIT_FROM_N),
        'certify_k_exponent': fitted_exponent(*zip(*certify_by_k), FIT_FROM_K),
        'certify_n_exponent': fitted_exponent(*zip(*certify_by_n), FIT_FROM_N),
    }


def memory_figures():
    """Return tracemalloc peaks: k = 10,000, n = 10 without and k = 1000 with certification."""
    workspace, query = workspace_and_query(10, 10, 10000, 3, 2)
    large = peak_memory(lambda: plan(workspace, query, certify=False))
    workspace, query = workspace_and_query(12, 10, 1000, 3, 2)
    certified = peak_memory(lambda: plan(workspace, query, certify=True))
    return {'plan_k10000_n10': large, 'certified_k1000_n10': certified,
            'input_k10000_n10': query.nbytes * 10}


def run(budget=0.5, quick=False):
    """Return every core speed figure as a dict."""
    figures = {'small': small_plan_figures(budget)}
    figures.update(scaling_figures(budget, quick))
    figures['memory'] = memory_figures()
    plan_by_k = dict(figures['plan_by_k'])
    certify_by_k = dict(figures['certify_by_k'])
    figures['large_plan'] = plan_by_k[10000]
    figures['certify_k1000'] = certify_by_k[1000]
    return figures


def _seconds(value):
    """Return a time in the unit that suits it."""
    if value < 1e-3:
        return f'{value * 1e6:.1f} us'
    if value < 1.0:
        return f'{value * 1e3:.2f} ms'
    return f'{value:.2f} s'


def _verdict(value, target):
    """Return 'met' or 'MISSED' with the ratio to the target."""
    return f'{"met" if value < target else "MISSED"} ({value / target:.2f}x target)'


def summary_rows(figures):
    """Return (figure, value, target / note) rows of the core's headline figures."""
    small = figures['small']
    rows = [
        ('plan k=8 r=3 n=3 d=2, certified (paper)', _seconds(small[('paper', True)][0]),
         _verdict(small[('paper', True)][0], TARGET_SMALL)),
        ('plan k=8 r=3 n=3 d=2, not certified (paper)', _seconds(small[('paper', False)][0]),
         '-'),
        ('plan k=8 r=3 n=3 d=2, certified (spread)', _seconds(small[('spread', True)][0]),
         _verdict(small[('spread', True)][0], TARGET_SMALL)),
        ('plan k=8 r=3 n=3 d=2, not certified (spread)',
         _seconds(small[('spread', False)][0]), '-'),
        ('plan k=10,000 n=10, not certified', _seconds(figures['large_plan']),
         _verdict(figures['large_plan'], TARGET_LARGE)),
        ('certify k=1000 n=10', _seconds(figures['certify_k1000']),
         _verdict(figures['certify_k1000'], TARGET_CERTIFY)),
        (f'growth exponent of plan time in k (k >= {FIT_FROM_K}, n=10)',
         f'{figures["plan_k_exponent"]:.2f}', 'n k log k allows ~1.0-1.1'),
        (f'growth exponent of plan time in n (n >= {FIT_FROM_N}, k=1000)',
         f'{figures["plan_n_exponent"]:.2f}', 'linear allows 1.0'),
        (f'growth exponent of certification in k (k >= {FIT_FROM_K}, n=10)',
         f'{figures["certify_k_exponent"]:.2f}', 'all pairs: 2.0'),
        (f'growth exponent of certification in n (n >= {FIT_FROM_N}, k=100)',
         f'{figures["certify_n_exponent"]:.2f}', 'linear: 1.0'),
        ('peak memory, plan k=10,000 n=10 (tracemalloc)',
         f'{figures["memory"]["plan_k10000_n10"] / 2**20:.1f} MiB',
         f'{figures["memory"]["plan_k10000_n10"] / figures["memory"]["input_k10000_n10"]:.0f}'
         'x the input'),
        ('peak memory, certified plan k=1000 n=10',
         f'{figures["memory"]["certified_k1000_n10"] / 2**20:.1f} MiB', 'chunked'),
    ]
    return rows


def scaling_rows(figures):
    """Return (size, plan ms, certify ms) rows of the scaling sweeps."""
    rows = [('k (n=10)', 'plan, not certified', 'certification alone')]
    certify_by_k = dict(figures['certify_by_k'])
    for k, seconds in figures['plan_by_k']:
        rows.append((str(k), _seconds(seconds),
                     _seconds(certify_by_k[k]) if k in certify_by_k else '-'))
    rows.append(('n (k=1000 plan, k=100 certify)', '', ''))
    certify_by_n = dict(figures['certify_by_n'])
    for n, seconds in figures['plan_by_n']:
        rows.append((str(n), _seconds(seconds), _seconds(certify_by_n[n])))
    return rows


def stage_breakdown(budget=0.3):
    """Return (stage, median seconds) of one k=8 r=3 n=3 d=2 plan, through the public API."""
    workspace, query = workspace_and_query(3, 3, 8, 3, 2)
    motion = plan(workspace, query, certify=False)
    calls = [
        ('Workspace(obstacles) (once per obstacle set)',
         lambda: Workspace(workspace.obstacles)),
        ('plan(certify=False)', lambda: plan(workspace, query, certify=False)),
        ('certify(times, positions, obstacles)',
         lambda: certify(motion.times, motion.positions, workspace.obstacles)),
        ('plan(certify=True)', lambda: plan(workspace, query)),
    ]
    return [(name, median_time(call, budget)[0]) for name, call in calls]


def profile_text(call, repeats, lines=14, sort='tottime', restrict=None):
    """Return cProfile's top functions (by `sort`, matching `restrict`) over repeated calls."""
    profiler = cProfile.Profile()
    profiler.enable()
    for _ in range(repeats):
        call()
    profiler.disable()
    out = io.StringIO()
    stats = pstats.Stats(profiler, stream=out).sort_stats(sort)
    stats.print_stats(*([restrict] if restrict else []), lines)
    # Paths relative to the checkout, the environment's folder and Python's own prefix
    # (a venv outside the checkout, the interpreter's standard library): the figures
    # name no machine's folders.
    text = out.getvalue()
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    for folder in (root, os.path.dirname(sys.prefix), sys.base_prefix):
        text = text.replace(folder + os.sep, '')
    return text[text.find('ncalls'):].rstrip()


def profiles():
    """Return {name: cProfile text} for the small certified plan and a large certification."""
    workspace, query = workspace_and_query(3, 3, 8, 3, 2)
    stages = profile_text(lambda: plan(workspace, query), 2000, sort='cumulative',
                          restrict='punctured_planner')
    small = profile_text(lambda: plan(workspace, query), 2000)
    workspace, query = workspace_and_query(12, 10, 1000, 3, 2)
    motion = plan(workspace, query, certify=False)
    large = profile_text(lambda: certify(motion.times, motion.positions,
                                         workspace.obstacles), 1, lines=8)
    return {'plan k=8 r=3 n=3 d=2 certified, 2000 calls, core functions by inclusive time':
            stages,
            'plan k=8 r=3 n=3 d=2 certified, 2000 calls, by own time': small,
            'certify k=1000 n=10, one call': large}


def format_table(rows):
    """Return rows as a Markdown table; the first row is the header."""
    rows = [tuple(str(cell) for cell in row) for row in rows]
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    lines = ['| ' + ' | '.join(cell.ljust(w) for cell, w in zip(row, widths)) + ' |'
             for row in rows]
    lines.insert(1, '|' + '|'.join('-' * (w + 2) for w in widths) + '|')
    return '\n'.join(lines)


def progress_printer():
    """Return a progress callback printing each label with the seconds since this call."""
    start = time.perf_counter()
    return lambda label: print(f'{time.perf_counter() - start:7.1f} s  {label}',
                               file=sys.stderr, flush=True)


def grid_report(settings, run, summary, table):
    """Run a grid benchmark on settings; return its Markdown lines: the headline, the table."""
    results = run(settings, progress_printer())
    return summary(results) + ['', format_table(table(results))]


def grid_main(doc, report, quick_settings, settings, argv=None):
    """Run a grid benchmark from the command line: ``--quick`` for its smoke grid."""
    parser = argparse.ArgumentParser(description=doc.strip().splitlines()[0])
    parser.add_argument('--quick', action='store_true', help='a small grid (smoke run)')
    args = parser.parse_args(argv)
    print('\n'.join(report(quick_settings() if args.quick else settings())))
    sys.stdout.flush()


def main(argv=None):
    """Print the core speed figures (and profiles with --profile)."""
    parser = argparse.ArgumentParser(description=__doc__.strip().splitlines()[0])
    parser.add_argument('--quick', action='store_true', help='shorter budget per figure')
    parser.add_argument('--profile', action='store_true', help='print cProfile output too')
    args = parser.parse_args(argv)
    figures = run(budget=0.1 if args.quick else 0.5, quick=args.quick)
    print(format_table([('figure', 'value', 'target')] + summary_rows(figures)))
    print()
    print(format_table(scaling_rows(figures)))
    if args.profile:
        print()
        stages = [(name, _seconds(seconds)) for name, seconds in stage_breakdown()]
        print(format_table([('stage', 'median')] + stages))
        for name, text in profiles().items():
            print(f'\n{name}\n{text}')
    return 0


if __name__ == '__main__':
    sys.exit(main())
