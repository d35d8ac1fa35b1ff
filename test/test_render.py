"""Pictures of plans: PNG, GIF and the domain picture render headless and show what they claim."""

import argparse

from matplotlib.image import imread
import numpy as np
from PIL import Image
from punctured_planner.core import plan, PlanningError, Workspace
from punctured_planner.core.complexity import domain_range
from punctured_planner.render import add_render_arguments, main, render_outputs
from punctured_planner.viz import (domain_picture, domain_values, example_plan, frame_parameters,
                                   render_animation, render_png, start_goal_grid,
                                   start_plane_grid)
from punctured_planner.viz.domain_picture import domain_colours, teaching_scene, thicken
from punctured_planner.viz.domains import snapped_axis, start_goal_specials
import pytest

PNG_SIGNATURE = b'\x89PNG\r\n\x1a\n'


def assert_picture(path, minimum_bytes=15000, minimum_side=300):
    """Check path is a PNG of some size whose pixels are not all one colour."""
    data = path.read_bytes()
    assert data[:8] == PNG_SIGNATURE
    assert len(data) > minimum_bytes
    pixels = imread(str(path))
    assert pixels.ndim == 3 and min(pixels.shape[:2]) >= minimum_side
    assert pixels[..., :3].std() > 0.05


def space_plan(dimension, robots=4, seed=1):
    """Return a spread plan of a random request through 3 configurations in R^dimension."""
    rng = np.random.default_rng(seed)
    obstacles = np.zeros((3, dimension))
    obstacles[:, 0] = [-2.0, 0.0, 2.0]
    obstacles[:, 1:] = rng.uniform(-0.5, 0.5, size=(3, dimension - 1))
    workspace = Workspace(obstacles, variant='spread')
    return plan(workspace, rng.uniform(-3, 3, size=(3, robots, dimension)))


@pytest.mark.parametrize('make', [example_plan, lambda: space_plan(3), lambda: space_plan(4)],
                         ids=['planar', 'three-d', 'four-d'])
def test_render_png_writes_a_picture(tmp_path, make):
    """Planar as is, d = 3 as 3-D and top view, d = 4 on the frame plane: a real picture."""
    path = tmp_path / 'plan.png'
    assert render_png(make(), path, title='test') == path
    assert_picture(path)


def test_raw_overlays_the_unrefined_motion_dashed(tmp_path):
    """--raw: the construction's paths join the picture, one dashed line per robot."""
    from punctured_planner.viz.picture import plan_figure
    p = example_plan('discs')
    plain, overlaid = plan_figure(p)[1][0], plan_figure(p, raw=True)[1][0]
    dashed = [line for line in overlaid.get_lines() if line.get_linestyle() == '--']
    assert len(dashed) - len([line for line in plain.get_lines()
                              if line.get_linestyle() == '--']) == p.positions.shape[1]
    path = tmp_path / 'raw.png'
    assert main(['example', '--variant', 'discs', '--raw', '--png', str(path)]) == 0
    assert_picture(path)


def test_render_png_without_obstacles_or_second_robot(tmp_path):
    """One robot and no obstacle: nothing to collide with, still a picture."""
    p = plan(Workspace([], dimension=2), [[[0.0, 1.0]], [[2.0, -1.0]]])
    assert p.clearance.kind == 'none'
    path = tmp_path / 'lonely.png'
    render_png(p, path)
    assert_picture(path, minimum_bytes=5000)


def test_walls_are_drawn_and_a_large_fleets_legend_fits():
    """
    A plan below walls shows them; 40 robots get 11 named and one entry for the rest.

    Before, the walls were not drawn, the legend named robots 0 - 38 and ran off the
    figure (its layers' entries lost), and a plan without obstacles listed 'obstacle'.
    """
    from punctured_planner.viz.draw2d import legend_handles, WALL_COLOUR
    from punctured_planner.viz.picture import plan_figure
    rng = np.random.default_rng(3)
    starts = np.c_[np.arange(40.0) * 0.6, np.zeros(40)]
    goals = starts[rng.permutation(40)] + [0.0, 3.0]
    workspace = Workspace([], dimension=2, bounds=[[-1.0, 25.0], [-20.0, 20.0]],
                          variant='discs', robot_radius=0.1)
    fleet = plan(workspace, [starts, goals])
    labels = [h.get_label() for h in legend_handles(fleet, ['k'] * 40)]
    assert labels[:12] == ['robot %d' % i for i in range(11)] + ['robots 11 - 39']
    assert 'walls' in labels and 'obstacle' not in labels
    axes = plan_figure(fleet)[1][0]
    walls = [line for line in axes.get_lines() if line.get_color() == WALL_COLOUR]
    assert len(walls) == 1
    assert sorted(set(walls[0].get_xdata())) == [-1.0, 25.0]
    assert sorted(set(walls[0].get_ydata())) == [-20.0, 20.0]


