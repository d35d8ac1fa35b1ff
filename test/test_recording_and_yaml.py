"""The MCAP recording's message definitions and the request YAML, without DDS."""

from punctured_planner.ros.recording import message_definition
import pytest


def test_full_definition_text_for_recordings():
    text = message_definition('nav_msgs/msg/Path')
    assert text.startswith('# An array of poses')
    assert text.count('=' * 80 + '\nMSG: ') == 6
    for name in ('std_msgs/msg/Header', 'builtin_interfaces/msg/Time',
                 'geometry_msgs/msg/PoseStamped', 'geometry_msgs/msg/Pose',
                 'geometry_msgs/msg/Point', 'geometry_msgs/msg/Quaternion'):
        assert ('MSG: %s\n' % name) in text
    with pytest.raises(LookupError):
        message_definition('nav_msgs/msg/NoSuchType')


def test_request_yaml_integers_out_of_range_are_refused():
    """An int32 field given 99999999999 is a clear error, not a silently wrapped value."""
    from punctured_planner.ros.msg_dict import fill_message
    from punctured_planner_interfaces.srv import PlanSequence
    with pytest.raises(ValueError, match='outside the range of int32'):
        fill_message(PlanSequence.Request(), {'samples_per_leg': 99999999999})
    request = fill_message(PlanSequence.Request(), {'samples_per_leg': -1})
    assert request.samples_per_leg == -1


def test_request_yaml_numbers_in_exponent_form_are_numbers():
    """
    1e-05, as JSON writes it, is a string to PyYAML (YAML 1.1): taken as ros2 cli takes it.

    Before, 'expected a number, got '1e-05'' and exit 2; words stay refused.
    """
    import yaml

    from punctured_planner.ros.msg_dict import fill_message
    from punctured_planner_interfaces.srv import PlanSequence
    data = yaml.safe_load('{max_speed: 1e-05, configurations: [{poses: [{position: '
                          '{x: 3e0, y: -2.5E+1, z: .5e1}}]}]}')
    request = fill_message(PlanSequence.Request(), data)
    assert request.max_speed == 1e-05
    assert [request.configurations[0].poses[0].position.x,
            request.configurations[0].poses[0].position.y,
            request.configurations[0].poses[0].position.z] == [3.0, -25.0, 5.0]
    with pytest.raises(ValueError, match="expected a number, got 'fast'"):
        fill_message(PlanSequence.Request(), {'max_speed': 'fast'})
