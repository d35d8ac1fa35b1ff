"""msg_docs/ stays in sync with the interface definitions."""

import glob
import os
import re

from conftest import REPO_ROOT
import pytest

INTERFACES = os.path.join(REPO_ROOT, 'punctured_planner_interfaces')
DOCS = os.path.join(REPO_ROOT, 'msg_docs')
LINE = re.compile(r'^\s*(?P<type>[\w/]+(?:\[\d*\])?)\s+(?P<name>\w+)\s*(?P<rest>.*)$')


def parse_interface(path):
    """
    Return the sections of a .srv/.msg file as lists of (type, name, constant value).

    Constant value is None for a field.
    """
    sections = [[]]
    with open(path, encoding='utf-8') as stream:
        for raw in stream:
            line = raw.split('#', 1)[0].strip()
            if line == '---':
                sections.append([])
                continue
            match = LINE.match(line)
            if not match:
                continue
            rest = match.group('rest')
            value = rest[1:].strip() if rest.startswith('=') else None
            sections[-1].append((match.group('type'), match.group('name'), value))
    return sections


def interface_files():
    """Return every .srv, .msg and .action file of the interface package."""
    return sorted(glob.glob(os.path.join(INTERFACES, 'srv', '*.srv'))
                  + glob.glob(os.path.join(INTERFACES, 'msg', '*.msg'))
                  + glob.glob(os.path.join(INTERFACES, 'action', '*.action')))


def test_every_interface_has_a_page():
    files = interface_files()
    assert files, 'no interface definitions found'
    for path in files:
        name = os.path.splitext(os.path.basename(path))[0]
        assert os.path.isfile(os.path.join(DOCS, name + '.md')), name


@pytest.mark.parametrize('path', interface_files(), ids=os.path.basename)
def test_page_names_every_field_and_constant(path):
    name = os.path.splitext(os.path.basename(path))[0]
    with open(os.path.join(DOCS, name + '.md'), encoding='utf-8') as stream:
        page = stream.read()
    rows = [line for line in page.splitlines() if line.startswith('|')]
    for section in parse_interface(path):
        for field_type, field, value in section:
            if value is None:
                assert any(row.startswith('| `%s` | `%s` |' % (field, field_type))
                           for row in rows), 'field %s %s not documented' % (field_type, field)
            else:
                assert any(row.startswith('| %s | `%s` |' % (value, field))
                           for row in rows), 'constant %s=%s not documented' % (field, value)


def test_every_kind_of_interface_is_checked():
    names = {os.path.basename(path) for path in interface_files()}
    assert {'PlanSequence.srv', 'Plan.msg', 'ExecutePlan.action'} <= names


def test_parser_sees_the_execute_plan_sections():
    goal, result, feedback = parse_interface(
        os.path.join(INTERFACES, 'action', 'ExecutePlan.action'))
    assert ('uint64', 'plan_id', None) in goal
    assert ('uint16', 'UNSAFE_PLAN', '4') in result
    assert ('string[]', 'stale_robots', None) in feedback


def test_parser_sees_the_plan_sequence_definition():
    request, response = parse_interface(
        os.path.join(INTERFACES, 'srv', 'PlanSequence.srv'))
    assert ('geometry_msgs/PoseArray[]', 'configurations', None) in request
    assert ('uint16', 'UNKNOWN', '99') in response
    assert ('nav_msgs/Path[]', 'paths', None) in response