def test_frame_parameters_are_evenly_spaced_in_the_plans_time():
    """Frames start at 0, end at 1 and are time-uniform, under an acceleration limit too."""
    p = example_plan()
    for acceleration in (0.0, 0.5):
        tau, seconds = frame_parameters(p, 40, 1.0, acceleration)
        assert tau.size == 40 and tau[0] == 0.0 and tau[-1] == 1.0
        assert np.all(np.diff(tau) > 0)
        assert seconds[-1] == pytest.approx(p.duration(1.0, acceleration))
        assert np.allclose(np.diff(seconds), seconds[-1] / 39)
        # each frame is where the plan is at its time
        assert np.allclose(np.interp(tau, p.times, p.stamps(1.0, acceleration)), seconds)


def test_render_animation_lasts_its_seconds_and_passes_every_breakpoint(tmp_path):
    """
    The GIF has fps x seconds frames of 1 / fps each; the trails pass every breakpoint.

    Before, every breakpoint was a frame as well: 145 frames of 500 ms (72.5 s) for fps 2
    and 1 s, and the clock ignored max_acceleration.
    """
    p = example_plan()
    path = tmp_path / 'plan.gif'
    assert p.times.size > 12
    assert render_animation(p, path, fps=6, seconds=2, dpi=50) == path
    assert path.stat().st_size > 10000
    with Image.open(path) as image:
        assert image.format == 'GIF'
        assert image.n_frames == 12
        durations = []
        for frame in range(image.n_frames):
            image.seek(frame)
            durations.append(image.info['duration'])
        last = np.asarray(image.convert('RGB'))
        image.seek(0)
        first = np.asarray(image.convert('RGB'))
    assert abs(sum(durations) - 2000) <= 12 * 10
    # GIF keeps whole centiseconds: at 40 fps a frame is 20 ms, so 100 frames make 2 s
    # (80 frames of 25 ms were stored as 20 ms each: 1.6 s)
    render_animation(p, path, fps=40, seconds=2, dpi=20)
    with Image.open(path) as image:
        durations = []
        for frame in range(image.n_frames):
            image.seek(frame)
            durations.append(image.info['duration'])
    assert sum(durations) == 2000
    assert np.any(first != last)
    with pytest.raises(ValueError, match='fps must be in'):
        render_animation(p, tmp_path / 'fast.gif', fps=100, seconds=1)


def test_render_animation_three_d(tmp_path):
    """A 3-D plan animates in both views."""
    path = tmp_path / 'space.gif'
    render_animation(space_plan(3, robots=2), path, fps=3, seconds=1, dpi=40)
    with Image.open(path) as image:
        assert image.n_frames > 1


def test_render_animation_refuses_other_formats(tmp_path):
    """Only GIF is written; an mp4 path is refused before any drawing."""
    with pytest.raises(ValueError, match='gif'):
        render_animation(example_plan(), tmp_path / 'plan.mp4')


def test_domain_values_agree_with_plan():
    """The vectorised domain equals plan().domain; NaN exactly where plan() refuses."""
    rng = np.random.default_rng(7)
    workspace = Workspace([[-2.0, 0.0], [0.0, 0.0], [2.0, 0.0]])
    grid = rng.integers(-3, 4, size=(300, 2, 2, 2)).astype(float)
    values = domain_values(workspace, grid)
    refused = 0
    for request, value in zip(grid, values):
        try:
            expected = plan(workspace, request, certify=False).domain
        except PlanningError:
            refused += 1
            assert np.isnan(value)
        else:
            assert value == expected
    assert 0 < refused < len(grid)
    assert len(set(values[np.isfinite(values)])) == 5


def test_snapped_axis_contains_the_special_values_exactly():
    """Special values inside the range are grid values; the grid stays sorted."""
    values = snapped_axis(-4.5, 4.5, 101, [-2.0, 1.2, 7.0])
    assert -2.0 in values and 1.2 in values and values.size == 101
    assert np.all(np.diff(values) > 0)


@pytest.mark.parametrize('robot_count', [1, 2])
def test_start_goal_grid_shows_every_domain(robot_count):
    """The (start x, goal x) slice meets all n k + 1 domains, l = n r .. n (k + r)."""
    scene = teaching_scene(robot_count)
    workspace, request = scene.workspace, scene.sliced
    starts, goals = (snapped_axis(-4.5, 4.5, 91, special)
                     for special in start_goal_specials(workspace, request))
    values = start_goal_grid(workspace, request, starts, goals)
    low, high = domain_range(2, robot_count, workspace.obstacle_count)
    assert set(values.ravel().tolist()) == set(range(low, high + 1))
    assert len(set(values.ravel().tolist())) == 2 * robot_count + 1


def test_start_plane_grid_drops_on_the_obstacle_lines():
    """Robot 0's start in the plane: one less on x = obstacle x, NaN on the obstacles."""
    scene = teaching_scene(1)
    workspace, request = scene.workspace, scene.plane
    xs = snapped_axis(-4.5, 4.5, 91, workspace.obstacles[:, 0])
    ys = snapped_axis(-4.5, 4.5, 91, [0.0])
    values = start_plane_grid(workspace, request, xs, ys)
    on_line = np.isin(xs, workspace.obstacles[:, 0])
    generic = values[:, ~on_line]
    assert np.all(generic == generic.flat[0])
    lines = values[:, on_line]
    assert np.all((lines == generic.flat[0] - 1) | np.isnan(lines))
    assert np.isnan(lines).sum() == 3


