"""
No reply or request of ``plan_sequence`` is dropped by a DDS history (issue 21).

rmw_fastrtps delivers every reply of a service to every client of it; each
client's reader keeps the replies it has not taken in a KEEP_LAST history
(doc/design.md section 15). These tests stall one side for longer than
rclpy's default depth of 10 and check that nothing is lost with the QoS of
:mod:`punctured_planner.ros.qos`; the default QoS beside it loses the reply,
which is the cause of the lost call of issue 21.
"""

import os
import signal
import time

from conftest import REPO_ROOT
from conftest import RosClient
import pytest
import yaml

pytestmark = [pytest.mark.ros, pytest.mark.slow]

SCENARIO = os.path.join(REPO_ROOT, 'config', 'default_scenario.yaml')
EXAMPLE = os.path.join(REPO_ROOT, 'config', 'example_request.yaml')
# More than rclpy's default service depth (10), well under the depths of ros.qos.
OTHER_CALLS = 30
WAITING_REQUESTS = 30


def example_request():
    """Return config/example_request.yaml as a PlanSequence request."""
    from punctured_planner.ros.msg_dict import fill_message
    from punctured_planner_interfaces.srv import PlanSequence
    with open(EXAMPLE, encoding='utf-8') as stream:
        return fill_message(PlanSequence.Request(), yaml.safe_load(stream))


@pytest.fixture
def clients():
    """Yield a function making RosClients (each its own participant); all closed after."""
    made = []

    def make(name):
        made.append(RosClient(name))
        return made[-1]

    yield make
    for ros in made:
        ros.close()


def plan_client(ros, node, qos):
    """Return a discovered PlanSequence client of ``node`` with ``qos``."""
    from punctured_planner_interfaces.srv import PlanSequence
    client = ros.node.create_client(PlanSequence, node.name('plan_sequence'), qos_profile=qos)
    ros.wait_for_service(client, timeout_sec=30.0)
    return client


def test_a_stalled_client_keeps_its_reply_while_others_are_answered(
        planner_process, clients):
    """A client that takes nothing while 30 other calls are answered still gets its reply."""
    from punctured_planner.ros.qos import CLIENT_QOS
    from punctured_planner_interfaces.srv import PlanSequence
    from rclpy.qos import qos_profile_services_default
    node = planner_process(params_file=SCENARIO)
    request = example_request()
    stalled = {}
    for name, qos in (('service_qos', CLIENT_QOS),
                      ('rclpy_default', qos_profile_services_default)):
        ros = clients('stalled_' + name)
        stalled[name] = (ros, plan_client(ros, node, qos))
    other = clients('other')
    other_client = plan_client(other, node, CLIENT_QOS)
    for ros, client in stalled.values():
        assert ros.call(client, request).error_code == PlanSequence.Response.NONE
    # Both send, then neither spins (takes) while the other client is answered.
    futures = {name: client.call_async(request) for name, (_, client) in stalled.items()}
    for _ in range(OTHER_CALLS):
        assert other.call(other_client, request).error_code == PlanSequence.Response.NONE
    got = {name: stalled[name][0].spin_until(future.done, 5.0)
           for name, future in futures.items()}
    assert got['service_qos'], 'the stalled client lost its reply:\n' + node.log()
    assert futures['service_qos'].result().error_code == PlanSequence.Response.NONE
    # The cause of issue 21, pinned: with rclpy's default depth the reply is dropped.
    assert not got['rclpy_default'], 'depth 10 kept its reply: doc/design.md section 15'


def test_requests_waiting_while_the_node_is_stopped_are_all_answered(
        planner_process, clients):
    """30 requests sent while the node process is frozen (SIGSTOP) are all answered."""
    from punctured_planner.ros.qos import CLIENT_QOS
    from punctured_planner_interfaces.srv import PlanSequence
    node = planner_process(params_file=SCENARIO)
    ros = clients('waiting')
    client = plan_client(ros, node, CLIENT_QOS)
    request = example_request()
    assert ros.call(client, request).error_code == PlanSequence.Response.NONE
    node.proc.send_signal(signal.SIGSTOP)
    try:
        futures = [client.call_async(request) for _ in range(WAITING_REQUESTS)]
        ros.spin_until(lambda: False, 0.5)  # the requests go out; none can be answered
        assert not any(f.done() for f in futures)
    finally:
        node.proc.send_signal(signal.SIGCONT)
    started = time.monotonic()
    ros.spin_until(lambda: all(f.done() for f in futures), 30.0)
    answered = [f.result().error_code for f in futures if f.done()]
    assert answered == [PlanSequence.Response.NONE] * WAITING_REQUESTS, (
        '%d of %d answered in %.1f s:\n%s' % (len(answered), WAITING_REQUESTS,
                                              time.monotonic() - started, node.log()))
    node.assert_running()


