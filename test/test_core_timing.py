"""Time parameterisation: the fastest robot of each leg at max_speed, or under a limit a."""

from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st
import numpy as np
from punctured_planner.core import plan, Workspace
from punctured_planner.core.timing import corner_jump, fleet_profile, speed_profile
from punctured_planner.execution import Reference
import pytest

REQUEST = [[[0.5, 1.0], [0.5, -2.0]], [[3.0, 0.5], [-1.0, 2.0]]]


def test_each_leg_takes_its_fastest_robot_at_max_speed():
    """Leg durations are the largest displacement over max_speed."""
    p = plan(Workspace([[0.0, 0.0], [1.0, 0.0]]), REQUEST, refine=False)
    stamps = p.stamps(2.0)
    steps = np.linalg.norm(np.diff(p.positions, axis=0), axis=2).max(axis=1)
    assert np.allclose(np.diff(stamps), steps / 2.0)
    assert stamps[0] == 0.0 and p.duration(2.0) == stamps[-1]
    # The slide: robot 1 travels 2.25 along its lane, robot 2 only 1.875.
    assert np.isclose(stamps[4] - stamps[3], 2.25 / 2.0)


def test_resampling_keeps_every_breakpoint_bit_for_bit():
    """Extra samples land inside legs; breakpoints and their stamps are unchanged."""
    p = plan(Workspace([[0.0, 0.0], [1.0, 0.0]]), REQUEST, refine=False)
    samples = p.sample(3, max_speed=1.5)
    # The last leg (D^-1 of C_2, in the top stratum) is the only one where nothing moves.
    assert samples.positions.shape[0] == 4 * (p.times.size - 2) + 1
    assert np.array_equal(samples.positions[::4], p.positions[:-1])
    assert np.array_equal(samples.values[::4], p.stamps(1.5)[:-1])
    by_tau = p.sample(3)
    assert np.allclose(by_tau.positions, p.position(by_tau.values))
    assert by_tau.positions.shape[0] == 4 * (p.times.size - 1) + 1


@pytest.mark.parametrize('samples_per_leg', [0, 2])
@pytest.mark.parametrize('variant', ['paper', 'spread'])
def test_no_pose_twice_and_every_configuration_exact(samples_per_leg, variant):
    """Stamps strictly increase (no 0/0 speed); C_m sits exactly at waypoints[m] (refined)."""
    obstacles = [[-2.0, 0.5], [0.0, -0.5], [2.5, 0.0]]
    request = np.array([[[-3.0, -2.0], [-1.0, -2.5], [1.0, -2.0], [3.0, -2.5]],
                        [[-2.0, -1.5], [0.0, 1.5], [1.5, -1.5], [3.5, 1.0]],
                        [[3.0, 3.0], [1.0, 3.5], [-1.0, 3.0], [-3.0, 3.5]]])
    p = plan(Workspace(obstacles, variant=variant), request)
    samples = p.sample(samples_per_leg, max_speed=0.5)
    assert np.all(np.diff(samples.values) > 0)
    assert np.array_equal(samples.positions[samples.waypoints], request)
    steps = np.abs(np.diff(samples.positions, axis=0)).max(axis=(1, 2))
    assert np.all(steps > 0)
    # Nothing is lost: the motion through the samples is the plan's motion.
    taus = np.interp(samples.values, p.stamps(0.5), p.times)
    assert np.allclose(samples.positions, p.position(taus))


# ---------------------------------------------------------------- acceleration limit

OBSTACLES = [[-2.0, 0.5], [0.0, -0.5], [2.5, 0.0]]
DEMO = np.array([[[-3.0, -2.0], [-1.0, -2.5], [1.0, -2.0], [3.0, -2.5]],
                 [[3.0, 3.0], [1.0, 3.5], [-1.0, 3.0], [-3.0, 3.5]]])


def todays_stamps(positions, max_speed):
    """Return the law before the acceleration limit, written out: each leg at max_speed."""
    steps = np.diff(positions, axis=0)
    lengths = np.sqrt(np.einsum('vkd,vkd->vk', steps, steps)).max(axis=1)
    return np.concatenate([[0.0], np.cumsum(lengths / max_speed)])


