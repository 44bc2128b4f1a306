"""Interacting multiple model (IMM) estimator over any single-model filters (paper 003, printed errors corrected).

One cycle, with mode-transition matrix ``Π`` (``Π[i, j] = P(mode j at k | mode i at k−1)``):

1. Interaction: ``c̄_j = Σ_i Π_ij μ_i``, ``μ_{i|j} = Π_ij μ_i / c̄_j``, ``x⁰_j = Σ_i μ_{i|j} x_i``,
   ``P⁰_j = Σ_i μ_{i|j} [P_i + (x_i − x⁰_j)(x_i − x⁰_j)ᵀ]``.
2. Mode-matched filtering: each filter restarts from ``(x⁰_j, P⁰_j)``, predicts and updates (the gain carries no
   ``+ Q_j``: the printed eq. 17 is wrong).
3. Mode probabilities: ``μ_j = Λ_j c̄_j / Σ_l Λ_l c̄_l`` with ``Λ_j = N(ν_j; 0, S_j)``, the m-dimensional Gaussian
   likelihood of the innovation (the printed eqs. 18–19 are wrong).
4. Combination: ``x = Σ μ_j x_j``, ``P = Σ μ_j [P_j + (x_j − x)(x_j − x)ᵀ]``.

Models may have different state layouts (e.g. CV ``(x, vx, y, vy)`` and CT ``(x, vx, y, vy, omega)``). When mixing
into model j, a component that model i lacks is taken from model j's own estimate (no cross-covariance); in the
combined output, a component a model lacks counts as 0 with zero variance (a CV model has zero turn rate and zero
acceleration). ``Π`` applies once per prediction; pass a callable ``Π(dt)`` for time-dependent switching.
With several sensors at one time, stack them in a :class:`~autonomy.estimation.measurements.StackedMeasurement`
(the centralised augmented-measurement filter of paper 003) or update sequentially.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from autonomy.estimation.base import TIME_TOLERANCE, Filter, GaussianFilter, Innovation
from autonomy.estimation.measurements import MeasurementLike, MeasurementModel, measurement_model
from autonomy.estimation.models import LinearMotionModel, Stopped

__all__ = ["IMM", "MoveStopSwitching", "cv_ct_imm", "move_stop_imm", "switching_matrix"]


class IMM(Filter):
    """Interacting multiple model estimator.

    Parameters
    ----------
    filters : sequence of GaussianFilter
        One filter per mode, all at the same time ``t``.
    transition : ndarray or callable
        Mode-transition matrix ``Π`` (rows sum to 1), or a function of the step ``dt`` (s) returning it.
    mu0 : ndarray, optional
        Initial mode probabilities (uniform by default).
    layout : tuple of str, optional
        Layout of the combined output; defaults to the longest filter layout.
    """

    def __init__(self, filters: Sequence[GaussianFilter], transition: np.ndarray | Callable[[float], np.ndarray],
                 mu0: np.ndarray | None = None, layout: tuple[str, ...] | None = None) -> None:
        if len(filters) == 0:
            raise ValueError("filters must hold at least one filter, got none")
        self.filters = list(filters)
        r = len(self.filters)
        ts = [f.t for f in self.filters]
        if max(ts) - min(ts) > TIME_TOLERANCE:
            raise ValueError(f"filters must share one time, got {ts}")
        self.t = float(ts[0])
        self._transition = transition
        self._Pi: np.ndarray | None = None
        if not callable(transition):
            self._Pi = np.array(transition, dtype=float)
            self._check_pi(self._Pi)
        mu = np.full(r, 1.0 / r) if mu0 is None else np.asarray(mu0, dtype=float)
        if mu.shape != (r,) or np.any(mu < 0) or not np.isclose(mu.sum(), 1.0):
            raise ValueError(f"mu0 must be {r} non-negative probabilities summing to 1, got {mu0!r}")
        self.mu = mu
        self.layout = layout if layout is not None else max((f.layout for f in self.filters), key=len)
        # index maps: output <- filter j, and filter j <- filter i (shared components)
        self._out_maps = [self._shared(f.layout, self.layout) for f in self.filters]
        self._mix_maps = [[self._shared(fi.layout, fj.layout) for fj in self.filters] for fi in self.filters]
        self._same_layout = all(f.layout == self.filters[0].layout for f in self.filters)
        self.last_innovations: list[Innovation] | None = None

    def _check_pi(self, Pi: np.ndarray) -> None:
        r = len(self.filters)
        if Pi.shape != (r, r) or np.any(Pi < 0) or not np.allclose(Pi.sum(axis=1), 1.0):
            raise ValueError(f"transition must be a {r}×{r} row-stochastic matrix, got {Pi!r}")

    @staticmethod
    def _shared(src: tuple[str, ...], dst: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
        names = [s for s in src if s in dst]
        return np.array([src.index(s) for s in names], dtype=int), np.array([dst.index(s) for s in names], dtype=int)

    # --- combined estimate ------------------------------------------------------------------------------------------
    def _padded(self) -> tuple[list[np.ndarray], list[np.ndarray]]:
        n = len(self.layout)
        xs, Ps = [], []
        for f, (si, di) in zip(self.filters, self._out_maps, strict=True):
            x = np.zeros(n)
            P = np.zeros((n, n))
            x[di] = f.x[si]
            P[np.ix_(di, di)] = f.P[np.ix_(si, si)]
            xs.append(x)
            Ps.append(P)
        return xs, Ps

    @property
    def x(self) -> np.ndarray:
        xs, _ = self._padded()
        return np.einsum("j,jn->n", self.mu, np.array(xs))

    @property
    def P(self) -> np.ndarray:
        xs, Ps = self._padded()
        x = np.einsum("j,jn->n", self.mu, np.array(xs))
        P = np.zeros_like(Ps[0])
        for mu, xj, Pj in zip(self.mu, xs, Ps, strict=True):
            d = xj - x
            P += mu * (Pj + np.outer(d, d))
        return 0.5 * (P + P.T)

    def set_state(self, x: np.ndarray, P: np.ndarray, t: float | None = None) -> None:
        """Set every mode's shared components from ``(x, P)`` in the output layout (others keep their values)."""
        for f, (si, di) in zip(self.filters, self._out_maps, strict=True):
            xf, Pf = f.x.copy(), f.P.copy()
            xf[si] = x[di]
            Pf[np.ix_(si, si)] = P[np.ix_(di, di)]
            f.set_state(xf, Pf, t)
        if t is not None:
            self.t = float(t)

    # --- cycle --------------------------------------------------------------------------------------------------------
    def _mix(self, Pi: np.ndarray) -> None:
        r = len(self.filters)
        cbar = self.mu @ Pi
        Mu = Pi * self.mu[:, None]
        w = Mu / cbar if cbar.min() > 0.0 else Mu / np.where(cbar > 0, cbar, 1.0)  # w[i, j] = μ_{i|j}
        self.mu = cbar
        if self._same_layout:
            # P⁰_j = Σ_i μ_{i|j} (P_i + d_i d_iᵀ) − d⁰_j d⁰_jᵀ with deviations d from one reference state (no
            # cancellation: the reference is one of the estimates), which needs a handful of batched operations.
            X = np.array([f.x for f in self.filters])  # (i, n)
            n = X.shape[1]
            ref = X[0]
            Dc = X - ref
            M = np.array([f.P for f in self.filters]) + Dc[:, :, None] * Dc[:, None, :]
            wT = w.T
            D0 = wT @ Dc  # (j, n)
            P0 = (wT @ M.reshape(r, n * n)).reshape(r, n, n) - D0[:, :, None] * D0[:, None, :]
            X0 = D0 + ref
            for j, f in enumerate(self.filters):
                f.set_state(X0[j], P0[j])
            return
        states = [(f.x, f.P) for f in self.filters]
        for j in range(r):
            xj_own, Pj_own = states[j]
            xs, Ps = [], []
            for i in range(r):
                si, dj = self._mix_maps[i][j]
                x = xj_own.copy()
                x[dj] = states[i][0][si]
                if i == j:
                    P = Pj_own
                else:
                    P = Pj_own.copy()
                    mask = np.zeros(x.size, dtype=bool)
                    mask[dj] = True
                    P[mask, :] = 0.0
                    P[:, mask] = 0.0
                    P[np.ix_(dj, dj)] = states[i][1][np.ix_(si, si)]
                xs.append(x)
                Ps.append(P)
            x0 = sum(w[i, j] * xs[i] for i in range(r))
            P0 = sum(w[i, j] * (Ps[i] + np.outer(xs[i] - x0, xs[i] - x0)) for i in range(r))
            self.filters[j].set_state(x0, 0.5 * (P0 + P0.T))

    def predict(self, t: float) -> None:
        dt = float(t) - self.t
        if dt < -TIME_TOLERANCE:
            raise ValueError(f"cannot predict backwards: t={t} < filter time {self.t} (out-of-sequence measurement)")
        if dt <= TIME_TOLERANCE:
            return
        if len(self.filters) > 1:
            if self._Pi is None:
                Pi = np.asarray(self._transition(dt), dtype=float)  # type: ignore[operator]
                self._check_pi(Pi)
            else:
                Pi = self._Pi
            self._mix(Pi)
        for f in self.filters:
            f.predict(t)
        self.t = float(t)

    def update(self, measurement: MeasurementLike, model: MeasurementModel | None = None) -> Innovation:
        """IMM update; returns the innovation of the most probable mode (all are in ``last_innovations``)."""
        self.predict(measurement.t_meas)
        models: dict[tuple[str, ...], MeasurementModel] = {}
        innovations = []
        for f in self.filters:
            mm = model
            if mm is None:
                mm = models.get(f.layout)
                if mm is None:
                    mm = models[f.layout] = measurement_model(measurement, f.layout, getattr(f, "target_height", 0.0))
            innovations.append(f.update(measurement, mm))
        logw = [inn.log_likelihood + math.log(mu) if mu > 0.0 else -math.inf
                for inn, mu in zip(innovations, self.mu.tolist(), strict=True)]
        top = max(logw)
        if math.isfinite(top):  # log-sum-exp normalisation; all-impossible updates leave μ unchanged
            w = [math.exp(lw - top) for lw in logw]
            total = sum(w)
            self.mu = np.array([v / total for v in w])
        self.last_innovations = innovations
        return innovations[int(np.argmax(self.mu))]


