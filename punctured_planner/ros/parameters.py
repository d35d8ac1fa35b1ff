"""
The parameter machinery of every node: a Spec per parameter, a Table per node.

A :class:`Spec` carries everything about one parameter: kind, default,
range or choices, its own check and its description; the specs several nodes
share (frame, obstacles, radii) are defined once, below. A node's settings
are a frozen dataclass whose fields are made by :meth:`Spec.field`, so the
defaults are written once; :class:`Table` reads the specs back from the
dataclass, in field order, and builds validated settings from parameter
values (the cross-parameter checks too). :class:`NodeParameters` binds a
table to a node the one way: declare every spec with its descriptor,
validate a change in the on-set callback (a refused change keeps the old
value, with the reason), apply it in the post-set callback.
The tables themselves are in :mod:`punctured_planner.ros.settings`.
"""

import dataclasses
from dataclasses import dataclass
import math
import re
from typing import Any
from typing import Callable
from typing import Generic
from typing import Iterable
from typing import Iterator
from typing import Sequence
from typing import TypeVar

import numpy as np
from rcl_interfaces.msg import FloatingPointRange
from rcl_interfaces.msg import IntegerRange
from rcl_interfaces.msg import ParameterDescriptor
from rcl_interfaces.msg import ParameterType
from rcl_interfaces.msg import SetParametersResult
import yaml

from .topics import robot_topic
from .topics import ROBOT_TOPICS
from ..core.limits import length_range
from ..core.limits import lengths_in_range

_KINDS = {
    'string': ParameterType.PARAMETER_STRING,
    'bool': ParameterType.PARAMETER_BOOL,
    'integer': ParameterType.PARAMETER_INTEGER,
    'double': ParameterType.PARAMETER_DOUBLE,
    'string_array': ParameterType.PARAMETER_STRING_ARRAY,
    'double_array': ParameterType.PARAMETER_DOUBLE_ARRAY,
}
# Names usable as the first token of '<name>/plan', '<name>/odom' and '<name>/cmd_vel'.
_NAME = re.compile(r'^[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$')


class InvalidParameter(ValueError):
    """
    A parameter value refused, with its culprits: the parameters at fault and the element.

    parameters names the parameter refused first, then any other whose value it
    does not fit (robot_count and robot_names); index is the list element at
    fault, where one is. The message says why, naming them.
    """

    def __init__(self, parameters: str | tuple[str, ...], message: str,
                 index: int | None = None) -> None:
        """Keep the culprits; message is the reason, worded with them."""
        self.parameters = (parameters,) if isinstance(parameters, str) else tuple(parameters)
        self.index = index
        super().__init__(message)


class InvalidParameterFile(ValueError):
    """
    A --params-file a node cannot use, with its culprits: the file and, where one is, the name.

    paths are the files at fault (every file where none of them applies),
    parameter the unknown name in the node's own section, if that is the fault.
    """

    def __init__(self, paths: Sequence[str], message: str,
                 parameter: str | None = None) -> None:
        """Keep the culprits; message is the reason, worded with them."""
        self.paths = tuple(paths)
        self.parameter = parameter
        super().__init__(message)


