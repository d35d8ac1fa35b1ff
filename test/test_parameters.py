"""Parameter table, validation and parameter files, without a node."""

import math
import os

from conftest import REPO_ROOT
import numpy as np
from punctured_planner.execution.execution import WrongCount
from punctured_planner.ros.parameters import FRAME_ID
from punctured_planner.ros.parameters import InvalidParameter
from punctured_planner.ros.parameters import InvalidParameterFile
from punctured_planner.ros.parameters import load_parameter_file
from punctured_planner.ros.settings import EXECUTOR
from punctured_planner.ros.settings import FLEET_SIM
from punctured_planner.ros.settings import PLANNER
import pytest


def test_values_take_the_parameter_kinds():
    """YAML integers become doubles, lists become tuples, None an empty list."""
    good = PLANNER.settings({'plane_z': 1, 'obstacles': [0, 0, 0], 'robot_names': None})
    assert isinstance(good.plane_z, float) and good.plane_z == 1.0
    assert good.obstacles == (0.0, 0.0, 0.0) and good.robot_names == ()


@pytest.mark.parametrize('values, words', [
    ({'dimension': 4}, 'dimension'), ({'variant': 'x'}, 'variant'),
    ({'obstacles': [1.0]}, 'multiple of 3'), ({'obstacles': [math.nan] * 3}, 'finite'),
    ({'robot_names': ['a', 'a']}, 'unique'), ({'robot_names': ['a b']}, 'ROS name'),
    ({'robot_names': ['a'], 'robot_count': 2}, 'robot_count'),
    ({'frame_id': ''}, 'frame_id'), ({'lane_spacing': 0.0}, 'lane_spacing'),
    ({'frame_id': 'bad frame'}, "frame_id 'bad frame' is not a frame id"),
    ({'robot_radius': 1e-200}, 'robot_radius: every value must be 0 or a real number between'),
    ({'required_clearance': 1e-120}, 'required_clearance: every value must be 0 or'),
    ({'obstacle_radius': [0.1, 1e-300]}, 'obstacle_radius: every value must be 0 or'),
    ({'frame_id': '/map'}, "tf2 takes no leading '/'"),
    ({'max_speed': True}, 'max_speed'), ({'dimension': 2.0}, 'integer'),
    ({'nonsense': 1}, 'unknown'), ({'robot_count': 5, 'max_robots': 4}, 'max_robots'),
    ({'refine': 1}, 'refine must be true or false'),
])
def test_settings_validation_gives_reasons(values, words):
    with pytest.raises(ValueError, match=words):
        PLANNER.settings(values)


@pytest.mark.parametrize('values', [
    [0.0, 1.0, 0.0], [0.0, 1.0, 2.0, 1.0], [0.0, 1.0, 0.0, 1.0, 0.0, 1.0],
    [2.0, 1.0, 0.0, 1.0], [5.0, 5.0, 0.0, 1.0],
])
def test_workspace_bounds_are_refused_exactly_where_the_core_refuses_them(values):
    """One rule: the parameter's reason is the core's, with the parameter, its axes, entries."""
    from punctured_planner.core import PlanningError
    from punctured_planner.core.walls import checked_bounds
    from punctured_planner.ros.wording import WallNames
    flat = np.asarray(values)
    with pytest.raises(PlanningError) as core:
        checked_bounds(flat.reshape(-1, 2) if flat.size % 2 == 0 else flat, 2)
    with pytest.raises(ValueError) as parameter:
        PLANNER.settings({'workspace_bounds': values})
    reason = str(parameter.value)
    # the same template, its wall named by the parameter entry that sets it
    assert reason.startswith('workspace_bounds [') and core.value.describe(WallNames()) in reason
    if core.value.wall is not None:
        assert '(workspace_bounds[%d])' % core.value.wall.index in reason, reason
    assert 'for dimension 2 (x_min, x_max, y_min, y_max)' in reason