def switching_matrix(n_modes: int, p_stay: float) -> np.ndarray:
    """Mode-transition matrix with ``p_stay`` on the diagonal and the rest spread evenly over the other modes."""
    if not 0.0 < p_stay < 1.0:
        raise ValueError(f"p_stay must be in (0, 1), got {p_stay}")
    off = (1.0 - p_stay) / (n_modes - 1) if n_modes > 1 else 0.0
    return np.full((n_modes, n_modes), off) + np.eye(n_modes) * (p_stay - off)


def cv_ct_imm(x0: np.ndarray, P0: np.ndarray, t0: float, *, q_cv: float, q_ct: float, turn_rate: float,
              p_stay: float, kind: str = "ekf", target_height: float = 0.0) -> IMM:
    """Paper 003's IMM: three filters of type ``kind`` on the CV model and the coordinated turns at ``±turn_rate``
    (rad/s), all on the layout ``(x, vx, y, vy)``, from ``(x0, P0)`` at ``t0`` (s).

    ``q_cv``, ``q_ct``: white-acceleration spectral densities of the CV and CT models (m²/s³); ``p_stay``: diagonal of
    the transition matrix (:func:`switching_matrix`); ``target_height``: the ground plane of the measurement models (m).
    """
    from autonomy.estimation.factory import make_filter
    from autonomy.estimation.models import ConstantVelocity, CoordinatedTurn

    if not turn_rate > 0:
        raise ValueError(f"turn_rate must be > 0 rad/s, got {turn_rate}")
    models = [ConstantVelocity(q=q_cv), CoordinatedTurn(omega=turn_rate, q=q_ct),
              CoordinatedTurn(omega=-turn_rate, q=q_ct)]
    filters = [make_filter(kind, m, x0, P0, t0, target_height=target_height) for m in models]
    return IMM(filters, switching_matrix(len(models), p_stay))


