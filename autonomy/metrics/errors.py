"""Estimation error metrics: mean Euclidean error, RMSE, NEES and NIS with their χ² acceptance bands.

Array conventions: the last axis holds the vector components; any leading axes (time, Monte Carlo run) broadcast.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.stats import chi2

from autonomy.estimation.measurements import state_indices, wrap_angle

__all__ = [
    "euclidean_errors", "mean_euclidean_error", "rmse", "nees", "nis", "ChiSquareBand", "chi2_band",
    "fraction_inside", "StateErrors", "state_errors",
]


def euclidean_errors(truth: np.ndarray, estimate: np.ndarray) -> np.ndarray:
    """``‖estimate − truth‖`` over the last axis (e.g. position error in m)."""
    return np.linalg.norm(np.asarray(estimate, dtype=float) - np.asarray(truth, dtype=float), axis=-1)


def mean_euclidean_error(truth: np.ndarray, estimate: np.ndarray) -> float:
    """Mean of ``‖estimate − truth‖`` over all samples (the papers' "mean position error", not RMSE)."""
    return float(np.mean(euclidean_errors(truth, estimate)))


def rmse(truth: np.ndarray, estimate: np.ndarray) -> float:
    """Root mean square Euclidean error ``√(mean ‖estimate − truth‖²)``."""
    return float(np.sqrt(np.mean(euclidean_errors(truth, estimate) ** 2)))


def nees(truth: np.ndarray, estimate: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Normalised estimation error squared ``eᵀ P⁻¹ e`` with ``e = estimate − truth``; χ²(n) when consistent."""
    e = np.asarray(estimate, dtype=float) - np.asarray(truth, dtype=float)
    sol = np.linalg.solve(np.asarray(P, dtype=float), e[..., None])[..., 0]
    return np.einsum("...i,...i->...", e, sol)


def nis(nu: np.ndarray, S: np.ndarray) -> np.ndarray:
    """Normalised innovation squared ``νᵀ S⁻¹ ν``; χ²(m) when consistent."""
    nu = np.asarray(nu, dtype=float)
    sol = np.linalg.solve(np.asarray(S, dtype=float), nu[..., None])[..., 0]
    return np.einsum("...i,...i->...", nu, sol)


@dataclass(frozen=True, kw_only=True)
class ChiSquareBand:
    """Two-sided acceptance interval of the average of ``n_runs`` independent χ²(``dof``) values.

    ``n_runs · average ~ χ²(n_runs · dof)``, so ``[lower, upper] = χ²⁻¹((1 ∓ confidence)/2; n_runs·dof) / n_runs``.
    """

    lower: float
    upper: float
    dof: int
    n_runs: int
    confidence: float

    def contains(self, value: np.ndarray | float) -> np.ndarray | bool:
        """Whether ``value`` (e.g. a Monte Carlo average NEES per time step) lies inside the band."""
        return (np.asarray(value) >= self.lower) & (np.asarray(value) <= self.upper)


def chi2_band(dof: int, n_runs: int = 1, confidence: float = 0.95) -> ChiSquareBand:
    """The :class:`ChiSquareBand` for the average of ``n_runs`` χ²(``dof``) values."""
    if dof < 1:
        raise ValueError(f"dof must be >= 1, got {dof}")
    if n_runs < 1:
        raise ValueError(f"n_runs must be >= 1, got {n_runs}")
    if not 0.0 < confidence < 1.0:
        raise ValueError(f"confidence must be in (0, 1), got {confidence}")
    k = dof * n_runs
    a = 0.5 * (1.0 - confidence)
    return ChiSquareBand(lower=float(chi2.ppf(a, k) / n_runs), upper=float(chi2.ppf(1.0 - a, k) / n_runs), dof=dof,
                        n_runs=n_runs, confidence=confidence)


def fraction_inside(values: np.ndarray, band: ChiSquareBand) -> float:
    """Fraction of ``values`` inside ``band``."""
    return float(np.mean(band.contains(values)))


@dataclass(frozen=True, kw_only=True)
class StateErrors:
    """Position and velocity error summary over all samples.

    Attributes
    ----------
    mean_position : float
        Mean ‖p̂ − p‖, m (papers 001 and 002 report this, not RMSE).
    rmse_position : float
        √(mean ‖p̂ − p‖²), m.
    mean_velocity : float
        Mean ‖v̂ − v‖, m/s.
    rmse_velocity : float
        √(mean ‖v̂ − v‖²), m/s.
    mean_speed : float
        Mean |‖v̂‖ − ‖v‖|, m/s (paper 001).
    mean_heading : float
        Mean |wrap(atan2(v̂_y, v̂_x) − atan2(v_y, v_x))|, rad (paper 001).
    """

    mean_position: float
    rmse_position: float
    mean_velocity: float
    rmse_velocity: float
    mean_speed: float
    mean_heading: float


def state_errors(truth: np.ndarray, estimate: np.ndarray, layout: tuple[str, ...]) -> StateErrors:
    """:class:`StateErrors` of estimates against truth, both of shape (..., n) in the state ``layout``."""
    pos, vel = state_indices(tuple(layout))
    if vel is None:
        raise ValueError(f"layout must contain velocities, got {layout}")
    T, E = np.asarray(truth, dtype=float), np.asarray(estimate, dtype=float)
    pos, vel = list(pos), list(vel)
    v_t, v_e = T[..., vel], E[..., vel]
    heading = wrap_angle(np.arctan2(v_e[..., 1], v_e[..., 0]) - np.arctan2(v_t[..., 1], v_t[..., 0]))
    return StateErrors(
        mean_position=mean_euclidean_error(T[..., pos], E[..., pos]),
        rmse_position=rmse(T[..., pos], E[..., pos]),
        mean_velocity=mean_euclidean_error(v_t, v_e),
        rmse_velocity=rmse(v_t, v_e),
        mean_speed=float(np.mean(np.abs(np.linalg.norm(v_e, axis=-1) - np.linalg.norm(v_t, axis=-1)))),
        mean_heading=float(np.mean(np.abs(heading))),
    )
