"""
The execution and simulation logic without DDS: tolerance, clock, reference, gaps, fleet.

The closed loop at the end runs the real Execution against the real Fleet on a
certified plan of the core, with a slow robot, a late robot and noise.
"""

from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st
import numpy as np
from punctured_planner.core import plan
from punctured_planner.core import Workspace
from punctured_planner.core.timing import corner_jump
from punctured_planner.core.timing import speed_profile
from punctured_planner.core.timing import tracking_tolerance
from punctured_planner.execution import Bodies
from punctured_planner.execution import clock_rate
from punctured_planner.execution import Execution
from punctured_planner.execution import ExecutionSettings
from punctured_planner.execution import Reference
from punctured_planner.execution.execution import ACCELERATION_SHARE
from punctured_planner.execution.execution import saturate
from punctured_planner.sim import Fleet
from punctured_planner.sim import FleetSettings
import pytest

IDENTITY = (0.0, 0.0, 0.0, 1.0)


def reference_of(seconds, positions):
    """Return a Reference with identity orientations."""
    positions = np.asarray(positions, dtype=float)
    return Reference(np.asarray(seconds, dtype=float), positions,
                     np.tile(IDENTITY, positions.shape[:2] + (1,)))


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 2 ** 32 - 1), st.integers(2, 8), st.integers(0, 3))
def test_within_the_tolerance_bodies_never_touch(seed, k, r):
    """Every robot within delta = min_gap / 2 of its reference: every gap stays >= 0."""
    rng = np.random.default_rng(seed)
    radius = rng.uniform(0.0, 0.3)
    obstacles = rng.uniform(-3, 3, (r, 3))
    bodies = Bodies(radius, obstacles, rng.uniform(0.0, 0.3, r))
    reference = rng.uniform(-3, 3, (k, 3))
    gap = bodies.smallest_gap(reference).value
    if not gap > 0:
        return
    delta = tracking_tolerance(gap, np.inf)
    directions = rng.normal(size=(k, 3))
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    # worst case: each robot as far as allowed, some straight at their nearest neighbour
    moved = reference + delta * rng.uniform(0.0, 1.0, (k, 1)) * directions
    assert bodies.smallest_gap(moved).value >= gap - 2 * delta - 1e-12 >= -1e-12
    toward = reference.copy()
    toward[0] += delta * (reference[1] - reference[0]) / np.linalg.norm(
        reference[1] - reference[0])
    toward[1] -= delta * (reference[1] - reference[0]) / np.linalg.norm(
        reference[1] - reference[0])
    assert bodies.smallest_gap(toward).value >= -1e-12


def test_clock_rate_runs_slows_and_holds():
    assert clock_rate(np.array([0.0, 0.05]), 0.2, 0.5, 0.9) == 1.0
    assert clock_rate(np.array([0.14]), 0.2, 0.5, 0.9) == pytest.approx(0.5)
    assert clock_rate(np.array([0.01, 0.19]), 0.2, 0.5, 0.9) == 0.0
    assert clock_rate(np.array([5.0]), np.inf, 0.5, 0.9) == 1.0
    assert clock_rate(np.zeros(0), 0.2, 0.5, 0.9) == 1.0


@settings(max_examples=100, deadline=None)
@given(st.lists(st.floats(0.0, 1.0), min_size=2, max_size=6))
def test_clock_rate_is_monotone_and_bounded(errors):
    rates = [clock_rate(np.array([e]), 1.0, 0.3, 0.8) for e in sorted(errors)]
    assert all(0.0 <= rate <= 1.0 for rate in rates)
    assert all(a >= b for a, b in zip(rates, rates[1:]))


def test_reference_interpolates_the_breakpoints_and_skips_repeated_stamps():
    positions = [[[0, 0, 0]], [[1, 0, 0]], [[1, 0, 0]], [[1, 2, 0]]]
    reference = reference_of([0.0, 1.0, 1.0, 3.0], positions)
    assert reference.duration == 3.0
    for s, expected in ((0.0, [0, 0, 0]), (0.5, [0.5, 0, 0]), (1.0, [1, 0, 0]),
                        (2.0, [1, 1, 0]), (3.0, [1, 2, 0]), (9.0, [1, 2, 0])):
        assert np.allclose(reference.position(s), [expected]), s
    assert np.allclose(reference.velocity(0.5), [[1, 0, 0]])
    assert np.allclose(reference.velocity(1.0), [[0, 1, 0]])
    assert np.allclose(reference.velocity(3.0), [[0, 0, 0]])


def test_saturation_keeps_direction_and_limit():
    velocities = np.array([[3.0, 4.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.0, 0.0]])
    result = saturate(velocities, 1.0)
    assert np.allclose(result, [[0.6, 0.8, 0.0], [0.1, 0.0, 0.0], [0.0, 0.0, 0.0]])


def test_gap_is_exact_over_a_step_even_when_robots_pass_through_each_other():
    bodies = Bodies(0.1)
    start = np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    end = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    assert bodies.smallest_gap(start).value == pytest.approx(1.8)
    assert bodies.smallest_gap(end).value == pytest.approx(1.8)
    gap = bodies.smallest_gap(start, end)
    assert gap.value == pytest.approx(-0.2) and (gap.kind, gap.first, gap.second) == (
        'robots', 0, 1)
    pillar = Bodies(0.1, np.array([[0.0, 0.5, 0.0]]), np.array([0.2]))
    gap = pillar.smallest_gap(start[:1], end[:1])
    assert gap.kind == 'obstacle' and gap.value == pytest.approx(0.2)


def test_stale_odometry_holds_the_clock_and_it_resumes():
    reference = reference_of([0.0, 10.0], [[[0, 0, 0], [5, 0, 0]], [[10, 0, 0], [5, 10, 0]]])
    execution = Execution(reference, 0.5, ExecutionSettings(speed_limit=2.0))
    positions = reference.position(0.0).copy()
    step = execution.step(0.1, positions, [False, False])
    assert step.rate == 1.0 and step.plan_time == pytest.approx(0.1)
    step = execution.step(0.1, positions, [False, True])
    assert step.rate == 0.0 and step.plan_time == pytest.approx(0.1)
    assert np.allclose(step.velocities[1], 0.0), 'a stale robot is sent zero velocity'
    assert np.linalg.norm(step.velocities[0]) > 0, 'the others track the held reference'
    step = execution.step(0.1, reference.position(0.1), [False, False])
    assert step.rate == 1.0 and step.plan_time == pytest.approx(0.2)


