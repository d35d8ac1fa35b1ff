"""
A colcon workspace built from a copy of this checkout, as a user with ROS 2 Jazzy builds it.

Shared by test/test_colcon_build.py and bench/stop_stress.py. colcon and ROS
come from the venv (PyPI) here.
"""

import os
import shlex
import shutil
import subprocess
import sys

REPO_ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# The README must show exactly this command (test/test_colcon_build.py checks).
COLCON_BUILD = (
    'colcon build --base-paths src src/punctured_planner/punctured_planner_interfaces')

IGNORED = shutil.ignore_patterns(
    '.venv', '.git', 'build', 'install', 'log', '__pycache__', '*.egg-info',
    '.pytest_cache', '.hypothesis')


def copy_checkout(destination):
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


def venv_env(base_env):
    """Return ``base_env`` with the venv as the ROS prefix colcon builds against."""
    venv = sys.prefix
    env = dict(base_env)
    env['PATH'] = os.path.join(venv, 'bin') + os.pathsep + env.get('PATH', '')
    env['VIRTUAL_ENV'] = venv
    env['AMENT_PREFIX_PATH'] = venv
    env['CMAKE_PREFIX_PATH'] = venv
    return env


def build_workspace(workspace, env):
    """Copy the checkout to ``workspace``/src/punctured_planner and colcon build it there."""
    copy_checkout(os.path.join(str(workspace), 'src', 'punctured_planner'))
    return subprocess.run(
        shlex.split(COLCON_BUILD), cwd=str(workspace), env=env,
        stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=900)


def installed_node_command(workspace, ros_args):
    """Return the command starting the colcon-installed planner_node (as ``ros2 run`` does)."""
    script = os.path.join(str(workspace), 'install', 'punctured_planner', 'lib',
                          'punctured_planner', 'planner_node')
    return ['bash', '-c', '. install/setup.sh && exec %s %s' % (
        shlex.quote(script), ' '.join(shlex.quote(a) for a in ros_args))]
