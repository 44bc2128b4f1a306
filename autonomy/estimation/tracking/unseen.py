"""Negative information from cameras: how much of a track's position distribution a camera frame had in view.

A frame that updated no track where one predicts a car in view lowers that track's ``unseen`` score by
``log(1 − p_D v)`` (:meth:`.multi.MultiTargetTracker.observe_coverage`); this module holds the settings of that rule
and the visible share ``v``.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from autonomy.sensing.coverage import FrameCoverage

__all__ = ["CAMERA_RESOLUTION_M", "UNSEEN_DROP", "UNSEEN_DROP_LOG", "UNSEEN_NODES", "visible_share"]

UNSEEN_DROP = 0.02
"""A track is dropped once the likelihood of the cameras' misses since a camera last saw it, ``Π (1 − p_D v)``,
falls below this: with ``p_D`` = 0.9, two frames in a row that had the whole track in view; seven that had half of
it."""
UNSEEN_DROP_LOG = math.log(UNSEEN_DROP)

CAMERA_RESOLUTION_M = 10.0
"""m: a track with another track this near is not judged by a frame that missed it: two cars this close may show as
one blob (the detector reports touching blobs as one car), taken by the other track."""

UNSEEN_NODES = 5
"""Gauss–Hermite nodes per axis over which a track's visible share is averaged (25 points)."""
_h, _hw = np.polynomial.hermite_e.hermegauss(UNSEEN_NODES)
_HERMITE_POINTS = np.array([(a, b) for a in _h for b in _h])  # standard-normal nodes, (25, 2)
_HERMITE_WEIGHTS = np.array([wa * wb for wa in _hw for wb in _hw]) / (2.0 * math.pi)  # sum 1


def visible_share(mean: np.ndarray, cov: np.ndarray, coverage: FrameCoverage, height: float) -> np.ndarray:
    """(N,) share of each position distribution ``N(mean[i], cov[i])`` ((N, 2) m, (N, 2, 2) m²) that ``coverage``
    had in view: the Gauss–Hermite average over :data:`UNSEEN_NODES` ² nodes of whether a car at each node, ``height``
    (m) above the ground, was in view (:meth:`FrameCoverage.visible`)."""
    L = np.linalg.cholesky(np.asarray(cov, dtype=float) + 1e-9 * np.eye(2))
    pts = np.asarray(mean, dtype=float)[:, None, :] + np.einsum("nij,kj->nki", L, _HERMITE_POINTS)
    ground = np.concatenate([pts.reshape(-1, 2), np.full((pts.shape[0] * pts.shape[1], 1), float(height))], axis=1)
    return coverage.visible(ground).reshape(pts.shape[:2]) @ _HERMITE_WEIGHTS
