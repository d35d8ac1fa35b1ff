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

The bound is loose (each constraint is taken alone, where they chain), so it
is a floor, not a reachable figure. Beside it: the construction's length, the
refined length (BLOCKS blocks, the schedule continuity allows), the
refinement's caps run to their fixed point (FIXED_POINT_BLOCKS blocks: safe,
but no longer continuous enough to ship), and a local optimum of the topology:
the fixed point sampled at OPTIMUM_KNOTS times a segment and shortened by
L-BFGS (scipy) against a barrier on every gap at the samples, so that no
winding can change (checked); being sampled, it may come a few millimetres
under the margin between samples, which the table reports. All on
bench/refinement.py's realistic disc fleets in the plane, with its seeds, with
how far the refined motion and the local optimum leave the box of
configurations and pillars (its excursion). Checked on every fleet: every one
of these motions sweeps the construction's angles (the topology kept).

Run alone: ``.venv/bin/python bench/topology.py [--quick]``.
"""

from contextlib import contextmanager
from dataclasses import dataclass

from core_speed import grid_main, grid_report
import numpy as np
from peers import length_ratio, motion_length
from punctured_planner.core import plan, Workspace
from punctured_planner.core import refine as refinement_stage
from punctured_planner.core.certificate import certify
from punctured_planner.core.pairs import point_radii
from refinement import each_fleet, excursion, PILLAR, RADIUS
from scipy.optimize import linprog, minimize

# Enough blocks for the caps' fixed point: 100 and 400 give the same medians to 0.01.
FIXED_POINT_BLOCKS = 400
# Swept angles of motions with the same topology agree to rounding; a different
# winding differs by at least pi.
SAME_TOPOLOGY = 1e-6
# The local optimum: samples per segment, the barrier -(g - reach)^2 log(g / reach) on
# every gap g below its reach (IPC's), weighted against the length, continued below
# BARRIER_FLOOR by a stiff quadratic so that L-BFGS's trial steps stay finite.
OPTIMUM_KNOTS = 128
BARRIER_REACH, BARRIER_WEIGHT, BARRIER_FLOOR, STIFFNESS = 0.1, 1e-3, 1e-3, 1e10
OPTIMUM_ITERATIONS = 3000


@dataclass
class Outcome:
    """One fleet: path length / straight-line bound of each motion, and the floor."""

    k: int
    construction: float
    refined: float
    fixed_point: float
    optimum: float
    optimum_shortfall: float
    floor: float
    refined_excursion: float
    optimum_excursion: float


@dataclass
class Motion:
    """A piecewise-linear motion: positions (T, k, d) and the configurations' indices."""

    positions: np.ndarray
    waypoint_indices: np.ndarray


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


def _pair_angles(positions, first, second):
    """Return the angles robots first sweep around robots second (pairs,) over positions."""
    return swept_angles(positions[:, first] - positions[:, second])


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
                        _pair_angles(positions, first, second), 2 * RADIUS + margin)
    rows = np.zeros((len(first), k))
    rows[np.arange(len(first)), first] = rows[np.arange(len(first)), second] = -1.0
    result = linprog(np.ones(k), A_ub=rows, b_ub=-pairs,
                     bounds=[(low, None) for low in alone], method='highs')
    assert result.status == 0, result.message
    return float(result.fun)


def floor_ratio(motion, pillars: np.ndarray, margin: float) -> float:
    """Return the floor of a plan's topology over its straight-line bound."""
    indices = motion.waypoint_indices
    return sum(segment_floor(motion.positions[a:b + 1], pillars, margin)
               for a, b in zip(indices[:-1], indices[1:])) / motion_length(motion.configurations)


def _topology(motion, pillars):
    """Return every swept angle of a plan, segment by segment (its topology)."""
    indices = motion.waypoint_indices
    first, second = np.triu_indices(motion.positions.shape[1], 1)
    return np.concatenate([
        np.concatenate([_pillar_angles(motion.positions[a:b + 1], pillars).ravel(),
                        _pair_angles(motion.positions[a:b + 1], first, second)])
        for a, b in zip(indices[:-1], indices[1:])])


def _ipc(gap):
    """Return IPC's barrier and its slope at gaps inside (0, BARRIER_REACH)."""
    ratio = np.log(gap / BARRIER_REACH)
    return (-(gap - BARRIER_REACH) ** 2 * ratio,
            -2 * (gap - BARRIER_REACH) * ratio - (gap - BARRIER_REACH) ** 2 / gap)


_FLOOR_VALUE, _FLOOR_SLOPE = _ipc(np.float64(BARRIER_FLOOR))


