"""
The supported values: finite, coordinates in range, lengths (spacings, radii, clearance).

One place for these rules; every layer finds its offender here and words its own
message (doc/design.md section 9).
"""

import numbers

import numpy as np

from .errors import ErrorCode, literal, PlanningError

# Coordinates beyond this magnitude are refused: squared distances must not
# overflow, and the certificate's resolution (1e-12 of the scale) stays useful.
MAX_COORDINATE = 1e15
# A length (lane_spacing, min_spacing, a radius, required_clearance) is 0 where that is
# allowed, else between MIN_LENGTH and MAX_COORDINATE. Below, the construction's squared
# lengths fall into subnormals (min_spacing = 1e-170 gave the discs' stack a fade of 0 and
# NaN heights) and a plan at that scale resolves distances whose squares do (the
# refinement's caps then came out wrong); above, sums of lengths overflow (min_spacing =
# 1e200 gave NaN times).
MIN_LENGTH = 1e-100


def first_non_finite(values: np.ndarray) -> tuple[int, ...] | None:
    """Return the index of the first non-finite entry (NaN, +-inf) of an array, or None."""
    finite = np.isfinite(values)
    if finite.all():  # the usual case: no search
        return None
    return tuple(int(i) for i in np.argwhere(~finite)[0])


def first_out_of_range(values: np.ndarray) -> tuple[int, ...] | None:
    """
    Return the index of the first finite coordinate beyond +-MAX_COORDINATE, or None.

    Non-finite values are not out of range (they have their own code,
    NON_FINITE_VALUE).
    """
    values = np.asarray(values)
    if (np.abs(values) <= MAX_COORDINATE).all():
        return None
    far = np.argwhere(np.isfinite(values) & (np.abs(values) > MAX_COORDINATE))
    return tuple(int(i) for i in far[0]) if far.size else None


def length_range(zero: bool) -> str:
    """Return the words for the lengths allowed: with zero, 0 as well."""
    words = f'a real number between {MIN_LENGTH:g} and {MAX_COORDINATE:g}'
    return f'0 or {words}' if zero else words


def lengths_in_range(values: np.ndarray, zero: bool) -> np.ndarray:
    """Return whether each of values is a supported length (with zero, 0 too); NaN is not."""
    values = np.asarray(values, dtype=float)
    return ((values >= MIN_LENGTH) & (values <= MAX_COORDINATE)) | (zero & (values == 0.0))


def checked_length(value: object, name: str, zero: bool) -> float:
    """
    Return value as a float length, or raise INVALID_REQUEST naming it and its range.

    A real number (Python's or numpy's, or a 0-d array of one) between MIN_LENGTH
    and MAX_COORDINATE, or with zero 0; anything else (a bool, a string, None, a
    list, NaN) is refused.
    """
    if isinstance(value, np.ndarray) and value.ndim == 0:
        value = value.item()  # a 0-d array holds one number
    if (isinstance(value, numbers.Real) and not isinstance(value, bool)
            and lengths_in_range(np.array(float(value)), zero)):
        return float(value)
    raise PlanningError(ErrorCode.INVALID_REQUEST,
                        f'{name} must be {length_range(zero)}, got '
                        f'{literal(repr(value))}', option=name)
