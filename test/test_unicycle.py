"""
Differential-drive robots without DDS: the tracking law's bound, the turns, the simulator.

The bound (doc/design.md section 13): the lead point's velocity keeps the
direction of the law's u under saturation, so with the clock held its error
never grows; the centre is within the lead e of it; a turn in place or a switch of
driving direction raises E = |reference - P| + e by at most 2e; parking never moves
away from the goal.
The closed loops run the real Execution against the real Fleet.
"""

from hypothesis import given
from hypothesis import settings
from hypothesis import strategies as st
import numpy as np
from punctured_planner.execution import Execution
from punctured_planner.execution import ExecutionSettings
from punctured_planner.execution import Reference
from punctured_planner.execution import Step
from punctured_planner.execution import unicycle
from punctured_planner.sim import Fleet
from punctured_planner.sim import FleetSettings
import pytest
from scipy.spatial.transform import Rotation

IDENTITY = (0.0, 0.0, 0.0, 1.0)

angles_st = st.floats(-np.pi, np.pi)


def quaternions(yaw_angles):
    """Return (k, 4) quaternions of yaw angles (k,)."""
    return Rotation.from_euler('z', np.asarray(yaw_angles)[:, None]).as_quat()


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.floats(-5, 5), st.floats(-5, 5), angles_st), min_size=1,
                max_size=5),
       st.floats(1e-3, 0.05), st.floats(0.05, 2.0), st.floats(0.1, 4.0))
def test_follow_moves_the_lead_point_toward_u_within_the_limits(rows, lead, speed, yaw):
    desired = np.array([[x, y, 0.0] for x, y, _ in rows])
    angles = np.array([a for _, _, a in rows])
    h = unicycle.headings(angles)
    side = np.c_[-h[:, 1], h[:, 0], np.zeros(len(h))]
    steering = 2 * lead
    command = unicycle.follow(desired, angles, steering, speed, yaw)
    assert np.all(np.abs(command.forward) <= speed * (1 + 1e-9))
    assert np.all(np.abs(command.yaw_rate) <= yaw * (1 + 1e-9))
    moved = command.forward[:, None] * h + lead * command.yaw_rate[:, None] * side
    for u, p, hi, si in zip(desired, moved, h, side):
        # P' = lambda D u, D = h h^T + (e / l) side side^T: one lambda in [0, 1] for both
        along, across = np.dot(u, hi), np.dot(u, si) * lead / steering
        scale = [np.dot(p, hi) / along if abs(along) > 1e-9 else None,
                 np.dot(p, si) / across if abs(across) > 1e-9 else None]
        known = [x for x in scale if x is not None]
        assert all(-1e-9 <= x <= 1 + 1e-9 for x in known)
        assert max(known, default=0) - min(known, default=0) <= 1e-6
        assert np.dot(u, p) >= -1e-12, 'P moves within 90 degrees of u'


def fleet_of(positions, angles, **physics):
    """Return a differential Fleet at positions (k, 3) facing angles (k,)."""
    fleet = Fleet(positions, FleetSettings(differential=np.ones(len(positions), dtype=bool),
                                           **physics))
    fleet.headings = np.array(angles, dtype=float)
    return fleet


@settings(max_examples=25, deadline=None)
@given(st.floats(-0.3, 0.3), st.floats(-0.3, 0.3), angles_st, st.floats(0.005, 0.05),
       st.floats(0.5, 5.0))
