"""
Plain-data (YAML/JSON) <-> ROS message conversion without rosidl_runtime_py.

rosidl_runtime_py (what ``ros2 service call`` uses) is not on PyPI, so this
module does the same small job: it fills a message from nested dicts and lists
in the shape ``ros2 service call`` accepts, and turns a message back into
plain data.
"""

import array
import importlib
import re
from typing import Any

_SEQUENCE = re.compile(r'^sequence<(?P<inner>[^,>]+)(?:, *\d+)?>$')
_ARRAY = re.compile(r'^(?P<inner>[^\[]+)\[\d+\]$')


def _is_message(value: object) -> bool:
    return hasattr(type(value), 'get_fields_and_field_types')


def _message_class(type_name: str) -> type | None:
    """Return the class for a field type such as ``geometry_msgs/PoseArray``."""
    package, _, name = type_name.partition('/')
    if not name:
        return None
    return getattr(importlib.import_module(package + '.msg'), name)


def _element_type(type_name: str) -> str | None:
    for pattern in (_SEQUENCE, _ARRAY):
        match = pattern.match(type_name)
        if match:
            return match.group('inner').strip()
    return None


def _integer_range(type_name: str) -> tuple[int, int]:
    """Return (lowest, highest) of an IDL integer type name such as 'int32' or 'uint16'."""
    bits = int(''.join(c for c in type_name if c.isdigit()) or 8)
    if type_name.startswith('u') or type_name in ('octet', 'char'):
        return 0, 2 ** bits - 1
    return -2 ** (bits - 1), 2 ** (bits - 1) - 1


# A number in exponent form without a decimal point, which PyYAML leaves a string.
EXPONENT_NUMBER = re.compile(r'[-+]?(\d+\.?\d*|\.\d+)[eE][-+]?\d+')


def _convert_scalar(type_name: str, value: Any, where: str) -> Any:
    if type_name == 'boolean':
        if not isinstance(value, bool):
            raise ValueError('%s: expected true or false, got %r' % (where, value))
        return value
    if type_name in ('float', 'double'):
        if isinstance(value, str) and EXPONENT_NUMBER.fullmatch(value):
            return float(value)  # YAML 1.1 reads 1e-05 (JSON's) as a string; ros2 cli takes it
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ValueError('%s: expected a number, got %r' % (where, value))
        return float(value)
    if 'int' in type_name or type_name in ('octet', 'char'):
        if isinstance(value, bool) or not isinstance(value, int):
            raise ValueError('%s: expected an integer, got %r' % (where, value))
        low, high = _integer_range(type_name)
        if not low <= value <= high:
            raise ValueError('%s: %d is outside the range of %s' % (where, value, type_name))
        return value
    if 'string' in type_name:
        if not isinstance(value, str):
            raise ValueError('%s: expected a string, got %r' % (where, value))
        return value
    return value


def _convert(type_name: str, current: Any, value: Any, where: str) -> Any:
    element = _element_type(type_name)
    if element is not None:
        if not isinstance(value, (list, tuple)):
            raise ValueError('%s: expected a list, got %r' % (where, value))
        cls = _message_class(element)
        if cls is not None:
            return [fill_message(cls(), item, '%s[%d]' % (where, i))
                    for i, item in enumerate(value)]
        return [_convert_scalar(element, item, '%s[%d]' % (where, i))
                for i, item in enumerate(value)]
    if _is_message(current):
        return fill_message(current, value, where)
    return _convert_scalar(type_name, value, where)


def fill_message(msg: Any, data: Any, where: str = 'request') -> Any:
    """
    Set the fields of ``msg`` from a dict (nested dicts for nested messages).

    Fields not named keep their defaults. Unknown field names and values of the
    wrong kind raise ValueError naming the field.
    """
    if data is None:
        return msg
    if not isinstance(data, dict):
        raise ValueError('%s: expected a mapping of field names, got %r' % (where, data))
    fields = msg.get_fields_and_field_types()
    for key, value in data.items():
        if key not in fields:
            raise ValueError('%s: unknown field %r (fields: %s)'
                             % (where, key, ', '.join(fields)))
        field_where = '%s.%s' % (where, key)
        setattr(msg, key, _convert(fields[key], getattr(msg, key), value, field_where))
    return msg


def message_to_dict(msg: Any) -> Any:
    """
    Return ``msg`` as plain dicts, lists and scalars, for YAML.

    Non-finite floats stay floats: YAML writes them .inf and .nan, which read back as
    numbers (as text, 'inf' read back as a string).
    """
    if _is_message(msg):
        return {name: message_to_dict(getattr(msg, name))
                for name in msg.get_fields_and_field_types()}
    if isinstance(msg, (list, tuple, array.array)):
        return [message_to_dict(item) for item in msg]
    if hasattr(msg, 'tolist'):
        return msg.tolist()
    return msg


def constant_names(cls: type, value: int) -> list[str]:
    """Return the names of the integer constants of ``cls`` equal to ``value``."""
    return [name for name in dir(cls)
            if name.isupper() and not name.startswith('_')
            and isinstance(getattr(cls, name), int) and getattr(cls, name) == value]
