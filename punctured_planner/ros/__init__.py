"""
The ROS layer that is not a node: QoS, conversions, parameters, publications, the runtime.

``runtime`` (start, spin and stop a node process), ``qos`` (the topics' QoS
profiles), ``parameters`` (the parameter machinery) and ``settings`` (each
node's table), ``conversions`` and ``cdr`` (every message <-> numpy
conversion and message builder), ``snapshot``, ``checks``, ``wording`` and
``planning`` (one PlanSequence request against one snapshot), ``goals``
(plan_executor's plans and robot state), ``publications`` and ``markers``
(what a plan publishes), ``topics`` (each robot's topic names), ``recording``
(MCAP) and ``msg_dict`` (YAML <-> messages). The nodes themselves are in
:mod:`punctured_planner.nodes`.
"""
