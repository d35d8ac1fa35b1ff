"""
A simulated fleet of disc robots, ROS-free (the ``fleet_sim`` node wraps it).

Each robot, holonomic or differential (a unicycle), integrates its commanded
velocity, applied after its command latency, reached within its acceleration
limit, saturated at the speed limit, scaled by its speed factor and perturbed
by velocity noise; the fleet keeps the true smallest surface gap
between bodies, exact over every step, and reports each new contact.
"""

from .fleet import Contact, Fleet, FleetSettings

__all__ = ['Contact', 'Fleet', 'FleetSettings']