def test_with_the_clock_held_the_lead_points_error_never_grows(x, y, angle, lead, gain):
    reference = np.array([[x, y, 0.0]])
    fleet = fleet_of(np.zeros((1, 3)), [angle], speed_limit=0.3, yaw_rate_limit=1.9)
    dt = 2e-3
    point = unicycle.lead_points(fleet.positions, fleet.headings, lead)
    start = last = np.linalg.norm(reference - point)
    for step in range(400):
        point = unicycle.lead_points(fleet.positions, fleet.headings, lead)
        error = np.linalg.norm(reference - point)
        # Euler steps of P' = lambda u: non-increasing up to the step's curvature
        assert error <= last + 1e-5
        assert np.linalg.norm(reference - fleet.positions) <= start + lead + 1e-5
        last = error
        command = unicycle.follow(gain * (reference - point), fleet.headings,
                                  unicycle.steering(lead), 0.3, 1.9)
        fleet.command(0, [command.forward[0], 0.0, 0.0], step * dt, command.yaw_rate[0])
        fleet.step(step * dt, dt)


@settings(max_examples=100, deadline=None)
@given(st.floats(-0.1, 0.1), st.floats(-0.1, 0.1), angles_st, angles_st,
       st.floats(0.001, 0.05))
def test_a_turn_in_place_raises_the_bound_by_at_most_twice_the_lead(
        x, y, before, after, lead):
    centre, reference = np.zeros((1, 3)), np.array([[x, y, 0.0]])

    def bound(angle):
        return np.linalg.norm(reference - unicycle.lead_points(centre, [angle], lead)) + lead

    assert bound(after) <= bound(before) + 2 * lead + 1e-12
    assert np.linalg.norm(reference - centre) <= min(bound(before), bound(after)) + 1e-12


@settings(max_examples=25, deadline=None)
@given(st.floats(-0.2, 0.2), st.floats(-0.2, 0.2), angles_st)
def test_parking_never_moves_away_from_the_goal(x, y, angle):
    goal = np.array([[x, y, 0.0]])
    fleet = fleet_of(np.zeros((1, 3)), [angle], speed_limit=0.3, yaw_rate_limit=1.9)
    last = np.linalg.norm(goal - fleet.positions)
    for step in range(600):
        command = unicycle.park(fleet.positions, fleet.headings, goal, 2.0, 0.3, 1.9)
        fleet.command(0, [command.forward[0], 0.0, 0.0], step * 0.01, command.yaw_rate[0])
        fleet.step(step * 0.01, 0.01)
        distance = np.linalg.norm(goal - fleet.positions)
        assert distance <= last + 1e-9
        last = distance
    assert last <= 0.005


def test_corners_slow_the_clock_before_a_turn_and_not_elsewhere():
    seconds = np.array([0.0, 2.0, 4.0])
    positions = np.array([[[0, 0, 0]], [[1, 0, 0]], [[1, 1, 0]]], dtype=float)
    corners = unicycle.Corners(seconds, positions)
    lead, limit = 0.01, 1.9
    caps = [corners.corner_caps(s, lead, limit)[0] for s in (0.0, 1.2, 1.6, 1.99, 2.5)]
    assert caps[0] == 1.0 and caps[-1] == 1.0, 'no corner within the lookahead'
    assert caps[1] > caps[2] > caps[3] >= unicycle.CORNER_RATE
    assert caps[3] <= unicycle.CORNER_RATE + 0.01
    upcoming = corners.upcoming(0.5)
    assert np.allclose(upcoming.directions, [[0.5, 0, 0]]) and upcoming.still_until[0] == 0.5


def test_a_robot_standing_still_turns_to_its_next_move_without_holding_the_clock():
    seconds = np.array([0.0, 3.0, 5.0])
    positions = np.array([[[0, 0, 0], [2, 0, 0]], [[1, 0, 0], [2, 0, 0]],
                          [[1, 0, 0], [2, 1, 0]]], dtype=float)
    reference = Reference(seconds, positions, np.tile([0.0, 0.0, 0.0, 1.0], (3, 2, 1)))
    execution = Execution(reference, 0.1, ExecutionSettings(
        drive=('differential',), speed_limit=0.5, yaw_rate_limit=1.9))
    step = execution.step(0.05, reference.position(0.0), [False, False], quaternions([0, 0]))
    assert step.rate == 1.0 and execution.turning.tolist() == [False, True]
    assert step.forward[1] == 0.0 and step.yaw_rates[1] > 0, 'robot 1 turns toward +y'


