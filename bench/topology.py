"""
What the topology allows (issues 18, 19): the refined length against a lower bound.

The refinement keeps the construction's topology: which way round every robot
passes every pillar, and which way round every robot pair passes each other
(doc/design.md section 14). In the plane that topology bounds the path length
from below, whatever the geometry. Per segment C_m -> C_{m+1}:

- a robot's path from x to x' keeps R + rho + margin from pillar q and sweeps
  the angle (around q) the plan's does: it is at least the shortest path with
  that swept angle around that disc (straight, or tangent, arc and tangent);
- a robot pair's relative position keeps 2R + margin from 0 and sweeps the
  plan's angle around it, and it moves by at most the two robots' path lengths
  together: their two lengths sum to at least that shortest path;
- the least total length meeting all these is a linear program (scipy HiGHS).

The bound is loose (each constraint is taken alone), so it is a floor, not a
reachable figure. Beside it: the construction's length, the refined length
(BLOCKS blocks, the schedule continuity allows) and the refinement's caps run
to their fixed point (FIXED_POINT_BLOCKS blocks: safe, but no longer
continuous enough to ship), on bench/refinement.py's realistic disc fleets in
the plane, with its seeds. Checked on every fleet: the refined motion and the
fixed point sweep the same angles as the construction's (the topology kept).

Run alone: ``.venv/bin/python bench/topology.py [--quick]``.
"""

from contextlib import contextmanager
from dataclasses import dataclass

from core_speed import grid_main, grid_report
import numpy as np
from punctured_planner.core import plan, Workspace
from punctured_planner.core import refine as refinement_stage
from refinement import each_fleet, PILLAR, RADIUS, straight_length
from scipy.optimize import linprog

# Enough blocks for the caps' fixed point: 100 and 400 give the same medians to 0.01.
FIXED_POINT_BLOCKS = 400
# Swept angles of motions with the same topology agree to rounding; a different
# winding differs by at least pi.
SAME_TOPOLOGY = 1e-6


@dataclass
class Outcome:
    """One fleet: path length / straight-line bound of each motion, and the floor."""

    k: int
    construction: float
    refined: float
    fixed_point: float
    floor: float


def swept_angles(relative: np.ndarray) -> np.ndarray:
    """
    Return the angle swept by piecewise-linear relative positions (V, ..., 2) around 0.

    Each straight piece that misses 0 sweeps less than pi either way, so the
    wrapped difference of consecutive angles is exact.
    """
    angles = np.arctan2(relative[..., 1], relative[..., 0])
    return (np.remainder(np.diff(angles, axis=0) + np.pi, 2 * np.pi) - np.pi).sum(axis=0)


def around_disc(start: np.ndarray, end: np.ndarray, swept: np.ndarray,
                radius: float) -> np.ndarray:
    """
    Return the shortest paths (...,) from start to end (..., 2) sweeping swept around a disc.

    The disc has the given radius about 0. Where the straight line sweeps that
    angle and misses the disc it is the path; otherwise the path is the two
    tangents from the ends and the arc between them.
    """
    near, far = np.linalg.norm(start, axis=-1), np.linalg.norm(end, axis=-1)
    seen = (np.arccos(np.minimum(1.0, radius / near))
            + np.arccos(np.minimum(1.0, radius / far)))
    wrapped = (np.sqrt(np.maximum(near ** 2 - radius ** 2, 0.0))
               + np.sqrt(np.maximum(far ** 2 - radius ** 2, 0.0))
               + radius * (np.abs(swept) - seen))
    return np.where(np.abs(swept) <= seen, np.linalg.norm(end - start, axis=-1), wrapped)


def _pillar_angles(positions, pillars):
    """Return the angles (k, r) each robot sweeps around each pillar over positions."""
    return swept_angles(positions[:, :, None, :] - pillars[None, None])


def _pair_angles(positions):
    """Return the angles (k, k) each robot sweeps around each other robot."""
    return swept_angles(positions[:, :, None, :] - positions[:, None, :, :])


def segment_floor(positions: np.ndarray, pillars: np.ndarray, margin: float) -> float:
    """Return the least total path length the topology of one segment (V, k, 2) allows."""
    k = positions.shape[1]
    start, end = positions[0], positions[-1]
    alone = np.linalg.norm(end - start, axis=1)
    if len(pillars):
        passes = around_disc(start[:, None] - pillars, end[:, None] - pillars,
                             _pillar_angles(positions, pillars), RADIUS + PILLAR + margin)
        alone = np.maximum(alone, passes.max(axis=1))
    first, second = np.triu_indices(k, 1)
    if not len(first):
        return float(alone.sum())
    pairs = around_disc(start[first] - start[second], end[first] - end[second],
                        _pair_angles(positions)[first, second], 2 * RADIUS + margin)
    rows = np.zeros((len(first), k))
    rows[np.arange(len(first)), first] = rows[np.arange(len(first)), second] = -1.0
    result = linprog(np.ones(k), A_ub=rows, b_ub=-pairs,
                     bounds=[(low, None) for low in alone], method='highs')
    assert result.status == 0, result.message
    return float(result.fun)


