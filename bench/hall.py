"""
Workspace bounds (issue 19): how many realistic fleets plan inside the walls of a hall.

Hidden hall fleets: bench/refinement.py's realistic disc fleets (R = 0.2 m, pillars of
rho = 0.15 m, robots covering 6% of the floor, centres at least 4R apart, n = 3
configurations, variant 'discs', refined and certified), on seeds no other
benchmark uses. The walls are the box of all configurations and pillars plus a
margin of 15% of its longest side on every side. Each request either comes back
inside the walls (checked here again, independently: every breakpoint's disc
inside) or is refused with OUTSIDE_WORKSPACE; the benchmark asserts that nothing
comes back outside. Figures per k: the share planned inside, the share refused,
any other refusal, and for the refused the median distance beyond the wall as a
share of the box's longest side; and the refined plan's length over the
straight-line bound, planned without the walls' refusal in the frame the walls
choose (core.frame.choose_frame) and in the default frame, side by side; and for
the fleets planned inside, their length inside the walls against that without them.

Why the rest is refused, measured in the walls' frame as shares of the box's side
(medians): the room between the staging height (above every pillar, by its zone
or the slots' gap) and the wall e2 points to, against how far above the staging
height the construction takes the fleet: its rise (core.discs.rise: the fleet
stacked on the staging height) and its lanes (core.discs: about 2 sqrt k, a
slot's pitch apart, without walls; with them at most the lanes that fit below
the far wall, discs.WallRoom, at least 2); and the staging line of k slots a
pitch apart (its centres' span, (k - 1) g) against the room between the walls
along e1 (their corners' extent along e1 less 2R). Both rooms are exact for an
axis frame and upper bounds for an oblique one (the farthest corner, the corners'
extent). And the construction's own limit: whether the two lanes passing needs (at
least) fit between the staging height and the walls' far side (the second farthest
corner along e2, R + nu inside: discs.WallRoom's ceiling), against the share then
planned inside, for k <= 10 (beyond, the staging line is the limit).

Run alone: ``.venv/bin/python bench/hall.py [--quick]``.
"""

from dataclasses import dataclass
import time

from core_speed import grid_main, grid_report
import numpy as np
from peers import length_ratio
from punctured_planner.core import ErrorCode, plan, PlanningError, Workspace
from punctured_planner.core.discs import rise, section
from punctured_planner.core.walls import box_corners
from refinement import each_fleet, PILLAR, RADIUS

MARGIN = 0.15
# Seeds of the hidden fleets: far from bench/refinement.py's 100 k + 10 d + seed.
SEED_BASE = 7_000_003


@dataclass
class Room:
    """
    Shares of the box's side, in the walls' frame: what the construction takes of the hall.

    Above the staging height: the room to the wall, the rise, the lanes; along
    e1: the room between the walls and the staging line.
    """

    room: float
    risen: float
    lanes: float
    width: float
    line: float
    two_lanes: bool


@dataclass
class Outcome:
    """One fleet in its hall: planned inside, or the refusal's code and distance."""

    k: int
    code: ErrorCode
    length: float
    default_length: float
    room: Room
    beyond: float = float('nan')
    seconds: float = float('nan')
    inside_length: float = float('nan')


def hall(fleet) -> np.ndarray:
    """Return the (d, 2) walls: the box of configurations and pillars, MARGIN x side beyond."""
    points = np.concatenate([fleet.configurations.reshape(-1, fleet.d), fleet.pillars])
    low, high = points.min(axis=0), points.max(axis=0)
    margin = MARGIN * float((high - low).max())
    return np.stack([low - margin, high + margin], axis=1)


def inside(positions: np.ndarray, bounds: np.ndarray) -> bool:
    """
    Return whether every disc of positions (V, k, d) is inside bounds: a check of its own.

    Plain floating point, so up to 1e-12 of the hall's scale (the core's check
    has the exact sign and may accept a disc exactly touching a wall).
    """
    rounding = 1e-12 * float(np.abs(bounds).max())
    return bool((positions - bounds[:, 0] - RADIUS >= -rounding).all()
                and (bounds[:, 1] - positions - RADIUS >= -rounding).all())


