"""
Clearance and path length of the 'paper' and 'spread' variants side by side (issue 4).

1,000 seeded random requests whose robots are at least 0.5 apart and at least
0.5 from every obstacle (lane_spacing 1, min_spacing 0.5): the certified
clearance of each variant, the spread variant's bound, and the path length
relative to the straight-line lower bound (the sum over robots of the
straight segments through C_1..C_n). Run: ``.venv/bin/python bench/spread_clearance.py``.
"""

import argparse
from functools import partial

import numpy as np

from punctured_planner.core import plan as core_plan, Workspace

# The construction's figures (the refinement's are bench/refinement.py's).
plan = partial(core_plan, refine=False)

SEPARATION = 0.5


def separated_points(rng, count, dimension, others, box):
    """Return count points in [-box, box]^d at least SEPARATION from each other and others."""
    points = list(others)
    chosen = []
    while len(chosen) < count:
        candidate = rng.uniform(-box, box, dimension)
        if all(np.linalg.norm(candidate - p) >= SEPARATION for p in points):
            points.append(candidate)
            chosen.append(candidate)
    return np.array(chosen).reshape(count, dimension)


def random_request(rng):
    """Return (obstacles, configurations) with k <= 8, r <= 5, n <= 5, d in {2, 3}."""
    d, k, r, n = rng.choice([2, 3]), rng.integers(2, 9), rng.integers(0, 6), rng.integers(2, 6)
    box = 2.0 + k / 2
    obstacles = separated_points(rng, r, d, [], box)
    configurations = np.stack([separated_points(rng, k, d, obstacles, box) for _ in range(n)])
    return obstacles, configurations


def path_length_ratio(p):
    """Return the robots' total path length over the straight-line lower bound."""
    travelled = np.linalg.norm(np.diff(p.positions, axis=0), axis=2).sum()
    straight = np.linalg.norm(np.diff(p.configurations, axis=0), axis=2).sum()
    return travelled / straight


def main():
    """Plan every request with both variants and print the figures."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--count', type=int, default=1000)
    parser.add_argument('--seed', type=int, default=2026)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    figures = {'paper': ([], []), 'spread': ([], [])}
    below_bound = 0
    same_domain = 0
    for _ in range(args.count):
        obstacles, configurations = random_request(rng)
        d = configurations.shape[2]
        plans = {variant: plan(Workspace(obstacles, dimension=d, variant=variant,
                                         lane_spacing=1.0, min_spacing=SEPARATION),
                               configurations)
                 for variant in figures}
        for variant, p in plans.items():
            figures[variant][0].append(p.min_clearance)
            figures[variant][1].append(path_length_ratio(p))
        spread_plan = plans['spread']
        # The bound is exact arithmetic; spaced positions carry a few ulps of rounding.
        below_bound += spread_plan.min_clearance < spread_plan.clearance_bound * (1 - 1e-12)
        same_domain += spread_plan.domain == plans['paper'].domain
    print(f'{args.count} requests, robots >= {SEPARATION} apart and from obstacles, '
          f'lane_spacing 1, min_spacing {SEPARATION}')
    print(f'{"variant":8} {"median clearance":>17} {"worst clearance":>16} '
          f'{"median length ratio":>20}')
    for variant, (clearances, ratios) in figures.items():
        print(f'{variant:8} {np.median(clearances):17.4g} {np.min(clearances):16.4g} '
              f'{np.median(ratios):20.3f}')
    print(f'spread plans below their clearance bound (beyond 1e-12 relative): {below_bound}; '
          f'same domain as paper: {same_domain}/{args.count}')


if __name__ == '__main__':
    main()
