"""One request against one snapshot (ros.planning.PlanSequenceHandler), without DDS."""

import numpy as np
from planner_helpers import flat
from planner_helpers import make_request
from planner_helpers import OBSTACLES
from punctured_planner.core import ErrorCode
from punctured_planner.ros import conversions
from punctured_planner.ros.planning import PlanSequenceHandler
from punctured_planner.ros.settings import PLANNER
from punctured_planner.ros.snapshot import ObstacleSet
from punctured_planner.ros.snapshot import Snapshot
import pytest


def snapshot(**values):
    settings = PLANNER.settings(values)
    return Snapshot(settings, ObstacleSet(conversions.obstacles_from_parameter(
        settings.obstacles)))


def test_planner_caches_one_workspace_per_obstacle_set():
    from punctured_planner_interfaces.srv import PlanSequence
    planner = PlanSequenceHandler()
    base = snapshot(obstacles=flat(OBSTACLES))
    first = planner.workspace(base.settings, np.array(OBSTACLES)[:, :2])
    assert planner.workspace(base.settings, np.array(OBSTACLES)[:, :2]) is first
    paper = PLANNER.settings({'variant': 'paper'})
    assert planner.workspace(paper, np.array(OBSTACLES)[:, :2]) is not first
    outcome = planner.handle(make_request(), PlanSequence.Response(), base, 0)
    assert outcome.ok and outcome.names == ['robot_0', 'robot_1', 'robot_2', 'robot_3']
    assert outcome.start_ns > 0
    again = planner.handle(make_request(), PlanSequence.Response(), base, 0)
    assert again.plan.workspace is first


def test_over_limit_requests_are_refused_before_conversion(monkeypatch):
    """REQUEST_OVER_LIMITS from list lengths: no pose is converted, whatever the values."""
    from geometry_msgs.msg import Pose
    from geometry_msgs.msg import PoseArray
    from punctured_planner_interfaces.srv import PlanSequence
    request = PlanSequence.Request()
    huge = PoseArray()
    huge.poses = [Pose()] * 20001  # one shared Pose: cheap to build
    request.configurations = [huge, huge]
    converted = []
    monkeypatch.setattr(conversions, 'pose_arrays_poses', converted.append)
    outcome = PlanSequenceHandler().handle(request, PlanSequence.Response(), snapshot(), 0)
    assert outcome.response.error_code == PlanSequence.Response.REQUEST_OVER_LIMITS
    assert 'max_robots 10000' in outcome.response.error_msg
    assert converted == []


def answer_poses(outcome):
    """Return how many poses an answer's paths hold in all."""
    return sum(len(path.poses) for path in outcome.response.paths)


def test_discs_answers_over_max_poses_are_refused_once_planned():
    """
    'discs' has no fixed legs: its pose count is checked against max_poses after planning.

    The count is the answer's own: a leg in which no robot moves lasts no time and adds
    no pose (this request has such legs), so an answer of exactly max_poses is given.
    """
    from punctured_planner_interfaces.srv import PlanSequence
    planned = PlanSequenceHandler().handle(
        make_request(), PlanSequence.Response(),
        snapshot(obstacles=flat(OBSTACLES), robot_radius=0.1, samples_per_leg=0), 0)
    poses = answer_poses(planned)
    assert poses < 4 * len(planned.plan.times)
    limited = snapshot(obstacles=flat(OBSTACLES), robot_radius=0.1, samples_per_leg=0,
                       max_poses=poses - 1)
    outcome = PlanSequenceHandler().handle(make_request(), PlanSequence.Response(), limited, 0)
    assert outcome.response.error_code == PlanSequence.Response.REQUEST_OVER_LIMITS
    assert 'more than max_poses %d' % (poses - 1) in outcome.response.error_msg
    enough = snapshot(obstacles=flat(OBSTACLES), robot_radius=0.1, samples_per_leg=0,
                      max_poses=poses)
    assert PlanSequenceHandler().handle(make_request(), PlanSequence.Response(), enough, 0).ok


