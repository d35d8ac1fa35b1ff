"""
``punctured-planner plan``: offline planning, pictures and the MCAP recording.

No ROS graph: the node's checks and conversions with a parameter file.
"""

import os
import subprocess

from conftest import REPO_ROOT
from conftest import venv_script
import numpy as np
from planner_helpers import scenario_plan
from punctured_planner.cli import main
import pytest
import yaml

SCENARIO = os.path.join(REPO_ROOT, 'config', 'default_scenario.yaml')
EXAMPLE = os.path.join(REPO_ROOT, 'config', 'example_request.yaml')


def run(capsys, *argv):
    """Run punctured-planner in process; return (exit code, parsed YAML, stderr)."""
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, yaml.safe_load(out) if out.strip() else None, err


def test_plan_prints_the_same_answer_as_the_node(capsys):
    code, data, err = run(capsys, 'plan', EXAMPLE, '--params', SCENARIO)
    assert code == 0, err
    expected = scenario_plan()
    assert data['error_code'] == 0 and data['error_msg'] == ''
    assert data['domain_index'] == expected.domain_index
    assert data['projection_counts'] == expected.projection_counts.tolist()
    assert len(data['paths']) == 4
    positions = [[p['pose']['position'][a] for a in 'xy'] for p in data['paths'][1]['poses']]
    assert np.array_equal(positions, expected.sample(0, 0.5).positions[:, 1])


def test_plan_refusals_and_exit_codes(capsys, tmp_path):
    code, data, err = run(capsys, 'plan', EXAMPLE)  # built-in defaults: no obstacles
    assert code == 0 and data['domain_count'] == 3 * (4 - 1) + 1
    request = yaml.safe_load(open(EXAMPLE, encoding='utf-8'))
    request['configurations'][1]['header']['frame_id'] = 'odom'
    bad_frame = tmp_path / 'odom.yaml'
    bad_frame.write_text(yaml.safe_dump(request), encoding='utf-8')
    code, data, err = run(capsys, 'plan', str(bad_frame), '--params', SCENARIO, '--no-paths')
    assert code == 1 and data['error_code'] == 7 and 'FRAME_MISMATCH' in err
    state = tmp_path / 'state.yaml'
    state.write_text(yaml.safe_dump({'configurations': request['configurations'][:1],
                                     'use_current_state': True}), encoding='utf-8')
    code, data, err = run(capsys, 'plan', str(state))
    assert code == 1 and data['error_code'] == 2
    params = tmp_path / 'bad.yaml'
    params.write_text('planner_node:\n  ros__parameters:\n    variant: fast\n', encoding='utf-8')
    code, data, err = run(capsys, 'plan', EXAMPLE, '--params', str(params))
    assert code == 2 and 'variant' in err
    # obstacles planner_node refuses at start-up (exit 2): the plan command refuses them too
    params.write_text('planner_node:\n  ros__parameters:\n    obstacles: [1.0, 1.0, 0.0, '
                      '1.0, 1.0, 0.0]\n', encoding='utf-8')
    code, data, err = run(capsys, 'plan', EXAMPLE, '--params', str(params))
    assert code == 2 and data is None, (code, data)
    assert 'bad parameter file: OBSTACLES_DEGENERATE with 2 obstacles' in err, err
    # parameters not a mapping; an output that cannot be written: exit 2, no traceback
    params.write_text('/**/planner_node:\n  ros__parameters: [1, 2]\n', encoding='utf-8')
    code, data, err = run(capsys, 'plan', EXAMPLE, '--params', str(params))
    assert code == 2 and 'ros__parameters must map names to values' in err, err
    nowhere = str(tmp_path / 'missing' / 'plan.mcap')
    code, data, err = run(capsys, 'plan', EXAMPLE, '--no-paths', '--mcap', nowhere)
    assert code == 2 and data['error_code'] == 0, err
    assert 'punctured-planner: cannot write the outputs' in err and nowhere in err, err
    assert 'Traceback' not in err
    # one robot and no obstacle: nothing to meet, min_gap inf, written as YAML reads it
    lonely = tmp_path / 'lonely.yaml'
    lonely.write_text('configurations:\n- poses: [{position: {x: 0.0, y: 0.0, z: 0.0}}]\n'
                      '- poses: [{position: {x: 1.0, y: 0.0, z: 0.0}}]\n', encoding='utf-8')
    code, data, err = run(capsys, 'plan', str(lonely), '--no-paths')
    assert code == 0 and data['min_gap'] == data['tracking_tolerance'] == float('inf'), data
    # a service or node name rclpy refuses: a usage error naming it (a traceback, exit 1);
    # a time that is no positive number (nan: a traceback; 0, -1: the request was sent)
    for argv, words in ((['call', EXAMPLE, '--service', 'bad name!'],
                         "'bad name!' is not a valid ROS name"),
                        (['reset-obstacles', '--node', 'bad name!'],
                         "'bad name!' is not a valid ROS name"),
                        (['call', EXAMPLE, '--timeout', 'nan'], 'not a positive finite'),
                        (['call', EXAMPLE, '--timeout', '0'], 'not a positive finite'),
                        (['call', EXAMPLE, '--wait', '-5'], 'not a positive finite'),
                        (['reset-obstacles', '--wait', 'nan'], 'not a positive finite')):
        with pytest.raises(SystemExit) as usage:
            main(argv)
        assert usage.value.code == 2
        assert words in capsys.readouterr().err