def test_thicken_keeps_values_and_widens_lower_strata():
    """Thickening never invents a value and makes a one-pixel line wider."""
    values = np.full((21, 21), 8.0)
    values[:, 10] = 7.0
    values[10, 10] = 6.0
    shown = thicken(values, width=2)
    assert set(np.unique(shown)) == {6.0, 7.0, 8.0}
    assert np.count_nonzero(shown[0] == 7.0) == 5
    assert np.count_nonzero(shown == 6.0) == 81


def test_domain_picture_shows_every_domain_colour(tmp_path):
    """For k = 1 the picture holds all n k + 1 = 3 domain colours."""
    path = tmp_path / 'domains.png'
    assert domain_picture(path, robot_count=1, resolution=181, dpi=60) == path
    assert_picture(path, minimum_bytes=8000, minimum_side=250)
    pixels = imread(str(path))[..., :3]
    colours, _ = domain_colours(6, 8)
    for value in range(3):
        colour = np.asarray(colours(value))[:3]
        assert np.count_nonzero(np.all(np.abs(pixels - colour) < 0.01, axis=2)) > 20


def test_command_line_and_wiring(tmp_path, capsys):
    """``python -m punctured_planner.render`` and the two-line wiring of ``plan``."""
    assert main(['domain', str(tmp_path / 'd.png'), '--robots', '2', '--dpi', '50']) == 0
    assert_picture(tmp_path / 'd.png', minimum_bytes=5000, minimum_side=250)
    parser = argparse.ArgumentParser()
    add_render_arguments(parser)
    args = parser.parse_args(['--png', str(tmp_path / 'p.png'), '--gif', str(tmp_path / 'p.gif'),
                              '--gif-fps', '4', '--gif-seconds', '1', '--dpi', '60'])
    written = list(render_outputs(args, example_plan()))
    assert written == [str(tmp_path / 'p.png'), str(tmp_path / 'p.gif')]
    assert list(render_outputs(parser.parse_args([]), example_plan())) == []
    # refused with the reason: PNG bytes named .gif, nothing to draw, no such folder
    with pytest.raises(SystemExit):
        main(['domain', str(tmp_path / 'd.gif')])
    assert "d.gif': the picture is written as a .png file" in capsys.readouterr().err
    assert not (tmp_path / 'd.gif').exists()
    with pytest.raises(SystemExit):
        main(['example'])
    assert 'give --png OUT.png and/or --gif OUT.gif' in capsys.readouterr().err
    assert main(['domain', str(tmp_path / 'no' / 'd.png')]) == 2
    assert 'cannot write: [Errno 2] no folder' in capsys.readouterr().err
    with pytest.raises(SystemExit):
        parser.parse_args(['--gif', 'out.mp4'])
    assert 'gif' in capsys.readouterr().err
    # refused with the reason, where they gave PNG bytes named .jpg, or a traceback
    for options, words in ((['--png', 'out.jpg'], 'written as a .png file'),
                           (['--gif-fps', 'inf'], 'not a positive finite number'),
                           (['--gif-fps', '100'], 'more than 50'),
                           (['--gif-fps', '0.001'], 'less than 0.0166667'),
                           (['--gif-seconds', '61'], 'more than 60'),
                           (['--dpi', '1e-3'], 'is not in [10, 1000]'),
                           (['--gif-dpi', '1e5'], 'is not in [10, 1000]')):
        with pytest.raises(SystemExit):
            parser.parse_args(options)
        assert words in capsys.readouterr().err, options


def test_an_output_is_written_whole_or_the_old_one_stays(tmp_path):
    """A write that fails half way leaves the file that was there, and no part of the new."""
    from punctured_planner.outputs import replacing
    path = tmp_path / 'plan.png'
    path.write_bytes(b'the good picture')
    with pytest.raises(OSError):
        with replacing(path) as part:
            with open(part, 'wb') as stream:
                stream.write(b'half of a')
            raise OSError(27, 'File too large')
    assert path.read_bytes() == b'the good picture'
    assert sorted(p.name for p in tmp_path.iterdir()) == ['plan.png']
    render_png(example_plan(), path, dpi=20)
    assert path.read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    assert sorted(p.name for p in tmp_path.iterdir()) == ['plan.png']
    # a link stays a link, its target replaced; a pipe (as /dev/null a device) is written
    # as it is, not replaced by a file
    import os
    import stat
    link = tmp_path / 'link.png'
    link.symlink_to(path)
    with replacing(link) as part:
        with open(part, 'wb') as stream:
            stream.write(b'new')
    assert link.is_symlink() and path.read_bytes() == b'new'
    pipe = tmp_path / 'pipe'
    os.mkfifo(pipe)
    with replacing(pipe) as part:
        assert part == str(pipe)
    assert stat.S_ISFIFO(os.stat(pipe).st_mode)