def test_refined_answers_are_checked_by_their_own_pose_count():
    """The refinement adds knots: max_poses is checked against the refined plan's poses."""
    from punctured_planner_interfaces.srv import PlanSequence
    raw = PlanSequenceHandler().handle(make_request(), PlanSequence.Response(),
                                       snapshot(obstacles=flat(OBSTACLES), refine=False), 0)
    refined = PlanSequenceHandler().handle(make_request(), PlanSequence.Response(),
                                           snapshot(obstacles=flat(OBSTACLES)), 0)
    assert raw.ok and refined.ok and raw.plan.raw is None and refined.plan.raw is not None
    poses = answer_poses(refined)
    assert answer_poses(raw) < poses
    # Enough for the construction's breakpoints, not for the refined plan's.
    limited = snapshot(obstacles=flat(OBSTACLES), max_poses=poses - 1)
    outcome = PlanSequenceHandler().handle(make_request(), PlanSequence.Response(), limited, 0)
    assert outcome.response.error_code == PlanSequence.Response.REQUEST_OVER_LIMITS
    assert 'more than max_poses %d' % (poses - 1) in outcome.response.error_msg
    enough = snapshot(obstacles=flat(OBSTACLES), max_poses=poses)
    assert PlanSequenceHandler().handle(make_request(), PlanSequence.Response(), enough, 0).ok


def test_max_poses_leaves_out_what_the_current_state_drops():
    """
    max_poses is judged on the answer: configurations the current state drops add no pose.

    Leading configurations that repeat the state are dropped once converted (design
    section 12), so ten repeats before the goal do not make an answer of two
    configurations' poses too many (the paper variant's count from its fixed legs,
    before planning, took all twelve and refused it).
    """
    from punctured_planner.ros.snapshot import RobotState
    from punctured_planner_interfaces.srv import PlanSequence
    start, goal = make_request().configurations[:2]
    state = RobotState(conversions.pose_array_positions(start), np.tile([0.0, 0, 0, 1], (4, 1)),
                       'map', 5, 'robot_states', 5)
    request = make_request()
    request.configurations = [start] * 10 + [goal]
    request.use_current_state = True
    values = {'obstacles': flat(OBSTACLES), 'variant': 'paper', 'samples_per_leg': 0,
              'refine': False}
    settings = PLANNER.settings(values)
    obstacles = ObstacleSet(conversions.obstacles_from_parameter(settings.obstacles))
    planned = PlanSequenceHandler().handle(request, PlanSequence.Response(),
                                           Snapshot(settings, obstacles, state), 10)
    assert planned.ok and list(planned.response.dropped_configurations) == list(range(10))
    limited = PLANNER.settings({**values, 'max_poses': answer_poses(planned)})
    outcome = PlanSequenceHandler().handle(request, PlanSequence.Response(),
                                           Snapshot(limited, obstacles, state), 10)
    assert outcome.ok, outcome.response.error_msg


def test_a_plan_refused_for_the_resolution_reports_the_gap_it_found():
    """
    min_gap reports the value found, as min_clearance does, when rounding is the reason.

    A robot 1e15 away makes the coordinates' resolution larger than the plan's
    clearance: CLEARANCE_BELOW_REQUIRED, and without radii the gap is the clearance
    (it read 0.0, 'touching', before).
    """
    from planner_helpers import CONFIGURATIONS
    from punctured_planner_interfaces.srv import PlanSequence
    far = [list(map(list, configuration)) for configuration in CONFIGURATIONS]
    far[1][2][0] = 1e15
    outcome = PlanSequenceHandler().handle(
        make_request(far), PlanSequence.Response(),
        snapshot(obstacles=flat(OBSTACLES)), 0)
    response = outcome.response
    assert response.error_code == PlanSequence.Response.CLEARANCE_BELOW_REQUIRED
    assert 'numerical resolution' in response.error_msg
    assert response.min_gap == response.min_clearance > 0.0


