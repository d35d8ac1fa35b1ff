"""
The ROS layer that is not a node: QoS, conversions, parameters, publications, the runtime.

``qos`` (the topics' QoS profiles), ``conversions`` (every message <-> numpy
conversion and message builder), ``parameters`` (the parameter machinery and
each node's table), ``planning`` with ``snapshot``, ``checks`` and ``wording``
(one PlanSequence request against one snapshot), ``publications`` and
``markers`` (what a plan publishes), ``recording`` (MCAP), ``msg_dict``
(YAML <-> messages) and ``runtime`` (start, spin, stop a node process).
The nodes themselves are in :mod:`punctured_planner.nodes`.
"""