def test_a_robot_off_its_moving_reference_follows_instead_of_turning_in_place():
    """60 degrees off a moving reference: no turn in place, the clock runs, even at dt = 0."""
    reference = Reference(np.array([0.0, 4.0]), np.array([[[0, 0, 0]], [[1, 1.7, 0]]], float),
                          np.tile([0.0, 0.0, 0.0, 1.0], (2, 1, 1)))
    execution = Execution(reference, 0.1, ExecutionSettings(
        drive=('differential',), speed_limit=0.5, yaw_rate_limit=1.9))
    for dt in (0.0, 0.05, 0.05):
        step = execution.step(dt, reference.position(execution.plan_time), [False],
                              quaternions([0.0]))
        assert not execution.turning.any() and not execution.reverse.any()
        assert step.forward[0] > 0 and step.yaw_rates[0] > 0, 'it drives and steers left'
    assert step.rate > 0


def test_drive_must_fit_the_robot_count():
    assert ExecutionSettings(drive=('differential',)).differential(3).tolist() == [True] * 3
    assert ExecutionSettings(drive=('holonomic', 'differential')).differential(2).tolist() \
        == [False, True]
    with pytest.raises(ValueError, match='drive has 2 values for 3 robots'):
        ExecutionSettings(drive=('holonomic', 'differential')).differential(3)


def test_differential_robots_whose_reference_changes_z_are_found():
    """plan_executor refuses them (UNKNOWN_ROBOTS): a 3-D plan was accepted, never arrived."""
    from punctured_planner.execution.execution import leaving_their_plane
    positions = np.zeros((2, 3, 3))
    positions[1] = [[1.0, 0.0, 0.0], [1.0, 0.0, 0.5], [0.0, 1.0, 0.5]]
    reference = Reference(np.array([0.0, 1.0]), positions, np.tile(IDENTITY, (2, 3, 1)))
    assert leaving_their_plane(np.array([True, True, False]), reference).tolist() == [1]
    assert leaving_their_plane(np.array([False] * 3), reference).size == 0


def test_differential_fleet_ignores_sideways_commands_and_follows_arcs():
    fleet = fleet_of(np.zeros((1, 3)), [0.0], speed_limit=1.0, yaw_rate_limit=np.pi)
    fleet.command(0, [0.0, 1.0, 0.0], 0.0)
    fleet.step(0.0, 0.1)
    assert np.allclose(fleet.positions, 0.0), 'linear.y is ignored'
    # a full circle of radius 1 / pi in 2 s at 1 m/s and pi rad/s: back at the start
    for step in range(20):
        fleet.command(0, [1.0, 0.0, 0.0], 0.1 * step, np.pi)
        fleet.step(0.1 * step, 0.1)
    assert np.allclose(fleet.positions, 0.0, atol=1e-9)
    assert abs(unicycle.wrap(fleet.headings[0])) < 1e-9


def test_differential_fleet_limits_speed_yaw_rate_and_accelerations():
    fleet = fleet_of(np.zeros((1, 3)), [0.0], speed_limit=0.3, yaw_rate_limit=1.9,
                     max_acceleration=1.0, max_yaw_acceleration=2.0)
    fleet.command(0, [5.0, 0.0, 0.0], 0.0, 10.0)
    fleet.step(0.0, 0.1)
    assert fleet.forward[0] == pytest.approx(0.1) and fleet.yaw_rates[0] == pytest.approx(0.2)
    for step in range(1, 20):
        fleet.command(0, [5.0, 0.0, 0.0], 0.1 * step, 10.0)
        fleet.step(0.1 * step, 0.1)
    assert fleet.forward[0] == pytest.approx(0.3) and fleet.yaw_rates[0] == pytest.approx(1.9)


