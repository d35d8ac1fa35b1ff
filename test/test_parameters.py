"""Parameter table, validation and parameter files, without a node."""

import math
import os

from conftest import REPO_ROOT
from punctured_planner.parameters import load_parameter_file
from punctured_planner.parameters import PARAMETERS
from punctured_planner.parameters import Settings
from punctured_planner.parameters import settings_from_values
import pytest


def test_defaults_are_the_table_defaults():
    assert settings_from_values({}) == Settings()
    assert {spec.name for spec in PARAMETERS} == set(Settings.__dataclass_fields__)
    for spec in PARAMETERS:
        assert getattr(Settings(), spec.name) == (tuple(spec.default)
                                                  if isinstance(spec.default, list)
                                                  else spec.default), spec.name
    good = settings_from_values({'plane_z': 1, 'obstacles': [0, 0, 0], 'robot_names': None})
    assert good.plane_z == 1.0 and good.obstacles == (0.0, 0.0, 0.0)


@pytest.mark.parametrize('values, words', [
    ({'dimension': 4}, 'dimension'), ({'variant': 'x'}, 'variant'),
    ({'obstacles': [1.0]}, 'multiple of 3'), ({'obstacles': [math.nan] * 3}, 'finite'),
    ({'robot_names': ['a', 'a']}, 'unique'), ({'robot_names': ['a b']}, 'ROS name'),
    ({'robot_names': ['a'], 'robot_count': 2}, 'robot_count'),
    ({'frame_id': ''}, 'frame_id'), ({'lane_spacing': 0.0}, 'lane_spacing'),
    ({'max_speed': True}, 'max_speed'), ({'dimension': 2.0}, 'integer'),
    ({'nonsense': 1}, 'unknown'), ({'robot_count': 5, 'max_robots': 4}, 'max_robots'),
    ({'refine': 1}, 'refine must be true or false'),
])
def test_settings_validation_gives_reasons(values, words):
    with pytest.raises(ValueError, match=words):
        settings_from_values(values)


def test_parameter_files(tmp_path):
    values = load_parameter_file(os.path.join(REPO_ROOT, 'config', 'default_scenario.yaml'))
    settings = settings_from_values(values)
    assert settings.robot_count == 4 and len(settings.obstacles) == 9
    path = tmp_path / 'p.yaml'
    path.write_text('/**:\n  ros__parameters: {variant: paper}\n'
                    'other_node:\n  ros__parameters: {variant: spread}\n'
                    '/fleet/planner_node:\n  ros__parameters: {max_speed: 2}\n')
    assert load_parameter_file(str(path)) == {'variant': 'paper', 'max_speed': 2}
    path.write_text('- not a mapping\n')
    with pytest.raises(ValueError):
        load_parameter_file(str(path))
