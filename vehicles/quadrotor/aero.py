"""Aerodynamic effects beyond rotor thrust: body drag, ground effect and downwash between UAVs."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

__all__ = ["body_drag_B", "ground_effect_factor", "DownwashConfig", "downwash_force_W"]


@njit(cache=True)
def body_drag_B(v_rel_B: np.ndarray, c_lin: np.ndarray, c_quad: np.ndarray) -> np.ndarray:
    """Drag force in the body frame (N, 3), N.

    .. math::  F_{d,B} = -c_1 \\odot v_B - c_2 \\odot |v_B| \\odot v_B

    Parameters
    ----------
    v_rel_B : np.ndarray
        (N, 3) air-relative velocity in the body frame (m/s).
    c_lin, c_quad : np.ndarray
        (N, 3) linear (N s/m) and quadratic (N s^2/m^2) coefficients per body axis.
    """
    out = np.empty(v_rel_B.shape)
    for i in range(v_rel_B.shape[0]):
        for j in range(3):
            v = v_rel_B[i, j]
            out[i, j] = -(c_lin[i, j] + c_quad[i, j] * abs(v)) * v
    return out


def ground_effect_factor(h: np.ndarray, rotor_radius: np.ndarray, min_height_ratio: float) -> np.ndarray:
    """Thrust multiplier in ground effect (Cheeseman and Bennett, 1955).

    .. math::  \\frac{T_{IGE}}{T_{OGE}} = \\frac{1}{1 - (R / 4h)^2}, \\quad h \\ge h_{min} = \\rho_{min} R

    The height is floored at ``min_height_ratio * R`` where the model stops being valid, which bounds the factor by
    ``1 / (1 - 1/(16 rho_min^2))``.

    Parameters
    ----------
    h : np.ndarray
        (N, 4) rotor heights above the ground (m).
    rotor_radius : np.ndarray
        (N, 1) or (N, 4) propeller radii (m).
    min_height_ratio : float
        ``rho_min`` (-), > 0.25.
    """
    hh = np.maximum(h, min_height_ratio * rotor_radius)
    return 1.0 / (1.0 - (rotor_radius / (4.0 * hh)) ** 2)


@dataclass(frozen=True, kw_only=True)
class DownwashConfig:
    """Wake of one UAV acting on the UAVs below it.

    Model: the far wake of rotors of total disk area ``A_j`` carrying thrust ``T_j`` has dynamic pressure ``T_j / A_j``
    (momentum theory: wake speed ``2 v_h``, ``T = 2 rho A v_h^2``). It spreads as a round jet of radius
    ``r_j + spread * dz`` with centre-line dynamic pressure decaying as ``(r_j / (r_j + spread dz))^2``; a UAV of
    disk area ``A_i`` at vertical gap ``dz`` below and horizontal offset ``d`` feels the downward force

    .. math::

        F_{ij} = C\\, T_j \\min(1, A_i/A_j) \\left(\\frac{r_j}{r_j + k\\,dz}\\right)^2
                 \\exp\\!\\left(-\\frac{d^2}{2 (r_j + k\\,dz)^2}\\right) S(dz / h_r),

    with ``S`` a smoothstep from 0 at ``dz = 0`` to 1 at ``dz = h_r`` so the force is continuous as the two UAVs pass
    the same altitude. Every factor is at most 1, so ``|F_ij| <= C T_j`` for every gap including ``dz -> 0`` (the
    empirical fit of gym-pybullet-drones grows as ``1/dz^2`` there).

    Attributes
    ----------
    coefficient : float
        ``C``, fraction of the upper UAV's wake momentum deposited on the lower one (-), in [0, 1].
    spread : float
        ``k``, growth of the wake radius per metre below the rotor plane (-), > 0.
    ramp_height : float
        ``h_r``, gap over which the force ramps in (m), > 0.
    """

    coefficient: float = 0.5
    spread: float = 0.2
    ramp_height: float = 0.1

    def __post_init__(self) -> None:
        if not (0.0 <= self.coefficient <= 1.0):
            raise ValueError(f"DownwashConfig.coefficient must be in [0, 1], got {self.coefficient!r}")
        if not (self.spread > 0):
            raise ValueError(f"DownwashConfig.spread must be > 0, got {self.spread!r}")
        if not (self.ramp_height > 0):
            raise ValueError(f"DownwashConfig.ramp_height must be > 0 m, got {self.ramp_height!r}")


def downwash_force_W(p_W: np.ndarray, thrust: np.ndarray, wake_radius: np.ndarray, disk_area: np.ndarray,
                     config: DownwashConfig) -> np.ndarray:
    """Vertical downwash force on every UAV from every UAV above it (see :class:`DownwashConfig`).

    Parameters
    ----------
    p_W : np.ndarray
        (N, 3) positions (m).
    thrust : np.ndarray
        (N,) total rotor thrust of each UAV (N).
    wake_radius : np.ndarray
        (N,) radius of each UAV's wake at its rotor plane (m).
    disk_area : np.ndarray
        (N,) total rotor disk area of each UAV (m^2).
    config : DownwashConfig
        Model constants.

    Returns
    -------
    np.ndarray
        (N, 3) force in the world frame (N); only the z component is non-zero.
    """
    # Pairwise: row i = affected (below), column j = source (above).
    dz = p_W[None, :, 2] - p_W[:, None, 2]
    d2 = (p_W[None, :, 0] - p_W[:, None, 0]) ** 2 + (p_W[None, :, 1] - p_W[:, None, 1]) ** 2
    gap = np.maximum(dz, 0.0)
    r = wake_radius[None, :] + config.spread * gap
    x = np.clip(dz / config.ramp_height, 0.0, 1.0)
    ramp = x * x * (3.0 - 2.0 * x)
    capture = np.minimum(1.0, disk_area[:, None] / disk_area[None, :])
    F = config.coefficient * thrust[None, :] * capture * (wake_radius[None, :] / r) ** 2 \
        * np.exp(-0.5 * d2 / r**2) * ramp
    out = np.zeros_like(p_W)
    out[:, 2] = -F.sum(axis=1)
    return out