def _unwalled(fleet, frame=None):
    """Return the refined plan without walls (so never refused for them), in a frame."""
    workspace = Workspace(fleet.pillars, variant='discs', robot_radius=RADIUS,
                          obstacle_radius=PILLAR, frame=frame)
    return plan(workspace, fleet.configurations, certify=False)


def _room(fleet, workspace, side) -> Room:
    """Return the room above the staging height and along e1, and what the plan takes of it."""
    frame, layout = workspace.frame, workspace.disc_layout
    corners = box_corners(workspace.bounds)
    room = float(frame.offset(corners).max()) - RADIUS - layout.top
    width = float(np.ptp(frame.project(corners))) - 2 * RADIUS
    risen = max(float((h + rise(p, h, layout, layout.reaches(c)).lift[-1]).max())
                for c, p, h in zip(fleet.configurations, frame.project(fleet.configurations),
                                   frame.offset(fleet.configurations)))
    lanes = float(section(fleet.configurations, layout).lane_heights.max())
    return Room(room / side, (risen - layout.top) / side, (lanes - layout.top) / side,
                width / side, (fleet.k - 1) * layout.pitch / side,
                layout.walls.ceiling - layout.top >= layout.pitch)


def run_one(fleet) -> Outcome:
    """Plan one fleet in its hall; assert a returned plan is inside."""
    bounds = hall(fleet)
    side = float((bounds[:, 1] - bounds[:, 0]).max()) / (1 + 2 * MARGIN)
    workspace = Workspace(fleet.pillars, variant='discs', robot_radius=RADIUS,
                          obstacle_radius=PILLAR, bounds=bounds)
    # Lengths with the walls' frame and with the default one, the walls' refusal left out.
    framed = _unwalled(fleet, workspace.frame)
    lengths = (length_ratio(framed.positions, fleet.configurations),
               length_ratio(_unwalled(fleet).positions, fleet.configurations))
    room = _room(fleet, workspace, side)
    begin = time.perf_counter()
    try:
        result = plan(workspace, fleet.configurations)
    except PlanningError as error:
        beyond = error.distance / side if error.code == ErrorCode.OUTSIDE_WORKSPACE else np.nan
        return Outcome(fleet.k, error.code, *lengths, room, beyond,
                       time.perf_counter() - begin)
    seconds = time.perf_counter() - begin
    assert inside(result.positions, bounds), f'k={fleet.k} seed={fleet.seed}: came back outside'
    return Outcome(fleet.k, ErrorCode.NONE, *lengths, room, 0.0, seconds,
                   length_ratio(result.positions, fleet.configurations))


@dataclass
class Settings:
    """Fleet sizes (d = 2) and seeds per size."""

    ks: tuple = (3, 5, 8, 10, 20, 40, 100)
    seeds: int = 20
    large_seeds: int = 5
    seed_base: int = SEED_BASE


def quick_settings() -> Settings:
    """Return a smoke-run grid."""
    return Settings(ks=(3, 8, 20), seeds=3, large_seeds=1)


def run(settings: Settings, progress=None) -> list[Outcome]:
    """Return the Outcome of every fleet of the grid."""
    fleets = each_fleet(settings.ks,
                        lambda k: settings.seeds if k <= 40 else settings.large_seeds,
                        lambda k, seed: settings.seed_base + 1000 * k + seed, progress)
    return [run_one(fleet) for fleet in fleets]


def _share(outcomes, code) -> str:
    """Return the share of outcomes with code, as 'p% (count)'."""
    count = sum(o.code == code for o in outcomes)
    return f'{100 * count / max(len(outcomes), 1):.0f}% ({count})'


