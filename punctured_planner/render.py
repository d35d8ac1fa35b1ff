"""
Pictures of plans from the command line, and the glue for ``punctured-planner plan``.

``python -m punctured_planner.render domain OUT.png [--robots 1|2]`` draws the
domain picture; ``python -m punctured_planner.render example --png OUT.png
--gif OUT.gif`` draws the example plan (the README pictures). The ``plan``
command of ``punctured-planner`` gets ``--png``/``--gif`` with two lines::

    add_render_arguments(plan_parser)      # when building the parser
    render_outputs(args, the_plan)         # once the plan is made
"""

import argparse
from collections.abc import Iterator
from collections.abc import Sequence
import os
import sys

from .cli import positive_float
from .core import Plan
from .viz import domain_picture, example_plan, render_animation, render_png
from .viz.animation import MAX_FPS, MAX_SECONDS, MIN_FPS

# Resolutions the pictures are drawn at: far below, an empty image; far above, no memory.
MIN_DPI, MAX_DPI = 10, 1000


def _within(high, low=0.0):
    """Return an argparse type: a positive finite float at most high and at least low."""
    def value_of(text):
        value = positive_float(text)
        if value > high:
            raise argparse.ArgumentTypeError(f'{text!r} is more than {high:g}')
        if value < low:
            raise argparse.ArgumentTypeError(f'{text!r} is less than {low:g}')
        return value
    return value_of


def _dpi(text):
    """Return text as a resolution in [MIN_DPI, MAX_DPI], or raise argparse.ArgumentTypeError."""
    value = positive_float(text)
    if not MIN_DPI <= value <= MAX_DPI:
        raise argparse.ArgumentTypeError(f'{text!r} is not in [{MIN_DPI}, {MAX_DPI}] dots per '
                                         'inch (1e-3 drew an empty image, 1e5 ran out of memory)')
    return value


def _file_of(extension, what):
    """Return an argparse type: a path ending in extension (what the file holds, for errors)."""
    def path_of(text):
        if not text.lower().endswith(extension):
            raise argparse.ArgumentTypeError(f'{text!r}: {what} is written as a {extension} '
                                             'file')
        return text
    return path_of


def add_render_arguments(parser: argparse.ArgumentParser) -> argparse._ArgumentGroup:
    """Add --png, --dpi, --raw, --gif, --gif-fps, --gif-seconds and --gif-dpi to a parser."""
    group = parser.add_argument_group('pictures')
    group.add_argument('--png', metavar='OUT.png', type=_file_of('.png', 'the picture'),
                       help='draw the plan (paths, lanes, waypoints, domain, clearance)')
    group.add_argument('--gif', metavar='OUT.gif', type=_file_of('.gif', 'the animation'),
                       help='animate the synchronous motion of all robots')
    group.add_argument('--gif-fps', type=_within(MAX_FPS, MIN_FPS), default=20.0,
                       help='frames per second of the animation, from 1/60 to 50 '
                       '(default: %(default)s)')
    group.add_argument('--gif-seconds', type=_within(MAX_SECONDS), default=8.0,
                       help='length of the animation in seconds, at most 60 '
                       '(default: %(default)s)')
    group.add_argument('--gif-dpi', type=_dpi, default=80.0,
                       help='resolution of the animation (default: %(default)s)')
    group.add_argument('--dpi', type=_dpi, default=100.0,
                       help='resolution of the PNG picture (default: %(default)s)')
    group.add_argument('--raw', action='store_true',
                       help="overlay the construction's unrefined motion, dashed, on the PNG")
    return group


def render_outputs(args: argparse.Namespace, plan: Plan, title: str | None = None,
                   max_speed: float = 1.0,
                   max_acceleration: float = 0.0) -> Iterator[str | os.PathLike[str]]:
    """
    Write the pictures asked for by add_render_arguments' options; yield each path written.

    One at a time, so a caller whose second file cannot be written still knows the first.
    """
    if getattr(args, 'png', None):
        yield render_png(plan, args.png, title=title, dpi=args.dpi,
                         raw=getattr(args, 'raw', False))
    if getattr(args, 'gif', None):
        yield render_animation(plan, args.gif, fps=args.gif_fps, seconds=args.gif_seconds,
                               dpi=args.gif_dpi, title=title, max_speed=max_speed,
                               max_acceleration=max_acceleration)


def _domain(args):
    """Draw the domain picture."""
    print(domain_picture(args.output, robot_count=args.robots, dpi=args.dpi))
    return 0


def _example(args):
    """Draw the example plan."""
    for path in render_outputs(args, example_plan(args.variant), title='example scenario'):
        print(path)
    return 0


def make_parser() -> argparse.ArgumentParser:
    """Return the parser of ``python -m punctured_planner.render``."""
    parser = argparse.ArgumentParser(prog='python -m punctured_planner.render',
                                     description='Draw pictures of the planner.')
    commands = parser.add_subparsers(dest='command', required=True)
    domain = commands.add_parser('domain', help='the domain picture (PNG)')
    domain.add_argument('output', metavar='OUT.png', type=_file_of('.png', 'the picture'))
    domain.add_argument('--robots', type=int, choices=(1, 2), default=1,
                        help='number of robots (default: %(default)s)')
    domain.add_argument('--dpi', type=_dpi, default=100.0,
                        help='resolution (default: %(default)s)')
    domain.set_defaults(func=_domain)
    example = commands.add_parser('example', help='the example plan (PNG and/or GIF)')
    add_render_arguments(example)
    example.add_argument('--variant', choices=('paper', 'spread', 'discs'), default='spread',
                         help='planner variant (default: %(default)s)')
    example.set_defaults(func=_example)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``python -m punctured_planner.render``; return the exit status (2: nothing drawn)."""
    parser = make_parser()
    args = parser.parse_args(argv)
    if args.command == 'example' and not (args.png or args.gif):
        parser.error('example: give --png OUT.png and/or --gif OUT.gif')
    try:
        return args.func(args)
    except OSError as error:
        print('%s: cannot write: %s' % (parser.prog, error), file=sys.stderr)
        return 2


if __name__ == '__main__':
    sys.exit(main())