def test_stamps_past_2038_name_the_limit_that_binds():
    """A motion too long for the stamps under a tiny max_acceleration says to raise that."""
    from punctured_planner_interfaces.srv import PlanSequence
    for max_acceleration, culprit in ((1e-20, 'raise max_acceleration'),
                                      (0.0, 'raise max_speed')):
        outcome = PlanSequenceHandler().handle(
            make_request(max_speed=1e-12 if max_acceleration == 0.0 else 1.0),
            PlanSequence.Response(),
            snapshot(obstacles=flat(OBSTACLES), max_acceleration=max_acceleration), 0)
        assert outcome.response.error_code == PlanSequence.Response.INVALID_REQUEST
        assert outcome.response.error_msg.endswith(culprit), outcome.response.error_msg


def test_a_request_no_answer_of_which_fits_is_refused_before_planning(monkeypatch):
    """Under max_poses even with one moving leg a segment: refused, nothing planned."""
    from punctured_planner_interfaces.srv import PlanSequence

    def planned(*args):
        raise AssertionError('planned a request no answer of which fits')

    monkeypatch.setattr(PlanSequenceHandler, '_plan', planned)
    request = make_request(samples_per_leg=100)  # 4 robots, 1 + 101 per segment at least
    outcome = PlanSequenceHandler().handle(
        request, PlanSequence.Response(),
        snapshot(obstacles=flat(OBSTACLES), max_poses=400), 0)
    assert outcome.response.error_code == PlanSequence.Response.REQUEST_OVER_LIMITS
    assert 'more than max_poses 400' in outcome.response.error_msg


def test_array_holding_dataclasses_compare_by_identity():
    """Frame, ObstacleSet, RobotState, PlaneView: == and hash work (no numpy ValueError)."""
    from punctured_planner.core import Workspace
    from punctured_planner.ros.snapshot import RobotState
    from punctured_planner.viz.geometry import PlaneView
    frame = Workspace(np.array(OBSTACLES)[:, :2]).frame
    items = [frame, ObstacleSet(np.zeros((2, 3))), RobotState(np.zeros((2, 3)), np.zeros((2, 4))),
             PlaneView(np.zeros(2), np.eye(2)[0], np.eye(2)[1], ('x', 'y'))]
    for item in items:
        twin = type(item)(*(getattr(item, name) for name in item.__dataclass_fields__))
        assert item == item and not item == twin and len({item, twin}) == 2


def state_snapshot(positions, received_ns, **values):
    """Return a snapshot with the example obstacles and a robot state received then."""
    from punctured_planner.ros.snapshot import RobotState
    settings = PLANNER.settings({'obstacles': flat(OBSTACLES), **values})
    state = RobotState(np.asarray(positions, dtype=float), np.zeros((len(positions), 4)),
                       'map', received_ns - 7, 'robot_states', received_ns)
    return Snapshot(settings, ObstacleSet(np.array(OBSTACLES)), state)


def answer(request, snapshot, now_ns):
    from punctured_planner_interfaces.srv import PlanSequence
    return PlanSequenceHandler().handle(request, PlanSequence.Response(), snapshot, now_ns)


def test_a_stale_robot_state_is_refused_with_its_age_and_source():
    """Issue 15.3: 5 s without robot_states is NO_ROBOT_STATE, not a plan from the past."""
    from planner_helpers import CONFIGURATIONS
    now = 1700000000 * 10 ** 9
    request = make_request(CONFIGURATIONS[1:], use_current_state=True)
    outcome = answer(request, state_snapshot(CONFIGURATIONS[0], now - 5 * 10 ** 9), now)
    assert outcome.response.error_code == 2, outcome.response.error_msg
    message = outcome.response.error_msg
    assert 'robot_states' in message and '5.000 s old' in message
    assert 'max_state_age 0.5' in message
    fresh = answer(request, state_snapshot(CONFIGURATIONS[0], now - 10 ** 8), now)
    assert fresh.ok, fresh.response.error_msg
    unchecked = answer(request, state_snapshot(CONFIGURATIONS[0], now - 5 * 10 ** 9,
                                               max_state_age=0.0), now)
    assert unchecked.ok