def table(outcomes: list[Outcome]) -> list[tuple]:
    """Return the rows per k: shares planned inside, refused outside, refused otherwise."""
    rows = [('k', 'fleets', 'planned inside', 'refused OUTSIDE_WORKSPACE', 'other refusals',
             'beyond the wall / side, median (refused)', 'plan ms, median',
             "length / straight line: walls' frame, default frame",
             'above the staging height / side, median: room, rise, lanes',
             'along e1 / side, median: room, staging line')]
    for k in sorted({o.k for o in outcomes}):
        group = [o for o in outcomes if o.k == k]
        others = [o.code.name for o in group
                  if o.code not in (ErrorCode.NONE, ErrorCode.OUTSIDE_WORKSPACE)]
        beyond = [o.beyond for o in group if o.code == ErrorCode.OUTSIDE_WORKSPACE]
        rows.append((str(k), str(len(group)), _share(group, ErrorCode.NONE),
                     _share(group, ErrorCode.OUTSIDE_WORKSPACE),
                     ', '.join(others) or '0',
                     f'{100 * np.median(beyond):.0f}%' if beyond else '-',
                     f'{1e3 * np.median([o.seconds for o in group]):.1f}',
                     f'{np.median([o.length for o in group]):.2f}, '
                     f'{np.median([o.default_length for o in group]):.2f}',
                     _cell(group, ('room', 'risen', 'lanes')),
                     _cell(group, ('width', 'line'))))
    return rows


def _median(outcomes, name) -> str:
    """Return the median of one of the outcomes' Room shares, as a percentage."""
    return f'{100 * np.median([getattr(o.room, name) for o in outcomes]):.0f}%'


def _cell(outcomes, names) -> str:
    """Return the medians of the named Room shares."""
    return ', '.join(_median(outcomes, name) for name in names)


def summary(outcomes: list[Outcome]) -> list[str]:
    """Return the headline: issue 19's target (>= 90% inside for k <= 40) against this run."""
    small = [o for o in outcomes if o.k <= 40]
    planned = _inside_count(small)
    fits = sum(o.room.risen <= o.room.room for o in small)
    lined = sum(o.room.line <= o.room.width for o in small)
    both = sum(max(o.room.risen, o.room.lanes) <= o.room.room and o.room.line <= o.room.width
               for o in small)
    inside_ = [o for o in small if o.code == ErrorCode.NONE]
    few = [o for o in outcomes if o.k <= 10]
    roomy = [o for o in few if o.room.two_lanes]
    tight = [o for o in few if not o.room.two_lanes]
    return [
        f'- Hall fleets k <= 40 planned inside the walls (15% margin): '
        f'{100 * planned / max(len(small), 1):.0f}% of {len(small)} (target >= 90%); every '
        f'other one refused, none returned outside (asserted).',
        f'- Why, k <= 40 (medians, shares of the side): the wall is {_median(small, "room")} '
        f'above the staging height, the rise takes the fleet {_median(small, "risen")} and '
        f'the lanes {_median(small, "lanes")} above it; the rise alone fits in '
        f'{100 * fits / max(len(small), 1):.0f}% of the fleets. Along e1 the staging line '
        f'is {_median(small, "line")} of the side against {_median(small, "width")} between '
        f'the walls; it fits in {100 * lined / max(len(small), 1):.0f}% of the fleets, and '
        f'the line, the rise and the lanes all fit in {100 * both / max(len(small), 1):.0f}%.',
        "- The construction's limit, k <= 10: the two lanes passing needs fit between the "
        f'staging height and the far side in {len(roomy)} of {len(few)} fleets, and '
        f'{_inside_count(roomy)} of them plan inside; of the {len(tight)} others, '
        f"{_inside_count(tight)} (the refinement's pull).",
        f'- The {len(inside_)} planned inside, length / straight line, median: '
        f'{np.median([o.inside_length for o in inside_]):.2f} inside the walls (their lanes '
        f"and the refinement's pull), {np.median([o.length for o in inside_]):.2f} without "
        f'them in the same frame.',
    ]


def _inside_count(outcomes) -> int:
    """Return how many of outcomes were planned inside."""
    return sum(o.code == ErrorCode.NONE for o in outcomes)


def report(settings: Settings) -> list[str]:
    """Run the benchmark; return its Markdown lines: the headline, then the table."""
    return grid_report(settings, run, summary, table)


def main(argv=None):
    """Run the benchmark and print its figures."""
    grid_main(__doc__, report, quick_settings, Settings, argv)


if __name__ == '__main__':
    main()