@dataclass(frozen=True)
class Spec:
    """
    One parameter: name, kind, default, range (inclusive) or choices, check, description.

    ``check(name, value)`` raises InvalidParameter with the reason for a value of
    the right kind that is still refused; ``prose`` says in words what the
    check accepts (the descriptor's additional_constraints).
    """

    name: str
    kind: str  # 'string', 'bool', 'integer', 'double', 'string_array', 'double_array'
    default: object
    description: str
    low: Any = None
    high: Any = None
    choices: tuple = ()
    check: Callable[[str, Any], None] | None = None
    prose: str = ''
    read_only: bool = False

    @property
    def constraints(self) -> str:
        """Return the accepted values in words, for a value without a range."""
        if self.choices:
            quoted = ["'%s'" % choice for choice in self.choices]
            return ', '.join(quoted[:-1]) + ' or ' + quoted[-1]
        return self.prose

    def field(self) -> Any:
        """Return the dataclass field of this parameter: its default (frozen), the spec."""
        default = tuple(self.default) if isinstance(self.default, list) else self.default
        return dataclasses.field(default=default, metadata={'spec': self})

    def value(self, raw: object) -> Any:
        """Return raw converted to the parameter's kind and checked; raise InvalidParameter."""
        value = _coerce(self, raw)
        if self.low is not None and not self.low <= value <= self.high:
            raise InvalidParameter(self.name, '%s must be in [%s, %s], got %r'
                                   % (self.name, self.low, self.high, value))
        if self.choices and value not in self.choices:
            raise InvalidParameter(self.name, '%s must be one of %s, got %r'
                                   % (self.name, ', '.join(self.choices), value))
        if self.check is not None:
            self.check(self.name, value)
        return value

    def descriptor(self) -> ParameterDescriptor:
        """Return the rcl_interfaces ParameterDescriptor of the parameter."""
        result = ParameterDescriptor(name=self.name, type=_KINDS[self.kind],
                                     description=self.description,
                                     additional_constraints=self.constraints,
                                     read_only=self.read_only)
        # Doubles accept YAML integers (plane_z: 0) and arrays accept [] (an untyped
        # empty list): their type is checked by Spec.value instead.
        result.dynamic_typing = self.kind in ('double', 'string_array', 'double_array')
        if self.kind == 'integer' and self.low is not None:
            result.integer_range = [IntegerRange(from_value=self.low, to_value=self.high,
                                                 step=1)]
        if self.kind == 'double' and self.low is not None:
            result.floating_point_range = [FloatingPointRange(
                from_value=float(self.low), to_value=float(self.high), step=0.0)]
        return result


def _is_number(value: object) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _coerce(spec: Spec, value: object) -> Any:
    """Return value converted to the parameter's kind, or raise InvalidParameter."""
    if spec.kind == 'string':
        if not isinstance(value, str):
            raise InvalidParameter(spec.name, '%s must be a string, got %r'
                                   % (spec.name, value))
        return value
    if spec.kind == 'bool':
        if not isinstance(value, bool):
            raise InvalidParameter(spec.name, '%s must be true or false, got %r'
                                   % (spec.name, value))
        return value
    if spec.kind == 'integer':
        if not isinstance(value, int) or isinstance(value, bool):
            raise InvalidParameter(spec.name, '%s must be an integer, got %r'
                                   % (spec.name, value))
        return int(value)
    if spec.kind == 'double':
        if not _is_number(value):
            raise InvalidParameter(spec.name, '%s must be a number, got %r'
                                   % (spec.name, value))
        number = float(value)  # type: ignore[arg-type]  # a number, checked above
        if not math.isfinite(number):
            raise InvalidParameter(spec.name, '%s must be finite, got %r'
                                   % (spec.name, number))
        return number
    if value is None:
        return ()
    if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
        raise InvalidParameter(spec.name, '%s must be a list, got %r' % (spec.name, value))
    items = list(value)
    if spec.kind == 'string_array':
        if not all(isinstance(item, str) for item in items):
            raise InvalidParameter(spec.name, '%s must be a list of strings, got %r'
                                   % (spec.name, items))
        return tuple(items)
    if not all(_is_number(item) for item in items):
        raise InvalidParameter(spec.name, '%s must be a list of numbers, got %r'
                               % (spec.name, items))
    numbers = tuple(float(item) for item in items)
    bad = [i for i, item in enumerate(numbers) if not math.isfinite(item)]
    if bad:
        raise InvalidParameter(spec.name, '%s[%d] is %r: values must be finite'
                               % (spec.name, bad[0], numbers[bad[0]]), index=bad[0])
    return numbers


# ---------------------------------------------------------------- checks of one value

def frame_name(name: str, value: str) -> None:
    """Refuse what tf2 cannot take as a frame id: empty, with whitespace, or a leading '/'."""
    if not value:
        raise InvalidParameter(name, '%s must not be empty' % name)
    if value.startswith('/') or any(character.isspace() for character in value):
        raise InvalidParameter(name, "%s %r is not a frame id: tf2 takes no leading '/' and "
                               'no whitespace' % (name, value))


def triples(name: str, value: tuple) -> None:
    """Refuse a flat list that is not x, y, z per point."""
    if len(value) % 3:
        raise InvalidParameter(name, '%s must hold x, y, z per obstacle: %d values is not a '
                               'multiple of 3' % (name, len(value)))


def lengths(name: str, value: float | tuple) -> None:
    """Refuse a length the core cannot take (core.limits): each 0 or a supported length."""
    values = np.atleast_1d(np.asarray(value, dtype=float))
    bad = np.flatnonzero(~lengths_in_range(values, zero=True))
    if bad.size:
        raise InvalidParameter(name, '%s: every value must be %s, got %r'
                               % (name, length_range(zero=True), float(values[bad[0]])),
                               index=int(bad[0]) if np.ndim(value) else None)