def test_a_state_from_odometry_names_the_robots_too_old_or_in_another_frame():
    """
    NO_ROBOT_STATE and FRAME_MISMATCH from odometry name the robot at fault, not the fleet.

    Both said 'the robot state from odometry of robot_0, robot_1, robot_2, robot_3': with
    50 robots, no word of which one to fix.
    """
    from planner_helpers import CONFIGURATIONS
    from punctured_planner.ros.snapshot import RobotOdometry
    from punctured_planner.ros.snapshot import take_snapshot
    now = 1700000000 * 10 ** 9
    names = ['r0', 'r1', 'r2', 'r3']
    settings = PLANNER.settings({'obstacles': flat(OBSTACLES), 'robot_names': names})
    request = make_request(CONFIGURATIONS[1:], use_current_state=True)

    def snapshot(ages, frames):
        odometry = {name: RobotOdometry(np.asarray(CONFIGURATIONS[0][i], dtype=float),
                                        np.array([0.0, 0.0, 0.0, 1.0]), frames[i], now,
                                        now - int(ages[i] * 1e9), 0.0)
                    for i, name in enumerate(names)}
        return take_snapshot(settings, ObstacleSet(np.array(OBSTACLES)), None, odometry)

    old = answer(request, snapshot([0.1, 3.5, 0.1, 0.9], ['map'] * 4), now)
    assert old.response.error_code == ErrorCode.NO_ROBOT_STATE, old.response.error_msg
    assert old.response.error_msg.endswith(
        'more than max_state_age 0.5 s: the odometry of r1 (3.500 s old) and r3 (0.900 s '
        'old)'), old.response.error_msg
    elsewhere = answer(request, snapshot([0.1] * 4, ['map', 'map', 'odom', 'map']), now)
    assert elsewhere.response.error_code == ErrorCode.FRAME_MISMATCH
    assert ("is in frame 'odom' (the odometry of r2), the planning frame is 'map'"
            in elsewhere.response.error_msg), elsewhere.response.error_msg
    assert answer(request, snapshot([0.1] * 4, ['map'] * 4), now).ok


def test_robots_are_named_by_robot_names_in_every_refusal():
    """
    With robot_names a refusal names robot i as 'robot i (its name)', without as 'robot i'.

    'robot 3 overlaps obstacle 1' left the operator of a named fleet to count.
    """
    from planner_helpers import CONFIGURATIONS
    settings = {'obstacles': flat(OBSTACLES), 'robot_names': ['r0', 'r1', 'r2', 'ghost']}
    on_pillar = [list(c) for c in CONFIGURATIONS]
    on_pillar[1] = on_pillar[1][:3] + [OBSTACLES[1]]
    same = [list(c) for c in CONFIGURATIONS]
    same[2] = [same[2][0], same[2][0]] + same[2][2:]
    for values, words in ((settings, ('robot 3 (ghost) is on obstacle 1',
                                      'robots 0 (r0) and 1 (r1) are at the same point')),
                          ({'obstacles': flat(OBSTACLES)},
                           ('robot 3 is on obstacle 1', 'robots 0 and 1 are at the same'))):
        snapshot = Snapshot(PLANNER.settings(values), ObstacleSet(np.array(OBSTACLES)))
        for configurations, expected in zip((on_pillar, same), words):
            outcome = answer(make_request(configurations), snapshot, 0)
            assert expected in outcome.response.error_msg, outcome.response.error_msg


