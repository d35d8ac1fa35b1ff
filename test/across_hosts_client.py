"""
The fleet manager of test_across_hosts.py: plans, executes and reports, as a process.

Usage: ``python across_hosts_client.py NAMESPACE SCENARIO_JSON``. It runs inside the
control host's network namespace (the test process itself stays in the machine's own,
so it starts this one there with ``ip netns exec``) and talks to the nodes only through
their public names under NAMESPACE. The scenario is JSON: ``{"robot_names": [...],
"frame_id": ..., "goal": [[x, y, z], ...], "discovery_timeout": s, "call_timeout": s,
"goal_timeout": s}``.

It waits for ``plan_sequence``, ``execute_plan`` and every robot's odometry, plans
from the robots' current state to the goal, executes that plan, and prints one JSON
line: ``{"plan": {...}, "goal_refusals": [...], "result": {...}, "positions": [[x, y,
z], ...], "true_gap", "odometry": {"messages", "bytes"}, "commands": {"messages",
"bytes"}}``. Odometry and commands are counted as their serialized (CDR) payloads: the
odometry comes from the simulator on the other host, so every byte of it crossed the
link between the hosts.
When something does not come up in time it prints ``{"error": "..."}`` and exits 1.
"""

import json
import sys
import time

# Settling time after the goal's result, so that the last odometry is the final state.
SETTLE_SEC = 0.3
# Pause before asking again for a plan the executor has not heard of yet.
NO_PLAN_RETRY_SEC = 0.5


