"""Target motion models: constant velocity (CV), constant acceleration (CA), coordinated turn (CT), Singer, and a
stopped target on any of their layouts (the stop mode of a move–stop IMM).

Every model names its state layout once. Linear models are axis-major blocks, following the papers'
``[x, ẋ, ẍ, y, ẏ, ÿ]`` ordering: the full transition is ``F = I_dim ⊗ F_axis`` and ``Q = I_dim ⊗ Q_axis``.
All matrices are available for any step ``dt`` (s), because filters predict to each measurement's own time stamp.

Units: positions m, velocities m/s, accelerations m/s², turn rate rad/s, time s.
"""

from __future__ import annotations

import functools
import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from scipy.linalg import expm

__all__ = [
    "CV_2D", "CV_3D", "CA_2D", "CA_3D", "SINGER", "SINGER_3D", "CT_2D", "CT_OMEGA_2D",
    "MotionModel", "LinearMotionModel", "ConstantVelocity", "ConstantAcceleration", "Singer",
    "CoordinatedTurn", "CoordinatedTurnEstimated", "Stopped", "van_loan",
]

CV_2D = ("x", "vx", "y", "vy")
CV_3D = ("x", "vx", "y", "vy", "z", "vz")
CA_2D = ("x", "vx", "ax", "y", "vy", "ay")
CA_3D = ("x", "vx", "ax", "y", "vy", "ay", "z", "vz", "az")
SINGER = CA_2D
SINGER_3D = CA_3D
CT_2D = CV_2D
CT_OMEGA_2D = ("x", "vx", "y", "vy", "omega")

_AXES = ("x", "y", "z")
_SMALL_OMEGA = 1e-9  # rad/s; below this the turn formulas use their ω → 0 limits


def _check_dim(dim: int, allowed: tuple[int, ...] = (2, 3)) -> None:
    if dim not in allowed:
        raise ValueError(f"dim must be one of {allowed}, got {dim!r}")


def _check_nonneg(name: str, value: float) -> None:
    if not (np.isfinite(value) and value >= 0.0):
        raise ValueError(f"{name} must be finite and >= 0, got {value!r}")


def _readonly(a: np.ndarray) -> np.ndarray:
    a.setflags(write=False)
    return a