def ros_names(name: str, value: tuple) -> None:
    """Refuse names that are not unique relative ROS names."""
    for index, item in enumerate(value):
        if not _NAME.match(item):
            raise InvalidParameter(name, '%s: %r is not a valid relative ROS name'
                                   % (name, item), index=index)
    if len(set(value)) != len(value):
        raise InvalidParameter(name, '%s must be unique, got %r' % (name, list(value)))


def within(low: float, high: float) -> Callable[[str, tuple], None]:
    """Return the check that every value of a list is in [low, high]."""
    def check(name: str, value: tuple) -> None:
        bad = [i for i, item in enumerate(value) if not low <= item <= high]
        if bad:
            raise InvalidParameter(name, '%s[%d] = %r is outside [%g, %g]'
                                   % (name, bad[0], value[bad[0]], low, high), index=bad[0])
    return check


# ---------------------------------------------------------------- shared specs

FRAME_ID = Spec(
    'frame_id', 'string', 'map',
    'The planning frame: frame_id of every message the node publishes; inputs with a '
    'non-empty header.frame_id must name it.', check=frame_name,
    prose="non-empty, no whitespace, no leading '/'")
OBSTACLES = Spec(
    'obstacles', 'double_array', [],
    'Obstacle centres as a flat list x0, y0, z0, x1, y1, z1, ...; for planner_node the '
    "latest of this parameter and the 'obstacles' topic is the obstacle set.",
    check=triples, prose='length a multiple of 3, finite values')
ROBOT_RADIUS = Spec(
    'robot_radius', 'double', 0.0,
    'Radius R of every robot (m): robots are discs (balls for dimension 3) and the gap of '
    'two robots is their centre distance - 2R; planner_node refuses overlapping bodies, '
    'and its min_gap and required_clearance are surface gaps.', low=0.0, high=1e6,
    check=lengths)
OBSTACLE_RADIUS = Spec(
    'obstacle_radius', 'double_array', [],
    'Radius rho of the obstacles (m): empty for 0, one value for all, or one per obstacle '
    'in obstacle order; a robot-obstacle gap is centre distance - R - rho.',
    check=lengths, prose='empty, one value or one per obstacle; each 0 or in [1e-100, 1e15]')


# ---------------------------------------------------------------- tables

S = TypeVar('S')


