"""
Answer first, publish after (msg_docs/topics.md): the reply, then Paths, domain index, Plan.

An in-process planner node over real DDS. The order is recorded where it
happens, inside the node's process: the real send and the real publishers are
wrapped by recorders that call through. A publication that fails after the
reply leaves the caller's success as it was, is logged (on ``/rosout``) and
retracts the robots' paths.
"""

from planner_helpers import InProcessPlanner
from planner_helpers import Latest
from planner_helpers import make_request
import pytest

pytestmark = pytest.mark.ros

ROBOTS = 4


@pytest.fixture
def node():
    """Yield an in-process planner of four robots; closed after the test."""
    started = InProcessPlanner(robot_count=ROBOTS)
    yield started
    started.close()


def plan_client(ros_client, node):
    """Return a PlanSequence client of the node, once the service is discovered."""
    from punctured_planner_interfaces.srv import PlanSequence
    client = ros_client.node.create_client(PlanSequence, node.name('plan_sequence'))
    ros_client.wait_for_service(client)
    return client


def test_the_reply_goes_out_before_paths_index_and_plan(node, ros_client, monkeypatch):
    from punctured_planner_interfaces.msg import Plan
    from rclpy.publisher import Publisher
    events = []
    send = node.node._send

    def recorded_send(response, header):
        events.append('reply')
        send(response, header)

    publish = Publisher.publish

    def recorded_publish(publisher, message):
        if publisher.topic_name.startswith(node.namespace + '/'):
            events.append(publisher.topic_name[len(node.namespace) + 1:])
        publish(publisher, message)

    monkeypatch.setattr(node.node, '_send', recorded_send)
    monkeypatch.setattr(Publisher, 'publish', recorded_publish)
    plan = Latest(ros_client.node, Plan, node.name('plan'))
    client = plan_client(ros_client, node)
    for expected_id in (1, 2):
        del events[:]
        response = ros_client.call(client, make_request())
        assert response.error_code == 0, response.error_msg
        assert response.plan_id == expected_id
        assert ros_client.spin_until(
            lambda: plan.last is not None and plan.last.plan_id == expected_id, 10)
        paths = ['robot_%d/plan' % i for i in range(ROBOTS)]
        assert events == ['reply'] + paths + ['plan_markers', 'domain_index', 'plan']


def test_a_publication_failing_after_the_reply_is_logged(node, ros_client, monkeypatch):
    from nav_msgs.msg import Path
    from punctured_planner.ros import publications
    from punctured_planner.ros.qos import LATCHED
    from rcl_interfaces.msg import Log

    def broken(outcome, settings):
        raise RuntimeError('injected publishing fault')

    logged = []
    ros_client.node.create_subscription(Log, '/rosout', logged.append, LATCHED)
    path = Latest(ros_client.node, Path, node.name('robot_0/plan'))
    client = plan_client(ros_client, node)
    monkeypatch.setattr(publications, 'plan_messages', broken)
    response = ros_client.call(client, make_request())
    # The caller keeps its success: the reply went out before the publication failed.
    assert response.error_code == 0 and response.plan_id == 1, response.error_msg
    assert ros_client.spin_until(lambda: any(
        'plan 1 answered, but publishing it failed' in entry.msg
        and 'injected publishing fault' in entry.msg for entry in logged), 10), \
        [entry.msg for entry in logged]
    # No robot keeps a partial plan: its path is retracted (latched, empty).
    assert ros_client.spin_until(lambda: path.last is not None, 10)
    assert len(path.last.poses) == 0
