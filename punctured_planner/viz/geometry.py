"""
What the pictures draw, in the plan's own coordinates: axis, lanes, legs, closest approach.

A PlaneView maps points of R^d to a drawing plane: the coordinate plane
(x, y) for d <= 3 (the top view when d = 3), the frame plane (e1, e2) for d > 3.
Lines of R^d stay lines there, so the e1 axis and the lanes are drawn as lines.
"""

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ..core import Plan


@dataclass(frozen=True, eq=False)
class PlaneView:
    """Orthogonal projection onto origin + span(u, v); labels name the two axes."""

    origin: np.ndarray
    u: np.ndarray
    v: np.ndarray
    labels: tuple

    def __call__(self, points: npt.ArrayLike) -> np.ndarray:
        """Return the (..., 2) drawing coordinates of points (..., d)."""
        basis = np.stack([self.u, self.v], axis=1)
        return (np.asarray(points, dtype=float) - self.origin) @ basis


def plane_view(plan: Plan) -> PlaneView:
    """Return the PlaneView of a plan: (x, y) for d <= 3, the frame's (e1, e2) beyond."""
    d = plan.positions.shape[2]
    if d <= 3:
        eye = np.eye(d)
        return PlaneView(np.zeros(d), eye[0], eye[1], ('x', 'y'))
    frame = plan.frame
    return PlaneView(frame.origin, frame.e1, frame.e2, ('e1', 'e2'))


def waypoints(plan: Plan) -> np.ndarray:
    """Return the (n, k, d) configurations C_1..C_n as they sit in the plan."""
    return plan.positions[plan.waypoint_indices]


def moving_legs(points: np.ndarray, minimum_length: float) -> tuple[np.ndarray, np.ndarray]:
    """Return (starts, ends) of the legs of one robot's path (V, m) at least that long."""
    starts, ends = points[:-1], points[1:]
    long_enough = np.linalg.norm(ends - starts, axis=1) >= minimum_length
    return starts[long_enough], ends[long_enough]


def closest_approach(plan: Plan) -> np.ndarray | None:
    """
    Return the (2, d) centres of the certified closest approach, or None if there is none.

    With robot or obstacle radii, the pair with the smallest surface gap.
    """
    clearance = plan.gap if plan.workspace.has_bodies else plan.clearance
    if clearance.kind == 'none' or not np.isfinite(clearance.distance):
        return None
    positions = plan.position(clearance.tau)
    a, b = clearance.indices
    other = positions[b] if clearance.kind == 'robots' else plan.workspace.obstacles[b]
    return np.stack([positions[a], other])


def extent(points: npt.ArrayLike) -> float:
    """Return the largest side of the bounding box of points (..., m), at least 1."""
    flat = np.asarray(points).reshape(-1, np.asarray(points).shape[-1])
    return max(float(np.ptp(flat, axis=0).max()), 1.0)
