"""A planner_node in its own process and a client node beside it, for the benchmarks."""

import contextlib
from dataclasses import dataclass
import os
import signal
import subprocess
import sys
import tempfile


@dataclass
class Session:
    """The running node process (namespace, Popen, log) and the client node with its executor."""

    namespace: str
    process: subprocess.Popen
    log_path: str
    node: object
    executor: object


@contextlib.contextmanager
def planner_session(tag, parameters, log_level='warn', domain_offset=50):
    """
    Start the installed planner_node and a client node; stop both on exit.

    The node runs in namespace /pp_<tag>_<pid> with `parameters` (name -> value
    text, as after ``-p name:=``); ROS_DOMAIN_ID, discovery range and log folder
    default to values of this process alone.
    """
    os.environ.setdefault('ROS_DOMAIN_ID', str(1 + (os.getpid() + domain_offset) % 101))
    os.environ.setdefault('ROS_AUTOMATIC_DISCOVERY_RANGE', 'LOCALHOST')
    os.environ.setdefault('ROS_LOG_DIR', tempfile.mkdtemp(prefix='pp_%s_log_' % tag))
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    namespace = '/pp_%s_%d' % (tag, os.getpid())
    log = tempfile.NamedTemporaryFile(prefix='pp_%s_node_' % tag, suffix='.log', delete=False)
    script = os.path.join(os.path.dirname(sys.executable), 'planner_node')
    args = [script, '--ros-args', '-r', '__ns:=' + namespace, '--log-level', log_level]
    for name, value in parameters.items():
        args += ['-p', '%s:=%s' % (name, value)]
    process = subprocess.Popen(args, stdout=log, stderr=subprocess.STDOUT,
                               stdin=subprocess.DEVNULL)
    rclpy.init(args=[])
    node = rclpy.create_node('%s_bench' % tag)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    try:
        yield Session(namespace, process, log.name, node, executor)
    finally:
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()
        process.send_signal(signal.SIGINT)
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
        log.close()
