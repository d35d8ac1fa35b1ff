"""
Output files written whole or not at all: the pictures, the GIFs and the recordings.

A picture or a recording written straight to its path and stopped half way (a full
disk, a file size limit, Ctrl-C) left a corrupt file where a good one had been.
:func:`replacing` writes beside it and moves the finished file into place, so a
reader finds the old file or the new one, never part of one.
"""

from collections.abc import Iterator
from contextlib import contextmanager
from contextlib import suppress
import errno
import os


@contextmanager
def replacing(path: str | os.PathLike[str]) -> Iterator[str]:
    """
    Yield the path to write instead of path; on success it replaces path, else it goes.

    The file is written in path's folder (a move within one file system is atomic,
    os.replace) under a hidden name of this process, created by the writer itself, so
    it gets the permissions any new file would.
    """
    folder, name = os.path.split(os.path.abspath(os.fspath(path)))
    if not os.path.isdir(folder):  # named for the path asked for, not the hidden one
        raise FileNotFoundError(errno.ENOENT, 'no folder %s' % folder, os.fspath(path))
    part = os.path.join(folder, '.%s.%d.part' % (name, os.getpid()))
    try:
        yield part
        os.replace(part, path)
    except BaseException:
        with suppress(OSError):
            os.unlink(part)
        raise