def test_a_control_period_longer_than_the_hold_margin_is_named():
    """
    period_overrun names each robot whose reference outruns (1 - hold_fraction) delta in a period.

    make run's plan (delta 0.035 m at 0.5 m/s) under the default executor (20 Hz,
    hold_fraction 0.6) moves 0.025 m a period against a margin of 0.014 m: over DDS
    three robots passed delta, by up to 33%, and nothing said so (msg_docs/ExecutePlan.md).
    """
    from punctured_planner.execution.hold import period_overrun
    from punctured_planner.execution.unicycle import Corners
    # robot 0 at 0.5 m/s, robot 1 at 0.1 m/s; two poses at one stamp are skipped
    reference = reference_of([0.0, 2.0, 2.0, 4.0],
                             [[[0, 0, 0], [5, 0, 0]], [[1, 0, 0], [5, 0.2, 0]],
                              [[1, 0, 0], [5, 0.2, 0]], [[1, 1, 0], [5, 0.2, 0]]])
    corners = Corners(reference.seconds, reference.positions)
    overrun = period_overrun(corners, 0.035, 0.6, 0.05)
    assert overrun.robots.tolist() == [0]
    assert overrun.distances == pytest.approx([0.025]) and overrun.margin == pytest.approx(0.014)
    assert period_overrun(corners, 0.035, 0.6, 0.02).robots.size == 0  # 50 Hz: 0.01 m
    assert period_overrun(corners, 0.035, 0.0, 0.05).robots.size == 0  # margin all of delta
    # and afterwards, the robots whose error passed delta
    execution = Execution(reference, 0.035, ExecutionSettings(speed_limit=2.0))
    assert execution.beyond_tolerance().size == 0
    execution.step(0.05, reference.position(0.0) + [[0.0, 0.0, 0.0], [0.0, 0.05, 0.0]],
                   [False, False])
    assert execution.beyond_tolerance().tolist() == [1]


def certified_fleet(k=6, seed=2, acceleration=0.0):
    """
    Return (plan reference, Bodies, min gap): k robots crossing a row of pillars.

    The stamps are at 0.5 m/s and under the acceleration limit (0: unlimited).
    """
    rng = np.random.default_rng(seed)
    obstacles = np.array([[-2.0, 0.4], [0.2, -0.3], [2.5, 0.2]])
    start = np.c_[np.linspace(-3, 3, k) + rng.uniform(-0.2, 0.2, k), np.full(k, 2.5)]
    goal = np.c_[np.linspace(3, -3, k), np.full(k, -2.5)]
    core = plan(Workspace(obstacles, variant='spread', min_spacing=0.6, lane_spacing=0.6),
                np.stack([start, goal]))
    positions = np.concatenate([core.positions, np.zeros(core.positions.shape[:2] + (1,))],
                               axis=-1)
    radius = 0.1
    bodies = Bodies(radius, np.c_[obstacles, np.zeros(3)], np.zeros(3))
    gap = core.min_clearance - 2 * radius
    reference = Reference.timed(core.stamps(0.5, acceleration), positions,
                                np.tile(IDENTITY, positions.shape[:2] + (1,)), 0.5,
                                acceleration, tracking_tolerance(gap, np.inf))
    return reference, bodies, gap


# plan_executor's default odom_timeout (s): odometry older than this is stale
ODOM_TIMEOUT = 0.5


def closed_loop(reference, bodies, gap, shared_clock, slow=0, late=1, limit=400.0,
                acceleration=0.0, adaptation=ExecutionSettings.feedforward_adaptation,
                speed=0.5, latency=0.2, seed=3, max_speeds=(), max_accelerations=(),
                muted=None):
    """
    Run Execution at 20 Hz against a Fleet at 40 Hz; return (fleet, execution, seconds).

    muted (robot, start, end): that robot's odometry stops from start to end (s), as a
    lost link: its last position ages, and is stale after ODOM_TIMEOUT, as the node
    says.
    """
    k = reference.robot_count
    fleet = Fleet(reference.position(0.0), FleetSettings(
        bodies=bodies, speed_limit=speed,
        speed_factors=np.where(np.arange(k) == slow, 0.5, 1.0),
        latencies=np.where(np.arange(k) == late, latency, 0.0), velocity_noise=0.05,
        seed=seed, max_acceleration=acceleration))
    execution = Execution(reference, tracking_tolerance(gap, np.inf),
                          ExecutionSettings(speed_limit=speed, shared_clock=shared_clock,
                                            feedforward_adaptation=adaptation,
                                            max_speeds=max_speeds,
                                            max_accelerations=max_accelerations),
                          bodies)
    now, heard, heard_at = 0.0, fleet.positions.copy(), np.zeros(k)
    while now < limit:
        silent = np.zeros(k, dtype=bool)
        if muted is not None:
            silent[muted[0]] = muted[1] <= now < muted[2]
        heard[~silent], heard_at[~silent] = fleet.positions[~silent], now
        ages = now - heard_at
        step = execution.step(0.05, heard.copy(), ages > ODOM_TIMEOUT, ages=ages)
        for robot in range(k):
            fleet.command(robot, step.velocities[robot], now)
        for _ in range(2):
            fleet.step(now, 0.025)
            now += 0.025
        if step.finished:
            break
    return fleet, execution, now


def test_closed_loop_with_a_slow_and_a_late_robot_keeps_bodies_apart():
    reference, bodies, gap = certified_fleet()
    assert gap > 0
    fleet, execution, seconds = closed_loop(reference, bodies, gap, shared_clock=True)
    assert fleet.min_gap >= 0
    assert execution.max_errors.max() <= tracking_tolerance(gap, np.inf)
    assert np.linalg.norm(fleet.positions - reference.positions[-1], axis=1).max() <= 0.02
    # the slow robot needs twice the plan's time where it is the fastest mover
    assert reference.duration < seconds <= 1.5 * 2 * reference.duration


def test_accelerations_limited_fleet_follows_a_plan_stamped_for_it():
    """1 m/s^2 robots on stamps made for 1 m/s^2: within delta, gap >= 0, at the goal."""
    reference, bodies, gap = certified_fleet(acceleration=1.0)
    assert reference.profile is not None
    fleet, execution, seconds = closed_loop(reference, bodies, gap, shared_clock=True,
                                            acceleration=1.0)
    assert fleet.min_gap >= 0
    assert execution.max_errors.max() <= tracking_tolerance(gap, np.inf)
    assert np.linalg.norm(fleet.positions - reference.positions[-1], axis=1).max() <= 0.02
    assert reference.duration < seconds <= 1.5 * 2 * reference.duration


def test_robots_own_acceleration_limit_times_a_plan_stamped_without_one():
    """
    1 m/s^2 robots given max_accelerations on stamps made without a limit: 0.46 delta.

    Their limit was taken only for a plan stamped under one of its own, so on this one the
    reference's velocity jumped at every corner: 0.95 delta here, past the clock's hold
    threshold (0.6 delta), and 3x the tolerance over DDS.
    """
    reference, bodies, gap = certified_fleet()
    assert reference.profile is None
    fleet, execution, seconds = closed_loop(reference, bodies, gap, shared_clock=True,
                                            acceleration=1.0, max_accelerations=(1.0,))
    timed = execution.reference
    assert np.all(timed.profile.max_acceleration == ACCELERATION_SHARE * 1.0)
    assert np.allclose(timed.profile.max_speed, 0.5)
    assert np.array_equal(timed.positions, reference.positions)
    assert fleet.min_gap >= 0
    assert execution.max_errors.max() <= (ExecutionSettings.hold_fraction
                                          * tracking_tolerance(gap, np.inf))
    assert np.linalg.norm(fleet.positions - reference.positions[-1], axis=1).max() <= 0.02