@pytest.mark.parametrize('refine', [False, True])
def test_zero_acceleration_keeps_todays_stamps_bit_for_bit(refine):
    """max_acceleration 0 is unlimited: the stamps and samples of the law without it."""
    p = plan(Workspace(OBSTACLES, robot_radius=0.1, variant='discs'), DEMO, refine=refine)
    for speed in (0.5, 1.0, 3.7):
        assert np.array_equal(p.stamps(speed, 0.0), todays_stamps(p.positions, speed))
        assert p.duration(speed, 0.0) == todays_stamps(p.positions, speed)[-1]
        samples = p.sample(3, speed, 0.0)
        breakpoints = np.unique(todays_stamps(p.positions, speed))
        assert np.array_equal(samples.values[::4], breakpoints)
        inner = breakpoints[:-1, None] + np.diff(breakpoints)[:, None] * (np.arange(4) / 4)
        assert np.array_equal(samples.values[:-1], inner.ravel())


def test_limits_that_are_not_positive_and_finite_are_refused():
    """An infinite acceleration (or speed) limit is refused, not stamped NaN."""
    p = plan(Workspace(OBSTACLES, robot_radius=0.1, variant='discs'), DEMO)
    for speed, acceleration in ((1.0, np.inf), (np.inf, 1.0), (np.inf, 0.0), (1.0, np.nan),
                                (0.0, 1.0)):
        with pytest.raises(ValueError, match='positive and finite'):
            p.stamps(speed, acceleration)
    with pytest.raises(ValueError, match='positive and finite'):
        fleet_profile(p.positions, np.full(4, 1.0), np.full(4, np.inf), 0.1)


polylines = st.tuples(st.integers(0, 2 ** 32 - 1), st.integers(2, 12), st.integers(1, 4),
                      st.sampled_from([0.0, 0.3, 1.0]))


def random_polyline(seed, vertices, robots, repeat):
    """Random (V, k, 2) breakpoints; with repeat > 0 some legs have no motion, some tiny."""
    rng = np.random.default_rng(seed)
    positions = np.cumsum(rng.normal(size=(vertices, robots, 2)), axis=0)
    for leg in range(1, vertices):
        if rng.uniform() < repeat:
            positions[leg] = positions[leg - 1] + rng.choice([0.0, 1e-9])
    return positions


@settings(max_examples=150, deadline=None)
@given(polylines, st.floats(0.05, 5.0), st.floats(0.05, 5.0), st.floats(0.0, 1.0))
def test_profile_respects_both_limits_and_every_corner(line, speed, acceleration, jump):
    """At rest at both ends, speed <= max_speed, |sigma''| <= a, corner jumps <= jump."""
    positions = random_polyline(*line)
    profile = speed_profile(positions, speed, acceleration, jump)
    speeds, lengths = profile.speeds, profile.lengths
    assert speeds[0] == 0.0 and speeds[-1] == 0.0
    assert np.all(speeds <= speed) and np.all(speeds >= 0)
    assert np.all(np.abs(np.diff(speeds ** 2)) <= 2 * acceleration * lengths + 1e-9)
    durations = profile.durations()
    assert np.all(durations >= lengths / speed - 1e-12)
    moving = np.flatnonzero(lengths > 0)
    rates = np.diff(positions, axis=0)[moving] / lengths[moving][:, None, None]
    # every robot's velocity jump at a corner: its change of rate x sigma's speed there
    jumps = np.linalg.norm(np.diff(rates, axis=0), axis=2).max(axis=1) * speeds[moving[1:]]
    assert np.all(jumps <= jump + 1e-9)
    for leg in moving:
        times = np.linspace(0.0, durations[leg], 41)
        states = [profile.state_at(leg, t) for t in times]
        distance = np.array([state.distance for state in states])
        assert np.all(np.diff(distance) >= -1e-12) and np.isclose(distance[-1], lengths[leg])
        assert np.isclose(states[0].speed, speeds[leg])
        assert np.isclose(states[-1].speed, speeds[leg + 1])
        assert max(state.speed for state in states) <= speed + 1e-9
        assert max(abs(state.acceleration) for state in states) <= acceleration
        # time_at inverts state_at
        assert np.allclose(profile.time_at(leg, distance), times, atol=1e-6 * (1 + times))