class Fleet:
    """The client node: the service and action clients and what it heard."""

    def __init__(self, namespace, names):
        """Create a Context, a node, the clients and the counting subscriptions."""
        import rclpy
        from rclpy.action import ActionClient
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import DurabilityPolicy
        from rclpy.qos import QoSProfile
        from rclpy.qos import ReliabilityPolicy

        from geometry_msgs.msg import Twist
        from nav_msgs.msg import Odometry
        from punctured_planner_interfaces.action import ExecutePlan
        from punctured_planner_interfaces.srv import PlanSequence
        from std_msgs.msg import Float64
        self.context = rclpy.context.Context()
        rclpy.init(context=self.context, args=[])
        self.node = rclpy.create_node('across_hosts_client', context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.names = list(names)
        self.odometry = {}
        self.counts = {'odometry': [0, 0], 'commands': [0, 0]}
        self.gap = []
        scoped = '%s/%%s' % namespace.rstrip('/')
        self.plan_sequence = self.node.create_client(PlanSequence, scoped % 'plan_sequence')
        self.action = ActionClient(self.node, ExecutePlan, scoped % 'execute_plan')
        for name in self.names:
            self.node.create_subscription(Odometry, scoped % (name + '/odom'),
                                          self._odometry(name), 10, raw=True)
            self.node.create_subscription(Twist, scoped % (name + '/cmd_vel'),
                                          self._counter('commands'), 10, raw=True)
        # the simulator's ~/min_gap is latched: reliable, transient local, depth 1
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.node.create_subscription(Float64, scoped % 'fleet_sim/min_gap',
                                      lambda msg: self.gap.append(msg.data), latched)

    def _counter(self, kind):
        def count(data):
            self.counts[kind][0] += 1
            self.counts[kind][1] += len(data)
        return count

    def _odometry(self, name):
        from nav_msgs.msg import Odometry
        from rclpy.serialization import deserialize_message
        count = self._counter('odometry')

        def callback(data):
            count(data)
            self.odometry[name] = deserialize_message(data, Odometry)
        return callback

    def spin_until(self, predicate, timeout_sec):
        """Spin until ``predicate()`` is true or the timeout; return whether it became true."""
        deadline = time.monotonic() + timeout_sec
        while not predicate():
            remaining = deadline - time.monotonic()
            if remaining <= 0:
                return False
            self.executor.spin_once(timeout_sec=min(remaining, 0.05))
        return True

    def positions(self):
        """Return every robot's latest odometry position, in robot order."""
        return [[o.pose.pose.position.x, o.pose.pose.position.y, o.pose.pose.position.z]
                for o in (self.odometry[name] for name in self.names)]

    def close(self):
        """Destroy the action client and the node, shut the Context down."""
        import rclpy
        self.action.destroy()
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


def seconds(duration):
    """Return a builtin_interfaces/Duration in seconds."""
    return duration.sec + duration.nanosec * 1e-9


def plan(fleet, goal, scenario):
    """
    Plan from the robots' current state to ``goal``; return the response or None.

    The planner's own odometry subscriptions may match later than ours: NO_ROBOT_STATE
    is asked again until the discovery timeout.
    """
    from geometry_msgs.msg import Pose
    from geometry_msgs.msg import PoseArray
    from punctured_planner_interfaces.srv import PlanSequence
    request = PlanSequence.Request(use_current_state=True)
    configuration = PoseArray()
    configuration.header.frame_id = scenario['frame_id']
    for x, y, z in goal:
        pose = Pose()
        pose.position.x, pose.position.y, pose.position.z = float(x), float(y), float(z)
        configuration.poses.append(pose)
    request.configurations = [configuration]
    deadline = time.monotonic() + scenario['discovery_timeout']
    while True:
        future = fleet.plan_sequence.call_async(request)
        if not fleet.spin_until(future.done, scenario['call_timeout']):
            fleet.plan_sequence.remove_pending_request(future)
            return None
        response = future.result()
        if (response.error_code != PlanSequence.Response.NO_ROBOT_STATE
                or time.monotonic() > deadline):
            return response
        fleet.spin_until(lambda: False, 0.2)


def execute(fleet, plan_id, scenario, refusals):
    """
    Execute plan ``plan_id``; return its result, or the reason there is none.

    The executor hears of a plan on the ``plan`` topic, which may match or arrive after
    the response that named it (measured: "no plan received yet" in 2 of 24 runs):
    NO_PLAN is asked again until the call timeout, each refusal kept in ``refusals``.
    """
    from punctured_planner_interfaces.action import ExecutePlan
    deadline = time.monotonic() + scenario['call_timeout']
    while True:
        sent = fleet.action.send_goal_async(ExecutePlan.Goal(plan_id=plan_id))
        if not fleet.spin_until(sent.done, scenario['call_timeout']):
            return 'execute_plan did not answer the goal'
        handle = sent.result()
        if not handle.accepted:
            return 'execute_plan refused the goal'
        result_future = handle.get_result_async()
        if not fleet.spin_until(result_future.done, scenario['goal_timeout']):
            return 'no result within %.0f s' % scenario['goal_timeout']
        result = result_future.result().result
        if result.error_code != ExecutePlan.Result.NO_PLAN or time.monotonic() > deadline:
            return result
        refusals.append(result.error_msg)
        fleet.spin_until(lambda: False, NO_PLAN_RETRY_SEC)


def run(fleet, scenario):
    """Discover, plan, execute; return the report (a JSON-ready dict)."""
    wait = scenario['discovery_timeout']
    if not fleet.plan_sequence.wait_for_service(timeout_sec=wait):
        return {'error': 'plan_sequence not discovered within %.0f s' % wait}
    if not fleet.action.wait_for_server(timeout_sec=wait):
        return {'error': 'execute_plan not discovered within %.0f s' % wait}
    if not fleet.spin_until(lambda: len(fleet.odometry) == len(fleet.names), wait):
        return {'error': 'odometry of %s not heard within %.0f s'
                % (sorted(set(fleet.names) - set(fleet.odometry)), wait)}
    response = plan(fleet, scenario['goal'], scenario)
    if response is None:
        return {'error': 'no answer from plan_sequence within %.0f s'
                % scenario['call_timeout']}
    report = {'plan': {'error_code': response.error_code, 'error_msg': response.error_msg,
                       'plan_id': response.plan_id, 'min_gap': response.min_gap,
                       'tracking_tolerance': response.tracking_tolerance,
                       'duration': seconds(response.duration)},
              'goal_refusals': []}
    if response.error_code != 0:
        return report
    result = execute(fleet, response.plan_id, scenario, report['goal_refusals'])
    if isinstance(result, str):
        return dict(report, error=result)
    fleet.spin_until(lambda: False, SETTLE_SEC)
    report['result'] = {'error_code': result.error_code, 'error_msg': result.error_msg,
                        'executed_duration': seconds(result.executed_duration),
                        'max_tracking_errors': list(result.max_tracking_errors)}
    report['positions'] = fleet.positions()
    report['true_gap'] = fleet.gap[-1] if fleet.gap else None
    report.update({kind: {'messages': count, 'bytes': size}
                   for kind, (count, size) in fleet.counts.items()})
    return report


def main(argv):
    """Run the scenario and print its report; return 0, or 1 when something was missing."""
    namespace, scenario = argv[1], json.loads(argv[2])
    fleet = Fleet(namespace, scenario['robot_names'])
    try:
        report = run(fleet, scenario)
    finally:
        fleet.close()
    print(json.dumps(report), flush=True)
    return 1 if 'error' in report else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
