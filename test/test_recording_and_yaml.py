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