def test_stale_odometry_brakes_the_clock_within_the_robots_acceleration_limit():
    """
    A robot's odometry stops mid-motion: no robot strays past the clock's slow threshold.

    Under an acceleration limit the clock brakes no harder than the robots can, for what
    the aging odometry may hide and then for the stale robot (on its feed-forward alone),
    and the aged position's feedback acts on its lag when measured; held at once, each
    robot at v overran its stopped reference by v^2 / (2 a), and the muted robot's
    feedback on its frozen position drove it ahead (here 0.089 m against a slow threshold
    of 0.06 m; a probe over DDS: 0.26 m against a tolerance of 0.15 m).
    """
    reference, bodies, gap = certified_fleet(acceleration=1.0)
    delta = tracking_tolerance(gap, np.inf)
    moving = 0.5 * reference.duration
    fleet, execution, seconds = closed_loop(reference, bodies, gap, shared_clock=True,
                                            acceleration=1.0, speed=0.5, latency=0.0,
                                            slow=-1, muted=(1, moving, moving + 1.5))
    assert fleet.min_gap >= 0
    threshold = ExecutionSettings.slow_fraction * delta
    assert execution.max_errors.max() <= threshold, (execution.max_errors, threshold)
    assert np.linalg.norm(fleet.positions - reference.positions[-1], axis=1).max() <= 0.02


def test_stale_odometry_holds_the_clock_after_braking_and_the_stale_robot_follows_it():
    """The rate falls by the acceleration share each step to 0; the stale robot is fed forward."""
    positions = np.array([[[0.0, 0.0, 0.0], [0.0, 2.0, 0.0]],
                          [[10.0, 0.0, 0.0], [10.0, 2.0, 0.0]]])
    timed = Reference.timed(np.array([0.0, 11.0]), positions,
                            np.tile(IDENTITY, (2, 2, 1)), 1.0, 1.0, 0.5)
    execution = Execution(timed, 0.5, ExecutionSettings(speed_limit=2.0))
    own = execution.reference
    for _ in range(60):
        step = execution.step(0.05, own.position(execution.plan_time), [False, False])
    assert step.rate == 1.0
    rates = []
    while step.rate > 0.0:
        speed = np.linalg.norm(own.velocity(execution.plan_time)[0])
        before = step.rate
        step = execution.step(0.05, own.position(execution.plan_time), [False, True])
        rates.append(step.rate)
        assert step.rate == pytest.approx(max(0.0, before - ACCELERATION_SHARE * 0.05 / speed))
        fed = step.rate * own.velocity(execution.plan_time)[1]
        assert np.linalg.norm(step.velocities[1] - fed) < 0.1, 'fed forward, not stopped'
    assert len(rates) > 3
    step = execution.step(0.05, own.position(execution.plan_time), [False, True])
    assert step.rate == 0.0 and np.all(step.velocities[1] == 0.0)
    linear = reference_of([0.0, 10.0], positions)
    unlimited = Execution(linear, 0.5, ExecutionSettings(speed_limit=2.0))
    unlimited.step(0.05, linear.position(0.0), [False, False])
    held = unlimited.step(0.05, linear.position(0.0), [False, True])
    assert held.rate == 0.0 and np.all(held.velocities[1] == 0.0), 'no limit: held at once'
    # while one robot is stale, another one stuck behind still holds the clock at once
    # (the braking took the stale robot's hold alone: a probe's 0.758 m for 0.15 m)
    both = Execution(timed, 0.5, ExecutionSettings(speed_limit=2.0))
    for _ in range(60):
        step = both.step(0.05, both.reference.position(both.plan_time), [False, False])
    stuck = both.reference.position(both.plan_time)
    stuck[0] -= [0.4, 0.0, 0.0]
    step = both.step(0.05, stuck, [False, True])
    assert step.rate == 0.0 and step.allowed == 0.0
    # without the shared clock a stale robot is not driven blind
    alone = Execution(timed, 0.5, ExecutionSettings(speed_limit=2.0, shared_clock=False))
    for _ in range(20):
        step = alone.step(0.05, alone.reference.position(alone.plan_time), [False, False])
    step = alone.step(0.05, alone.reference.position(alone.plan_time), [False, True])
    assert np.all(step.velocities[1] == 0.0)


def test_a_stale_robot_keeps_its_last_heading():
    """fleet_state: a stale robot's last orientation, which its feed-forward is rotated by."""
    from planner_helpers import faulty_plan
    from punctured_planner.ros import conversions
    from punctured_planner.ros.goals import fleet_state
    from punctured_planner.ros.snapshot import RobotOdometry
    plan = conversions.known_plan(faulty_plan('none'))
    facing_y = np.array([0.0, 0.0, np.sqrt(0.5), np.sqrt(0.5)])
    odometry = {name: RobotOdometry(plan.reference.position(0.0)[i], facing_y, 'map', 0, 0,
                                    0.0)
                for i, name in enumerate(plan.names)}
    state = fleet_state(plan, odometry, int(2e9), 0.5)
    assert state.stale == tuple(plan.names)
    assert np.array_equal(state.orientations, np.tile(facing_y, (len(plan.names), 1)))


def test_odometry_in_another_frame_names_the_robot_and_both_frames():
    """fleet_state: an empty frame is the plan's; another one is a WrongFrame, as data."""
    from planner_helpers import faulty_plan
    from punctured_planner.ros import conversions
    from punctured_planner.ros.goals import fleet_state
    from punctured_planner.ros.goals import WrongFrame
    from punctured_planner.ros.snapshot import RobotOdometry
    plan = conversions.known_plan(faulty_plan('none'))
    frames = {name: '' for name in plan.names}
    for frame, expected in (('', None), ('odom', WrongFrame(plan.names[1], 'odom', 'map'))):
        frames[plan.names[1]] = frame
        odometry = {name: RobotOdometry(plan.reference.position(0.0)[i], IDENTITY, frames[name],
                                        0, 0, 0.0) for i, name in enumerate(plan.names)}
        assert fleet_state(plan, odometry, 0, 0.5).wrong_frame == expected


def demo_plan():
    """
    Return (Reference, Bodies, min gap) of the demo's plan: four discs, 1 m/s, 1 m/s^2.

    The discs construction's rise (a stop per robot): many legs of about 0.2 m, shorter than
    the 0.5 m a robot brakes in from 1 m/s, with corners between them.
    """
    from planner_helpers import CONFIGURATIONS
    from planner_helpers import flat
    from planner_helpers import make_request
    from planner_helpers import OBSTACLES
    from punctured_planner.cli import offline_plan
    from punctured_planner.ros import conversions
    from punctured_planner.ros.settings import PLANNER
    settings = PLANNER.settings({'obstacles': flat(OBSTACLES), 'robot_radius': 0.1,
                                 'max_speed': 1.0, 'max_acceleration': 1.0})
    outcome = offline_plan(make_request([CONFIGURATIONS[0], CONFIGURATIONS[2]],
                                        max_speed=1.0), settings, now_ns=10 ** 18)
    assert outcome.ok
    message = conversions.plan_message(outcome, settings)
    return (conversions.plan_reference(message), conversions.plan_bodies(message),
            message.min_gap)


