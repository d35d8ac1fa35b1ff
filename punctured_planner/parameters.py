"""
Parameters of ``planner_node``: names, defaults, ranges, descriptions and validation.

One table (:data:`PARAMETERS`) drives everything: the node declares each entry
with a ParameterDescriptor, its on-set callback refuses a bad value with the
reason :func:`settings_from_values` gives (the old value stays), and the
offline ``punctured-planner plan --params FILE`` reads the same ROS parameter
file into the same :class:`Settings`. This module imports no rclpy at import
time, so the offline tools stay ROS-graph free.
"""

from dataclasses import dataclass
import math
import re

import yaml

from .core import VARIANTS

# The variant parameter's default: 'discs' with a robot radius, else 'spread'.
AUTO = 'auto'

NODE_NAME = 'planner_node'
# Largest samples_per_leg a parameter or a request may ask for.
MAX_SAMPLES_PER_LEG = 1000
# Names usable as the first token of '<name>/plan' and '<name>/odom'.
_NAME = re.compile(r'^[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*$')


@dataclass(frozen=True)
class Spec:
    """One parameter: its name, kind, default, range (inclusive) and description."""

    name: str
    kind: str  # 'string', 'bool', 'integer', 'double', 'string_array', 'double_array'
    default: object
    description: str
    low: object = None
    high: object = None
    constraints: str = ''


PARAMETERS = (
    Spec('frame_id', 'string', 'map',
         'Planning frame: frame_id of the published paths and markers; inputs with a '
         'non-empty header.frame_id must name it.', constraints='non-empty'),
    Spec('dimension', 'integer', 2,
         'Dimension d of the planning space: 2 (planar, z fixed at plane_z) or 3.',
         low=2, high=3),
    Spec('plane_z', 'double', 0.0,
         'z of the plane in planar mode (dimension 2): every input z must equal it '
         '(within 1e-9).', low=-1e9, high=1e9),
    Spec('robot_names', 'string_array', [],
         "Robot names: '<name>/plan' topics and '<name>/odom' subscriptions, in robot "
         'order; empty: robot_0..robot_{k-1} and no odometry.',
         constraints='unique ROS names; robot_count must be 0 or their number'),
    Spec('robot_count', 'integer', 0,
         'Number of robots every request must have; 0: any (taken from the request), '
         'or the number of robot_names when they are set.', low=0, high=1000000),
    Spec('obstacles', 'double_array', [],
         'Obstacles as a flat list x0, y0, z0, x1, y1, z1, ...; the latest of this '
         "parameter and the 'obstacles' topic is the obstacle set.",
         constraints='length a multiple of 3, finite values'),
    Spec('variant', 'string', AUTO,
         "Planner variant: 'discs' (disc robots and pillars: bodies never touch under "
         "the separation condition of doc/design.md section 6), 'spread' (clearance-aware "
         "spreading leg) or 'paper' (the paper's construction exactly); all give the "
         "same domain index. 'auto': 'discs' when robot_radius > 0, else 'spread'.",
         constraints="'auto', 'discs', 'spread' or 'paper'"),
    Spec('robot_radius', 'double', 0.0,
         'Radius R of every robot (m): robots are discs (balls for dimension 3); then '
         'overlapping bodies are refused, min_gap is the surface gap and '
         'required_clearance applies to it.', low=0.0, high=1e6),
    Spec('obstacle_radius', 'double_array', [],
         'Radius of the obstacles (m): empty for 0, one value for all, or one per '
         'obstacle in obstacle order (then the obstacle set must have that many).',
         constraints='empty, one value or one per obstacle; finite, >= 0'),
    Spec('lane_spacing', 'double', 1.0,
         'Spacing of the lanes the robots slide along (m); 1 gives the paper heights.',
         low=1e-6, high=1e6),
    Spec('min_spacing', 'double', 0.5,
         'Spread variant: spacing g the spreading leg aims for between robots on the '
         'axis and from the obstacles (m).', low=1e-6, high=1e6),
    Spec('required_clearance', 'double', 0.0,
         'Refuse a plan whose certified minimum clearance is below this (m); 0 accepts '
         'every collision-free plan.', low=0.0, high=1e6),
    Spec('refine', 'bool', True,
         "Refine the construction's motion (doc/design.md section 14): shorter, in the "
         "same domain, its gap never below the construction's; false: the construction's "
         'own motion.', constraints='true or false'),
    Spec('max_state_age', 'double', 0.5,
         'Largest age (s, by arrival on the node clock) of the robot state a '
         'use_current_state request may start from; older is refused (NO_ROBOT_STATE). '
         '0 switches the check off: unsafe, a robot may be planned from where it was.',
         low=0.0, high=1e6),
    Spec('repeat_tolerance', 'double', 1e-3,
         'With use_current_state, leading request configurations whose every robot is '
         'within this distance (m) of the current state are dropped before planning '
         '(reported in dropped_configurations).', low=0.0, high=1e6),
    Spec('max_speed', 'double', 1.0,
         "Speed of the fastest robot on each leg (m/s) when a request's max_speed is "
         '<= 0.', low=1e-6, high=1e6),
    Spec('samples_per_leg', 'integer', 0,
         "Extra poses between consecutive breakpoints when a request's samples_per_leg "
         'is < 0.', low=0, high=MAX_SAMPLES_PER_LEG),
    Spec('max_robots', 'integer', 10000,
         'Largest number of robots a request may have (REQUEST_OVER_LIMITS above).',
         low=1, high=1000000),
    Spec('max_configurations', 'integer', 1000,
         'Largest number of configurations in a request, the current state included '
         '(REQUEST_OVER_LIMITS above).', low=2, high=1000000),
    Spec('max_poses', 'integer', 2000000,
         'Largest number of poses in all paths of one answer, robots x poses per path '
         '(REQUEST_OVER_LIMITS above).', low=1, high=1000000000),
)
SPECS = {spec.name: spec for spec in PARAMETERS}


