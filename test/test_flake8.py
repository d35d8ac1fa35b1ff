"""flake8 over the whole repository with ament_flake8's configuration (as ament does)."""

import os

from ament_flake8.main import main_with_errors
from conftest import REPO_ROOT
import pytest

# colcon workspaces that someone may have built inside the repository
BUILD_DIRS = ('build', 'install', 'log')


@pytest.mark.flake8
@pytest.mark.linter
def test_flake8(monkeypatch):
    # ament_flake8 walks the current directory for AMENT_IGNORE markers
    monkeypatch.chdir(REPO_ROOT)
    excludes = [d for d in BUILD_DIRS if os.path.isdir(d)]
    argv = ['.'] + (['--exclude'] + excludes if excludes else [])
    rc, errors = main_with_errors(argv=argv)
    assert rc == 0, \
        'Found %d code style errors / warnings:\n' % len(errors) + '\n'.join(errors)