def deaf_and_served(planner_process, clients):
    """
    Start the node; return it, a request, a deaf and a served client (ros, client) each.

    The deaf client's replies never reach it: its transient-local requests match the
    node's volatile request reader, but the node's volatile reply writer never matches
    its transient-local reply reader. The served client has had one reply.
    """
    from punctured_planner.ros.qos import CLIENT_QOS
    from punctured_planner_interfaces.srv import PlanSequence
    from rclpy.qos import DurabilityPolicy
    from rclpy.qos import QoSProfile
    node = planner_process(params_file=SCENARIO)
    request = example_request()
    deaf = clients('deaf')
    deaf_client = deaf.node.create_client(
        PlanSequence, node.name('plan_sequence'),
        qos_profile=QoSProfile(depth=10, durability=DurabilityPolicy.TRANSIENT_LOCAL))
    served = clients('served')
    served_client = plan_client(served, node, CLIENT_QOS)
    assert served.call(served_client, request).error_code == PlanSequence.Response.NONE
    return node, request, deaf, deaf_client, served, served_client


def test_every_reply_that_cannot_be_sent_is_an_error_naming_its_request(
        planner_process, clients):
    """
    A client whose reply reader never matches: each attempt of each reply is logged.

    A reply gets SEND_ATTEMPTS attempts (100 ms each), one once the reply before it failed
    them all (its caller had gone), until a reply goes out: callers that left after
    sending held the service's thread 1.1 s each (doc/design.md section 15).
    """
    from punctured_planner.nodes.planner import SEND_ATTEMPTS
    from punctured_planner_interfaces.srv import PlanSequence
    node, request, deaf, deaf_client, served, served_client = deaf_and_served(
        planner_process, clients)
    futures = []

    def unsent(number, attempts):
        """
        Send a deaf request taken as #number; wait for its last attempt.

        Sent again only while none is taken: one sent before the deaf client matched
        the node is lost, and one more taken would shift the numbers.
        """
        taken = 'plan_sequence #%d: ' % number
        while taken not in node.log():
            futures.append(deaf_client.call_async(request))
            deaf.spin_until(lambda: taken in node.log(), 5.0)
        last = 'plan_sequence #%d: reply (error code 0) not sent to the client' % number
        assert deaf.spin_until(lambda: last in node.log() and (
            'attempt %d of %d' % (attempts, attempts)) in node.log().split(last)[-1],
            10.0), node.log()

    unsent(2, SEND_ATTEMPTS)
    unsent(3, 1)  # the caller of #2 had gone: one attempt
    assert served.call(served_client, request).error_code == PlanSequence.Response.NONE
    unsent(5, SEND_ATTEMPTS)  # #4 went out: every attempt again
    log = node.log()
    for number, attempts in ((2, SEND_ATTEMPTS), (3, 1), (5, SEND_ATTEMPTS)):
        lines = [line for line in log.splitlines()
                 if 'plan_sequence #%d: reply (error code 0) not sent' % number in line]
        assert len(lines) == attempts, log
        assert all(line.startswith('[ERROR]') for line in lines), lines
    assert not any(f.done() for f in futures)
    assert 'Traceback' not in log
    node.assert_running()


def test_callers_that_have_gone_cannot_hold_the_stop(planner_process, clients):
    """
    Requests of a caller that never gets its replies, sent all through a stop: it ends.

    Their replies fail (100 ms an attempt); one of them gets SEND_ATTEMPTS attempts,
    the rest one each, and the linger takes none after LINGER_LIMIT_SEC. Callers that
    left after sending held a stop 60 s (exit 1, a call sent before it lost) and a
    linger 90 s (doc/design.md section 16).
    """
    from punctured_planner.nodes.planner import SEND_ATTEMPTS
    from punctured_planner.ros.runtime import LINGER_LIMIT_SEC, STOP_TIMEOUT_SEC
    # the served client stays a client: the stop lingers for it
    node, request, deaf, deaf_client, _, _ = deaf_and_served(planner_process, clients)
    node.proc.send_signal(signal.SIGINT)
    deadline = time.monotonic() + STOP_TIMEOUT_SEC + LINGER_LIMIT_SEC
    while node.proc.poll() is None and time.monotonic() < deadline:
        deaf_client.call_async(request)
        deaf.spin_until(lambda: False, 0.02)
    assert node.proc.poll() == 0, node.log()
    log = node.log()
    failed = [line for line in log.splitlines() if 'not sent to the client' in line]
    assert failed, log  # the stop took some of the requests
    retried = {line.split(':')[1] for line in failed if 'attempt 2 of' in line}
    assert len(retried) <= 1, retried
    assert sum('attempt 1 of %d' % SEND_ATTEMPTS in line for line in failed) <= 1
    assert 'Traceback' not in log
