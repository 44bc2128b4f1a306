"""Position fixes of a scan: what starts tracks and judges divergence.

A detection fixes a ground position alone when its model has an inverse (:meth:`DetectionModel.ground_fix`: a radar
return, a box). With scan stacking, bearings of two or more sensors whose lines cross at ``min_crossing_angle`` or
more also fix one: their least-squares intersection, with the inverse of the bearings' Fisher information as its
covariance.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from autonomy.estimation.measurements import MeasurementLike, StackedMeasurement

__all__ = ["PositionFixer", "triangulate"]

Fix = tuple[MeasurementLike, np.ndarray, np.ndarray]


def triangulate(dets: Sequence[MeasurementLike], min_crossing_angle: float) -> Fix | None:
    """Least-squares intersection of the bearing lines among ``dets`` (taken at one time):
    ``(stacked measurement, (x, y), 2x2 covariance)`` (m, m²), or None unless two lines cross at
    ``min_crossing_angle`` (rad) or more with the target ahead of every sensor. The covariance is the inverse of the
    bearings' Fisher information ``Σ n_i n_iᵀ / (σ_i² r_i²)`` at the intersection (n_i: normal of line i)."""
    lines = [(d, ln) for d in dets if (ln := d.model.bearing_line(d)) is not None]
    if len(lines) < 2:
        return None
    bearings = [d for d, _ in lines]
    az = np.array([ln[0] for _, ln in lines])
    p_s = np.array([np.asarray(d.p_sensor_W, dtype=float)[:2] for d in bearings])
    n = np.c_[-np.sin(az), np.cos(az)]
    A = n.T @ n
    # two lines at angle β give λ_min(Σ n nᵀ) = 1 − |cos β|; more lines only add
    if np.linalg.eigvalsh(A)[0] < 1.0 - np.cos(min_crossing_angle):
        return None
    xy = np.linalg.solve(A, n.T @ np.sum(n * p_s, axis=1))
    ahead = np.sum((xy - p_s) * np.c_[np.cos(az), np.sin(az)], axis=1)
    if np.any(ahead <= 0):
        return None
    var = np.array([ln[1] for _, ln in lines]) * np.sum((xy - p_s) ** 2, axis=1)
    F = (n / var[:, None]).T @ n
    return StackedMeasurement(parts=tuple(bearings)), xy, np.linalg.inv(F)


class PositionFixer:
    """The position fixes of one scan.

    Parameters
    ----------
    target_height : float
        Height of the ground targets (m): the plane a radar return is inverted onto.
    min_crossing_angle : float or None
        Smallest angle between two bearing lines for their intersection to fix a position (rad); None: bearings
        never fix one (scans of one sensor, where lines of one time cannot cross usefully).
    """

    def __init__(self, target_height: float, min_crossing_angle: float | None) -> None:
        self.target_height = float(target_height)
        self.min_crossing_angle = min_crossing_angle

    def fixes(self, scan: Sequence[MeasurementLike]) -> list[Fix]:
        """``(measurement, (x, y), 2x2 covariance)`` of each detection that fixes a position alone, in scan order,
        then of the crossing bearings, if any."""
        out = []
        for d in scan:
            if d.model.fixes_position:
                xy, P = d.model.ground_fix(d, self.target_height)
                out.append((d, xy, P))
        if self.min_crossing_angle is not None and (tri := triangulate(scan, self.min_crossing_angle)) is not None:
            out.append(tri)
        return out

    def fixes_position(self, scan: Sequence[MeasurementLike]) -> bool:
        """Whether ``scan`` fixes a position at all (a radar or box detection, or crossing bearings)."""
        return any(d.model.fixes_position for d in scan) or (
            self.min_crossing_angle is not None and triangulate(scan, self.min_crossing_angle) is not None)
