"""Construction of a filter by name."""

from __future__ import annotations

from typing import Literal

import numpy as np

from autonomy.estimation.base import GaussianFilter
from autonomy.estimation.ekf import EKF
from autonomy.estimation.models import MotionModel
from autonomy.estimation.scif import SCIF
from autonomy.estimation.sigma_point import CKF, UKF

__all__ = ["FILTERS", "make_filter"]

FILTERS: dict[str, type[GaussianFilter]] = {"ekf": EKF, "ukf": UKF, "ckf": CKF, "scif": SCIF}


def make_filter(kind: Literal["ekf", "ukf", "ckf", "scif"], model: MotionModel, x0: np.ndarray, P0: np.ndarray,
                t0: float = 0.0, **kwargs) -> GaussianFilter:
    """A filter of type ``kind`` on ``model`` from ``(x0, P0)`` at ``t0`` (s); ``kwargs`` go to its constructor."""
    try:
        cls = FILTERS[kind]
    except KeyError:
        raise ValueError(f"kind must be one of {sorted(FILTERS)}, got {kind!r}") from None
    return cls(model, x0, P0, t0, **kwargs)