class Table(Generic[S]):
    """
    A node's parameters: the specs of a settings dataclass, and the settings from values.

    ``checks`` are the cross-parameter rules: each takes the settings and
    raises InvalidParameter with the reason.
    """

    def __init__(self, node_name: str, settings_type: type[S],
                 checks: tuple[Callable[[S], None], ...] = ()) -> None:
        """Read the specs from the fields of settings_type (made by Spec.field)."""
        self.node_name = node_name
        self.settings_type = settings_type
        self.specs: tuple[Spec, ...] = tuple(
            item.metadata['spec'] for item in dataclasses.fields(settings_type))  # type: ignore
        for item, spec in zip(dataclasses.fields(settings_type), self.specs):  # type: ignore
            assert item.name == spec.name, (item.name, spec.name)
        self.by_name = {spec.name: spec for spec in self.specs}
        self._checks = checks

    def check_files(self, arguments: Sequence[str]) -> None:
        """
        Raise InvalidParameterFile for a --params-file of the command line the node cannot use.

        rcl refuses a file it cannot parse, with a traceback; a node starts on its
        defaults from files none of whose sections applies to it (a misspelt section
        name), and ignores a misspelt name in its own section (robot_radiuss). All are
        refused here with the reason, as ``punctured-planner plan --params`` refuses
        them (load_parameter_file); one file of several may be other nodes' alone.
        The values are the node's to check when it declares them. A command line that
        renames the node (__node:=) is not checked: its sections carry the new name.
        Sections are matched against the node's full name as rcl matches them, its
        namespace from the command line's __ns:= (a section for /other/planner_node
        started a node in / on its defaults).
        """
        arguments = list(arguments)
        # -r __node:=NAME, or -r planner_node:__node:=NAME for this node alone
        if any('__node:=' in argument or '__name:=' in argument for argument in arguments):
            return
        # -r __ns:=/NS, or -r planner_node:__ns:=/NS; the last one counts
        namespaces = [argument.split('__ns:=', 1)[1] for argument in arguments
                      if '__ns:=' in argument]
        namespace = namespaces[-1] if namespaces else '/'
        paths = [arguments[i + 1] for i, argument in enumerate(arguments[:-1])
                 if argument == '--params-file']
        applies = not paths
        for path in paths:
            try:
                read = read_parameter_file(path, self, namespace)
            except OSError as error:
                raise InvalidParameterFile([path], '--params-file %s: %s'
                                           % (path, error.strerror)) from None
            except yaml.YAMLError as error:
                raise InvalidParameterFile([path], '--params-file %s: not YAML: %s' % (
                    path, ' '.join(str(error).split()))) from None
            applies = applies or read.applies
            unknown = self._first_unknown(read.values)
            if unknown is not None:
                raise InvalidParameterFile([path], '%s: %s' % (path, self._unknown(unknown)),
                                           parameter=unknown)
        if not applies:
            raise InvalidParameterFile(paths, '--params-file %s: %s'
                                       % (', '.join(paths), _no_section(self, namespace)))

    def settings(self, values: dict) -> S:
        """
        Return the settings of parameter values (missing names keep their defaults).

        Raises InvalidParameter (a ValueError) whose message is the reason a value is
        refused; unknown names are refused too.
        """
        unknown = self._first_unknown(values)
        if unknown is not None:
            raise InvalidParameter(unknown, self._unknown(unknown))
        settings = self.settings_type(**{name: self.by_name[name].value(value)
                                         for name, value in values.items()})
        for check in self._checks:
            check(settings)
        return settings

    def _first_unknown(self, names: Iterable[str]) -> str | None:
        """Return the first of names (sorted) that is none of the node's parameters, if any."""
        return min(set(names) - set(self.by_name), default=None)

    def _unknown(self, name: str) -> str:
        """Return the reason an unknown parameter name is refused, naming the known ones."""
        return 'unknown parameter %r of %s (parameters: %s)' % (
            name, self.node_name, ', '.join(self.by_name))