def barrier(gap: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the weighted barrier of gaps (any shape) and its slope: 0 beyond the reach."""
    value, slope = np.zeros_like(gap), np.zeros_like(gap)
    near = (gap < BARRIER_REACH) & (gap >= BARRIER_FLOOR)
    value[near], slope[near] = _ipc(gap[near])
    below = gap < BARRIER_FLOOR
    under = gap[below] - BARRIER_FLOOR
    value[below] = _FLOOR_VALUE + _FLOOR_SLOPE * under + STIFFNESS * under ** 2
    slope[below] = _FLOOR_SLOPE + 2 * STIFFNESS * under
    return BARRIER_WEIGHT * value, BARRIER_WEIGHT * slope


def _objective(free, start, movable, pillars, margin):
    """Return the length plus the barriers of the samples, and its gradient on movable."""
    positions = start.copy()
    positions[movable] = free.reshape(-1, *start.shape[1:])
    steps = np.diff(positions, axis=0)
    lengths = np.linalg.norm(steps, axis=2)
    directions = steps / np.maximum(lengths, np.finfo(float).tiny)[..., None]
    gradient = np.zeros_like(positions)
    gradient[:-1] -= directions
    gradient[1:] += directions
    total = lengths.sum()
    first, second = np.triu_indices(start.shape[1], 1)
    relative = positions[:, first] - positions[:, second]
    distance = np.linalg.norm(relative, axis=2)
    value, slope = barrier(distance - 2 * RADIUS - margin)
    pull = (slope / distance)[..., None] * relative
    np.add.at(gradient, (slice(None), first), pull)
    np.add.at(gradient, (slice(None), second), -pull)
    total += value.sum()
    if len(pillars):
        away = positions[:, :, None] - pillars
        distance = np.linalg.norm(away, axis=3)
        value, slope = barrier(distance - RADIUS - PILLAR - margin)
        gradient += ((slope / distance)[..., None] * away).sum(axis=2)
        total += value.sum()
    return total, gradient[movable].ravel()


def local_optimum(motion, pillars: np.ndarray, margin: float) -> Motion:
    """Return the motion sampled at OPTIMUM_KNOTS a segment, shortened by L-BFGS."""
    segments = len(motion.waypoint_indices) - 1
    start = motion.position(np.linspace(0.0, 1.0, segments * OPTIMUM_KNOTS + 1))
    movable = np.ones(len(start), dtype=bool)
    movable[::OPTIMUM_KNOTS] = False  # the configurations hold
    result = minimize(_objective, start[movable].ravel(), jac=True, method='L-BFGS-B',
                      args=(start, movable, pillars, margin),
                      options={'maxiter': OPTIMUM_ITERATIONS})
    positions = start.copy()
    positions[movable] = result.x.reshape(-1, *start.shape[1:])
    return Motion(positions, np.arange(0, len(start), OPTIMUM_KNOTS))


@contextmanager
def _blocks(count):
    """Run the refinement with count blocks (a measurement, not a schedule to ship)."""
    kept = refinement_stage.BLOCKS
    refinement_stage.BLOCKS = count
    try:
        yield
    finally:
        refinement_stage.BLOCKS = kept


def run_one(fleet) -> Outcome:
    """Plan one fleet three ways, optimise it locally and bound its topology."""
    workspace = Workspace(fleet.pillars, variant='discs', robot_radius=RADIUS,
                          obstacle_radius=PILLAR)
    refined = plan(workspace, fleet.configurations)
    with _blocks(FIXED_POINT_BLOCKS):
        fixed = plan(workspace, fleet.configurations)
    raw = refined.raw
    optimum = local_optimum(fixed, fleet.pillars, refined.margin)
    topology = _topology(raw, fleet.pillars)
    for other in (refined, fixed, optimum):
        assert np.abs(_topology(other, fleet.pillars) - topology).max() < SAME_TOPOLOGY, (
            f'k={fleet.k} seed={fleet.seed}: the topology changed')
    radii = point_radii(fleet.k, RADIUS, np.full(len(fleet.pillars), PILLAR))
    samples = np.linspace(0.0, 1.0, len(optimum.positions))
    shortfall = refined.margin - certify(samples, optimum.positions, fleet.pillars,
                                         radii).distance
    ratios = (length_ratio(motion.positions, fleet.configurations)
              for motion in (raw, refined, fixed, optimum))
    outcome = Outcome(fleet.k, *ratios, max(shortfall, 0.0),
                      floor_ratio(raw, fleet.pillars, refined.margin),
                      excursion(refined.positions, fleet), excursion(optimum.positions, fleet))
    # A floor above a motion of that topology would be no floor.
    assert outcome.floor <= min(outcome.refined, outcome.fixed_point, outcome.optimum), outcome
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


def _median(outcomes, name):
    """Return the median of one Outcome field over outcomes."""
    return float(np.median([getattr(o, name) for o in outcomes]))


def table(outcomes: list[Outcome]) -> list[tuple]:
    """Return the rows per k: median length ratios, the optimum's shortfall and the floor."""
    rows = [('k', 'fleets', 'construction', f'refined ({refinement_stage.BLOCKS} blocks)',
             f"caps' fixed point ({FIXED_POINT_BLOCKS} blocks)", 'local optimum (L-BFGS)',
             'its largest shortfall under the margin, mm', 'floor of the topology',
             'excursion: refined, local optimum')]
    for k in sorted({o.k for o in outcomes}):
        group = [o for o in outcomes if o.k == k]
        rows.append((str(k), str(len(group)), f'{_median(group, "construction"):.2f}',
                     f'{_median(group, "refined"):.2f}', f'{_median(group, "fixed_point"):.2f}',
                     f'{_median(group, "optimum"):.2f}',
                     f'{1e3 * max(o.optimum_shortfall for o in group):.1f}',
                     f'{_median(group, "floor"):.2f}',
                     f'{100 * _median(group, "refined_excursion"):.0f}%, '
                     f'{100 * _median(group, "optimum_excursion"):.0f}%'))
    return rows


def summary(outcomes: list[Outcome]) -> list[str]:
    """Return the headline: issue 18's k <= 10 target beside what the topology reaches."""
    small = [o for o in outcomes if o.k <= 10]
    refined, fixed, optimum, floor = (
        _median(small, name) for name in ('refined', 'fixed_point', 'optimum', 'floor'))
    return [
        f'- k <= 10, path length / straight-line bound (median of {len(small)} fleets): '
        f"refined {refined:.2f}, caps' fixed point {fixed:.2f}, local optimum of the "
        f"construction's topology {optimum:.2f}, its floor {floor:.2f} (issue 18 asks "
        '<= 1.7). Topology kept in every motion (asserted).',
    ]


def main(argv=None):
    """Run the benchmark and print its headline and table."""
    grid_main(__doc__, lambda settings: grid_report(settings, run, summary, table),
              quick_settings, Settings, argv)


if __name__ == '__main__':
    main()