def floor_ratio(motion, pillars: np.ndarray, margin: float, straight: float) -> float:
    """Return the floor of a plan's topology over its straight-line bound."""
    indices = motion.waypoint_indices
    return sum(segment_floor(motion.positions[a:b + 1], pillars, margin)
               for a, b in zip(indices[:-1], indices[1:])) / straight


def _topology(motion, pillars):
    """Return every swept angle of a plan, segment by segment (its topology)."""
    indices = motion.waypoint_indices
    return np.concatenate([
        np.concatenate([_pillar_angles(motion.positions[a:b + 1], pillars).ravel(),
                        _pair_angles(motion.positions[a:b + 1]).ravel()])
        for a, b in zip(indices[:-1], indices[1:])])


@contextmanager
def _blocks(count):
    """Run the refinement with count blocks (a measurement, not a schedule to ship)."""
    kept = refinement_stage.BLOCKS
    refinement_stage.BLOCKS = count
    try:
        yield
    finally:
        refinement_stage.BLOCKS = kept


def _length(motion) -> float:
    """Return the summed path length of every robot."""
    return float(np.linalg.norm(np.diff(motion.positions, axis=0), axis=2).sum())


def run_one(fleet) -> Outcome:
    """Plan one fleet three ways and bound its topology."""
    workspace = Workspace(fleet.pillars, variant='discs', robot_radius=RADIUS,
                          obstacle_radius=PILLAR)
    refined = plan(workspace, fleet.configurations)
    with _blocks(FIXED_POINT_BLOCKS):
        fixed = plan(workspace, fleet.configurations)
    raw = refined.raw
    topology = _topology(raw, fleet.pillars)
    for other in (refined, fixed):
        assert np.abs(_topology(other, fleet.pillars) - topology).max() < SAME_TOPOLOGY, (
            f'k={fleet.k} seed={fleet.seed}: the refinement changed the topology')
    straight = straight_length(fleet.configurations)
    outcome = Outcome(fleet.k, _length(raw) / straight, _length(refined) / straight,
                      _length(fixed) / straight,
                      floor_ratio(raw, fleet.pillars, refined.margin, straight))
    # A floor above a motion of that topology would be no floor.
    assert outcome.floor <= min(outcome.refined, outcome.fixed_point), outcome
    return outcome


@dataclass
class Settings:
    """Fleet sizes (d = 2) and seeds per size (bench/refinement.py's seeds)."""

    ks: tuple = (3, 5, 8, 10, 20)
    seeds: int = 6


def quick_settings() -> Settings:
    """Return a smoke-run grid."""
    return Settings(ks=(3, 8), seeds=2)


def run(settings: Settings, progress=None) -> list[Outcome]:
    """Return the Outcome of every fleet of the grid."""
    # bench/refinement.py's seeds in the plane: 100 k + 10 d + seed.
    fleets = each_fleet(settings.ks, lambda k: settings.seeds,
                        lambda k, seed: 100 * k + 20 + seed, progress)
    return [run_one(fleet) for fleet in fleets]


def table(outcomes: list[Outcome]) -> list[tuple]:
    """Return the rows per k: median length ratios and the floor."""
    rows = [('k', 'fleets', 'construction', f'refined ({refinement_stage.BLOCKS} blocks)',
             f"caps' fixed point ({FIXED_POINT_BLOCKS} blocks)", 'floor of the topology',
             'refined / floor')]
    for k in sorted({o.k for o in outcomes}):
        group = [o for o in outcomes if o.k == k]

        def median(name, group=group):
            return float(np.median([getattr(o, name) for o in group]))
        rows.append((str(k), str(len(group)), f'{median("construction"):.2f}',
                     f'{median("refined"):.2f}', f'{median("fixed_point"):.2f}',
                     f'{median("floor"):.2f}',
                     f'{np.median([o.refined / o.floor for o in group]):.2f}'))
    return rows


def summary(outcomes: list[Outcome]) -> list[str]:
    """Return the headline: issue 18's k <= 10 target beside the floor and the fixed point."""
    small = [o for o in outcomes if o.k <= 10]
    refined, fixed, floor = (float(np.median([getattr(o, name) for o in small]))
                             for name in ('refined', 'fixed_point', 'floor'))
    return [
        f'- k <= 10, path length / straight-line bound (median of {len(small)} fleets): '
        f"refined {refined:.2f}, caps' fixed point {fixed:.2f}, floor of the "
        f"construction's topology {floor:.2f} (issue 18 asks <= 1.7). Topology kept in "
        'every plan (asserted).',
    ]


def main(argv=None):
    """Run the benchmark and print its headline and table."""
    grid_main(__doc__, lambda settings: grid_report(settings, run, summary, table),
              quick_settings, Settings, argv)


if __name__ == '__main__':
    main()