def test_a_late_robot_keeps_the_tolerance_on_a_reference_braking_at_the_limit():
    """
    The demo without DDS: a 100 ms robot within delta where the plan brakes at a throughout.

    Timed at the robots' whole acceleration, the reference left a late robot no
    acceleration to shed what it gained in its latency: 1.0-1.3 delta.
    """
    reference, bodies, gap = demo_plan()
    assert np.median(reference.profile.lengths) < 0.25
    for seed in (3, 4, 5):
        fleet, execution, _ = closed_loop(reference, bodies, gap, shared_clock=True,
                                          acceleration=1.0, speed=1.0, latency=0.1,
                                          seed=seed, max_speeds=(0.5, 1.0, 1.0, 1.0))
        assert fleet.min_gap >= 0
        assert execution.max_errors.max() <= tracking_tolerance(gap, np.inf), seed
        assert np.linalg.norm(fleet.positions - reference.positions[-1], axis=1).max() <= 0.02


def test_feedforward_gain_learns_the_slow_robot():
    """A robot that achieves half its commands gets about twice the feed-forward: faster."""
    reference, bodies, gap = certified_fleet()
    _, learning, learned = closed_loop(reference, bodies, gap, shared_clock=True)
    _, fixed, unlearned = closed_loop(reference, bodies, gap, shared_clock=True, adaptation=0.0)
    assert np.all(fixed.feedforward_gains == 1.0)
    assert learning.feedforward_gains[0] > 1.5
    assert np.all(np.delete(learning.feedforward_gains, 0) < learning.feedforward_gains[0])
    assert learned < 0.9 * unlearned
    assert learning.max_errors.max() <= tracking_tolerance(gap, np.inf)


def test_clock_speeds_up_within_the_plans_acceleration_limit():
    """After a hold the clock rises by at most h a dt / |r'| per step; without a limit at once."""
    positions = np.array([[[0.0, 0.0, 0.0]], [[10.0, 0.0, 0.0]]])
    timed = Reference.timed(np.array([0.0, 11.0]), positions,
                            np.tile(IDENTITY, (2, 1, 1)), 1.0, 1.0, 0.5)
    assert timed.duration == pytest.approx(11.0)
    execution = Execution(timed, 0.5, ExecutionSettings(speed_limit=2.0))
    own = execution.reference
    for _ in range(40):
        step = execution.step(0.05, own.position(execution.plan_time), [False])
    assert step.rate == 1.0
    while step.rate > 0.0:  # stale odometry brakes the clock to a hold
        step = execution.step(0.05, own.position(execution.plan_time), [True])
    speed = np.linalg.norm(own.velocity(execution.plan_time))
    step = execution.step(0.05, own.position(execution.plan_time), [False])
    assert step.rate == pytest.approx(ACCELERATION_SHARE * 1.0 * 0.05 / speed)
    linear = reference_of([0.0, 10.0], positions)
    unlimited = Execution(linear, 0.5, ExecutionSettings(speed_limit=2.0))
    unlimited.step(0.05, linear.position(0.0), [True])
    assert unlimited.step(0.05, linear.position(0.0), [False]).rate == 1.0


def test_feedforward_includes_the_references_acceleration():
    """On a speeding-up reference the command leads the velocity by a x rate^2 x dt."""
    positions = np.array([[[0.0, 0.0, 0.0]], [[10.0, 0.0, 0.0]]])
    timed = Reference.timed(np.array([0.0, 11.0]), positions,
                            np.tile(IDENTITY, (2, 1, 1)), 1.0, 1.0, 0.5)
    execution = Execution(timed, 0.5, ExecutionSettings(speed_limit=2.0, gain=0.0,
                                                        feedforward_adaptation=0.0))
    own = execution.reference
    for _ in range(5):
        step = execution.step(0.05, own.position(execution.plan_time), [False])
    rate, s = step.rate, step.plan_time
    assert rate > 0
    expected = rate * own.velocity(s) + rate ** 2 * 0.05 * own.acceleration(s)
    assert np.allclose(step.velocities, expected)
    assert own.acceleration(s)[0, 0] == pytest.approx(ACCELERATION_SHARE * 1.0)


def test_holonomic_acceleration_limit_one_value_per_robot():
    """The executed velocity moves toward the command at most max_acceleration_i x dt."""
    fleet = Fleet(np.zeros((3, 3)), FleetSettings(speed_limit=1.0,
                                                  max_acceleration=np.array([1.0, 0.0, 4.0])))
    for robot in range(3):
        fleet.command(robot, [1.0, 0.0, 0.0], 0.0)
    fleet.step(0.0, 0.1)
    assert np.allclose(fleet.velocities[:, 0], [0.1, 1.0, 0.4])
    for robot in range(3):
        fleet.command(robot, [0.0, -1.0, 0.0], 0.1)
    fleet.step(0.1, 0.1)
    change = np.linalg.norm(fleet.velocities - [[0.1, 0, 0], [1.0, 0, 0], [0.4, 0, 0]], axis=1)
    assert np.allclose(change[[0, 2]], [0.1, 0.4]) and np.allclose(fleet.velocities[1],
                                                                   [0.0, -1.0, 0.0])
    one = Fleet(np.zeros((2, 3)), FleetSettings(speed_limit=1.0, max_acceleration=2.0))
    one.command(0, [1.0, 0.0, 0.0], 0.0)
    one.step(0.0, 0.1)
    assert np.allclose(one.velocities[0], [0.2, 0.0, 0.0])


def test_new_obstacles_of_another_count_take_effect_at_the_next_step():
    """fleet_sim's obstacles set to another count: the next step measures the new pairs."""
    three = Bodies(0.2, np.array([[5.0, 0.0, 0.0], [6.0, 0.0, 0.0], [7.0, 0.0, 0.0]]),
                   np.full(3, 0.1))
    fleet = Fleet(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]),
                  FleetSettings(bodies=three, speed_limit=1.0))
    fleet.step(0.0, 0.1)
    one = Bodies(0.2, np.array([[1.25, 0.0, 0.0]]), np.full(1, 0.1))
    fleet.configure(FleetSettings(bodies=one, speed_limit=1.0))
    contacts = fleet.step(0.1, 0.1)  # robot 1 already overlaps the new pillar: not new
    assert contacts == [] and fleet.min_gap == pytest.approx(-0.05)
    fleet.command(0, [1.0, 0.0, 0.0], 0.2)
    while not (contacts := fleet.step(0.2, 0.1)):
        pass
    assert [(c.kind, c.first, c.second) for c in contacts] == [('robots', 0, 1)]


def test_without_the_shared_clock_the_slow_robot_falls_behind():
    reference, bodies, gap = certified_fleet()
    _, execution, _ = closed_loop(reference, bodies, gap, shared_clock=False)
    assert execution.max_errors.max() > 2 * tracking_tolerance(gap, np.inf)


def test_fleet_latency_speed_factor_and_command_timeout():
    fleet = Fleet(np.zeros((2, 3)), FleetSettings(
        speed_limit=1.0, speed_factors=np.array([0.5, 1.0]), latencies=np.array([0.0, 0.2]),
        command_timeout=0.3))
    for robot in range(2):
        fleet.command(robot, [2.0, 0.0, 0.0], 0.0)
    fleet.step(0.0, 0.1)
    assert np.allclose(fleet.positions[:, 0], [0.05, 0.0]), 'saturated, halved; not yet'
    fleet.step(0.2, 0.1)
    assert np.allclose(fleet.positions[:, 0], [0.1, 0.1])
    fleet.step(0.45, 0.1)
    assert np.allclose(fleet.velocities[0], 0.0), 'no command for 0.45 s: stopped'
    assert np.allclose(fleet.velocities[1], [1.0, 0.0, 0.0])