@dataclass(frozen=True)
class Settings:
    """A validated, immutable set of parameter values (one snapshot of the node's)."""

    frame_id: str = 'map'
    dimension: int = 2
    plane_z: float = 0.0
    robot_names: tuple = ()
    robot_count: int = 0
    obstacles: tuple = ()
    variant: str = AUTO
    robot_radius: float = 0.0
    obstacle_radius: tuple = ()
    lane_spacing: float = 1.0
    min_spacing: float = 0.5
    required_clearance: float = 0.0
    refine: bool = True
    max_state_age: float = 0.5
    repeat_tolerance: float = 1e-3
    max_speed: float = 1.0
    samples_per_leg: int = 0
    max_robots: int = 10000
    max_configurations: int = 1000
    max_poses: int = 2000000

    @property
    def core_variant(self) -> str:
        """Return the core variant to plan with: 'auto' resolved by robot_radius."""
        if self.variant != AUTO:
            return self.variant
        return 'discs' if self.robot_radius > 0 else 'spread'

    def obstacle_radii(self, obstacle_count: int) -> float | tuple:
        """Return the core's obstacle_radius for r obstacles: a scalar, or one per obstacle."""
        if len(self.obstacle_radius) <= 1:
            return self.obstacle_radius[0] if self.obstacle_radius else 0.0
        return self.obstacle_radius

    @property
    def expected_robot_count(self):
        """Return the robot count requests must have, or 0 when any count is fine."""
        return len(self.robot_names) or self.robot_count


def _is_number(value):
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _coerce(spec, value):
    """Return value converted to the parameter's kind, or raise ValueError with a reason."""
    if spec.kind == 'string':
        if not isinstance(value, str):
            raise ValueError('%s must be a string, got %r' % (spec.name, value))
        return value
    if spec.kind == 'bool':
        if not isinstance(value, bool):
            raise ValueError('%s must be true or false, got %r' % (spec.name, value))
        return value
    if spec.kind == 'integer':
        if not isinstance(value, int) or isinstance(value, bool):
            raise ValueError('%s must be an integer, got %r' % (spec.name, value))
        return int(value)
    if spec.kind == 'double':
        if not _is_number(value):
            raise ValueError('%s must be a number, got %r' % (spec.name, value))
        value = float(value)
        if not math.isfinite(value):
            raise ValueError('%s must be finite, got %r' % (spec.name, value))
        return value
    if value is None:
        return ()
    if isinstance(value, (str, bytes)) or not hasattr(value, '__iter__'):
        raise ValueError('%s must be a list, got %r' % (spec.name, value))
    items = list(value)
    if spec.kind == 'string_array':
        if not all(isinstance(item, str) for item in items):
            raise ValueError('%s must be a list of strings, got %r' % (spec.name, items))
        return tuple(items)
    if not all(_is_number(item) for item in items):
        raise ValueError('%s must be a list of numbers, got %r' % (spec.name, items))
    numbers = tuple(float(item) for item in items)
    bad = [i for i, item in enumerate(numbers) if not math.isfinite(item)]
    if bad:
        raise ValueError('%s[%d] is %r: values must be finite'
                         % (spec.name, bad[0], numbers[bad[0]]))
    return numbers