def test_a_robot_made_holonomic_faces_x_again_and_moves_as_commanded():
    """fleet_sim's drive switched at run time: before, the old heading turned +x into -y."""
    fleet = fleet_of(np.zeros((1, 3)), [1.6], speed_limit=1.0)
    fleet.configure(FleetSettings(speed_limit=1.0))
    assert fleet.headings.tolist() == [0.0]
    fleet.command(0, [0.5, 0.0, 0.0], 0.0)
    fleet.step(0.0, 0.1)
    assert np.allclose(fleet.positions, [[0.05, 0.0, 0.0]])


def test_a_robot_made_holonomic_while_driving_brakes_where_it_goes():
    """Made holonomic at speed along +y and told to stop, it brakes along +y (it slid along +x)."""
    fleet = fleet_of(np.zeros((1, 3)), [np.pi / 2], speed_limit=1.0, max_acceleration=1.0)
    now = 0.0
    for _ in range(100):
        fleet.command(0, [0.5, 0.0, 0.0], now)
        fleet.step(now, 0.01)
        now += 0.01
    fleet.configure(FleetSettings(speed_limit=1.0, max_acceleration=np.array([1.0])))
    start = fleet.positions.copy()
    for _ in range(100):
        fleet.command(0, [0.0, 0.0, 0.0], now)
        fleet.step(now, 0.01)
        now += 0.01
    moved = fleet.positions[0] - start[0]
    assert abs(moved[0]) < 1e-9 and 0.1 < moved[1] < 0.15  # v^2 / 2a = 0.125 m along +y


def test_a_robot_made_differential_while_driving_keeps_its_speed():
    """Made differential at 0.5 m/s along +x (its heading), its forward speed ramps from 0.5."""
    fleet = Fleet(np.zeros((1, 3)), FleetSettings(max_acceleration=np.array([0.5])))
    now = 0.0
    for _ in range(40):
        fleet.command(0, [0.5, 0.0, 0.0], now)
        fleet.step(now, 0.05)
        now += 0.05
    fleet.configure(FleetSettings(max_acceleration=np.array([0.5]),
                                  differential=np.array([True])))
    fleet.command(0, [0.5, 0.0, 0.0], now)
    fleet.step(now, 0.05)
    assert fleet.forward[0] == pytest.approx(0.5)  # it fell to 0.025, 9.5 m/s^2


def test_a_differential_robot_on_a_reference_of_one_pose_finishes():
    """A reference of one pose: the robot is there and finishes (the turns ahead raised)."""
    reference = Reference(np.zeros(1), np.array([[[1.0, 1.0, 0.0]]]),
                          np.array([[IDENTITY]]))
    execution = Execution(reference, 0.2, ExecutionSettings(drive=('differential',)))
    for _ in range(20):
        step = execution.step(0.05, reference.position(0.0).copy(), np.zeros(1, dtype=bool))
        assert np.all(step.velocities == 0.0) and np.all(step.yaw_rates == 0.0)
    assert step.finished


