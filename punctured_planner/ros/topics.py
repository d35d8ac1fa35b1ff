"""
The names of each robot's topics, relative to the node's namespace (msg_docs/topics.md).

Robot names are relative ROS names (the parameters' ros_names check), so
'<robot>/<topic>' is one too, resolved in the namespace of the node that uses it.
"""

# planner_node latches each robot's Path here.
PLAN = 'plan'
# A robot's pose and twist: the planner's current state, the executor's feedback.
ODOM = 'odom'
# The executor's commands to a robot, and the reference they track.
CMD_VEL = 'cmd_vel'
REFERENCE_POSE = 'reference_pose'
# Every topic a robot has.
ROBOT_TOPICS = (PLAN, ODOM, CMD_VEL, REFERENCE_POSE)


def robot_topic(robot: str, topic: str) -> str:
    """Return the topic of a robot, '<robot>/<topic>': 'robot_0/odom' for robot_0's ODOM."""
    return '%s/%s' % (robot, topic)