def test_fleet_reports_each_contact_once():
    fleet = Fleet(np.array([[-1.0, 0.0, 0.0], [1.0, 0.0, 0.0]]),
                  FleetSettings(bodies=Bodies(0.2), speed_limit=1.0))
    contacts = []
    for step in range(30):
        fleet.command(0, [1.0, 0.0, 0.0], step * 0.1)
        contacts += fleet.step(step * 0.1, 0.1)
    assert len(contacts) == 1
    assert (contacts[0].kind, contacts[0].first, contacts[0].second) == ('robots', 0, 1)
    assert fleet.min_gap == pytest.approx(-0.4)


def test_plan_message_round_trip_to_the_executor_reference():
    """The published Plan carries the motion, the bodies and delta = min_gap / 2."""
    from planner_helpers import make_request
    from punctured_planner.cli import offline_plan
    from punctured_planner.ros import conversions
    from punctured_planner.ros.settings import PLANNER
    settings = PLANNER.settings({'obstacles': [-2.0, 0.5, 0.0, 0.0, -0.5, 0.0,
                                               2.5, 0.0, 0.0]})
    outcome = offline_plan(make_request(max_speed=0.5), settings, now_ns=10 ** 18)
    assert outcome.ok
    outcome.plan_id = 3
    message = conversions.plan_message(outcome, settings)
    assert message.plan_id == 3 and message.robot_names == [f'robot_{i}' for i in range(4)]
    assert message.tracking_tolerance == outcome.plan.min_gap / 2 == \
        outcome.response.tracking_tolerance
    reference = conversions.plan_reference(message)
    samples = outcome.plan.sample(0, 0.5)
    assert np.array_equal(reference.positions[:, :, :2], samples.positions)
    assert np.allclose(reference.seconds, samples.values, atol=1e-8)
    bodies = conversions.plan_bodies(message)
    assert bodies.obstacles.shape == (3, 3) and bodies.obstacle_radii.tolist() == [0.0] * 3
    # the paths share their Header objects: give one pose a header of its own
    from std_msgs.msg import Header
    message.paths[1].poses[2].header = Header(frame_id='map', stamp=conversions.time_from_ns(1))
    with pytest.raises(ValueError, match='robot_1'):
        conversions.plan_reference(message)


@pytest.mark.parametrize('fault, words, culprits', [
    ('paths', 'plan 3 has 4 robot_names and 3 paths', ('paths', None, None)),
    ('name', "plan 3: robot_names: '1bad' is not a valid relative ROS name",
     ('robot_names', None, None)),
    ('twice', 'plan 3: robot_names must be unique', ('robot_names', None, None)),
    ('nan', 'plan 3: the path of robot_2 has a non-finite pose (pose 1)',
     ('paths', 'robot_2', 1)),
    ('back', 'plan 3: its stamps do not increase at pose 3', ('paths', None, 3)),
    ('radii', 'plan 3 has 2 obstacle_radii for 3 obstacles', ('obstacle_radii', None, None)),
    ('one pose', 'plan 3 has 1 pose per path, a motion at least 2', ('paths', None, None)),
    ('tolerance', 'plan 3: tracking_tolerance inf is more than min_gap / 2',
     ('tracking_tolerance', None, None)),
    ('acceleration', 'plan 3: max_acceleration is inf, not a finite number >= 0',
     ('max_acceleration', None, None)),
    ('frame', "plan 3: the path of robot_1 is in frame 'odom', that of robot_0 in 'map'",
     ('paths', 'robot_1', None)),
])
def test_a_plan_message_that_is_not_a_plan_is_refused_naming_the_fault(fault, words,
                                                                       culprits):
    """
    The executor's intake refuses it (InvalidPlan, culprits as data): no crash, no wild goal.

    Before, a name that is no ROS name crashed plan_executor when it subscribed to the
    robot's odometry, a NaN pose made a goal command NaN velocities forever, stamps going
    back ended a goal at once as executed, one path for two names an IndexError, one pose
    ended a differential goal UNKNOWN, an infinite tolerance never slowed the clock, an
    infinite acceleration gave NaN references and a path in another frame was run in the
    first path's.
    """
    from planner_helpers import faulty_plan
    from punctured_planner.ros import conversions
    from punctured_planner.ros.goals import InvalidPlan
    with pytest.raises(InvalidPlan) as refused:
        conversions.known_plan(faulty_plan(fault))
    assert words in str(refused.value), str(refused.value)
    error = refused.value
    assert (error.plan_id, error.field, error.robot, error.pose) == (3, *culprits)


def test_a_goal_for_an_ignored_plan_gets_the_reason_never_an_older_plan():
    """
    plan_executor's store: a message that is no plan is no plan under its id, nor the latest.

    Before, a goal for an ignored plan waited 5 s and ended "not there" (the reason only in
    the executor's log), a goal for the latest plan (0) ran the plan before it, and after a
    planner restart a goal for plan 2 ran the old planner's plan 2.
    """
    from planner_helpers import faulty_plan
    from punctured_planner.ros import conversions
    from punctured_planner.ros.goals import PlanStore
    from punctured_planner.ros.goals import Result
    store = PlanStore()
    assert not store.heard(0) and store.lookup(0, 'plan').code == Result.NO_PLAN
    store.add(conversions.known_plan(faulty_plan('none')))
    message = faulty_plan('nan')
    message.plan_id = 4
    with pytest.raises(ValueError) as refused:
        conversions.known_plan(message)
    store.ignore(4, str(refused.value))
    assert store.heard(0) and store.heard(3) and store.heard(4) and not store.heard(5)
    latest, named = store.lookup(0, '/ns/plan'), store.lookup(4, '/ns/plan')
    assert latest.code == named.code == Result.NO_PLAN and latest.plan is None
    assert latest.message.startswith('the latest, plan 4 on /ns/plan was ignored: plan 4: '
                                     'the path of robot_2 has a non-finite pose'), latest
    assert named.message.startswith('plan 4 on /ns/plan was ignored'), named
    assert store.lookup(3, 'plan').runnable.plan_id == 3
    newer = faulty_plan('none')
    newer.plan_id = 5
    store.add(conversions.known_plan(newer))
    assert store.lookup(0, 'plan').runnable.plan_id == 5
    store.ignore(5, 'robot_names must be unique')  # heard again, and no plan now
    assert store.lookup(5, 'plan').runnable is None and store.lookup(0, 'plan').plan is None
    # a restarted planner numbers from 1 again: its plan 1 makes the old ids unknown, so a
    # goal for its plan 2 waits for that one (before, it ran the old planner's plan 2)
    again = faulty_plan('none')
    again.plan_id = 1
    store.add(conversions.known_plan(again))
    assert not store.heard(3) and not store.heard(5) and not store.heard(4)
    assert store.lookup(0, 'plan').runnable.plan_id == 1
    # id 0 is no planner's numbering (an offline plan played back): it forgets nothing
    offline = faulty_plan('none')
    offline.plan_id = 0
    store.add(conversions.known_plan(offline))
    assert store.heard(1)