def test_a_configuration_repeating_the_current_state_is_dropped():
    """Issue 15.2: resending the current positions first is no 30 s detour."""
    from planner_helpers import CONFIGURATIONS
    now = 10 ** 18
    state = np.array(CONFIGURATIONS[0])
    again = state + [[1e-4, 0.0, 0.0]] * 4  # within repeat_tolerance 1e-3
    resent = answer(make_request([again] + CONFIGURATIONS[1:], use_current_state=True),
                    state_snapshot(state, now), now)
    direct = answer(make_request(CONFIGURATIONS[1:], use_current_state=True),
                    state_snapshot(state, now), now)
    assert resent.ok and direct.ok, resent.response.error_msg
    assert list(resent.response.dropped_configurations) == [0]
    assert list(direct.response.dropped_configurations) == []
    assert resent.plan.duration(1.0) == direct.plan.duration(1.0)
    assert list(resent.response.projection_counts) == list(direct.response.projection_counts)
    assert len(resent.response.waypoint_indices) == 3
    only = answer(make_request([again], use_current_state=True), state_snapshot(state, now),
                  now)
    assert only.response.error_code == 1
    assert 'already there' in only.response.error_msg
    # Beyond the tolerance the configuration is planned, as before.
    moved = answer(make_request([state + [[0.01, 0.0, 0.0]] * 4], use_current_state=True),
                   state_snapshot(state, now), now)
    assert moved.ok and list(moved.response.dropped_configurations) == []


def test_messages_name_the_culprit_the_one_way():
    """Issue 15.5: the count mismatch blames the state and says robot_count; obstacles named."""
    from planner_helpers import CONFIGURATIONS
    now = 10 ** 18
    request = make_request([c[:3] for c in CONFIGURATIONS[1:]], use_current_state=True)
    outcome = answer(request, state_snapshot(CONFIGURATIONS[0], now, robot_count=3), now)
    assert outcome.response.error_code == 5
    assert outcome.response.error_msg == (
        'configuration 0 (the current robot state from robot_states) has 4 robots but the '
        'node is configured for robot_count 3')
    on_obstacle = [list(p) for p in CONFIGURATIONS[1]]
    on_obstacle[2] = OBSTACLES[1]
    outcome = answer(make_request([CONFIGURATIONS[0], on_obstacle], use_current_state=True),
                     state_snapshot(CONFIGURATIONS[0], now), now)
    assert outcome.response.error_code == 11
    # configurations[0] repeats the state and is dropped: numbering stays the request's.
    assert outcome.response.error_msg == (
        'configuration 2 (request configurations[1]): robot 2 is on obstacle 1 at '
        '(0, -0.5, 0) (from the parameter)')


def test_log_stamps_keep_every_nanosecond():
    """Issue 15.6: ...870.584161458 was logged as ...870.584161758 through a float."""
    from punctured_planner.ros.snapshot import RobotState
    stamp = 1700000870584161458
    assert '1700000870.584161458' in ObstacleSet(np.zeros((1, 3)), 'map', '/obstacles',
                                                 stamp).describe()
    assert '1700000870.584161458' in RobotState(np.zeros((1, 3)), np.zeros((1, 4)), 'map',
                                                stamp).describe()


def test_bundled_scenario_refuses_a_goal_grazing_an_obstacle():
    """
    Issue 15.7: the bundled scenario has bodies and a required gap.

    A goal 1 um from an obstacle's centre puts the robot's disc on the pillar
    (ROBOT_ON_OBSTACLE); one whose disc touches the pillar's is planned but
    refused for the gap (CLEARANCE_BELOW_REQUIRED).
    """
    import os
    from conftest import REPO_ROOT
    from planner_helpers import CONFIGURATIONS
    from punctured_planner.ros.parameters import load_parameter_file
    values = load_parameter_file(os.path.join(REPO_ROOT, 'config', 'default_scenario.yaml'),
                                 PLANNER)
    settings = PLANNER.settings(values)
    assert settings.required_clearance > 0
    snapshot = Snapshot(settings, ObstacleSet(conversions.obstacles_from_parameter(
        settings.obstacles)))
    assert settings.robot_radius > 0 and settings.core_variant == 'discs'
    goal = [list(p) for p in CONFIGURATIONS[2]]
    goal[0] = [OBSTACLES[2][0] + 1e-6, OBSTACLES[2][1], 0.0]
    outcome = answer(make_request([CONFIGURATIONS[0], goal]), snapshot, 0)
    assert outcome.response.error_code == 11, outcome.response.error_msg
    assert 'overlaps obstacle 2' in outcome.response.error_msg
    touching = settings.robot_radius + settings.obstacle_radius[0]
    goal[0] = [OBSTACLES[2][0], OBSTACLES[2][1] - touching, 0.0]
    outcome = answer(make_request([CONFIGURATIONS[0], goal]), snapshot, 0)
    assert outcome.response.error_code == 12, outcome.response.error_msg
    assert outcome.response.min_gap < settings.required_clearance
    assert answer(make_request(), snapshot, 0).ok