class NodeParameters(Generic[S]):
    """
    A table bound to a node: declared, validated in on-set, applied in post-set.

    :attr:`settings` is always the node's accepted settings; ``apply(settings,
    changed names)``, when given, takes them further into the node;
    it runs in the post-set callback, so a change it cannot take is logged,
    never raised into the parameter service. ``check(settings, changed
    names)``, when given, is what the node adds to the table's checks (its own
    state against the new settings): a ValueError refuses the change in on-set.
    A parameter is never deleted: rclpy would undeclare it, and every later
    change would fail on it.
    """

    def __init__(self, node: Any, table: Table[S],
                 apply: Callable[[S, set[str]], None] | None = None,
                 check: Callable[[S, set[str]], None] | None = None) -> None:
        """Declare every parameter; raise ValueError for invalid start values."""
        self._node = node
        self._table = table
        self._apply = apply
        self._check = check
        self._retyping = False
        for spec in table.specs:
            node.declare_parameter(spec.name, spec.default, spec.descriptor())
        self.settings: S = table.settings(self.values())
        self._retype(table.by_name)
        self._check_robot_topics(self.settings, table.by_name)
        if check is not None:
            check(self.settings, set(table.by_name))
        node.add_on_set_parameters_callback(self._on_set)
        node.add_post_set_parameters_callback(self._after_set)

    def _retype(self, names: Iterable[str]) -> None:
        """
        Give the named parameters their spec's type where they arrived with another.

        Doubles and lists take other types on purpose (dynamic typing: ``ros2 param set
        ... robot_radius 1`` is an integer, ``[]`` a byte or bool array, and a start
        value may be either), checked by Spec.value; but then ``ros2 param get`` and
        describe_parameters said integer or bool array where msg_docs says double. An
        empty list default rclpy types as a byte array, and ``[]`` in a parameter file
        leaves the parameter unset: ``ros2 param dump`` wrote null, and loading that dump
        was refused. Not read-only ones: rclpy keeps those.
        """
        from rclpy.parameter import Parameter  # the node's: rclpy is loaded
        # rclpy's Parameter.Type values are rcl_interfaces' ParameterType's (_KINDS)
        retyped = []
        for name in names:
            spec = self._table.by_name[name]
            wanted = Parameter.Type(_KINDS[spec.kind])
            if spec.read_only or self._node.get_parameter(name).type_ == wanted:
                continue
            value = getattr(self.settings, name)
            retyped.append(Parameter(name, wanted,
                                     list(value) if spec.kind.endswith('_array') else value))
        if retyped:
            self._retyping = True  # the same values: the post-set below applies them
            try:
                self._node.set_parameters(retyped)
            finally:
                self._retyping = False

    def values(self, change: Iterable[Any] = ()) -> dict:
        """Return the node's parameter values, with a proposed change (rclpy Parameters)."""
        values = {name: self._node.get_parameter(name).value for name in self._table.by_name}
        values.update({p.name: p.value for p in change if p.name in self._table.by_name})
        return values

    def _on_set(self, parameters: list) -> SetParametersResult:
        """Refuse a deletion, or a change that makes the settings invalid, with the reason."""
        deleted = [p.name for p in parameters if p.name in self._table.by_name
                   and p.type_.value == ParameterType.PARAMETER_NOT_SET]
        if deleted:
            return SetParametersResult(successful=False, reason=(
                '%s cannot be deleted: set a value instead (an empty list [] where none is '
                'allowed)' % ', '.join(deleted)))
        try:
            settings = self._table.settings(self.values(parameters))
            self._check_robot_topics(settings, {p.name for p in parameters})
            if self._check is not None:
                self._check(settings, {p.name for p in parameters})
        except ValueError as error:
            return SetParametersResult(successful=False, reason=str(error))
        return SetParametersResult(successful=True)

    def _check_robot_topics(self, settings: S, names: Iterable[str]) -> None:
        """
        Raise InvalidParameter for a robot name whose topics rcl refuses in the namespace.

        Of the parameters names (those set; all at declaration) that hold robot names:
        refused in on-set and at declaration, before any subscription is replaced
        (robot_topics_refused).
        """
        for name in names:
            spec = self._table.by_name.get(name)
            if spec is None or spec.check is not ros_names:
                continue
            for index, robot in enumerate(getattr(settings, spec.name)):
                refused = robot_topics_refused(self._node, robot)
                if refused:
                    raise InvalidParameter(spec.name, '%s[%d]: %s' % (spec.name, index, refused),
                                           index=index)

    def _after_set(self, parameters: list) -> None:
        """Take the accepted values into the settings and the node."""
        try:
            self.settings = self._table.settings(self.values())
            if self._retyping:
                return
            changed = {p.name for p in parameters}
            self._retype(changed & set(self._table.by_name))
            if self._apply is not None:
                self._apply(self.settings, changed)
        except Exception as error:  # a parameter change never stops the node
            self._node.get_logger().error('applying parameters failed: %r' % error)
            return
        self._node.get_logger().info('parameters set: %s' % ', '.join(
            '%s=%r' % (p.name, p.value) for p in parameters))


# The longest of a robot's topic names (ros.topics): if it resolves, every one does.
_LONGEST_ROBOT_TOPIC = max(ROBOT_TOPICS, key=len)


def robot_topics_refused(node: Any, robot: str) -> str:
    """
    Return why rcl refuses the topics of robot in node's namespace, '' when it takes them.

    A relative name (ros_names) can still make a topic longer than rcl allows (247
    characters) once the node's namespace is put before it.
    """
    try:
        node.resolve_topic_name(robot_topic(robot, _LONGEST_ROBOT_TOPIC))
    except Exception as error:  # noqa: B902 - rclpy's RCLError, not exported
        return ('the topics of robot %r are no valid topic names in namespace %s: %s'
                % (robot, node.get_namespace(), rcl_reason(error)))
    return ''


# The section names that stand for any node (and, '**', any namespace too).
_WILDCARDS = ('*', '**')
# Parameters rclpy declares on every node: a file may set them; they are not ours.
RCLPY_PARAMETERS = ('use_sim_time', 'start_type_description_service')


@dataclass(frozen=True)
class FileValues:
    """One node's values from a parameter file, and whether any section of it applies."""

    values: dict
    applies: bool   # a section names the node or /** (also nested: ns: {node: })


def load_parameter_file(path: str, table: Table) -> dict:
    """
    Return one node's parameter values from a ROS 2 parameter YAML file.

    As read_parameter_file; raises InvalidParameterFile for a file none of whose
    sections applies to the node, too.
    """
    read = read_parameter_file(path, table)
    if not read.applies:
        raise InvalidParameterFile([path], '%s: %s' % (path, _no_section(table)))
    return read.values