def van_loan(A: np.ndarray, Qc: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact discretisation of ``ẋ = A x + w``, ``E[w wᵀ] = Qc δ(t)`` over ``dt`` (Van Loan 1978).

    With ``M = [[-A, Qc], [0, Aᵀ]]·dt`` and ``E = expm(M)``: ``F = E₂₂ᵀ`` and ``Q = F E₁₂``.
    """
    n = A.shape[0]
    M = np.zeros((2 * n, 2 * n))
    M[:n, :n] = -A
    M[:n, n:] = Qc
    M[n:, n:] = A.T
    E = expm(M * dt)
    F = E[n:, n:].T
    Q = F @ E[:n, n:]
    return F, 0.5 * (Q + Q.T)


class MotionModel(ABC):
    """Base class of target motion models.

    Attributes
    ----------
    layout : tuple of str
        Names of the state components, in order.
    is_linear : bool
        True when ``propagate(X, dt) == F(dt) @ X``.
    """

    layout: tuple[str, ...]
    is_linear: bool = False

    @property
    def n(self) -> int:
        """State dimension."""
        return len(self.layout)

    @abstractmethod
    def propagate(self, X: np.ndarray, dt: float) -> np.ndarray:
        """Noise-free transition of a state ``(n,)`` or of columns of states ``(n, m)`` over ``dt`` s."""

    @abstractmethod
    def jacobian(self, x: np.ndarray, dt: float) -> np.ndarray:
        """Jacobian ``∂f/∂x`` of the transition at ``x``, shape ``(n, n)``."""

    @abstractmethod
    def process_noise(self, dt: float, x: np.ndarray | None = None) -> np.ndarray:
        """Discrete process-noise covariance ``Q(dt)``, shape ``(n, n)``."""


class LinearMotionModel(MotionModel):
    """A linear time-invariant model ``x⁺ = F(dt) x + w``, ``w ~ N(0, Q(dt))``; ``F``, ``Q`` cached per ``dt``."""

    is_linear = True

    @abstractmethod
    def _matrices(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Uncached ``(F, Q)`` for step ``dt``."""

    @functools.lru_cache(maxsize=64)  # noqa: B019  (models are frozen, hashable and few)
    def matrices(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        """Read-only ``(F, Q)`` for step ``dt`` (s)."""
        F, Q = self._matrices(float(dt))
        return _readonly(np.ascontiguousarray(F, dtype=float)), _readonly(np.ascontiguousarray(Q, dtype=float))

    def F(self, dt: float) -> np.ndarray:
        """Transition matrix over ``dt`` s."""
        return self.matrices(dt)[0]

    def propagate(self, X: np.ndarray, dt: float) -> np.ndarray:
        return self.matrices(dt)[0] @ X

    def jacobian(self, x: np.ndarray, dt: float) -> np.ndarray:
        return self.matrices(dt)[0]

    def process_noise(self, dt: float, x: np.ndarray | None = None) -> np.ndarray:
        return self.matrices(dt)[1]


def _per_axis(F1: np.ndarray, Q1: np.ndarray, dim: int) -> tuple[np.ndarray, np.ndarray]:
    eye = np.eye(dim)
    return np.kron(eye, F1), np.kron(eye, Q1)


@dataclass(frozen=True, kw_only=True)
class ConstantVelocity(LinearMotionModel):
    """Nearly-constant velocity with continuous white acceleration per axis.

    Per axis ``F = [[1, T], [0, 1]]``, ``Q = q [[T³/3, T²/2], [T²/2, T]]``.
    """

    q: float = field(metadata={"doc": "spectral density of the white acceleration, m²/s³"})
    dim: int = field(default=2, metadata={"doc": "number of Cartesian axes (2 or 3)"})

    def __post_init__(self) -> None:
        _check_nonneg("q", self.q)
        _check_dim(self.dim)

    @property
    def layout(self) -> tuple[str, ...]:  # type: ignore[override]
        return CV_2D if self.dim == 2 else CV_3D

    def _matrices(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        T = dt
        F1 = np.array([[1.0, T], [0.0, 1.0]])
        Q1 = self.q * np.array([[T**3 / 3, T**2 / 2], [T**2 / 2, T]])
        return _per_axis(F1, Q1, self.dim)


@dataclass(frozen=True, kw_only=True)
class ConstantAcceleration(LinearMotionModel):
    """Nearly-constant acceleration (white jerk) per axis.

    Per axis ``F = [[1, T, T²/2], [0, 1, T], [0, 0, 1]]``,
    ``Q = q [[T⁵/20, T⁴/8, T³/6], [T⁴/8, T³/3, T²/2], [T³/6, T²/2, T]]``.
    """

    q: float = field(metadata={"doc": "spectral density of the white jerk, m²/s⁵"})
    dim: int = field(default=2, metadata={"doc": "number of Cartesian axes (2 or 3)"})

    def __post_init__(self) -> None:
        _check_nonneg("q", self.q)
        _check_dim(self.dim)

    @property
    def layout(self) -> tuple[str, ...]:  # type: ignore[override]
        return CA_2D if self.dim == 2 else CA_3D

    def _matrices(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        T = dt
        F1 = np.array([[1.0, T, T**2 / 2], [0.0, 1.0, T], [0.0, 0.0, 1.0]])
        Q1 = self.q * np.array(
            [[T**5 / 20, T**4 / 8, T**3 / 6], [T**4 / 8, T**3 / 3, T**2 / 2], [T**3 / 6, T**2 / 2, T]]
        )
        return _per_axis(F1, Q1, self.dim)


def singer_axis_exact(alpha: float, sigma_a: float, T: float) -> tuple[np.ndarray, np.ndarray]:
    """Exact per-axis Singer ``(F, Q)`` (Singer 1970), state ``[p, v, a]``, ``ȧ = −α a + w``.

    ``F = [[1, T, (e^{−αT} + αT − 1)/α²], [0, 1, (1 − e^{−αT})/α], [0, 0, e^{−αT}]]`` and ``Q = 2ασ² q̃`` with the
    closed-form entries of q̃. For ``αT < 1e-2`` the closed form loses digits to cancellation, so ``F`` and ``Q``
    then come from the Van Loan matrix exponential (also exact).
    """
    a, s2 = alpha, sigma_a**2
    e1, aT = math.exp(-a * T), a * T
    F = np.array([[1.0, T, (e1 + aT - 1.0) / a**2], [0.0, 1.0, (1.0 - e1) / a], [0.0, 0.0, e1]])
    if aT < 1e-2:
        A = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -a]])
        return van_loan(A, np.diag([0.0, 0.0, 2.0 * a * s2]), T)
    e2 = e1 * e1
    q11 = (1 - e2 + 2 * aT + 2 * aT**3 / 3 - 2 * aT**2 - 4 * aT * e1) / (2 * a**5)
    q12 = (e2 + 1 - 2 * e1 + 2 * aT * e1 - 2 * aT + aT**2) / (2 * a**4)
    q13 = (1 - e2 - 2 * aT * e1) / (2 * a**3)
    q22 = (4 * e1 - 3 - e2 + 2 * aT) / (2 * a**3)
    q23 = (e2 + 1 - 2 * e1) / (2 * a**2)
    q33 = (1 - e2) / (2 * a)
    Q = 2 * a * s2 * np.array([[q11, q12, q13], [q12, q22, q23], [q13, q23, q33]])
    return F, Q


@dataclass(frozen=True, kw_only=True)
class Singer(LinearMotionModel):
    """Singer model: each acceleration is a first-order Gauss–Markov process ``ȧ = −α a + w``, ``Var(a) = σa²``.

    ``discretisation="exact"`` gives the closed-form Singer ``F`` and ``Q`` (paper 002).
    ``discretisation="euler"`` is paper 000's form: ``F = I + T·F0`` with ``F0 = [[0,1,0],[0,0,1],[0,0,−α]]`` and
    the rank-deficient ``Q = diag(0, 0, T²σa²)`` per axis.
    """

    alpha: float = field(metadata={"doc": "manoeuvre (reciprocal time-constant) rate α, 1/s"})
    sigma_a: float = field(metadata={"doc": "standard deviation of the target acceleration σa, m/s²"})
    dim: int = field(default=2, metadata={"doc": "number of Cartesian axes (2 or 3)"})
    discretisation: Literal["exact", "euler"] = field(default="exact", metadata={"doc": "'exact' or 'euler'"})

    def __post_init__(self) -> None:
        if not (np.isfinite(self.alpha) and self.alpha > 0):
            raise ValueError(f"alpha must be finite and > 0, got {self.alpha!r}")
        _check_nonneg("sigma_a", self.sigma_a)
        _check_dim(self.dim)
        if self.discretisation not in ("exact", "euler"):
            raise ValueError(f"discretisation must be 'exact' or 'euler', got {self.discretisation!r}")

    @property
    def layout(self) -> tuple[str, ...]:  # type: ignore[override]
        return SINGER if self.dim == 2 else SINGER_3D

    def _matrices(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        if self.discretisation == "exact":
            F1, Q1 = singer_axis_exact(self.alpha, self.sigma_a, dt)
        else:
            F0 = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.0, 0.0, -self.alpha]])
            F1 = np.eye(3) + dt * F0
            Q1 = np.diag([0.0, 0.0, dt**2 * self.sigma_a**2])
        return _per_axis(F1, Q1, self.dim)