def test_errors_carry_their_culprits_and_are_worded_by_the_layer_that_answers():
    """The core's error names obstacles its way; the response names them the node's way."""
    from punctured_planner.core import PlanningError
    from punctured_planner.core import Workspace
    from punctured_planner.ros.wording import ObstacleNames
    points = np.array([[0.0, 1.0], [2.0, 0.0], [0.0, 1.0]])
    with pytest.raises(PlanningError) as refused:
        Workspace(points)
    error = refused.value
    assert error.obstacles == (0, 2) and error.obstacle == 0
    assert str(error) == 'OBSTACLES_DEGENERATE: obstacles 0 and 2 are at the same point'
    named = ObstacleSet(np.c_[points, np.zeros(3)], source='/fleet/obstacles')
    assert error.describe(ObstacleNames(named.name)) == (
        'obstacle 0 at (0, 1, 0) (from topic /fleet/obstacles) and obstacle 2 at (0, 1, 0) '
        '(from topic /fleet/obstacles) are at the same point')


def test_the_parameters_hint_says_how_to_change_obstacles_and_radii_together():
    """
    The hint to set both atomically comes only where one of the two changed alone.

    A parameter set (ros2 param set, ros2 param load) applies one at a time, so four
    obstacles against three radii are refused; at start-up (every parameter changed)
    and for a pillar beyond a wall the hint has nothing to say.
    """
    three = [0.0, 0.0, 0.0, 2.0, 1.0, 0.0, -2.0, -1.0, 0.0]
    settings = PLANNER.settings({'robot_radius': 0.2, 'obstacle_radius': [0.1, 0.2, 0.3],
                                 'obstacles': three + [3.0, 3.0, 0.0]})
    four = ObstacleSet(conversions.obstacles_from_parameter(settings.obstacles))
    handler = PlanSequenceHandler()
    for changed, hinted in (({'obstacles'}, True), ({'obstacles', 'obstacle_radius'}, False)):
        with pytest.raises(ValueError) as refused:
            handler.check_parameter_obstacles(settings, four, changed)
        assert 'obstacle_radius must be a scalar or one value per obstacle' in str(refused.value)
        assert ('set_parameters_atomically' in str(refused.value)) == hinted
        assert refused.value.parameters == tuple(sorted(changed)) + (
            ('obstacle_radius',) if changed == {'obstacles'} else ())
    walled = PLANNER.settings({'robot_radius': 0.2, 'obstacle_radius': [0.3],
                               'obstacles': three, 'workspace_bounds': [-5, 5, -0.5, 5]})
    with pytest.raises(ValueError) as refused:
        handler.check_parameter_obstacles(walled, ObstacleSet(
            conversions.obstacles_from_parameter(walled.obstacles)), {'obstacles'})
    assert 'OUTSIDE_WORKSPACE' in str(refused.value) and 'y_min' in str(refused.value)
    # the culprits as data: the parameters (the changed one first), the core's refusal
    # with its obstacle and wall as the cause
    assert refused.value.parameters == ('obstacles', 'workspace_bounds')
    cause = refused.value.__cause__
    assert (cause.code, cause.obstacle) == (ErrorCode.OUTSIDE_WORKSPACE, 2)
    assert cause.wall.name == 'y_min'
    assert 'together' not in str(refused.value)


