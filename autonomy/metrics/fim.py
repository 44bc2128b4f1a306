"""Fisher information of bearing measurements and the det(FIM)-optimal sensor geometry (paper 003).

For sensors with bearing noise σ (rad) at ranges ``r_i`` from a target, ``c_i = 1/(σ r_i)`` (1/m) and ``M_i`` the unit
vector from the target to sensor i, the 2-D position FIM is ``F = Σ c_i² (I − M_i M_iᵀ)`` (1/m²). Its determinant is
bounded by ``(½ Σ c_i²)²``, reached iff ``Σ c_i² [sin 2θ_i, cos 2θ_i] = 0``, possible iff ``c_j² ≤ ½ Σ c_i²``
for every j.

Paper 003, Example 1: sensors (−10, 0), (0, 0), (0, 10), target (5, 5), σ = 0.1 give ``c² = (0.4, 2, 2)`` and
``det F = 4.800``; the optimum is ``2.2² = 4.84``. (The paper prints φ12 = φ13 = π/2 and positions reaching only 4.800;
the correct angles are φ12 = φ13 = arccos(0.1) = 1.4706.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["bearing_fim", "bearing_fim_from_directions", "max_det_bearing_fim", "OptimalGeometry",
           "optimal_bearing_geometry"]


def bearing_fim_from_directions(c2: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """``F = Σ c_i² (I − M_i M_iᵀ)`` with ``M_i = [cos θ_i, sin θ_i]`` (θ: direction target → sensor, rad)."""
    c2 = np.asarray(c2, dtype=float)
    M = np.stack([np.cos(theta), np.sin(theta)], axis=-1)
    return np.sum(c2[:, None, None] * (np.eye(2) - M[:, :, None] * M[:, None, :]), axis=0)


def bearing_fim(p_target: np.ndarray, p_sensors: np.ndarray, sigma: float | np.ndarray) -> np.ndarray:
    """2-D position FIM (1/m²) of bearings from sensors at ``p_sensors`` (N × 2, m) with noise ``sigma`` (rad)."""
    d = np.asarray(p_sensors, dtype=float)[:, :2] - np.asarray(p_target, dtype=float)[:2]
    r = np.linalg.norm(d, axis=1)
    if np.any(r <= 0):
        raise ValueError("p_sensors must not coincide with p_target")
    c2 = 1.0 / (np.broadcast_to(np.asarray(sigma, dtype=float), r.shape) * r) ** 2
    return bearing_fim_from_directions(c2, np.arctan2(d[:, 1], d[:, 0]))


def max_det_bearing_fim(c2: np.ndarray) -> float:
    """Largest ``det F`` over sensor directions for fixed ``c_i²``.

    ``(½ Σ c²)²`` when ``max c² ≤ ½ Σ c²``; otherwise the dominant sensor is best orthogonal to all the others, giving
    ``c_max² · (Σ c² − c_max²)``.
    """
    c2 = np.asarray(c2, dtype=float)
    s, cmax = c2.sum(), c2.max()
    if cmax <= 0.5 * s:
        return float((0.5 * s) ** 2)
    return float(cmax * (s - cmax))


@dataclass(frozen=True, kw_only=True)
class OptimalGeometry:
    """Result of :func:`optimal_bearing_geometry`.

    Attributes
    ----------
    directions : ndarray (N, 2)
        Unit vectors ``M_i`` from the target to each sensor.
    positions : ndarray (N, 2)
        Sensor positions ``p_T + r_i M_i``, m.
    det_fim : float
        ``det F`` of that geometry, 1/m⁴.
    """

    directions: np.ndarray
    positions: np.ndarray
    det_fim: float


def optimal_bearing_geometry(p_target: np.ndarray, ranges: np.ndarray, sigma: float) -> OptimalGeometry:
    """Algorithm 1 of paper 003: sensor directions maximising ``det F`` at fixed ranges (sorted order kept).

    Sensors are grouped as ``l1 = c_1² + … + c_{N0−1}²`` (pointing along ``[1, 0]``), ``l2 = c_{N0}²`` and ``l3`` = the
    rest, with N0 the first index where the cumulative sum reaches ``½ Σ c²``; then the three vectors
    ``l_k [cos 2θ, sin 2θ]`` close a triangle: ``φ12 = arccos((l1² + l2² − l3²)/(2 l1 l2))``,
    ``φ13 = arccos((l1² + l3² − l2²)/(2 l1 l3))``, ``M_{N0}`` at angle ``(π + φ12)/2`` and the rest at ``(π − φ13)/2``.
    If one sensor dominates (``c_j² > ½ Σ c²``), it is placed orthogonal to all others.
    """
    r = np.asarray(ranges, dtype=float)
    c2 = 1.0 / (sigma * r) ** 2
    N = len(c2)
    half = 0.5 * c2.sum()
    theta = np.zeros(N)
    j_max = int(np.argmax(c2))
    if c2[j_max] > half or N < 3:
        theta[:] = 0.0
        theta[j_max] = 0.5 * np.pi
    else:
        cum = np.cumsum(c2)
        n0 = int(np.searchsorted(cum, half - 1e-12 * half))  # 0-based index of sensor N0
        l1 = cum[n0 - 1] if n0 > 0 else 0.0
        l2 = c2[n0]
        l3 = c2.sum() - l1 - l2
        if l1 <= 0.0 or l3 <= 0.0:  # l2 alone is half of the total: the others must be orthogonal to it
            theta[:] = 0.0
            theta[n0] = 0.5 * np.pi
        else:
            phi12 = np.arccos(np.clip((l1**2 + l2**2 - l3**2) / (2 * l1 * l2), -1.0, 1.0))
            phi13 = np.arccos(np.clip((l1**2 + l3**2 - l2**2) / (2 * l1 * l3), -1.0, 1.0))
            theta[n0] = 0.5 * (np.pi + phi12)
            theta[n0 + 1:] = 0.5 * (np.pi - phi13)
    M = np.stack([np.cos(theta), np.sin(theta)], axis=1)
    pos = np.asarray(p_target, dtype=float)[:2] + r[:, None] * M
    det = float(np.linalg.det(bearing_fim_from_directions(c2, theta)))
    return OptimalGeometry(directions=M, positions=pos, det_fim=det)
