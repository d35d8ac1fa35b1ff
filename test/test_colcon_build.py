"""
colcon builds both packages from a plain clone in ws/src, with the README's command.

This is what a user with ROS 2 Jazzy does; here colcon and ROS come from the
venv (PyPI). The test also runs the colcon-installed node (the layout ``ros2
run`` uses: lib/punctured_planner/planner_node) and calls it over DDS.
"""

import os
import re
import subprocess
import sys

from colcon_workspace import build_workspace
from colcon_workspace import COLCON_BUILD
from colcon_workspace import installed_node_command
from colcon_workspace import venv_env
from conftest import NodeProcess
from conftest import REPO_ROOT
import pytest
from stop_check import node_arguments
from test_clean_stop import assert_clean
from test_clean_stop import FIXED
from test_clean_stop import stop_cycles


def test_readme_gives_the_colcon_command():
    with open(os.path.join(REPO_ROOT, 'README.md'), encoding='utf-8') as stream:
        readme = stream.read()
    commands = [line.strip() for line in readme.splitlines()
                if re.match(r'\s*colcon build\b', line)]
    assert COLCON_BUILD in commands, commands


@pytest.mark.slow
@pytest.mark.ros
def test_colcon_build_from_a_clone(tmp_path, ros_env, ros_client):
    workspace = tmp_path / 'ws'
    env = venv_env(ros_env)
    result = build_workspace(workspace, env)
    assert result.returncode == 0, result.stdout[-6000:]
    for package in ('punctured_planner_interfaces', 'punctured_planner'):
        assert 'Finished <<< %s [' % package in result.stdout, result.stdout[-3000:]

    install = workspace / 'install'
    pkg = install / 'punctured_planner'
    iface = install / 'punctured_planner_interfaces'
    site = os.path.join('lib', 'python%d.%d' % sys.version_info[:2], 'site-packages')
    for path in (
            pkg / 'lib' / 'punctured_planner' / 'planner_node',
            pkg / 'lib' / 'punctured_planner' / 'punctured-planner',
            pkg / 'share' / 'ament_index' / 'resource_index' / 'packages' / 'punctured_planner',
            pkg / 'share' / 'punctured_planner' / 'package.xml',
            pkg / site / 'punctured_planner' / 'core' / '__init__.py',
            pkg / site / 'punctured_planner' / 'ros' / 'fastdds_profile.xml',
            iface / 'share' / 'punctured_planner_interfaces' / 'srv' / 'PlanSequence.srv',
            iface / site / 'punctured_planner_interfaces' / 'srv' / '_plan_sequence.py'):
        assert path.exists(), path
    assert os.access(str(pkg / 'lib' / 'punctured_planner' / 'planner_node'), os.X_OK)

    # With install/setup.sh sourced, Python finds the colcon-installed copies.
    probe = subprocess.run(
        ['bash', '-c', '. install/setup.sh && exec python -c "%s"' % (
            'import punctured_planner, punctured_planner_interfaces.srv as s; '
            'print(punctured_planner.__file__); print(s.__file__)')],
        cwd=str(workspace), env=env, capture_output=True, text=True, timeout=120)
    assert probe.returncode == 0, probe.stderr
    for line in probe.stdout.split():
        assert line.startswith(str(install)), probe.stdout

    # The colcon-installed node serves PlanSequence over DDS (what `ros2 run` starts).
    from punctured_planner_interfaces.srv import PlanSequence
    namespace = '/pp_colcon_test'
    node = NodeProcess(
        installed_node_command(workspace, ['--ros-args', '-r', '__ns:=' + namespace]),
        env, str(tmp_path / 'colcon_node.log'), namespace, cwd=str(workspace))
    try:
        client = ros_client.node.create_client(PlanSequence, node.name('plan_sequence'))
        ros_client.wait_for_service(client)
        response = ros_client.call(client, PlanSequence.Request())
        assert response.error_code != PlanSequence.Response.NONE
        assert response.error_msg
    finally:
        assert node.stop() == 0, node.log()

    # It stops cleanly on SIGINT and SIGTERM, during a call too (bench/stop_stress.py: 300).
    cycles = stop_cycles(ros_client, lambda ns: installed_node_command(
        workspace, node_arguments(ns)), env, tmp_path, FIXED[:2], seed=14, cwd=str(workspace))
    assert_clean(cycles)