class MoveStopSwitching:
    """Mode-transition matrix ``Π(dt)`` of a car that drives for ``mean_moving_s`` on average before it stops and
    stays stopped ``mean_stopped_s`` on average: the two-state continuous-time Markov chain with rates
    ``a = 1/mean_moving_s`` (move → stop) and ``b = 1/mean_stopped_s`` (stop → move), exactly,
    ``Π(dt) = [[1 − a·e, a·e], [b·e, 1 − b·e]]`` with ``e = (1 − exp(−(a + b) dt)) / (a + b)``; mode 0 moves, mode
    1 is stopped. ``Π(s) Π(t) = Π(s + t)``: the switching does not depend on how often the sensors report."""

    def __init__(self, mean_moving_s: float, mean_stopped_s: float) -> None:
        for name, value in (("mean_moving_s", mean_moving_s), ("mean_stopped_s", mean_stopped_s)):
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"MoveStopSwitching.{name} must be finite and > 0 s, got {value!r}")
        self.a = 1.0 / float(mean_moving_s)
        self.b = 1.0 / float(mean_stopped_s)

    @property
    def stationary(self) -> np.ndarray:
        """The long-run share of time in each mode, ``(b, a) / (a + b)``."""
        return np.array([self.b, self.a]) / (self.a + self.b)

    def __call__(self, dt: float) -> np.ndarray:
        rate = self.a + self.b
        e = -math.expm1(-rate * max(float(dt), 0.0)) / rate
        return np.array([[1.0 - self.a * e, self.a * e], [self.b * e, 1.0 - self.b * e]])


def move_stop_imm(x0: np.ndarray, P0: np.ndarray, t0: float, *, moving: LinearMotionModel, mean_moving_s: float,
                  mean_stopped_s: float, stopped_q: float, kind: str = "ekf", target_height: float = 0.0,
                  **filter_kwargs: object) -> IMM:
    """An IMM of a car that moves and stops: a filter of type ``kind`` on ``moving`` (CV or Singer) and one on the
    :class:`~autonomy.estimation.models.Stopped` model of its layout (position random-walk density ``stopped_q``,
    m²/s), switching as :class:`MoveStopSwitching` says, from ``(x0, P0)`` at ``t0`` (s), the modes weighted by the
    chain's long-run shares. A stopped car's detections then average into its position instead of feeding a
    velocity of noise (the moving model alone lets a radar-only track of a stopped car wander by the radar's
    cross-range error). ``filter_kwargs`` go to each mode's filter (e.g. an EKF's ``iterations``)."""
    from autonomy.estimation.factory import make_filter

    switching = MoveStopSwitching(mean_moving_s, mean_stopped_s)
    models = [moving, Stopped(layout_of=moving.layout, q=stopped_q)]
    filters = [make_filter(kind, m, x0, P0, t0, target_height=target_height, **filter_kwargs) for m in models]
    return IMM(filters, switching, mu0=switching.stationary)
