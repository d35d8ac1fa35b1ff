"""
punctured_planner: sequential collision-free motion planning in punctured R^d.

The math core lives in :mod:`punctured_planner.core` (numpy only, no ROS); the
node, message conversions and command-line client sit beside it.
"""
