"""
A load-test client process: calls ``plan_sequence`` COUNT times and reports every answer.

Usage: ``python reliability_client.py SERVICE COUNT REQUEST_JSON``. The request is
JSON: ``{"configurations": [[frame_id, [[x, y, z], ...]], ...],
"use_current_state": bool, "max_speed": float, "samples_per_leg": int}``, plus
optional ``"call_timeout"`` (seconds per call, default 20), ``"retry_lost"``
(call again after a lost call until COUNT answers came, within 90 s) and
``"client_qos"``: ``"project"`` (default, punctured_planner.ros.qos.CLIENT_QOS)
or ``"rclpy"`` (rclpy's default service QoS, depth 10; bench/load_stress.py
compares the two).

Each process has its own rclpy Context (a separate DDS participant). It prints one
JSON line per call: ``{"i", "error_code", "error_msg", "domain_index",
"projection_counts", "min_clearance", "digest", "seconds"}`` where digest is the
SHA-1 of the paths' positions as a (k, M, 3) float64 array, or ``{"i", "lost": true}``
when no answer came within the timeout. The last line is ``{"done": true}``.
"""

import hashlib
import json
import sys
import time

import numpy as np

# The load scenario of test/test_reliability.py and bench/load_stress.py: obstacles
# and robot states alternate between two sets while the clients call.
OBSTACLES = ((-2.0, 0.5, 0.0), (0.0, -0.5, 0.0), (2.5, 0.0, 0.0))
OTHER_OBSTACLES = ((-1.25, 1.0, 0.0), (0.75, -1.0, 0.0), (3.25, 0.5, 0.0))
CONFIGURATIONS = (
    ((-3.0, -2.0, 0.0), (-1.0, -2.5, 0.0), (1.0, -2.0, 0.0), (3.0, -2.5, 0.0)),
    ((-2.0, -1.5, 0.0), (0.0, 1.5, 0.0), (1.5, -1.5, 0.0), (3.5, 1.0, 0.0)),
    ((3.0, 3.0, 0.0), (1.0, 3.5, 0.0), (-1.0, 3.0, 0.0), (-3.0, 3.5, 0.0)),
)
STATES = (((-3.5, -3.0, 0.0), (-1.5, -3.5, 0.0), (1.5, -3.0, 0.0), (3.5, -3.5, 0.0)),
          ((-3.0, 2.0, 0.0), (-1.0, 2.5, 0.0), (1.0, 2.0, 0.0), (3.0, 2.5, 0.0)))
CALL_TIMEOUT_SEC = 20.0
DISCOVERY_TIMEOUT_SEC = 60.0
RETRY_DEADLINE_SEC = 90.0


def build_request(spec):
    """Return a PlanSequence request from its JSON description."""
    from geometry_msgs.msg import Pose
    from geometry_msgs.msg import PoseArray
    from punctured_planner_interfaces.srv import PlanSequence
    request = PlanSequence.Request()
    for frame_id, points in spec['configurations']:
        msg = PoseArray()
        msg.header.frame_id = frame_id
        for x, y, z in points:
            pose = Pose()
            pose.position.x, pose.position.y, pose.position.z = float(x), float(y), float(z)
            msg.poses.append(pose)
        request.configurations.append(msg)
    request.use_current_state = bool(spec.get('use_current_state', False))
    request.max_speed = float(spec.get('max_speed', 0.0))
    request.samples_per_leg = int(spec.get('samples_per_leg', -1))
    return request


def path_digest(paths):
    """Return the SHA-1 of the paths' positions, a (k, M, 3) float64 array."""
    positions = np.array([[(p.pose.position.x, p.pose.position.y, p.pose.position.z)
                           for p in path.poses] for path in paths], dtype=float)
    return hashlib.sha1(positions.tobytes()).hexdigest()


def summary(index, response, seconds):
    """Return the JSON-ready record of one answer."""
    return {'i': index, 'error_code': int(response.error_code),
            'error_msg': response.error_msg, 'domain_index': int(response.domain_index),
            'projection_counts': [int(c) for c in response.projection_counts],
            'min_clearance': float(response.min_clearance),
            'digest': path_digest(response.paths), 'seconds': seconds}


def main(argv):
    """Call the service COUNT times, one JSON line per answer; return 0, or 1 on any loss."""
    service, count, spec = argv[1], int(argv[2]), json.loads(argv[3])
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from punctured_planner.ros.qos import CLIENT_QOS
    from punctured_planner_interfaces.srv import PlanSequence
    from rclpy.qos import qos_profile_services_default
    qos = {'project': CLIENT_QOS, 'rclpy': qos_profile_services_default}[
        spec.get('client_qos', 'project')]
    context = rclpy.context.Context()
    rclpy.init(context=context, args=[])
    node = rclpy.create_node('reliability_client', context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    client = node.create_client(PlanSequence, service, qos_profile=qos)
    lost = 0
    try:
        if not client.wait_for_service(timeout_sec=DISCOVERY_TIMEOUT_SEC):
            print(json.dumps({'error': 'service %s not discovered' % service}), flush=True)
            return 1
        request = build_request(spec)
        timeout = float(spec.get('call_timeout', CALL_TIMEOUT_SEC))
        retry_until = time.monotonic() + RETRY_DEADLINE_SEC
        index = answered = 0
        while answered < count:
            started = time.perf_counter()
            future = client.call_async(request)
            deadline = time.monotonic() + timeout
            while not future.done() and time.monotonic() < deadline:
                executor.spin_once(timeout_sec=0.05)
            if future.done():
                record = summary(index, future.result(), time.perf_counter() - started)
                answered += 1
            else:
                client.remove_pending_request(future)
                lost += 1
                record = {'i': index, 'lost': True}
                if not spec.get('retry_lost') or time.monotonic() > retry_until:
                    answered += 1
            print(json.dumps(record), flush=True)
            index += 1
        print(json.dumps({'done': True}), flush=True)
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    return 1 if lost else 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
