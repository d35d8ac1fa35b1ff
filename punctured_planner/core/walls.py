"""
Workspace bounds: the walls of an axis-aligned box and the signed slack of bodies to them.

The box is a (d, 2) array, [low, high] per axis, in the coordinates the
configurations come in (the request's x, y, z), not the core's frame, which
may be oblique. A body of radius R with centre x has the slack x_i - low_i - R
to the wall min of axis i and high_i - x_i - R to its wall max: the distance
of the centre to the wall minus R, so a disc is inside exactly when its
centre keeps R from every wall (slack >= 0). The slack is affine in x, so
along a leg, on which x is linear in tau, it is linear too and its minimum is
at one of the leg's ends: the breakpoints give the exact minimum over the
whole motion (doc/design.md section 17).
"""

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from .errors import axis_name, ErrorCode, PlanningError, Wall
from .limits import first_non_finite, first_out_of_range, MAX_COORDINATE


@dataclass(frozen=True)
class WallSlack:
    """
    The smallest wall slack found: where, which body, which wall, and its value.

    ``index`` is the position along the first axis of the positions searched
    (a configuration m, or for a motion its leg), ``body`` the robot or pillar;
    ``slack`` < 0 means the body reaches ``beyond`` = -slack past the wall.
    """

    index: int
    body: int
    wall: Wall
    slack: float

    @property
    def beyond(self) -> float:
        """Return how far the body reaches past the wall (> 0 when outside)."""
        return -self.slack

    def words(self, bounds: np.ndarray, centre: float, radius: float,
              radius_name: str) -> str:
        """
        Return the template 'D beyond {wall} = 5 (...)', centre the body's coordinate.

        The parenthesis gives the centre's coordinate, and the radius it must keep
        from the wall when the body has one.
        """
        keeps = f', which must keep {radius_name} {radius:.6g} from it' if radius > 0 else ''
        return (f'{self.beyond:.6g} beyond {{wall}} = '
                f'{self.wall.position(bounds):.6g} (centre {axis_name(self.wall.axis)} = '
                f'{centre:.6g}{keeps})')


def checked_bounds(bounds: npt.ArrayLike | None, dimension: int) -> np.ndarray | None:
    """
    Return bounds as a float (d, 2) array of [low, high] per axis, or None for none.

    Raises INVALID_REQUEST, saying which shape was expected and which arrived,
    for a non-finite value, a value beyond the supported range (core.limits), or
    for a low not below its high (the wall at fault as ``wall``: the non-finite
    one, the one out of range, or the low).
    """
    if bounds is None:
        return None
    try:
        array = np.asarray(bounds, dtype=float)
    except (TypeError, ValueError):
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            'bounds must be real numbers, [low, high] per axis',
                            option='bounds') from None
    if array.shape != (dimension, 2):
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            f'bounds must have shape (d, 2) = ({dimension}, 2), one '
                            f'[min, max] per axis; got shape {array.shape}', option='bounds')
    bad = first_non_finite(array)
    if bad is not None:
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            f'bounds must be finite; {{wall}} is {array[bad]}',
                            wall=Wall(bad[0], bool(bad[1])), option='bounds')
    far = first_out_of_range(array)
    if far is not None:
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            f'bounds: {{wall}} = {array[far]:.6g} is beyond the supported range '
                            f'+-{MAX_COORDINATE:.0e}', wall=Wall(far[0], bool(far[1])),
                            option='bounds')
    empty = np.flatnonzero(~(array[:, 0] < array[:, 1]))
    if empty.size:
        axis = int(empty[0])
        raise PlanningError(ErrorCode.INVALID_REQUEST,
                            f'bounds: {{wall}} = {array[axis, 0]:.6g} must be below '
                            f'{Wall(axis, True).name} = {array[axis, 1]:.6g}',
                            wall=Wall(axis, False), option='bounds')
    return array


def box_corners(bounds: np.ndarray) -> np.ndarray:
    """
    Return the (2^d, d) corners of the box bounds (d, 2).

    Corner i takes axis a's high wall where bit d - 1 - a of i is set, so two
    corners whose indices differ in one bit are the ends of one of the box's edges.
    """
    return np.stack(np.meshgrid(*bounds, indexing='ij'), axis=-1).reshape(-1, bounds.shape[0])


