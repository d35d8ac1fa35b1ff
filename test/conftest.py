"""
Shared pytest set-up: an isolated ROS 2 domain per run and node-process helpers.

At session start (``pytest_configure``, before any test imports rclpy or starts
a process) the environment gets:

* ``ROS_DOMAIN_ID``: 1 + pid % 101, so parallel or leftover runs never cross-talk
  (avoids 0, the default domain of real robots);
* ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``: discovery stays on this machine;
* ``RMW_IMPLEMENTATION=rmw_fastrtps_cpp``;
* ``ROS_LOG_DIR``: a temporary folder (rclpy needs a log directory).

Child processes get ``os.environ`` whole (see :func:`ros_env`): the
ros-wheels-bootstrapper re-execs Python with LD_LIBRARY_PATH set and a guard
variable; a child with the guard but without LD_LIBRARY_PATH cannot import rclpy.

Fixtures for node tests: ``ros_domain_id``, ``ros_env``, ``ros_client`` (an rclpy
node with its own Context and executor) and ``planner_process`` (starts the
installed ``planner_node`` console script in a unique namespace).
"""

import itertools
import os
import shutil
import signal
import subprocess
import sys
import tempfile

import pytest

REPO_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
_namespace_counter = itertools.count(1)


def pick_domain_id(pid=None):
    """Return the ROS_DOMAIN_ID of this test run: 1 + pid % 101 (1..101)."""
    return 1 + (os.getpid() if pid is None else pid) % 101


def pytest_configure(config):
    """Isolate this run's DDS traffic before any test or child process starts."""
    os.environ['ROS_DOMAIN_ID'] = str(pick_domain_id())
    os.environ['ROS_AUTOMATIC_DISCOVERY_RANGE'] = 'LOCALHOST'
    os.environ.pop('ROS_LOCALHOST_ONLY', None)
    os.environ.pop('ROS_STATIC_PEERS', None)
    os.environ['RMW_IMPLEMENTATION'] = 'rmw_fastrtps_cpp'
    log_dir = tempfile.mkdtemp(prefix='punctured_planner_ros_log_')
    config._punctured_planner_log_dir = log_dir
    os.environ['ROS_LOG_DIR'] = log_dir


def pytest_unconfigure(config):
    """Remove the temporary ROS log folder."""
    log_dir = getattr(config, '_punctured_planner_log_dir', None)
    if log_dir:
        shutil.rmtree(log_dir, ignore_errors=True)


def pytest_report_header(config):
    """Show the DDS domain of this run in pytest's header."""
    return 'ROS_DOMAIN_ID=%s (discovery LOCALHOST)' % os.environ.get('ROS_DOMAIN_ID')


def venv_script(name):
    """
    Return the path of an installed console script next to this Python.

    Fails the test with a hint when the script is missing (run ``make setup``).
    """
    path = os.path.join(os.path.dirname(sys.executable), name)
    if not os.access(path, os.X_OK):
        pytest.fail('console script %s is not installed next to %s; run `make setup`'
                    % (name, sys.executable))
    return path


@pytest.fixture(scope='session')
def ros_domain_id():
    """ROS_DOMAIN_ID of this test run (already set in os.environ)."""
    return int(os.environ['ROS_DOMAIN_ID'])


@pytest.fixture
def ros_env():
    """Return a copy of the whole environment, for child processes (keep it whole)."""
    return dict(os.environ)


class RosClient:
    """
    An rclpy node with its own Context and single-threaded executor.

    ``call`` spins with ``spin_once`` until the future is done (in rclpy 7.1,
    repeated spin_until_future_complete accumulates stale tasks).
    """

    def __init__(self, name='test_client'):
        """Initialise a private Context, a node in it and an executor for it."""
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        self.context = rclpy.context.Context()
        rclpy.init(context=self.context)
        self.node = rclpy.create_node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)

    def wait_for_service(self, client, timeout_sec=20.0):
        """Wait until ``client``'s service is discovered; fail the test if it is not."""
        if not client.wait_for_service(timeout_sec=timeout_sec):
            pytest.fail('service %s not discovered within %.1f s'
                        % (client.srv_name, timeout_sec))

    def call(self, client, request, timeout_sec=20.0):
        """Send ``request`` and return the response; fail the test on timeout."""
        from punctured_planner.ros.client import call_service
        response = call_service(self.executor, client, request, timeout_sec)
        if response is None:
            pytest.fail('no response from %s within %.1f s' % (client.srv_name, timeout_sec))
        return response

    def spin_until(self, predicate, timeout_sec=10.0):
        """Spin until ``predicate()`` is true; return whether it became true."""
        from punctured_planner.ros.client import spin_until
        return spin_until(self.executor, predicate, timeout_sec)

    def close(self):
        """Shut the executor down, destroy the node, shut the Context down."""
        import rclpy
        self.executor.shutdown()
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.context)


@pytest.fixture
def ros_client():
    """Yield a :class:`RosClient` (own Context); closed after the test."""
    client = RosClient()
    yield client
    client.close()


class NodeProcess:
    """A planner node started from its installed console script."""

    def __init__(self, args, env, log_path, namespace, cwd=REPO_ROOT):
        """Start ``args`` with ``env`` in ``cwd``; stdout and stderr go to ``log_path``."""
        self.args = list(args)
        self.namespace = namespace
        self.log_path = log_path
        self._log = open(log_path, 'wb')
        self.proc = subprocess.Popen(
            self.args, env=env, stdout=self._log, stderr=subprocess.STDOUT,
            stdin=subprocess.DEVNULL, cwd=cwd)

    def name(self, relative):
        """Return the absolute name of a relative topic or service of the node."""
        return '%s/%s' % (self.namespace.rstrip('/'), relative)

    def log(self):
        """Return what the process printed so far (also after stop())."""
        if not self._log.closed:
            self._log.flush()
        with open(self.log_path, 'rb') as stream:
            return stream.read().decode('utf-8', 'replace')

    def assert_running(self):
        """Fail the test with the node's output if the process has exited."""
        if self.proc.poll() is not None:
            pytest.fail('planner_node exited with %s:\n%s' % (self.proc.returncode, self.log()))

    def stop(self, timeout_sec=10.0):
        """Send SIGINT (Ctrl-C), wait, then kill; return the exit code."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(timeout=timeout_sec)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._log.close()
        return self.proc.returncode


@pytest.fixture
def planner_process(ros_env, tmp_path):
    """
    Return a function that starts the installed ``planner_node`` console script.

    ``start(*ros_args, params_file=None, namespace=None, env=None)`` launches
    ``.venv/bin/planner_node --ros-args -r __ns:=<namespace> [--params-file F]
    [ros_args...]`` with the whole environment (plus ``env`` overrides). The
    namespace defaults to a fresh ``/pp_test_<pid>_<n>`` so a test never reaches another
    test's node; use ``proc.name('plan_sequence')`` for the service name. Every
    process is stopped (SIGINT, then kill) after the test.
    """
    started = []

    def start(*ros_args, params_file=None, namespace=None, env=None):
        if namespace is None:
            namespace = '/pp_test_%d_%d' % (os.getpid(), next(_namespace_counter))
        args = [venv_script('planner_node'), '--ros-args', '-r', '__ns:=' + namespace]
        if params_file is not None:
            args += ['--params-file', str(params_file)]
        args += list(ros_args)
        child_env = dict(ros_env)
        child_env.update(env or {})
        log_path = tmp_path / ('planner_node_%d.log' % (len(started) + 1))
        process = NodeProcess(args, child_env, str(log_path), namespace)
        started.append(process)
        return process

    yield start
    for process in started:
        process.stop()
