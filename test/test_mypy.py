"""mypy over the annotated modules (the files listed in mypy.ini), as ros2/demos does."""

import os

from conftest import REPO_ROOT
from mypy import api
import pytest


@pytest.mark.linter
@pytest.mark.mypy
def test_mypy(monkeypatch):
    monkeypatch.chdir(REPO_ROOT)
    stdout, stderr, status = api.run(['--config-file', os.path.join(REPO_ROOT, 'mypy.ini'),
                                      '--cache-dir', os.devnull])
    assert status == 0, 'mypy found type errors:\n' + stdout + stderr
