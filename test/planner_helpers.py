"""
Helpers for the planner node tests: requests, an in-process node, latched subscribers.

The in-process node runs in its own rclpy Context, spun in background threads by
the ExecutorThreads ``main()`` runs it with; the test talks to it
over real DDS from the ``ros_client`` fixture's own Context.
"""

import copy
import itertools
import os
import time

import numpy as np
import pytest

OBSTACLES = [[-2.0, 0.5, 0.0], [0.0, -0.5, 0.0], [2.5, 0.0, 0.0]]
# Four robots through three configurations, clear of the obstacles (z = 0).
CONFIGURATIONS = [
    [[-3.0, -2.0, 0.0], [-1.0, -2.5, 0.0], [1.0, -2.0, 0.0], [3.0, -2.5, 0.0]],
    [[-2.0, -1.5, 0.0], [0.0, 1.5, 0.0], [1.5, -1.5, 0.0], [3.5, 1.0, 0.0]],
    [[3.0, 3.0, 0.0], [1.0, 3.5, 0.0], [-1.0, 3.0, 0.0], [-3.0, 3.5, 0.0]],
]
_counter = itertools.count(1)


def flat(points):
    """Return points (r, 3) as the flat list of the obstacles parameter."""
    return [float(v) for point in points for v in point]


def pose_array(points, frame_id='map', orientations=None):
    """Return a geometry_msgs/PoseArray of points (k, 3), optional quaternions (k, 4)."""
    from geometry_msgs.msg import Pose
    from geometry_msgs.msg import PoseArray
    msg = PoseArray()
    msg.header.frame_id = frame_id
    for i, point in enumerate(points):
        pose = Pose()
        pose.position.x, pose.position.y, pose.position.z = (float(v) for v in point)
        if orientations is not None:
            q = orientations[i]
            pose.orientation.x, pose.orientation.y = float(q[0]), float(q[1])
            pose.orientation.z, pose.orientation.w = float(q[2]), float(q[3])
        msg.poses.append(pose)
    return msg


def make_request(configurations=CONFIGURATIONS, frame_id='map', **fields):
    """Return a PlanSequence request through configurations (each (k, 3))."""
    from punctured_planner_interfaces.srv import PlanSequence
    request = PlanSequence.Request()
    request.configurations = [pose_array(c, frame_id) for c in configurations]
    for name, value in fields.items():
        setattr(request, name, value)
    return request


def unique_namespace(tag='inproc'):
    """Return a namespace no other test (or test run) uses."""
    return '/pp_%s_%d_%d' % (tag, os.getpid(), next(_counter))


class InProcessPlanner:
    """A PlannerNode in its own Context, spun in threads as ``main()`` spins it."""

    def __init__(self, namespace=None, **parameters):
        """Start the node with parameter overrides (name=value)."""
        import rclpy
        from rclpy.parameter import Parameter

        from punctured_planner.nodes.planner import planner_nodes
        from punctured_planner.ros.runtime import ExecutorThreads
        self.namespace = namespace or unique_namespace()
        self.context = rclpy.context.Context()
        rclpy.init(context=self.context, args=[])
        overrides = [Parameter(name, value=value) for name, value in parameters.items()]
        group = planner_nodes(context=self.context, namespace=self.namespace,
                              parameter_overrides=overrides)
        self.node = group.nodes[0]
        self.before_teardown = group.before_teardown
        self.threads = ExecutorThreads(group.nodes, context=self.context,
                                       on_stop=group.on_stop)
        self.threads.start()

    def name(self, relative):
        """Return the absolute name of one of the node's topics or services."""
        return '%s/%s' % (self.namespace, relative)

    def set_parameters(self, **parameters):
        """Set parameters through the node's callbacks; return the SetParametersResults."""
        from rclpy.parameter import Parameter
        return self.node.set_parameters([Parameter(name, value=value)
                                         for name, value in parameters.items()])

    def close(self):
        """Stop the executor threads, destroy the nodes, shut the Context down."""
        import rclpy
        closed = self.threads.close(before_teardown=self.before_teardown)
        assert closed, 'callbacks still running: %s' % self.threads.stuck()
        rclpy.try_shutdown(context=self.context)


class Latest:
    """Keep the last message of a transient-local subscription (latched topics)."""

    def __init__(self, node, msg_type, topic):
        """Subscribe to topic with the node's latched QoS."""
        from punctured_planner.ros.qos import LATCHED
        self.messages = []
        self.subscription = node.create_subscription(msg_type, topic, self.messages.append,
                                                     LATCHED)

    @property
    def last(self):
        """Return the last message received, or None."""
        return self.messages[-1] if self.messages else None


