"""
punctured_planner: sequential collision-free motion planning in punctured R^d.

ROS-free parts: the math core :mod:`punctured_planner.core` (numpy only),
:mod:`~punctured_planner.execution`, :mod:`~punctured_planner.sim` and
:mod:`~punctured_planner.viz`. The ROS layer that is not a node is
:mod:`punctured_planner.ros`; the three nodes are :mod:`punctured_planner.nodes`.
The top level holds the entry points: ``cli``, ``demo`` and ``render``.
"""
