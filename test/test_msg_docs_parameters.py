"""msg_docs/parameters.md lists every parameter with its type, default and range."""

import os

from conftest import REPO_ROOT
from punctured_planner.parameters import PARAMETERS

KINDS = {'string': 'string', 'integer': 'integer', 'double': 'double',
         'string_array': 'string array', 'double_array': 'double array'}


def expected_row(spec):
    """Return the table row of one parameter, as msg_docs/parameters.md must show it."""
    if isinstance(spec.default, list):
        default = '`[]`'
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
    assert rows == [expected_row(spec) for spec in PARAMETERS]