def test_the_tracking_tolerance_keeps_the_robots_off_the_walls():
    """
    The tolerance is min(min_gap / 2, the smallest gap to a wall), in the reply and the Plan.

    The README's request below walls [-3.3, 3.3, -2.8, 3.8] passed 0.032 m from one, and
    delta was min_gap / 2 = 0.070 m: a robot within its tolerance could touch the wall.
    """
    from planner_helpers import make_request
    from punctured_planner.cli import offline_plan
    from punctured_planner.ros import conversions
    from punctured_planner.ros.settings import PLANNER
    settings = PLANNER.settings({'obstacles': [-2.0, 0.5, 0.0, 0.0, -0.5, 0.0, 2.5, 0.0, 0.0],
                                 'robot_radius': 0.18, 'obstacle_radius': [0.15],
                                 'workspace_bounds': [-3.2, 3.7, -2.7, 3.7]})
    outcome = offline_plan(make_request(max_speed=0.5), settings, now_ns=10 ** 18)
    assert outcome.ok, outcome.response.error_msg
    plan = outcome.plan
    xy = plan.positions[..., :2]
    bounds = np.array([[-3.2, 3.7], [-2.7, 3.7]])
    nearest = min((xy - bounds[:, 0]).min(), (bounds[:, 1] - xy).min()) - 0.18
    assert plan.wall_gap == pytest.approx(nearest, abs=1e-12)
    assert plan.wall_gap < plan.min_gap / 2
    assert outcome.response.tracking_tolerance == plan.wall_gap
    outcome.plan_id = 1
    message = conversions.plan_message(outcome, settings)
    assert message.tracking_tolerance == plan.wall_gap
    assert conversions.known_plan(message).tolerance == plan.wall_gap
    # Under an acceleration limit the corners spend a share of that tolerance, in the
    # planner's stamps and in the executor's rebuild of them alike (doc/design.md section 8).
    limited = PLANNER.settings({**{spec: getattr(settings, spec) for spec in (
        'obstacles', 'robot_radius', 'obstacle_radius', 'workspace_bounds')},
        'max_acceleration': 0.8})
    outcome = offline_plan(make_request(max_speed=0.5), limited, now_ns=10 ** 18)
    samples = outcome.plan.sample(0, 0.5, 0.8)
    reference = conversions.plan_reference(conversions.plan_message(outcome, limited))
    assert np.allclose(reference.profile.stamps(), samples.values, atol=1e-8)
    budgets = {delta: speed_profile(reference.positions, 0.5, 0.8, corner_jump(0.8, delta))
               for delta in (plan.wall_gap, plan.min_gap / 2)}
    assert np.allclose(budgets[plan.wall_gap].stamps(), samples.values, atol=1e-8)
    assert budgets[plan.min_gap / 2].stamps()[-1] < samples.values[-1] - 0.1
    # at every corner between two legs of a real length, a jump within the budget (an ulp
    # leg between two corners merges them: doc/design.md section 8)
    legs = np.linalg.norm(np.diff(reference.positions, axis=0), axis=2).max(axis=1)
    corners = np.flatnonzero((legs[:-1] > 1e-9) & (legs[1:] > 1e-9)) + 1
    jumps = [np.linalg.norm(reference.velocity(reference.seconds[j] + 1e-7)
                            - reference.velocity(reference.seconds[j] - 1e-7), axis=1).max()
             for j in corners]
    assert max(jumps) <= corner_jump(0.8, plan.wall_gap) + 1e-6


def test_plan_message_carries_the_acceleration_limit_to_the_executor():
    """A planner max_acceleration > 0: the stamps' profile, and the executor's rebuild of it."""
    from planner_helpers import make_request
    from punctured_planner.cli import offline_plan
    from punctured_planner.ros import conversions
    from punctured_planner.ros.settings import PLANNER
    settings = PLANNER.settings({'obstacles': [-2.0, 0.5, 0.0, 0.0, -0.5, 0.0,
                                               2.5, 0.0, 0.0], 'max_acceleration': 0.8})
    outcome = offline_plan(make_request(max_speed=0.5), settings, now_ns=10 ** 18)
    assert outcome.ok and outcome.max_acceleration == 0.8
    message = conversions.plan_message(outcome, settings)
    assert message.max_acceleration == 0.8 and message.max_speed == 0.5
    duration = outcome.response.duration.sec + outcome.response.duration.nanosec * 1e-9
    assert duration == pytest.approx(outcome.plan.duration(0.5, 0.8), abs=1e-9)
    assert duration > outcome.plan.duration(0.5)
    reference = conversions.plan_reference(message)
    assert reference.profile is not None
    assert reference.profile.max_acceleration == 0.8
    samples = outcome.plan.sample(0, 0.5, 0.8)
    assert np.allclose(reference.seconds, samples.values, atol=1e-8)
    for j, s in enumerate(reference.seconds):
        assert np.array_equal(reference.position(s), reference.positions[j])
    unlimited = conversions.plan_reference(conversions.plan_message(
        offline_plan(make_request(max_speed=0.5), PLANNER.settings(
            {'obstacles': [-2.0, 0.5, 0.0, 0.0, -0.5, 0.0, 2.5, 0.0, 0.0]}),
            now_ns=10 ** 18), settings))
    assert unlimited.profile is None


def test_retimed_reference_keeps_the_poses_and_each_robots_own_speed():
    """
    Same poses in the same order; robot i never faster than its own limits, nor the plan.

    A plan stamped without an acceleration limit is timed under the robots' own.
    """
    for acceleration in (0.0, 1.0):
        reference, _, gap = certified_fleet(acceleration=acceleration)
        k = reference.robot_count
        speeds = np.where(np.arange(k) == 0, 0.25, 0.5)
        accelerations = np.where(np.arange(k) == 0, 0.5, 1.0)
        retimed = reference.retimed(speeds, accelerations, tracking_tolerance(gap, np.inf))
        assert np.array_equal(retimed.positions, reference.positions)
        assert retimed.duration > reference.duration
        times = np.linspace(0.0, retimed.duration, 3001)
        velocity = np.array([np.linalg.norm(retimed.velocity(s), axis=1) for s in times])
        assert np.all(velocity <= speeds + 1e-6)
        change = np.array([np.linalg.norm(retimed.acceleration(s), axis=1) for s in times])
        assert np.all(change <= accelerations + 1e-6)
        # limits above the plan's change nothing: its own profile's stamps (no acceleration
        # limit on a plan without one)
        same = reference.retimed(np.full(k, 9.0), np.full(k, 9.0 if acceleration else np.inf),
                                 tracking_tolerance(gap, np.inf))
        own = reference.profile.stamps() if acceleration else reference.seconds
        assert np.allclose(same.seconds, own, atol=1e-9)