def _no_section(table: Table, namespace: str | None = None) -> str:
    """Return the reason a file is not the node's: no section names it (in namespace)."""
    where = '' if namespace is None else ' in namespace %s' % namespace
    return 'no section applies to %s%s (/** or %s)' % (table.node_name, where,
                                                       table.node_name)


def rcl_reason(error: BaseException) -> str:
    """Return rcl's (or rclpy's) error text without its source locations (', at ...')."""
    return str(error).split(', at ')[0]


def _section_pattern(key: str) -> re.Pattern:
    """
    Return the full node names a section key applies to, as rcl reads the key.

    A leading '/' is implied; '*' is one name of the path, '**' any number of them.
    """
    tokens = ['(/[^/]+)*' if token == '**' else '/[^/]+' if token == '*'
              else '/' + re.escape(token) for token in key.strip('/').split('/')]
    return re.compile(''.join(tokens))


def _node_of(key: str) -> str:
    """Return the node name a section key ends with (a wildcard for every node)."""
    return key.rstrip('/').split('/')[-1]


def _applies(key: str, node_name: str, namespace: str | None) -> bool:
    """
    Return whether the section key applies to node_name in namespace.

    namespace None: in any namespace (``punctured-planner plan``, which has none): the
    key's last name is the node's or a wildcard.
    """
    if namespace is None:
        return _node_of(key) in (node_name, *_WILDCARDS)
    full_name = '/'.join(['', *namespace.strip('/').split('/'), node_name]).replace('//', '/')
    return _section_pattern(key).fullmatch(full_name) is not None


def _sections(data: dict, prefix: str = '') -> Iterator[tuple[str, Any]]:
    """
    Yield (name, section) of a parameter file's mapping, nested namespaces joined by '/'.

    A mapping of mappings without ros__parameters is a namespace (rcl's nested form);
    anything else is a node's section, or a malformed one (a value before any
    ros__parameters, as a misspelt ros_parameters makes: its reader refuses it, as rcl
    refuses the file).
    """
    for key, section in data.items():
        name = prefix + str(key)
        if (isinstance(section, dict) and section and 'ros__parameters' not in section
                and all(isinstance(inner, dict) for inner in section.values())):
            yield from _sections(section, name.rstrip('/') + '/')
        else:
            yield name, section


def read_parameter_file(path: str, table: Table,
                        namespace: str | None = None) -> FileValues:
    """
    Return one node's parameter values from a ROS 2 parameter YAML file.

    Sections that apply to the node in namespace (None: any, _applies) are merged in
    file order, each key read as rcl reads it (_section_pattern: ``/**``,
    ``/**/planner_node``, ``/*``, ``/ns/planner_node``, ``planner_node`` for
    ``/planner_node``). As a node takes what it declares, a section whose node name is
    a wildcard gives only the table's parameters (the others are other nodes'), and rclpy's own
    (use_sim_time) are left out; a name the node's own section sets and the table
    lacks is kept (settings() refuses it: a typo). rcl's nested form (a namespace
    mapping to node sections, ``robots: {planner_node: {ros__parameters: ...}}``) is
    read as the name it spells (robots/planner_node). Raises InvalidParameterFile for a
    file that is not a ROS parameter file.
    """
    with open(path, encoding='utf-8') as stream:
        data = yaml.safe_load(stream) or {}
    if not isinstance(data, dict):
        raise InvalidParameterFile([path], '%s: not a ROS parameter file (a mapping of node '
                                   'names)' % path)
    values: dict = {}
    applied = False
    for key, section in _sections(data):
        # whichever node it is for: rcl refuses the whole file
        if not isinstance(section, dict) or 'ros__parameters' not in section:
            raise InvalidParameterFile([path], '%s: section %r has no ros__parameters'
                                       % (path, key))
        if not _applies(key, table.node_name, namespace):
            continue
        # a section for every node (its name a wildcard) holds other nodes' parameters too
        shared = _node_of(key) in _WILDCARDS
        applied = True
        parameters = section['ros__parameters'] or {}
        if not isinstance(parameters, dict):
            raise InvalidParameterFile([path], '%s: section %r: ros__parameters must map names '
                                       'to values, got %r' % (path, key, parameters))
        values.update((name, value) for name, value in parameters.items()
                      if name not in RCLPY_PARAMETERS
                      and (name in table.by_name or not shared))
    return FileValues(values, applied or not data)