def test_a_change_the_topics_obstacles_cannot_take_is_refused_on_set():
    """
    With the set from the topic in use, a change that would refuse every request is refused.

    Three radii for the topic's two obstacles, or a wall the topic's pillar lies beyond,
    were taken before and refused every request after (INVALID_REQUEST for a malformed
    one); they name the changed parameter, never 'obstacles' (the parameter is not in use).
    """
    topic = ObstacleSet(np.array([[0.0, 0.0, 0.0], [2.0, 5.0, 0.0]]), 'map', '/obstacles', 5)
    handler = PlanSequenceHandler()
    radii = PLANNER.settings({'obstacle_radius': [0.1, 0.2, 0.3]})
    with pytest.raises(ValueError) as refused:
        handler.check_parameter_obstacles(radii, topic, {'obstacle_radius'})
    assert 'obstacle_radius must be a scalar or one value per obstacle' in str(refused.value)
    assert 'from topic /obstacles' in str(refused.value)
    assert refused.value.parameters == ('obstacle_radius',)
    walled = PLANNER.settings({'workspace_bounds': [-10.0, 10.0, -10.0, 2.0]})
    with pytest.raises(ValueError) as refused:
        handler.check_parameter_obstacles(walled, topic, {'workspace_bounds'})
    assert refused.value.parameters == ('workspace_bounds',)
    assert refused.value.__cause__.obstacle == 1
    # what the topic's set can take is taken
    handler.check_parameter_obstacles(PLANNER.settings({'obstacle_radius': [0.1, 0.2]}),
                                      topic, {'obstacle_radius'})


def test_no_obstacles_plan_whatever_the_per_obstacle_radii():
    """
    An empty obstacle set beside per-obstacle radii plans: the radii wait for a set.

    The parameter set was taken, and then every request was refused (INVALID_REQUEST,
    'obstacle_radius must be a scalar or one value per obstacle'); the same empty set
    on the topic was refused.
    """
    from punctured_planner_interfaces.srv import PlanSequence
    handler = PlanSequenceHandler()
    settings = PLANNER.settings({'obstacle_radius': [0.1, 0.2], 'robot_radius': 0.1})
    empty = ObstacleSet(np.zeros((0, 3)), 'map', '/obstacles', 5)
    handler.check_parameter_obstacles(settings, empty, {'obstacles'})
    handler.check_obstacles(settings, empty)
    outcome = handler.handle(make_request(), PlanSequence.Response(),
                             Snapshot(settings, empty), 0)
    assert outcome.ok, outcome.response.error_msg


def test_a_request_faster_than_the_parameters_range_is_refused():
    """max_speed 1e9: INVALID_REQUEST (its stamps, 1 ns apart, spanned 68 ns for 5 ns)."""
    from punctured_planner_interfaces.srv import PlanSequence
    for speed in (1e9, 1e300):
        outcome = PlanSequenceHandler().handle(make_request(max_speed=speed),
                                               PlanSequence.Response(),
                                               snapshot(obstacles=flat(OBSTACLES)), 0)
        assert outcome.response.error_code == PlanSequence.Response.INVALID_REQUEST
        assert 'at most 1e+06 m/s' in outcome.response.error_msg
    assert PlanSequenceHandler().handle(make_request(max_speed=1e6), PlanSequence.Response(),
                                        snapshot(obstacles=flat(OBSTACLES)), 0).ok


def test_free_text_in_a_message_is_never_read_as_a_slot():
    """A frame id with braces is quoted as it is (the message is a template)."""
    outcome = answer(make_request(frame_id='{configuration}'), snapshot(), 0)
    assert outcome.response.error_code == 7
    assert outcome.response.error_msg == (
        "configuration 0 is in frame '{configuration}', the planning frame is 'map'")