@dataclass(frozen=True, kw_only=True)
class Stopped(LinearMotionModel):
    """A stopped target on the layout of a moving model (CV, CA or Singer): the stop mode of a move–stop IMM
    (Kirubarajan & Bar-Shalom's move–stop–move targets). The position is held, up to a random walk of density
    ``q`` (m²/s: a car creeping in a queue, the road's roughness); every derivative is zero, with a small residual
    variance ``sigma_rate²`` (velocity in (m/s)², acceleration in (m/s²)²) that keeps the covariance positive
    definite. Per axis ``F = diag(1, 0[, 0])``, ``Q = diag(q T, σ², [σ²])``.
    """

    layout_of: tuple[str, ...] = field(metadata={"doc": "the moving model's layout, axis-major (CV, CA or Singer)"})
    q: float = field(default=0.01, metadata={"doc": "position random-walk density, m²/s"})
    sigma_rate: float = field(default=0.05, metadata={"doc": "residual standard deviation of each derivative"})

    def __post_init__(self) -> None:
        if tuple(self.layout_of) not in (CV_2D, CV_3D, CA_2D, CA_3D):
            raise ValueError(f"Stopped.layout_of must be a CV or CA/Singer layout, got {self.layout_of!r}")
        _check_nonneg("q", self.q)
        if not (np.isfinite(self.sigma_rate) and self.sigma_rate > 0):
            raise ValueError(f"sigma_rate must be finite and > 0, got {self.sigma_rate!r}")

    @property
    def layout(self) -> tuple[str, ...]:  # type: ignore[override]
        return tuple(self.layout_of)

    def _matrices(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        per_axis = 2 if tuple(self.layout_of) in (CV_2D, CV_3D) else 3
        F1 = np.zeros((per_axis, per_axis))
        F1[0, 0] = 1.0
        Q1 = np.diag([self.q * dt] + [self.sigma_rate**2] * (per_axis - 1))
        return _per_axis(F1, Q1, len(self.layout_of) // per_axis)


def _ct_coefficients(omega: np.ndarray | float, T: float):
    """``(sin ωT/ω, (1 − cos ωT)/ω, cos ωT, sin ωT)`` with the ω → 0 limits."""
    w = np.asarray(omega, dtype=float)
    small = np.abs(w) < _SMALL_OMEGA
    ws = np.where(small, 1.0, w)
    s, c = np.sin(w * T), np.cos(w * T)
    a = np.where(small, T, s / ws)
    b = np.where(small, 0.5 * w * T**2, 2.0 * np.sin(0.5 * w * T) ** 2 / ws)  # 1 − cos = 2 sin²(·/2): no cancellation
    return a, b, c, s


@dataclass(frozen=True, kw_only=True)
class CoordinatedTurn(LinearMotionModel):
    """Coordinated turn with a known turn rate ω (counter-clockwise positive), state ``(x, vx, y, vy)``.

    ``F = [[1, sin ωT/ω, 0, −(1−cos ωT)/ω], [0, cos ωT, 0, −sin ωT],
    [0, (1−cos ωT)/ω, 1, sin ωT/ω], [0, sin ωT, 0, cos ωT]]``;
    ``Q`` is the exact discretisation of white acceleration of density ``q`` on both axes (Van Loan).
    """

    omega: float = field(metadata={"doc": "turn rate, rad/s (counter-clockwise positive)"})
    q: float = field(metadata={"doc": "spectral density of the white acceleration, m²/s³"})

    def __post_init__(self) -> None:
        if not np.isfinite(self.omega):
            raise ValueError(f"omega must be finite, got {self.omega!r}")
        _check_nonneg("q", self.q)

    @property
    def layout(self) -> tuple[str, ...]:  # type: ignore[override]
        return CT_2D

    def _matrices(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        w = self.omega
        A = np.array([[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, -w], [0.0, 0.0, 0.0, 1.0], [0.0, w, 0.0, 0.0]])
        Qc = np.diag([0.0, self.q, 0.0, self.q])
        _, Q = van_loan(A, Qc, dt)
        a, b, c, s = (float(v) for v in _ct_coefficients(w, dt))
        F = np.array([[1.0, a, 0.0, -b], [0.0, c, 0.0, -s], [0.0, b, 1.0, a], [0.0, s, 0.0, c]])
        return F, Q


@dataclass(frozen=True, kw_only=True)
class CoordinatedTurnEstimated(MotionModel):
    """Coordinated turn with the turn rate in the state, ``(x, vx, y, vy, omega)`` (nonlinear).

    Transition as :class:`CoordinatedTurn` with ω taken from the state; ``ω⁺ = ω + w_ω``.
    ``Q`` = the CV blocks of density ``q`` on x and y, plus ``q_omega·T`` on ω.
    """

    q: float = field(metadata={"doc": "spectral density of the white acceleration, m²/s³"})
    q_omega: float = field(metadata={"doc": "spectral density of the turn-rate random walk, rad²/s³"})

    def __post_init__(self) -> None:
        _check_nonneg("q", self.q)
        _check_nonneg("q_omega", self.q_omega)

    @property
    def layout(self) -> tuple[str, ...]:  # type: ignore[override]
        return CT_OMEGA_2D

    def propagate(self, X: np.ndarray, dt: float) -> np.ndarray:
        x, vx, y, vy, w = X
        a, b, c, s = _ct_coefficients(w, dt)
        return np.array([x + a * vx - b * vy, c * vx - s * vy, y + b * vx + a * vy, s * vx + c * vy,
                         w * np.ones_like(x)])

    def jacobian(self, x: np.ndarray, dt: float) -> np.ndarray:
        _, vx, _, vy, w = (float(v) for v in x)
        T = dt
        a, b, c, s = (float(v) for v in _ct_coefficients(w, T))
        if abs(w) < _SMALL_OMEGA:
            da, db = 0.0, 0.5 * T**2  # d(sin ωT/ω)/dω → −ωT³/3 → 0 ; d((1−cos ωT)/ω)/dω → T²/2
        else:
            da = (T * c * w - s) / w**2
            db = (T * s * w - b * w) / w**2
        return np.array([
            [1.0, a, 0.0, -b, da * vx - db * vy],
            [0.0, c, 0.0, -s, -T * s * vx - T * c * vy],
            [0.0, b, 1.0, a, db * vx + da * vy],
            [0.0, s, 0.0, c, T * c * vx - T * s * vy],
            [0.0, 0.0, 0.0, 0.0, 1.0],
        ])

    def process_noise(self, dt: float, x: np.ndarray | None = None) -> np.ndarray:
        T = dt
        Q = np.zeros((5, 5))
        blk = self.q * np.array([[T**3 / 3, T**2 / 2], [T**2 / 2, T]])
        Q[0:2, 0:2] = blk
        Q[2:4, 2:4] = blk
        Q[4, 4] = self.q_omega * T
        return Q
