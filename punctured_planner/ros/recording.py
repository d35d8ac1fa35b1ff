"""
A plan as an MCAP recording: what the node would publish, for Foxglove and ``ros2 bag``.

The file follows the MCAP ``ros2`` profile: CDR messages serialised by the
real ROS 2 type support (``rclpy.serialization``), one schema per type in the
``ros2msg`` encoding whose text is the complete message definition assembled
from the installed ``.msg`` files (the top-level definition, then every nested
type after a line of 80 ``=`` and ``MSG: pkg/msg/Type``, as rosbag2 writes it).

Channels (absolute topic names, as ``ros2 bag`` records them):

* ``/<robot_name>/plan`` nav_msgs/msg/Path, one per robot;
* ``/plan_markers`` visualization_msgs/msg/MarkerArray;
* ``/domain_index`` std_msgs/msg/UInt32;
* ``/plan`` punctured_planner_interfaces/msg/Plan (plan_id 0: not published by a node).

Every message is logged at the plan's start stamp. A metadata record
``punctured_planner`` carries the plan's figures (domain, clearance, ...).
"""

from collections.abc import Iterable
from collections.abc import Mapping
from collections.abc import Sequence
import importlib
import os
import re

import numpy as np

from .settings import PlannerSettings
from .snapshot import Outcome
from ..outputs import replacing

_SEPARATOR = '=' * 80
_PRIMITIVES = {'bool', 'byte', 'char', 'float32', 'float64', 'int8', 'uint8', 'int16',
               'uint16', 'int32', 'uint32', 'int64', 'uint64', 'string', 'wstring'}
_FIELD = re.compile(r'^\s*(?P<type>[A-Za-z][\w/]*)(?P<array>\[[^\]]*\])?(?:<=\d+)?\s+\w+')


def _share_prefixes(package: str) -> list[str]:
    """Return the install prefixes where ``share/<package>`` may be, best first."""
    prefixes = [p for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p]
    try:
        module = importlib.import_module(package)
        if module.__file__ is not None:  # None for a namespace package (a source tree)
            # <prefix>/lib/pythonX.Y/site-packages/<package>/__init__.py
            here = os.path.dirname(os.path.abspath(module.__file__))
            prefixes.append(os.path.dirname(os.path.dirname(os.path.dirname(
                os.path.dirname(here)))))
    except ImportError:
        pass
    return prefixes


def message_definition_file(type_name: str) -> str:
    """Return the path of the installed .msg file of ``pkg/msg/Type``; raise LookupError."""
    package, _, name = type_name.split('/')
    for prefix in _share_prefixes(package):
        path = os.path.join(prefix, 'share', package, 'msg', name + '.msg')
        if os.path.isfile(path):
            return path
    raise LookupError('no installed definition %s.msg for %s' % (name, type_name))


def _dependencies(text: str, package: str) -> list[str]:
    """Return the complex field types of a .msg text as 'pkg/msg/Type' names, in order."""
    found = []
    for line in text.splitlines():
        line = line.split('#', 1)[0]
        match = _FIELD.match(line)
        if not match:
            continue  # blank, comment; constants and defaults have primitive types
        field_type = match.group('type')
        if field_type in _PRIMITIVES:
            continue
        if '/' in field_type:
            pkg, _, name = field_type.rpartition('/')
            pkg = pkg.split('/')[0]
        else:
            pkg, name = package, field_type
        full = '%s/msg/%s' % (pkg, name)
        if full not in found:
            found.append(full)
    return found


def message_definition(type_name: str) -> str:
    """
    Return the complete ros2msg definition text of ``pkg/msg/Type``.

    The type's own .msg text first, then each nested type once (depth first)
    after an 80-character ``=`` line and ``MSG: pkg/msg/Type``.
    """
    texts: dict[str, str] = {}
    order: list[str] = []

    def visit(name: str) -> None:
        with open(message_definition_file(name), encoding='utf-8') as stream:
            text = stream.read()
        texts[name] = text
        for dependency in _dependencies(text, name.split('/')[0]):
            if dependency not in texts:
                order.append(dependency)
                visit(dependency)

    visit(type_name)
    parts = [texts[type_name].rstrip('\n')]
    for name in order:
        parts.append('%s\nMSG: %s\n%s' % (_SEPARATOR, name, texts[name].rstrip('\n')))
    return '\n'.join(parts) + '\n'


def _type_name(msg_type: type) -> str:
    """Return 'pkg/msg/Type' of a generated ROS 2 message class."""
    return '%s/msg/%s' % (msg_type.__module__.split('.')[0], msg_type.__name__)


def write_mcap(path: str | os.PathLike[str], messages: Iterable[tuple[str, object]],
               log_time_ns: int | Sequence[int],
               metadata: Mapping[str, object] | None = None) -> str | os.PathLike[str]:
    """
    Write [(topic, message)] to an MCAP file at ``path``; return the path.

    A message is a ROS message, serialised by rclpy (exact CDR), or a
    :class:`punctured_planner.ros.publications.Publication` (recorded as the node
    publishes it, perhaps bytes already). Each is logged at
    ``log_time_ns``: one time for all, or a sequence with one per message;
    metadata (dict of str) goes into a ``punctured_planner`` metadata record.
    """
    from mcap.well_known import MessageEncoding
    from mcap.well_known import Profile
    from mcap.well_known import SchemaEncoding
    from mcap.writer import Writer

    from .publications import Publication

    schemas = {}
    channels = {}
    with replacing(path) as part, open(part, 'wb') as stream:
        writer = Writer(stream)
        writer.start(profile=Profile.ROS2, library='punctured_planner')
        for sequence, (topic, message) in enumerate(messages):
            if not isinstance(message, Publication):
                message = Publication(topic, type(message), message)
            type_name = _type_name(message.msg_type)
            if type_name not in schemas:
                schemas[type_name] = writer.register_schema(
                    name=type_name, encoding=SchemaEncoding.ROS2,
                    data=message_definition(type_name).encode('utf-8'))
            if topic not in channels:
                channels[topic] = writer.register_channel(
                    topic=topic, message_encoding=MessageEncoding.CDR,
                    schema_id=schemas[type_name])
            stamp = int(log_time_ns if isinstance(log_time_ns, (int, np.integer))
                        else log_time_ns[sequence])
            writer.add_message(channel_id=channels[topic], log_time=stamp,
                               publish_time=stamp, sequence=sequence,
                               data=message.serialized())
        if metadata:
            writer.add_metadata('punctured_planner',
                                {str(k): str(v) for k, v in metadata.items()})
        writer.finish()
    return path


def record_plan(path: str | os.PathLike[str], outcome: Outcome,
                settings: PlannerSettings) -> str | os.PathLike[str]:
    """Write a successful planning Outcome to an MCAP file (see the module docstring)."""
    planned = outcome.planned()
    p = planned.plan
    metadata = {
        'domain_index': p.domain_index, 'domain_count': p.domain_count,
        'domain': p.domain, 'sequential_complexity': p.sequential_complexity or 0,
        'optimal': p.optimal, 'min_clearance': repr(float(p.min_clearance)),
        'variant': p.variant, 'frame_id': settings.frame_id,
        'max_speed': outcome.max_speed, 'robots': ','.join(planned.names),
        'projection_counts': ','.join(str(int(c)) for c in p.projection_counts),
    }
    from .publications import plan_messages
    messages = [('/' + message.topic, message) for message in plan_messages(outcome, settings)]
    return write_mcap(path, messages, outcome.start_ns, metadata)