@pytest.mark.parametrize('table, values, parameters, index', [
    (PLANNER, {'robot_names': ['a', 'a b']}, ('robot_names',), 1),
    (PLANNER, {'obstacle_radius': [0.1, 1e-300]}, ('obstacle_radius',), 1),
    (PLANNER, {'robot_radius': 1e-200}, ('robot_radius',), None),
    (PLANNER, {'robot_names': ['a'], 'robot_count': 2}, ('robot_count', 'robot_names'), None),
    (PLANNER, {'workspace_bounds': [0.0, 1.0, 0.0]}, ('workspace_bounds', 'dimension'), None),
    (PLANNER, {'nonsense': 1}, ('nonsense',), None),
    (EXECUTOR, {'slow_fraction': 0.7}, ('slow_fraction', 'hold_fraction'), None),
    (EXECUTOR, {'drive': ['holonomic', 'tank']}, ('drive',), 1),
    (FLEET_SIM, {'robot_names': ['a'], 'initial_positions': [0.0] * 3,
                 'muted_robots': ['a', 'b']}, ('muted_robots', 'robot_names'), 1),
    (FLEET_SIM, {'robot_names': ['a'], 'initial_positions': [0.0] * 3,
                 'speed_factors': [11.0]}, ('speed_factors',), 0),
])
def test_a_refused_value_carries_its_parameters_and_element(table, values, parameters, index):
    """The culprits as data: the parameter refused first, any it does not fit, the element."""
    with pytest.raises(InvalidParameter) as refused:
        table.settings(values)
    assert (refused.value.parameters, refused.value.index) == (parameters, index)


@pytest.mark.parametrize('values, parameters, items', [
    ({'max_acceleration': [1.0, 0.5, 2.0]}, ('max_acceleration', 'robot_names'), 'robots'),
    ({'obstacles': [0.0] * 6, 'obstacle_radius': [1.0] * 3}, ('obstacle_radius', 'obstacles'),
     'obstacles'),
])
def test_a_count_that_fits_neither_all_nor_each_carries_its_counts(values, parameters, items):
    """An InvalidParameter naming both parameters; the WrongCount with its counts the cause."""
    with pytest.raises(InvalidParameter) as refused:
        FLEET_SIM.settings({'robot_names': ['a', 'b'], 'initial_positions': [0.0] * 6,
                            **values})
    assert refused.value.parameters == parameters
    cause = refused.value.__cause__
    assert isinstance(cause, WrongCount)
    assert (cause.name, cause.given, cause.expected, cause.items) == (parameters[0], 3, 2, items)


def test_workspace_bounds_become_the_cores_box_for_the_dimension():
    """Empty: no walls; 4 values in the plane, 6 in 3-D, each axis [min, max]."""
    assert PLANNER.settings({}).core_bounds is None
    planar = PLANNER.settings({'workspace_bounds': [-1, 2, 0, 3.5]}).core_bounds
    assert planar.tolist() == [[-1.0, 2.0], [0.0, 3.5]]
    spatial = PLANNER.settings({'dimension': 3, 'workspace_bounds': [0, 1, 0, 2, -1, 0]})
    assert spatial.core_bounds.tolist() == [[0.0, 1.0], [0.0, 2.0], [-1.0, 0.0]]
    with pytest.raises(ValueError, match=r'\(x_min, x_max, y_min, y_max, z_min, z_max\)'):
        PLANNER.settings({'dimension': 3, 'workspace_bounds': [0, 1, 0, 2]})


def test_parameter_files(tmp_path):
    values = load_parameter_file(os.path.join(REPO_ROOT, 'config', 'default_scenario.yaml'),
                                 PLANNER)
    settings = PLANNER.settings(values)
    assert settings.robot_count == 4 and len(settings.obstacles) == 9
    path = tmp_path / 'p.yaml'
    path.write_text('/**:\n  ros__parameters: {variant: paper}\n'
                    'other_node:\n  ros__parameters: {variant: spread}\n'
                    '/fleet/planner_node:\n  ros__parameters: {max_speed: 2}\n')
    assert load_parameter_file(str(path), PLANNER) == {'variant': 'paper', 'max_speed': 2}
    # what planner_node starts with: a shared section with rclpy's and other nodes'
    # parameters (refused as unknown before), while its own section's typo is one
    path.write_text('/**:\n  ros__parameters: {use_sim_time: false, speed_limit: 1.0, '
                    'frame_id: odom}\n'
                    'planner_node:\n  ros__parameters: {use_sim_time: false, max_sped: 2}\n')
    values = load_parameter_file(str(path), PLANNER)
    assert values == {'frame_id': 'odom', 'max_sped': 2}
    with pytest.raises(ValueError, match="unknown parameter 'max_sped'"):
        PLANNER.settings(values)
    path.write_text('planer_node:\n  ros__parameters: {max_speed: 2}\n')
    with pytest.raises(ValueError, match='no section applies to planner_node'):
        load_parameter_file(str(path), PLANNER)
    path.write_text('- not a mapping\n')
    with pytest.raises(ValueError):
        load_parameter_file(str(path), PLANNER)
    # a misspelt ros__parameters beside a /** section: refused, as rcl refuses the file (read
    # as a namespace, it was ignored and the shared values alone taken)
    path.write_text('/**:\n  ros__parameters: {max_speed: 1.0}\n'
                    'planner_node:\n  ros_parameters: {max_speed: 2.0}\n')
    with pytest.raises(ValueError, match="'planner_node/ros_parameters' has no ros__param"):
        load_parameter_file(str(path), PLANNER)