@settings(max_examples=100, deadline=None)
@given(polylines, st.integers(0, 2 ** 32 - 1), st.floats(0.0, 1.0))
def test_fleet_profile_keeps_every_robot_within_its_own_limits(line, seed, tolerance):
    """Robot i: speed <= its v_i, acceleration <= its a_i, corner jumps <= its J_i; stops."""
    positions = random_polyline(*line)
    rng = np.random.default_rng(seed)
    k = positions.shape[1]
    speeds, accelerations = rng.uniform(0.05, 2.0, k), rng.uniform(0.05, 2.0, k)
    stops = rng.uniform(size=len(positions)) < 0.2
    profile = fleet_profile(positions, speeds, accelerations, tolerance, stops)
    assert profile.speeds[0] == 0.0 and profile.speeds[-1] == 0.0
    assert np.all(profile.speeds[stops] == 0.0)
    lengths = profile.lengths
    moving = np.flatnonzero(lengths > 0)
    steps = np.diff(positions, axis=0)
    durations = profile.durations()
    for leg in moving:
        rates = np.linalg.norm(steps[leg], axis=1) / lengths[leg]         # |u_ij|
        for t in np.linspace(0.0, durations[leg], 21):
            state = profile.state_at(leg, t)
            assert np.all(rates * state.speed <= speeds + 1e-9)
            assert np.all(rates * abs(state.acceleration) <= accelerations + 1e-9)
    rates = steps[moving] / lengths[moving][:, None, None]
    jumps = np.linalg.norm(np.diff(rates, axis=0), axis=2) * profile.speeds[moving[1:], None]
    allowed = np.array([corner_jump(a, tolerance) for a in accelerations])
    assert np.all(jumps <= allowed + 1e-9)


@settings(max_examples=50, deadline=None)
@given(polylines, st.floats(0.05, 5.0), st.floats(0.05, 5.0), st.floats(0.0, 1.0))
def test_fleet_profile_at_the_plans_limits_is_the_plans_profile(
        line, speed, acceleration, tolerance):
    """Every robot at max_speed and max_acceleration, no stop: the planner's own stamps."""
    positions = random_polyline(*line)
    k = positions.shape[1]
    plan_stamps = speed_profile(positions, speed, acceleration,
                                corner_jump(acceleration, tolerance)).stamps()
    fleet_stamps = fleet_profile(positions, np.full(k, speed), np.full(k, acceleration),
                                 tolerance).stamps()
    assert np.allclose(fleet_stamps, plan_stamps, rtol=1e-9, atol=1e-9)


def test_corners_are_slowed_into_and_straight_runs_are_not():
    """A right angle is passed at jump / sqrt 2; a straight joint at full speed."""
    square = np.array([[[0.0, 0.0]], [[4.0, 0.0]], [[8.0, 0.0]], [[8.0, 4.0]]])
    profile = speed_profile(square, 1.0, 1.0, 0.2)
    assert profile.speeds[1] == 1.0                      # collinear, same rate: no corner
    assert np.isclose(profile.speeds[2], 0.2 / np.sqrt(2))
    # the straight 8 m: 1 s (0.5 m) up to speed, cruising, then braking to the corner speed
    corner = profile.speeds[2]
    assert np.isclose(profile.stamps()[2], 1.0 + (8.0 - 0.5 - (1 - corner ** 2) / 2)
                      + (1 - corner))


