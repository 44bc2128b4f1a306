"""Validation helpers of the shared types: finite numbers and finite vectors, with messages naming the field."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["all_finite", "finite_number", "finite_vector"]


_SMALL = 32  # entries up to which all_finite checks a list of floats (about where numpy's check gets cheaper)


def all_finite(arr: np.ndarray) -> bool:
    """Whether every entry of the float array ``arr`` is finite. A state's arrays are small (a few to a few dozen
    entries) and are checked thousands of times per simulated second among traffic: ``math.isfinite`` over the list
    of entries takes a third to a half of the time of ``np.isfinite(arr).all()`` there (numpy's reduction
    machinery), so small arrays are checked that way and larger ones by numpy."""
    if arr.size <= _SMALL:
        return all(map(math.isfinite, arr.reshape(-1).tolist()))
    return bool(np.isfinite(arr).all())


def finite_number(owner: str, name: str, value: object) -> float:
    """``value`` as a float; raises ``ValueError`` naming ``owner.name`` unless it is one finite real number."""
    if isinstance(value, float) and math.isfinite(value):  # the usual case, without numpy's generic dispatch
        return float(value)
    number = None
    if not isinstance(value, (str, bytes)) and np.ndim(value) == 0:
        try:
            number = float(value)
        except (TypeError, ValueError):
            number = None
    if number is None or not math.isfinite(number):
        raise ValueError(f"{owner}.{name} must be a finite number, got {value!r}")
    return number


def finite_vector(owner: str, name: str, value: object, sizes: tuple[int, ...]) -> np.ndarray:
    """``value`` as a read-only float array of one of the lengths ``sizes``; raises ``ValueError`` naming the field."""
    arr = np.array(value, dtype=float).reshape(-1)
    if arr.shape[0] not in sizes or not all_finite(arr):
        lengths = " or ".join(map(str, sizes))
        raise ValueError(f"{owner}.{name} must be a finite array of length {lengths}, got {value!r}")
    arr.setflags(write=False)
    return arr