def test_a_nodes_parameter_files_are_checked_together(tmp_path):
    """One of several files may be other nodes' alone; none of them the node's is refused."""
    own, others = tmp_path / 'own.yaml', tmp_path / 'others.yaml'
    own.write_text('/**/planner_node:\n  ros__parameters: {max_speed: 2.0}\n')
    others.write_text('/**/plan_executor:\n  ros__parameters: {gain: 1.0}\n')
    PLANNER.check_files(['planner_node', '--ros-args', '--params-file', str(own),
                         '--params-file', str(others)])
    with pytest.raises(InvalidParameterFile, match='no section applies to planner_node') as no:
        PLANNER.check_files(['--ros-args', '--params-file', str(others)])
    assert (no.value.paths, no.value.parameter) == ((str(others),), None)
    typo = tmp_path / 'typo.yaml'
    typo.write_text('planner_node:\n  ros__parameters: {max_sped: 2.0}\n')
    with pytest.raises(InvalidParameterFile) as unknown:
        PLANNER.check_files(['--ros-args', '--params-file', str(own), '--params-file', str(typo)])
    assert (unknown.value.paths, unknown.value.parameter) == ((str(typo),), 'max_sped')
    # renamed, its sections carry the new name: not checked
    for rename in ('__node:=fleet_planner', 'planner_node:__node:=fleet_planner'):
        PLANNER.check_files(['--ros-args', '-r', rename, '--params-file', str(others)])
    # rcl's nested form is read as the name it spells: its values (as the node takes
    # them in that namespace), its typos, and other nodes' sections alone refused
    nested = tmp_path / 'nested.yaml'
    in_fleet = ['--ros-args', '-r', '__ns:=/fleet', '--params-file', str(nested)]
    nested.write_text('fleet:\n  planner_node:\n    ros__parameters: {max_speed: 2.0}\n')
    PLANNER.check_files(in_fleet)
    assert load_parameter_file(str(nested), PLANNER) == {'max_speed': 2.0}
    nested.write_text('fleet:\n  planner_node:\n    ros__parameters: {max_sped: 2.0}\n')
    with pytest.raises(InvalidParameterFile, match="unknown parameter 'max_sped'"):
        PLANNER.check_files(in_fleet)
    nested.write_text('fleet:\n  plan_executor:\n    ros__parameters: {gain: 1.0}\n'
                      '  "**":\n    ros__parameters: {max_speed: 3.0, gain: 1.0}\n')
    assert load_parameter_file(str(nested), PLANNER) == {'max_speed': 3.0}
    nested.write_text('fleet:\n  plan_executor:\n    ros__parameters: {gain: 1.0}\n')
    with pytest.raises(InvalidParameterFile, match='no section applies to planner_node'):
        PLANNER.check_files(in_fleet)
    # sections are matched against the node's full name as rcl matches them: a node in
    # / or /robots started on its defaults from a section for another namespace, and
    # /* (every node in /) was refused
    for section, namespace, applies in (('/other/planner_node', '/', False),
                                        ('planner_node', '/robots', False),
                                        ('fleet: {planner_node: ', '/', False),
                                        ('/robots/**', '/', False),
                                        ('/robots/**', '/robots', True),
                                        ('/*', '/', True), ('/*', '/robots', False),
                                        ('/**/planner_node', '/a/b', True)):
        if section.endswith(': '):
            nested.write_text(section + '{ros__parameters: {max_speed: 2.0}}}\n')
        else:
            nested.write_text('%s:\n  ros__parameters: {max_speed: 2.0}\n' % section)
        arguments = ['--ros-args', '-r', '__ns:=' + namespace, '--params-file', str(nested)]
        if applies:
            PLANNER.check_files(arguments)
        else:
            with pytest.raises(InvalidParameterFile, match='in namespace %s' % namespace):
                PLANNER.check_files(arguments)


