"""
The three node adapters: messages in, a ROS-free call, messages out.

``planner`` (``planner_node``: the PlanSequence service), ``executor``
(``plan_executor``: the ExecutePlan action) and ``fleet_sim`` (the simulated
fleet). Each runs through :func:`punctured_planner.ros.runtime.run_nodes`.
"""