def line_section(bounds: np.ndarray, point: np.ndarray, direction: np.ndarray,
                 keep: float) -> tuple[float, float]:
    """
    Return (low, high): the t at which point + t direction keeps `keep` from every wall.

    Per axis a with direction_a != 0, l_a + keep <= point_a + t direction_a <= h_a - keep
    bounds t; low > high when those bounds leave no t. The walls of an axis the line
    runs parallel to are as far from every point of it, so they bound no t and are not
    looked at: a line beyond them gets the range the other walls leave.
    """
    axes = direction != 0.0
    inner = bounds[axes] + [keep, -keep]  # (a, 2): the walls, less keep
    ends = (inner - point[axes, None]) / direction[axes, None]
    return float(ends.min(axis=1).max()), float(ends.max(axis=1).min())


def _two_sum(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return (s, e): s = fl(a + b) and its rounding error, a + b = s + e exactly (Knuth)."""
    total = a + b
    virtual = total - a
    return total, (a - (total - virtual)) + (b - virtual)


def _exact_sign_sum(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """
    Return a + b + c rounded so that its sign (and zero) is the exact sum's.

    Shewchuk's grow-expansion turns the sum into three non-overlapping parts
    q, h1, h0 of decreasing magnitude; then q + (h1 + h0) cannot round across
    zero. A plain (x - low) - R can: a centre one ulp closer than R to a wall
    rounds to a slack of exactly 0.
    """
    high, low = _two_sum(a, b)
    partial, h0 = _two_sum(c, low)
    q, h1 = _two_sum(partial, high)
    return q + (h1 + h0)


def wall_slack(positions: npt.ArrayLike, bounds: np.ndarray,
               radius: npt.ArrayLike = 0.0) -> np.ndarray:
    """
    Return (..., k, d, 2) the signed slack of k centres (..., k, d) to the 2d walls.

    [..., i, a, 0] is the slack to the wall min of axis a, [..., i, a, 1] to its
    wall max; radius is one value or one per body (k,). Each slack is the exact
    x - low - R (or high - x - R) rounded once, with its exact sign: a body
    exactly R from a wall has slack 0, one closer a negative slack, however
    little closer.
    """
    positions = np.asarray(positions, dtype=float)
    radii = np.asarray(radius, dtype=float)
    if radii.ndim:
        radii = radii[:, None, None]
    centres = positions[..., None]
    signed = np.array([1.0, -1.0])
    return _exact_sign_sum(signed * centres, -signed * bounds,
                           np.broadcast_to(-radii, centres.shape[:-1] + (2,)))


def _slack_at(slack: np.ndarray, index: int, entry: int) -> WallSlack:
    """Return the WallSlack of slack (N, k, d, 2) at index and the flat entry of (k, d, 2)."""
    body, axis, side = np.unravel_index(entry, slack.shape[1:])
    return WallSlack(index, int(body), Wall(int(axis), bool(side)),
                     float(slack[index, body, axis, side]))


def first_outside(positions: npt.ArrayLike, bounds: np.ndarray,
                  radius: npt.ArrayLike = 0.0) -> WallSlack | None:
    """
    Return the worst body of the first of positions (N, k, d) with one outside, or None.

    Outside means a slack below 0 (wall_slack); in that first position the body
    and wall with the smallest slack are named, the first in order on a tie.
    """
    slack = wall_slack(positions, bounds, radius)
    flat = slack.reshape(len(slack), -1)
    outside = np.flatnonzero(flat.min(axis=1, initial=np.inf) < 0)
    if outside.size == 0:
        return None
    index = int(outside[0])
    return _slack_at(slack, index, int(np.argmin(flat[index])))


def smallest_leg_slack(positions: npt.ArrayLike, bounds: np.ndarray,
                       radius: npt.ArrayLike = 0.0) -> WallSlack:
    """
    Return the exact smallest wall slack of the motion through breakpoints (V, k, d).

    The slack is linear along each leg, so its minimum over the motion is its
    minimum over the breakpoints. ``index`` is the first leg that reaches it:
    the one that ends at the first breakpoint where it is found (leg 0 if that
    is the start).
    """
    slack = wall_slack(positions, bounds, radius)
    flat = slack.reshape(len(slack), -1)
    vertex, entry = np.unravel_index(int(np.argmin(flat)), flat.shape)
    found = _slack_at(slack, int(vertex), int(entry))
    return WallSlack(max(found.index - 1, 0), found.body, found.wall, found.slack)
