"""pydocstyle over the whole repository with ament_pep257's settings (as ament does)."""

import os

from ament_pep257.main import main
from conftest import REPO_ROOT
import pytest

BUILD_DIRS = ('build', 'install', 'log')


@pytest.mark.linter
@pytest.mark.pep257
def test_pep257(monkeypatch):
    monkeypatch.chdir(REPO_ROOT)
    excludes = [d for d in BUILD_DIRS if os.path.isdir(d)]
    argv = ['.'] + (['--exclude'] + excludes if excludes else [])
    rc = main(argv=argv)
    assert rc == 0, 'Found code style errors / warnings'
