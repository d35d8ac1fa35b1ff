"""msg_docs lists every parameter of every node with its type, default and range."""

import os

from conftest import REPO_ROOT
from punctured_planner.ros.settings import EXECUTOR
from punctured_planner.ros.settings import FLEET_SIM
from punctured_planner.ros.settings import PLANNER
import pytest

KINDS = {'string': 'string', 'bool': 'bool', 'integer': 'integer', 'double': 'double',
         'string_array': 'string array', 'double_array': 'double array'}


def expected_row(spec):
    """Return the table row of one parameter, as msg_docs/parameters.md must show it."""
    if isinstance(spec.default, list):  # ['holonomic'] as YAML writes it, [] for none
        default = '`[%s]`' % ', '.join(repr(item) for item in spec.default)
    elif isinstance(spec.default, str):
        default = "`'%s'`" % spec.default
    else:
        default = '`%r`' % (spec.default,)
    limits = '[%s, %s]' % (spec.low, spec.high) if spec.low is not None else spec.constraints
    return '| `%s` | %s | %s | %s | %s |' % (spec.name, KINDS[spec.kind], default, limits,
                                             spec.description)


def test_every_parameter_row_matches_the_declaration():
    with open(os.path.join(REPO_ROOT, 'msg_docs', 'parameters.md'), encoding='utf-8') as f:
        rows = [line for line in f.read().splitlines() if line.startswith('| `')]
    assert rows == [expected_row(spec) for spec in PLANNER.specs]


@pytest.mark.parametrize('table', [EXECUTOR, FLEET_SIM], ids=lambda t: t.node_name)
def test_node_page_parameter_rows_match_the_declarations(table):
    """The '## Parameters' table of msg_docs/<node>.md, row for row."""
    with open(os.path.join(REPO_ROOT, 'msg_docs', table.node_name + '.md'),
              encoding='utf-8') as f:
        section = f.read().split('## Parameters', 1)[1].split('\n## ', 1)[0]
    rows = [line for line in section.splitlines() if line.startswith('| `')]
    assert rows == [expected_row(spec) for spec in table.specs]