def test_commands_and_odometry_are_in_each_robots_body_frame():
    """The executor's commands and the simulator's odometry: rotated into each robot's frame."""
    step = Step(plan_time=0.0, rate=1.0, positions=np.zeros((2, 3)),
                orientations=np.tile(IDENTITY, (2, 1)),
                velocities=np.array([[1.0, 0.0, 0.0], [0.3, 0.4, 0.0]]), errors=np.zeros(2),
                watched=np.zeros(2), finished=False, differential=np.array([False, True]),
                forward=np.array([0.0, 0.5]), yaw_rates=np.array([0.0, 0.2]), allowed=1.0)
    # a holonomic robot facing +y told +x goes to its right; a differential one forward only
    commands = step.body_commands(quaternions([np.pi / 2, 1.0]))
    assert np.allclose(commands, [[0.0, -1.0, 0.0], [0.5, 0.0, 0.0]])
    # the simulator's orientations are its headings' (yaw_quaternions, yaws' inverse)
    assert np.allclose(unicycle.yaw_quaternions(np.array([0.7, -2.0])), quaternions([0.7, -2.0]))
    fleet = fleet_of(np.array([[0.0, 0.0, 0.0], [2.0, 0.0, 0.0]]), [0.7, -2.0],
                     speed_limit=1.0)
    assert np.allclose(fleet.orientations, quaternions([0.7, -2.0]))
    fleet.command(0, [0.5, 0.0, 0.0], 0.0)
    fleet.step(0.0, 0.1)
    assert fleet.forward[0] > 0.0
    assert np.allclose(fleet.body_velocities, [[fleet.forward[0], 0.0, 0.0], [0.0, 0.0, 0.0]])
    # a holonomic robot faces +x: its body frame is the world's, its twist its velocity
    holonomic = Fleet(np.zeros((1, 3)), FleetSettings(speed_limit=1.0))
    holonomic.command(0, [0.3, -0.4, 0.0], 0.0)
    holonomic.step(0.0, 0.1)
    assert np.allclose(holonomic.body_velocities, [[0.3, -0.4, 0.0]])
    assert np.allclose(holonomic.orientations, [IDENTITY])


def polyline_reference(points, speed):
    """Return a one-robot Reference along points (n, 2) at speed, with a final heading."""
    points = np.c_[np.asarray(points, dtype=float), np.zeros(len(points))]
    seconds = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(points, axis=0), axis=1) / speed)]
    orientations = np.tile([0.0, 0.0, 0.0, 1.0], (len(points), 1, 1))
    orientations[-1, 0] = quaternions([2.0])[0]
    return Reference(seconds, points[:, None, :], orientations)


@settings(max_examples=10, deadline=None)
@given(st.lists(st.tuples(st.floats(-1, 1), st.floats(-1, 1)), min_size=2, max_size=4),
       st.floats(0.03, 0.15), angles_st, st.booleans())
def test_closed_loop_keeps_the_centre_within_the_tolerance(points, tolerance, start, late):
    """Random polylines, any start heading, 100 ms latency (where delta allows) or none."""
    points = [points[0]] + [p for p, q in zip(points[1:], points) if np.hypot(
        p[0] - q[0], p[1] - q[1]) > 0.05]
    if len(points) < 2:
        return
    reference = polyline_reference(points, 0.3)
    # a latency L needs v L within the clock's margin (1 - hold_fraction) delta (section 13)
    latency = 0.1 if late and 0.3 * 0.1 <= 0.4 * tolerance else 0.0
    fleet = fleet_of(reference.position(0.0), [start], speed_limit=0.3, yaw_rate_limit=1.9,
                     max_acceleration=1.0, max_yaw_acceleration=8.0,
                     latencies=np.array([latency]))
    execution = Execution(reference, tolerance, ExecutionSettings(
        drive=('differential',), speed_limit=0.3, yaw_rate_limit=1.9))
    now, step = 0.0, None
    while now < 20 * reference.duration + 30 and not (step and step.finished):
        step = execution.step(0.05, fleet.positions, [False], quaternions(fleet.headings))
        assert step.errors[0] <= tolerance
        fleet.command(0, [step.forward[0], 0.0, 0.0], now, step.yaw_rates[0])
        for _ in range(2):
            fleet.step(now, 0.025)
            now += 0.025
    assert step.finished
    assert np.linalg.norm(fleet.positions - reference.positions[-1]) <= 0.01
    # stopped as the executor stops it; the commands still in flight turn it a little on
    for _ in range(40):
        fleet.command(0, [0.0, 0.0, 0.0], now)
        fleet.step(now, 0.025)
        now += 0.025
    assert np.linalg.norm(fleet.positions - reference.positions[-1]) <= 0.01
    assert abs(unicycle.wrap(fleet.headings[0] - 2.0)) <= 0.05