@pytest.mark.parametrize('table, values, words', [
    (EXECUTOR, {'mode': 'torque'}, 'mode must be one of velocity, reference'),
    (EXECUTOR, {'shared_clock': 'yes'}, 'shared_clock'),
    (EXECUTOR, {'slow_fraction': 0.7}, 'below hold_fraction'),
    (EXECUTOR, {'gain': -1.0}, r'gain must be in \[0.0, 100.0\]'),
    (FLEET_SIM, {'robot_names': ['a'], 'initial_positions': [0.0, 0.0]}, '3 per robot'),
    (FLEET_SIM, {'robot_names': ['a', 'a'], 'initial_positions': [0.0] * 6}, 'unique'),
    (FLEET_SIM, {'muted_robots': ['b']}, 'not among robot_names'),
    (FLEET_SIM, {'robot_names': ['a'], 'initial_positions': [0.0] * 3,
                 'speed_factors': [11.0]}, r'outside \[0, 10\]'),
    (FLEET_SIM, {'robot_names': ['a'], 'initial_positions': [0.0] * 3,
                 'latencies': [0.1, 0.2]}, '2 values for 1 robots'),
    (FLEET_SIM, {'obstacles': [0.0] * 6, 'obstacle_radius': [1.0] * 3}, 'one per obstacle'),
    (FLEET_SIM, {'frame_id': ''}, 'frame_id must not be empty'),
    (EXECUTOR, {'drive': ['tank']}, r"drive\[0\] = 'tank' is not one of holonomic"),
    (EXECUTOR, {'drive': []}, 'one value or one per robot'),
    (EXECUTOR, {'final_heading': 'any'}, 'final_heading'),
    (FLEET_SIM, {'robot_names': ['a', 'b'], 'initial_positions': [0.0] * 6,
                 'drive': ['differential'] * 3}, 'drive has 3 values for 2 robots'),
])
def test_executor_and_simulator_validation_gives_reasons(table, values, words):
    with pytest.raises(ValueError, match=words):
        table.settings(values)


def test_shared_specs_are_one_object_in_every_table():
    """frame_id, obstacles and the radii: the same Spec (one check, one range) everywhere."""
    for name in ('frame_id', 'obstacles', 'robot_radius', 'obstacle_radius'):
        assert PLANNER.by_name[name] is FLEET_SIM.by_name[name], name
    assert PLANNER.by_name['frame_id'] is FRAME_ID


def test_read_only_parameters_are_the_ones_that_shape_the_node():
    """A descriptor marks read_only exactly where the spec does (one way to mark it)."""
    read_only = {table.node_name: {s.name for s in table.specs if s.descriptor().read_only}
                 for table in (PLANNER, EXECUTOR, FLEET_SIM)}
    assert read_only == {'planner_node': set(), 'plan_executor': {'control_rate'},
                         'fleet_sim': {'robot_names', 'initial_positions', 'rate', 'seed'}}


def test_simulator_settings_become_the_fleet_physics():
    settings = FLEET_SIM.settings({'robot_names': ['a', 'b'], 'initial_positions': [0.0] * 6,
                                   'obstacles': [1.0, 2.0, 0.0], 'obstacle_radius': [0.5],
                                   'robot_radius': 0.2, 'speed_factors': [1.0, 0.5]})
    fleet = settings.fleet()
    assert settings.initial.shape == (2, 3)
    assert fleet.bodies.robot_radius == 0.2
    assert fleet.bodies.obstacle_radii.tolist() == [0.5]
    assert fleet.speed_factors.tolist() == [1.0, 0.5] and fleet.latencies is None
    assert fleet.differential.tolist() == [False, False]
    differential = FLEET_SIM.settings({
        'robot_names': ['a', 'b'], 'initial_positions': [0.0] * 6,
        'drive': ['holonomic', 'differential'], 'yaw_rate_limit': 1.9,
        'max_acceleration': [1.0], 'max_yaw_acceleration': 4.0}).fleet()
    assert differential.differential.tolist() == [False, True]
    assert (differential.yaw_rate_limit, differential.max_yaw_acceleration) == (1.9, 4.0)
    assert differential.max_acceleration.tolist() == [1.0, 1.0]
    assert fleet.max_acceleration.tolist() == [0.0, 0.0]
    each = FLEET_SIM.settings({'robot_names': ['a', 'b'], 'initial_positions': [0.0] * 6,
                               'max_acceleration': [1.0, 0.5]}).fleet()
    assert each.max_acceleration.tolist() == [1.0, 0.5]
    with pytest.raises(ValueError, match='max_acceleration has 3 values for 2 robots'):
        FLEET_SIM.settings({'robot_names': ['a', 'b'], 'initial_positions': [0.0] * 6,
                            'max_acceleration': [1.0, 0.5, 2.0]})
    execution = EXECUTOR.settings({'drive': ['differential'], 'yaw_rate_limit': 1.9,
                                   'final_heading': 'none'}).execution
    assert execution.differential(3).tolist() == [True] * 3
    assert execution.yaw_rate_limit == 1.9 and not execution.final_heading