def test_plan_png_and_mcap_from_the_console_script(tmp_path, ros_env):
    """The installed command writes a PNG and an MCAP whose Paths are the breakpoints."""
    png, mcap = tmp_path / 'plan.png', tmp_path / 'plan.mcap'
    result = subprocess.run(
        [venv_script('punctured-planner'), 'plan', EXAMPLE, '--params', SCENARIO,
         '--no-paths', '--png', str(png), '--mcap', str(mcap)],
        env=ros_env, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert png.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n' and png.stat().st_size > 10000
    check_recording(mcap, scenario_plan())


def check_recording(path, expected):
    """Read an MCAP back with the mcap reader; compare the Paths with the plan."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory
    from nav_msgs.msg import Path
    from rclpy.serialization import deserialize_message

    with open(path, 'rb') as stream:
        reader = make_reader(stream, decoder_factories=[DecoderFactory()])
        assert reader.get_header().profile == 'ros2'
        decoded = list(reader.iter_decoded_messages())
        stream.seek(0)
        metadata = {m.name: m.metadata for m in make_reader(stream).iter_metadata()}
    topics = [channel.topic for _, channel, _, _ in decoded]
    robots = ['/robot_%d/plan' % i for i in range(expected.positions.shape[1])]
    assert sorted(topics) == sorted(robots + ['/plan_markers', '/domain_index', '/plan'])
    for schema, channel, message, ros_msg in decoded:
        if channel.topic == '/plan':
            assert schema.name == 'punctured_planner_interfaces/msg/Plan'
            assert ros_msg.plan_id == 0 and len(ros_msg.paths) == len(robots)
            assert ros_msg.tracking_tolerance == pytest.approx(expected.min_gap / 2)
            continue
        assert schema.encoding == 'ros2msg' and channel.message_encoding == 'cdr'
        if channel.topic in robots:
            i = robots.index(channel.topic)
            assert schema.name == 'nav_msgs/msg/Path'
            assert 'MSG: geometry_msgs/msg/PoseStamped' in schema.data.decode()
            positions = np.array([[p.pose.position.x, p.pose.position.y, p.pose.position.z]
                                  for p in ros_msg.poses])
            assert np.array_equal(positions[:, :2], expected.sample(0, 0.5).positions[:, i])
            stamps_ns = [p.header.stamp.sec * 10 ** 9 + p.header.stamp.nanosec
                         for p in ros_msg.poses]
            assert np.all(np.diff(stamps_ns) > 0), 'the recording repeats a pose'
            # the bytes are what the real type support reads
            real = deserialize_message(message.data, Path)
            assert len(real.poses) == len(positions) and real.header.frame_id == 'map'
            stamps = [(p.header.stamp.sec, p.header.stamp.nanosec) for p in ros_msg.poses]
            assert stamps == [(p.header.stamp.sec, p.header.stamp.nanosec)
                              for p in real.poses]
        elif channel.topic == '/domain_index':
            assert ros_msg.data == expected.domain_index
        else:
            assert {m.ns for m in ros_msg.markers} >= {'obstacles', 'paths', 'waypoints'}
    assert metadata['punctured_planner']['domain_index'] == str(expected.domain_index)


@pytest.mark.parametrize('option', ['--gif'])
def test_plan_gif(capsys, tmp_path, option):
    out = tmp_path / 'plan.gif'
    code, _, err = run(capsys, 'plan', EXAMPLE, '--params', SCENARIO, '--no-paths', option,
                       str(out), '--gif-seconds', '1', '--gif-fps', '4', '--gif-dpi', '40')
    assert code == 0, err
    assert out.read_bytes()[:6] in (b'GIF89a', b'GIF87a')


def test_the_demo_refuses_its_files_before_starting_a_node(capsys, tmp_path):
    """A missing request or a parameter file without fleet_sim: a usage error, no node run."""
    from punctured_planner.demo import main as demo
    for argv, words in ((['--request', str(tmp_path / 'missing.yaml')],
                         '--request %s: [Errno 2]' % (tmp_path / 'missing.yaml')),
                        (['--params', SCENARIO], 'no section applies to fleet_sim')):
        with pytest.raises(SystemExit) as usage:
            demo(argv + ['--mcap', str(tmp_path / 'd.mcap'), '--gif', str(tmp_path / 'd.gif')])
        assert usage.value.code == 2
        err = capsys.readouterr()
        assert words in err.err and 'started' not in err.out, err


def test_an_answer_that_cannot_be_written_is_said_so(tmp_path):
    """Standard output on a full disk: a one-line reason and exit 2 (a traceback and 1)."""
    with open('/dev/full', 'wb') as full:  # Linux's always-full device
        process = subprocess.run([venv_script('punctured-planner'), 'plan', EXAMPLE,
                                  '--params', SCENARIO, '--no-paths'],
                                 stdout=full, stderr=subprocess.PIPE, timeout=120)
    err = process.stderr.decode()
    assert process.returncode == 2, err
    assert 'No space left on device' in err and 'Traceback' not in err, err


def test_a_reader_that_goes_away_ends_the_output_quietly(tmp_path):
    """`punctured-planner plan ... | head -3`: no traceback, exit 141, the files written."""
    with open(EXAMPLE, encoding='utf-8') as stream:
        request = yaml.safe_load(stream)
    request['samples_per_leg'] = 100  # megabytes of YAML: far more than a pipe holds
    path = tmp_path / 'long.yaml'
    path.write_text(yaml.safe_dump(request))
    picture = tmp_path / 'long.png'
    process = subprocess.Popen([venv_script('punctured-planner'), 'plan', str(path),
                                '--params', SCENARIO, '--png', str(picture)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    head = [process.stdout.readline() for _ in range(3)]
    process.stdout.close()  # as head does after three lines
    err = process.stderr.read().decode()
    assert process.wait(timeout=60) == 141, err
    assert head[0].startswith(b'error_code: 0')
    assert err == '', err
    # the files asked for are written before the answer (before, never: the pipe ended it)
    assert picture.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