def test_resampled_stamps_follow_the_profile_and_keep_every_breakpoint():
    """Samples are evenly spaced along each leg, stamped where the profile reaches them."""
    p = plan(Workspace(OBSTACLES, robot_radius=0.1, variant='discs'), DEMO)
    stamps = p.stamps(1.0, 1.0)
    assert p.duration(1.0, 1.0) > p.duration(1.0)
    samples = p.sample(3, 1.0, 1.0)
    assert np.all(np.diff(samples.values) > 0)
    assert np.array_equal(samples.positions[samples.waypoints], DEMO)
    assert samples.values[-1] == stamps[-1]
    assert np.array_equal(np.unique(np.intersect1d(samples.values, stamps)),
                          np.unique(stamps))
    # the executor's profile of the samples puts each sample where the plan's profile does
    xyz = np.concatenate([samples.positions, np.zeros(samples.positions.shape[:2] + (1,))], -1)
    reference = Reference.timed(samples.values, xyz,
                                np.tile([0.0, 0.0, 0.0, 1.0], xyz.shape[:2] + (1,)), 1.0, 1.0,
                                p.tracking_tolerance)
    breakpoints = Reference.timed(stamps, np.concatenate(
        [p.positions, np.zeros(p.positions.shape[:2] + (1,))], -1),
        np.tile([0.0, 0.0, 0.0, 1.0], p.positions.shape[:2] + (1,)), 1.0, 1.0,
        p.tracking_tolerance)
    for s in np.linspace(0.0, stamps[-1], 301):
        assert np.allclose(reference.position(s), breakpoints.position(s), atol=1e-7)
        assert np.allclose(reference.velocity(s), breakpoints.velocity(s), atol=1e-5)


def test_timed_reference_is_exact_at_stamps_and_followable_between():
    """Poses at their stamps; velocity continuous inside intervals, |acceleration| <= a."""
    p = plan(Workspace(OBSTACLES, robot_radius=0.1, variant='discs'), DEMO)
    samples = p.sample(0, 1.0, 0.8)
    xyz = np.concatenate([samples.positions, np.zeros(samples.positions.shape[:2] + (1,))], -1)
    reference = Reference.timed(samples.values, xyz,
                                np.tile([0.0, 0.0, 0.0, 1.0], xyz.shape[:2] + (1,)), 1.0, 0.8,
                                p.tracking_tolerance)
    for j, s in enumerate(samples.values):
        assert np.array_equal(reference.position(s), xyz[j])
    times = np.linspace(0.0, reference.duration, 4001)
    velocities = np.array([reference.velocity(s) for s in times])
    accelerations = np.array([reference.acceleration(s) for s in times])
    assert np.linalg.norm(velocities, axis=2).max() <= 1.0 + 1e-9
    assert np.linalg.norm(accelerations, axis=2).max() <= 0.8 + 1e-9
    jumps = np.linalg.norm(np.diff(velocities, axis=0), axis=2).max(axis=1)
    # between grid points a velocity changes by a dt, or by at most a corner's jump
    assert jumps.max() <= corner_jump(0.8, p.tracking_tolerance) + 0.8 * np.diff(times)[0] + 1e-9
    assert np.array_equal(reference.velocity(reference.duration), np.zeros((4, 3)))


def test_a_legs_state_is_never_beyond_the_leg():
    """
    At and just before a leg's end, and past it, sigma is never beyond the leg's length.

    A leg that ends cruising came an ulp past its end just before it (the braking phase
    was clamped, the cruising one not): a reference an ulp beyond its pose.
    """
    rng = np.random.default_rng(0)
    for _ in range(300):
        positions = np.cumsum(rng.normal(size=(6, 2, 2)), axis=0)
        profile = speed_profile(positions, rng.uniform(0.1, 2), rng.uniform(0.1, 2),
                                rng.uniform(0.0, 1.0))
        durations = profile.durations()
        for leg, duration in enumerate(durations):
            for t in (np.nextafter(duration, 0.0), duration, 1e9):
                assert profile.state_at(leg, t).distance <= profile.lengths[leg]


def test_a_robot_moving_half_as_far_may_be_half_as_fast():
    """fleet_profile takes each robot's own move: one at half the speed over half the way."""
    positions = np.array([[[0.0, 0.0], [0.0, 5.0]], [[20.0, 0.0], [10.0, 5.0]]])
    fleet = fleet_profile(positions, np.array([1.0, 0.5]), np.array([1.0, 1.0]), 0.5)
    alone = speed_profile(positions, 1.0, 1.0, corner_jump(1.0, 0.5))
    assert fleet.stamps()[-1] == pytest.approx(alone.stamps()[-1])
