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
import stat


@contextmanager
def replacing(path: str | os.PathLike[str]) -> Iterator[str]:
    """
    Yield the path to write instead of path; on success it replaces path, else it goes.

    The file is written in the folder of the file path names (a link is followed: the
    link stays, its target is replaced; a move within one file system is atomic,
    os.replace) under a hidden name of this process, created by the writer itself, so
    it gets the permissions any new file would. A path that is no regular file (a
    device such as /dev/null, a pipe) is written as it is: replacing it would put a
    file in its place.
    """
    target = os.path.realpath(os.fspath(path))
    if os.path.exists(target) and not stat.S_ISREG(os.stat(target).st_mode):
        yield target
        return
    folder, name = os.path.split(target)
    if not os.path.isdir(folder):  # named for the path asked for, not the hidden one
        raise FileNotFoundError(errno.ENOENT, 'no folder %s' % folder, os.fspath(path))
    part = os.path.join(folder, '.%s.%d.part' % (name, os.getpid()))
    try:
        yield part
        os.replace(part, target)
    except BaseException:
        with suppress(OSError):
            os.unlink(part)
        raise
