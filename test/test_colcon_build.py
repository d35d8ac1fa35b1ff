"""
colcon builds both packages from a plain clone in ws/src, with the README's command.

This is what a user with ROS 2 Jazzy does; here colcon and ROS come from the
venv (PyPI). The test also runs the colcon-installed node (the layout ``ros2
run`` uses: lib/punctured_planner/planner_node) and calls it over DDS.
"""

import os
import re
import shlex
import shutil
import subprocess
import sys

from conftest import NodeProcess
from conftest import REPO_ROOT
import pytest

# The README must show exactly this command (checked below).
COLCON_BUILD = (
    'colcon build --base-paths src src/punctured_planner/punctured_planner_interfaces')

IGNORED = shutil.ignore_patterns(
    '.venv', '.git', 'build', 'install', 'log', '__pycache__', '*.egg-info',
    '.pytest_cache', '.hypothesis')


def _copy_checkout(destination):
    """Copy what a clone would hold (tracked and not-ignored files) to ``destination``."""
    try:
        listing = subprocess.run(
            ['git', 'ls-files', '-z', '--cached', '--others', '--exclude-standard'],
            cwd=REPO_ROOT, capture_output=True, check=True, timeout=60).stdout
    except (OSError, subprocess.CalledProcessError):
        shutil.copytree(REPO_ROOT, destination, ignore=IGNORED)
        return
    for relative in listing.decode().split('\0'):
        source = os.path.join(REPO_ROOT, relative)
        if not relative or not os.path.isfile(source):
            continue  # deleted in the work tree
        target = os.path.join(destination, relative)
        os.makedirs(os.path.dirname(target), exist_ok=True)
        shutil.copy2(source, target)


def _venv_env(base_env):
    venv = sys.prefix
    env = dict(base_env)
    env['PATH'] = os.path.join(venv, 'bin') + os.pathsep + env.get('PATH', '')
    env['VIRTUAL_ENV'] = venv
    env['AMENT_PREFIX_PATH'] = venv
    env['CMAKE_PREFIX_PATH'] = venv
    return env


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
    clone = workspace / 'src' / 'punctured_planner'
    _copy_checkout(str(clone))
    env = _venv_env(ros_env)

    result = subprocess.run(
        shlex.split(COLCON_BUILD), cwd=str(workspace), env=env,
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=900)
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
        ['bash', '-c', '. install/setup.sh && exec %s --ros-args -r __ns:=%s' % (
            shlex.quote(str(pkg / 'lib' / 'punctured_planner' / 'planner_node')),
            namespace)],
        env, str(tmp_path / 'colcon_node.log'), namespace, cwd=str(workspace))
    try:
        client = ros_client.node.create_client(PlanSequence, node.name('plan_sequence'))
        ros_client.wait_for_service(client)
        response = ros_client.call(client, PlanSequence.Request())
        assert response.error_code != PlanSequence.Response.NONE
        assert response.error_msg
    finally:
        assert node.stop() == 0, node.log()