def test_a_reversal_is_driven_backward_not_turned_round():
    reference = Reference(np.array([0.0, 4.0]), np.array([[[0, 0, 0]], [[-1, 0, 0]]], float),
                          np.tile([0.0, 0.0, 0.0, 1.0], (2, 1, 1)))
    execution = Execution(reference, 0.1, ExecutionSettings(
        drive=('differential',), speed_limit=0.5, yaw_rate_limit=1.9))
    step = execution.step(0.05, reference.position(0.0), [False], quaternions([0.0]))
    assert execution.reverse.tolist() == [True] and not execution.turning.any()
    assert step.forward[0] < 0 and abs(step.yaw_rates[0]) < 1e-9


def test_a_timed_plan_stops_where_a_differential_robot_switches_direction():
    """Under an acceleration limit a turn beyond 90 degrees is a stop at rest, no ramp."""
    positions = np.array([[[0, 0, 0], [0, 2, 0]], [[2, 0, 0], [2, 2, 0]],
                          [[0, 2, 0], [4, 2, 0]]], dtype=float)
    orientations = np.tile([0.0, 0.0, 0.0, 1.0], (3, 2, 1))
    timed = Reference.timed(np.array([0.0, 3.0, 6.0]), positions, orientations, 1.0, 1.0, 0.25)
    assert timed.profile.speeds[1] > 0, 'the plan passes its corner moving'
    holonomic = Execution(timed, 0.25, ExecutionSettings(speed_limit=1.0))
    assert holonomic.reference.at_rest().tolist() == [True, False, True], 'no stop'
    drive = ('differential', 'holonomic')
    differential = Execution(timed, 0.25, ExecutionSettings(
        drive=drive, speed_limit=1.0, yaw_rate_limit=1.9))
    rests = differential.reference.at_rest()
    assert rests.tolist() == [True, True, True], 'robot 0 turns by 135 degrees at pose 1'
    assert np.array_equal(differential.reference.positions, positions)
    corner = differential.reference.seconds[1]
    caps = differential.corners.corner_caps(corner - 0.3, differential.steering, 1.9)
    assert caps.tolist() == [1.0, 1.0], 'a stop at rest needs no ramp before it'
    # a right angle is followed moving, slowed into by the corner ramp
    right = positions.copy()
    right[2, 0] = [2, 2, 0]
    square = Reference.timed(np.array([0.0, 3.0, 6.0]), right, orientations, 1.0, 1.0, 0.25)
    bent = Execution(square, 0.25, ExecutionSettings(drive=drive, speed_limit=1.0,
                                                     yaw_rate_limit=1.9))
    assert bent.reference.at_rest().tolist() == [True, False, True]
    corner = bent.reference.seconds[1]
    assert bent.corners.corner_caps(corner - 0.3, bent.steering, 1.9)[0] < 1.0
    # the differential robot straight, the holonomic one turning: no stop
    straight = positions.copy()
    straight[2] = [[4, 0, 0], [2, 4, 0]]
    plain = Reference.timed(np.array([0.0, 3.0, 6.0]), straight, orientations, 1.0, 1.0, 0.25)
    assert Execution(plain, 0.25, ExecutionSettings(drive=drive)).reference.at_rest(
    ).tolist() == [True, False, True]


def test_the_lead_fits_half_the_room_between_the_thresholds():
    """The lead e is at most (hold - slow) delta / 2, even below LEAD_FRACTION delta."""
    assert unicycle.lead(0.1, 0.5, 0.6) <= 0.5 * (0.6 - 0.5) * 0.1


def test_the_creep_rate_is_the_same_on_either_side():
    """A reference to the robot's right slows the clock as one to its left does."""
    rates = unicycle.creep_rate(np.array([0.5, -0.5]), np.array([1.0, 1.0]), 0.1, 1.0)
    assert rates[0] == rates[1] < 1.0