def test_limits_must_fit_the_robot_count():
    settings = ExecutionSettings(max_speeds=(0.5,), max_accelerations=(1.0, 2.0, 3.0))
    speeds, accelerations = settings.limits(3)
    assert speeds.tolist() == [0.5] * 3 and accelerations.tolist() == [1.0, 2.0, 3.0]
    assert ExecutionSettings().limits(3) == (None, None)
    with pytest.raises(ValueError, match='max_accelerations has 3 values for 2 robots'):
        settings.limits(2)


def test_a_slow_robot_known_up_front_holds_the_clock_less():
    """max_speeds times the plan for the half-speed robot: the clock slows for it less often."""
    reference, bodies, gap = certified_fleet(acceleration=1.0)
    k = reference.robot_count
    runs = {}
    known = tuple(np.where(np.arange(k) == 0, 0.25, 0.5))
    for label, speeds in (('unknown', ()), ('known', known)):
        fleet = Fleet(reference.position(0.0), FleetSettings(
            bodies=bodies, speed_limit=0.5, speed_factors=np.where(np.arange(k) == 0, 0.5, 1),
            velocity_noise=0.05, seed=3, max_acceleration=1.0))
        execution = Execution(reference, tracking_tolerance(gap, np.inf),
                              ExecutionSettings(speed_limit=0.5, max_speeds=speeds), bodies)
        slowed, now, step = 0, 0.0, None
        while not (step and step.finished) and now < 400:
            step = execution.step(0.05, fleet.positions, np.zeros(k, dtype=bool))
            slowed += step.rate < 1.0 and step.plan_time < execution.reference.duration
            for robot in range(k):
                fleet.command(robot, step.velocities[robot], now)
            fleet.step(now, 0.05)
            now += 0.05
        assert step.finished and fleet.min_gap >= 0
        assert execution.max_errors.max() <= tracking_tolerance(gap, np.inf)
        runs[label] = slowed
    assert runs['known'] < 0.75 * runs['unknown']   # 468 against 758 steps when written


def test_old_odometry_is_compared_then_and_counts_as_error():
    """A position 0.4 s old is compared with the reference of 0.4 s ago; the clock holds."""
    reference = reference_of([0.0, 10.0], [[[0, 0, 0]], [[10, 0, 0]]])
    execution = Execution(reference, 0.5, ExecutionSettings(speed_limit=2.0))
    for _ in range(20):
        step = execution.step(0.05, reference.position(execution.plan_time), [False],
                              ages=[0.0])
    assert step.rate == 1.0 and np.linalg.norm(step.velocities[0]) > 0.9
    then = reference.position(execution.plan_time - 0.05)
    fresh = execution.step(0.05, then, [False], ages=[0.05])
    assert fresh.rate == 1.0, 'one control step of age is the sampling the margin covers'
    assert fresh.errors[0] == pytest.approx(0.0, abs=1e-9)
    then = reference.position(execution.plan_time - 0.4)
    held = execution.step(0.05, then, [False], ages=[0.4])
    assert held.errors[0] == pytest.approx(0.0, abs=1e-9), 'on its reference 0.4 s ago'
    assert held.rate == 0.0, 'it may have moved 0.35 m since: more than hold_fraction delta'
    measured_now = execution.step(0.05, then, [False])
    assert measured_now.errors[0] == pytest.approx(0.4), 'without its age: 0.4 m behind'


def test_feedforward_gain_does_not_wind_up_at_the_speed_limit():
    """A robot 0.42 m behind a 2 m/s reference (the clock at 0.6): no growth at a 1 m/s limit."""
    reference = reference_of([0.0, 5.0], [[[0, 0, 0]], [[10, 0, 0]]])
    gains = {}
    for limit in (1.0, 3.0):
        execution = Execution(reference, 0.5, ExecutionSettings(
            speed_limit=limit, slow_fraction=0.8, hold_fraction=0.9))
        for _ in range(40):
            behind = reference.position(execution.plan_time) - [[0.42, 0.0, 0.0]]
            step = execution.step(0.05, behind, [False])
        assert step.rate == pytest.approx(0.6)
        gains[limit] = execution.feedforward_gains[0]
    assert gains[1.0] == 1.0, 'its feed-forward alone, 1.2 m/s, is beyond the limit'
    assert gains[3.0] > 1.0, 'below the limit the same lag is learnt'


def test_a_robot_ahead_of_its_reference_does_not_hold_the_clock():
    """0.35 m ahead: the clock runs (a hold would let it overshoot); 0.35 m behind: it holds."""
    reference = reference_of([0.0, 10.0], [[[0, 0, 0]], [[10, 0, 0]]])
    for offset, rate in ((0.35, 1.0), (-0.35, 0.0)):
        execution = Execution(reference, 0.5, ExecutionSettings(speed_limit=2.0))
        execution.step(0.05, reference.position(0.0), [False])
        step = execution.step(0.05, reference.position(execution.plan_time) + [[offset, 0, 0]],
                              [False])
        assert step.rate == rate and step.errors[0] == pytest.approx(0.35)
    sideways = Execution(reference, 0.5, ExecutionSettings(speed_limit=2.0))
    sideways.step(0.05, reference.position(0.0), [False])
    step = sideways.step(0.05, reference.position(sideways.plan_time) + [[0.1, 0.35, 0]],
                         [False])
    assert step.rate == 0.0, 'its sideways error counts, ahead or not'


def test_one_hold_whatever_holds_the_clock_ends_after_its_timeout():
    """
    ClockHold: stale odometry and a clock held for errors are one hold, never reset by flaps.

    A robot whose odometry flapped (stale, fresh with the clock still held, stale) holds
    one hold that ends after the timeout, naming it stale; the clock moving with fresh
    odometry ends a hold; a goal's first step (dt 0) starts none.
    """
    from punctured_planner.execution.hold import ClockHold
    hold = ClockHold()
    assert hold.update(0.0, (), 0.0, 0.0, 1.0) is None and hold.since is None
    steps = [(0.0, ('r1',)), (0.0, ()), (0.0, ('r1',)), (0.0, ())] * 3
    over = None
    for i, (rate, stale) in enumerate(steps):
        over = hold.update(rate, stale, 0.1 * (i + 1), 0.1, 1.0)
        if over is not None:
            break
    assert over is not None and over.stale == ('r1',) and over.seconds == pytest.approx(1.0)
    moving = ClockHold()
    for i in range(30):
        assert moving.update(0.0 if i % 2 else 1.0, (), 0.1 * i, 0.1, 1.0) is None
    held = ClockHold()
    results = [held.update(0.0, (), 0.1 * i, 0.1, 1.0) for i in range(12)]
    assert results[-1] is not None and results[-1].stale == ()
    # a clock that crawls towards 0 without reaching it is held
    crawling = ClockHold()
    results = [crawling.update(0.5 ** i, (), 0.1 * i, 0.1, 1.0) for i in range(20)]
    assert results[-1] is not None and results[-1].seconds >= 1.0


