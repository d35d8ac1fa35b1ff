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


def interface_comments(path):
    """Return {field or constant name: its same-line comment} of a .srv/.msg file."""
    comments = {}
    with open(path, encoding='utf-8') as stream:
        for raw in stream:
            code, _, comment = raw.partition('#')
            match = LINE.match(code.strip())
            if match:
                comments[match.group('name')] = comment.strip()
    return comments


def first_sentence(text):
    """Return text up to its first full stop followed by a space or the end (code spans kept)."""
    masked = re.sub(r'`[^`]*`', lambda m: '_' * len(m.group()), text)
    end = re.search(r'\.(\s|$)', masked)
    return text[:end.start() + 1] if end else text


def page_meanings(page):
    """Return {field or constant name: meaning} from the tables of a msg_docs page."""
    meanings = {}
    for line in page.splitlines():
        cells = [cell.strip() for cell in line.strip().strip('|').split('|')]
        if len(cells) < 3:
            continue
        name = cells[1] if re.fullmatch(r'\d+', cells[0]) else cells[0]
        if re.fullmatch(r'`\w+`', name):
            meanings[name.strip('`')] = cells[-1]
    return meanings


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


def test_each_field_and_constant_has_the_pages_first_sentence_as_comment():
    """`ros2 interface show` explains each line: its comment opens its msg_docs row."""
    path = os.path.join(INTERFACES, 'srv', 'PlanSequence.srv')
    with open(os.path.join(DOCS, 'PlanSequence.md'), encoding='utf-8') as stream:
        meanings = page_meanings(stream.read())
    comments = interface_comments(path)
    for section in parse_interface(path):
        for _, field, _ in section:
            assert comments[field] == first_sentence(meanings[field]), field


def test_first_sentence_skips_full_stops_in_code():
    assert first_sentence('Sum `a + ... + b`. More.') == 'Sum `a + ... + b`.'
    assert first_sentence('Uses 1.5 m. Then') == 'Uses 1.5 m.'


def test_parser_sees_the_plan_sequence_definition():
    request, response = parse_interface(
        os.path.join(INTERFACES, 'srv', 'PlanSequence.srv'))
    assert ('geometry_msgs/PoseArray[]', 'configurations', None) in request
    assert ('uint16', 'UNKNOWN', '99') in response
    assert ('nav_msgs/Path[]', 'paths', None) in response