def _check_value(spec, value):
    """Raise ValueError with a reason if value is outside the parameter's range."""
    if spec.low is not None and not spec.low <= value <= spec.high:
        raise ValueError('%s must be in [%s, %s], got %r'
                         % (spec.name, spec.low, spec.high, value))
    if spec.name == 'frame_id' and not value:
        raise ValueError('frame_id must not be empty')
    if spec.name == 'variant' and value not in (AUTO,) + VARIANTS:
        raise ValueError('variant must be one of %s, got %r'
                         % (', '.join((AUTO,) + VARIANTS), value))
    if spec.name == 'obstacle_radius' and any(radius < 0 for radius in value):
        raise ValueError('obstacle_radius values must be >= 0, got %r' % (list(value),))
    if spec.name == 'obstacles' and len(value) % 3:
        raise ValueError('obstacles must hold x, y, z per obstacle: %d values is not a '
                         'multiple of 3' % len(value))
    if spec.name == 'robot_names':
        for name in value:
            if not _NAME.match(name):
                raise ValueError('robot_names: %r is not a valid relative ROS name' % name)
        if len(set(value)) != len(value):
            raise ValueError('robot_names must be unique, got %r' % (list(value),))


def settings_from_values(values):
    """
    Return Settings from a dict of parameter values (missing names keep their defaults).

    Raises ValueError whose message is the reason a value is refused; unknown
    names are refused too.
    """
    merged = {}
    for name, value in values.items():
        if name not in SPECS:
            raise ValueError('unknown parameter %r (parameters: %s)'
                             % (name, ', '.join(SPECS)))
        spec = SPECS[name]
        merged[name] = _coerce(spec, value)
        _check_value(spec, merged[name])
    settings = Settings(**merged)
    if settings.robot_names and settings.robot_count not in (0, len(settings.robot_names)):
        raise ValueError('robot_count %d differs from the %d robot_names; set robot_count to '
                         '0 or to their number' % (settings.robot_count,
                                                   len(settings.robot_names)))
    if settings.expected_robot_count > settings.max_robots:
        raise ValueError('%d robots configured but max_robots is %d'
                         % (settings.expected_robot_count, settings.max_robots))
    return settings


def load_parameter_file(path, node_name=NODE_NAME):
    """
    Return the planner's parameter values from a ROS 2 parameter YAML file.

    Sections that apply to the node are merged in file order: ``/**``, the node's
    name with or without a leading slash or namespace. Raises ValueError for a
    file that is not a ROS parameter file.
    """
    with open(path, encoding='utf-8') as stream:
        data = yaml.safe_load(stream) or {}
    if not isinstance(data, dict):
        raise ValueError('%s: not a ROS parameter file (a mapping of node names)' % path)
    values: dict = {}
    for key, section in data.items():
        key = str(key)
        applies = key in ('/**', '**') or key.rstrip('/').split('/')[-1] == node_name
        if not applies:
            continue
        if not isinstance(section, dict) or 'ros__parameters' not in section:
            raise ValueError('%s: section %r has no ros__parameters' % (path, key))
        values.update(section['ros__parameters'] or {})
    return values


def node_values(node, specs, change=()) -> dict:
    """
    Return a node's values of the parameters named in specs, with change applied.

    change is the list of rclpy Parameters an on-set callback receives; the
    caller validates the result (its own settings_from_values).
    """
    values = {name: node.get_parameter(name).value for name in specs}
    values.update({p.name: p.value for p in change if p.name in specs})
    return values


def descriptor(spec, read_only=False):
    """Return the rcl_interfaces ParameterDescriptor of a parameter (imports rclpy types)."""
    from rcl_interfaces.msg import FloatingPointRange
    from rcl_interfaces.msg import IntegerRange
    from rcl_interfaces.msg import ParameterDescriptor
    from rcl_interfaces.msg import ParameterType

    kinds = {
        'string': ParameterType.PARAMETER_STRING,
        'bool': ParameterType.PARAMETER_BOOL,
        'integer': ParameterType.PARAMETER_INTEGER,
        'double': ParameterType.PARAMETER_DOUBLE,
        'string_array': ParameterType.PARAMETER_STRING_ARRAY,
        'double_array': ParameterType.PARAMETER_DOUBLE_ARRAY,
    }
    result = ParameterDescriptor(name=spec.name, type=kinds[spec.kind],
                                 description=spec.description,
                                 additional_constraints=spec.constraints,
                                 read_only=read_only)
    # Doubles accept YAML integers (plane_z: 0) and arrays accept [] (an untyped
    # empty list): their type is checked by settings_from_values instead.
    result.dynamic_typing = spec.kind in ('double', 'string_array', 'double_array')
    if spec.kind == 'integer' and spec.low is not None:
        result.integer_range = [IntegerRange(from_value=spec.low, to_value=spec.high, step=1)]
    if spec.kind == 'double' and spec.low is not None:
        result.floating_point_range = [FloatingPointRange(from_value=float(spec.low),
                                                          to_value=float(spec.high),
                                                          step=0.0)]
    return result


def parameter_value(spec, value):
    """Return value converted to the parameter's kind and checked; raise ValueError (reason)."""
    value = _coerce(spec, value)
    _check_value(spec, value)
    return value