def test_a_robot_that_cannot_move_holds_the_clock_below_the_held_rate():
    """
    Its error tends to the hold threshold, the rate to 0: below HELD_RATE, and it stays.

    So ClockHold, which counts a clock below HELD_RATE as held, ends such a goal
    CLOCK_HELD after hold_timeout however the rate approaches 0.
    """
    from punctured_planner.execution.hold import HELD_RATE
    reference, bodies, gap = certified_fleet()
    k = reference.robot_count
    fleet = Fleet(reference.position(0.0), FleetSettings(
        bodies=bodies, speed_limit=0.5, speed_factors=np.where(np.arange(k) == 1, 0.0, 1.0)))
    execution = Execution(reference, tracking_tolerance(gap, np.inf),
                          ExecutionSettings(speed_limit=0.5), bodies)
    rates, now = [], 0.0
    while now < 60.0:
        step = execution.step(0.05, fleet.positions, np.zeros(k, dtype=bool))
        rates.append(step.rate)
        for robot in range(k):
            fleet.command(robot, step.velocities[robot], now)
        fleet.step(now, 0.05)
        now += 0.05
    below = np.flatnonzero(np.array(rates) < HELD_RATE)
    assert below.size and np.all(np.array(rates[below[0]:]) < HELD_RATE)


def test_a_goal_starts_only_at_the_plans_start_and_a_hold_names_who_it_waits_for():
    """off_start: the robots beyond the tolerance, and how far; waited_for: who holds it."""
    from punctured_planner.execution.hold import off_start, waited_for
    reference, _, gap = certified_fleet()
    delta = tracking_tolerance(gap, np.inf)
    positions = reference.position(0.0).copy()
    assert off_start(reference, positions, delta).robots.size == 0
    positions[2] += [0.0, 2 * delta, 0.0]
    far = off_start(reference, positions, delta)
    assert far.robots.tolist() == [2] and far.distances[0] == pytest.approx(2 * delta)
    assert waited_for(np.array([0.1, 0.5, 0.7]), 0.5).tolist() == [1, 2]
    assert waited_for(np.array([0.1, 0.3, 0.2]), 0.5).tolist() == [1]


def _two_robots():
    """Return a linear two-robot Reference of 10 s: one along x, one along y."""
    positions = np.array([[[0.0, 0.0, 0.0], [5.0, 0.0, 0.0]],
                          [[10.0, 0.0, 0.0], [5.0, 10.0, 0.0]]])
    return Reference(np.array([0.0, 10.0]), positions, np.tile(IDENTITY, (2, 2, 1)))


def _timed_pair():
    """Return a two-robot Reference stamped under 1 m/s and 1 m/s^2, tolerance 0.5 m."""
    positions = np.array([[[0.0, 0.0, 0.0], [0.0, 2.0, 0.0]],
                          [[10.0, 0.0, 0.0], [10.0, 2.0, 0.0]]])
    return Reference.timed(np.array([0.0, 11.0]), positions, np.tile(IDENTITY, (2, 2, 1)),
                           1.0, 1.0, 0.5)


def test_a_stale_robots_unknown_position_is_no_tracking_error():
    """A stale robot 100 m off counts no error: its position says nothing (it is held)."""
    reference = _two_robots()
    execution = Execution(reference, 0.5, ExecutionSettings(speed_limit=2.0))
    far = reference.position(0.0).copy()
    far[1] += [100.0, 0.0, 0.0]
    step = execution.step(0.1, far, [False, True])
    assert step.errors[1] == 0.0
    assert execution.beyond_tolerance().size == 0


def test_the_plan_time_stops_at_the_plans_end_and_a_stall_moves_it_one_step():
    """A control step of 3 s moves the clock by MAX_STEP at most; it never passes the end."""
    from punctured_planner.execution.execution import MAX_STEP
    reference = _two_robots()
    execution = Execution(reference, 0.5, ExecutionSettings(speed_limit=2.0))
    step = execution.step(3.0, reference.position(0.0), [False, False])
    assert 0.0 < step.plan_time <= MAX_STEP
    for _ in range(80):
        step = execution.step(0.2, reference.position(execution.plan_time), [False, False])
    assert step.plan_time == reference.duration


def test_a_stale_robots_feedforward_keeps_its_speed_limit():
    """The stale robot, driven on its feed-forward alone, is never commanded past its limit."""
    execution = Execution(_timed_pair(), 0.5, ExecutionSettings(speed_limit=0.5))
    own = execution.reference
    for _ in range(60):
        step = execution.step(0.05, own.position(execution.plan_time), [False, False])
    assert step.rate > 0.5
    step = execution.step(0.05, own.position(execution.plan_time), [False, True])
    assert step.rate > 0.0
    assert np.linalg.norm(step.velocities[1]) <= 0.5 + 1e-12


def test_the_clock_rises_from_rest_within_the_acceleration_limit():
    """At rest the reference's speed is 0: the first step's rate is still bounded."""
    from punctured_planner.execution.execution import ADAPT_SPEED
    execution = Execution(_timed_pair(), 0.5, ExecutionSettings(speed_limit=2.0))
    step = execution.step(0.05, execution.reference.position(0.0), [False, False])
    assert 0.0 < step.rate <= float(execution.accelerations.min()) * 0.05 / ADAPT_SPEED


def test_a_lag_below_the_slow_threshold_leaves_the_feedforward_gains_alone():
    """Half the slow threshold behind a moving reference, 40 steps: every gain stays 1."""
    reference = _two_robots()
    settings = ExecutionSettings(speed_limit=5.0)
    execution = Execution(reference, 0.5, settings)
    lag = 0.5 * settings.slow_fraction * 0.5
    for _ in range(40):
        velocity = reference.velocity(execution.plan_time)
        behind = reference.position(execution.plan_time) - lag * velocity / np.linalg.norm(
            velocity, axis=1, keepdims=True)
        execution.step(0.05, behind, [False, False])
    assert execution.plan_time > 1.0
    assert np.all(execution.feedforward_gains == 1.0)


def test_a_robot_whose_speed_is_nan_is_not_at_rest():
    """A goal starts only with every robot at rest: NaN odometry speed is not rest."""
    from punctured_planner.execution.hold import still_moving
    assert still_moving(np.array([np.nan, 0.0, 0.1])).tolist() == [0, 2]


def test_stamps_longer_than_the_profile_stretch_velocity_and_acceleration_with_it():
    """A timed plan on stamps twice its own: velocity and acceleration are the derivatives."""
    positions = np.array([[[0.0, 0.0, 0.0]], [[4.0, 0.0, 0.0]], [[4.0, 3.0, 0.0]]])
    stamps = Reference.timed(np.array([0.0, 1.0, 2.0]), positions,
                             np.tile(IDENTITY, (3, 1, 1)), 1.0, 1.0, 0.5).profile.stamps()
    stretched = Reference.timed(2.0 * stamps, positions, np.tile(IDENTITY, (3, 1, 1)),
                                1.0, 1.0, 0.5)
    h = 1e-5
    for s in np.linspace(0.05, 2.0 * stamps[-1] - 0.05, 37):
        if np.any(np.abs(s - 2.0 * stamps) < 1e-3):
            continue
        velocity = (stretched.position(s + h) - stretched.position(s - h)) / (2 * h)
        change = (stretched.velocity(s + h) - stretched.velocity(s - h)) / (2 * h)
        assert np.allclose(stretched.velocity(s), velocity, atol=1e-6)
        assert np.allclose(stretched.acceleration(s), change, atol=1e-4)