def wait_for(predicate, timeout_sec=10.0, what='condition'):
    """Poll predicate (no spinning) until it is true; fail the test after timeout."""
    deadline = time.monotonic() + timeout_sec
    while not predicate():
        if time.monotonic() > deadline:
            pytest.fail('timed out waiting for %s' % what)
        time.sleep(0.01)


def path_positions(path):
    """Return the positions of a nav_msgs/Path as an (M, 3) array."""
    return np.array([(p.pose.position.x, p.pose.position.y, p.pose.position.z)
                     for p in path.poses], dtype=float).reshape(-1, 3)


def path_stamps_ns(path):
    """Return the stamps of a nav_msgs/Path's poses as an (M,) integer array (ns)."""
    from punctured_planner.ros.conversions import stamp_to_ns
    return np.array([stamp_to_ns(p.header.stamp) for p in path.poses], dtype=np.int64)


def path_array(path):
    """Return (positions (M, 3), stamps_ns (M,)) of a nav_msgs/Path."""
    return path_positions(path), path_stamps_ns(path)


def scenario_plan(configurations=CONFIGURATIONS):
    """Return the core's plan with the bundled scenario's parameters (its radii, variant)."""
    from conftest import REPO_ROOT
    from punctured_planner.ros.parameters import load_parameter_file
    from punctured_planner.ros.settings import PLANNER
    settings = PLANNER.settings(load_parameter_file(
        os.path.join(REPO_ROOT, 'config', 'default_scenario.yaml'), PLANNER))
    return core_plan(configurations, variant=settings.core_variant,
                     lane_spacing=settings.lane_spacing, min_spacing=settings.min_spacing,
                     required_clearance=settings.required_clearance,
                     robot_radius=settings.robot_radius,
                     obstacle_radius=settings.core_obstacle_radius)


def core_plan(configurations=CONFIGURATIONS, obstacles=OBSTACLES, dimension=2, **options):
    """Return the core's plan for the same input the node gets (spread by default)."""
    from punctured_planner.core import plan
    from punctured_planner.core import Workspace
    options.setdefault('variant', 'spread')
    workspace = Workspace(np.asarray(obstacles, dtype=float)[:, :dimension].reshape(
        -1, dimension), dimension=dimension, **options)
    return plan(workspace, np.asarray(configurations, dtype=float)[..., :dimension])


def faulty_plan(fault, **fields):
    """
    Return the Plan message of a request with one fault (its id 3; 'none': no fault).

    fields are the request's (samples_per_leg for a large plan).
    """
    from punctured_planner.cli import offline_plan
    from punctured_planner.ros import conversions
    from punctured_planner.ros.settings import PLANNER
    settings = PLANNER.settings({'obstacles': [-2.0, 0.5, 0.0, 0.0, -0.5, 0.0,
                                               2.5, 0.0, 0.0]})
    outcome = offline_plan(make_request(max_speed=0.5, **fields), settings, now_ns=10 ** 18)
    outcome.plan_id = 3
    message = conversions.plan_message(outcome, settings)
    if fault == 'paths':
        message.paths = message.paths[:3]
    elif fault == 'name':
        message.robot_names = ['1bad'] + message.robot_names[1:]
    elif fault == 'long name':  # a valid relative name, too long a topic in most namespaces
        message.robot_names = ['r' * 240] + message.robot_names[1:]
    elif fault == 'twice':
        message.robot_names = ['robot_0'] * 4
    elif fault == 'nan':
        pose = message.paths[2].poses[1]
        pose.pose.position.x = float('nan')
    elif fault == 'back':
        stamps = [p.header for p in message.paths[0].poses]
        stamps[2].stamp, stamps[3].stamp = stamps[3].stamp, stamps[2].stamp
    elif fault == 'radii':
        message.obstacle_radii = [0.1] * 2
    elif fault == 'one pose':
        for path in message.paths:
            path.poses = path.poses[:1]
    elif fault == 'tolerance':
        message.tracking_tolerance = float('inf')
    elif fault == 'acceleration':
        message.max_acceleration = float('inf')
    elif fault == 'frame':  # the paths share one Header: robot_1's a copy of its own
        header = copy.deepcopy(message.paths[1].header)
        header.frame_id = 'odom'
        message.paths[1].header = header
    return message
