"""The EKF updates of one scan's assigned pairs, batched: many car tracks take their detections in one set of array
operations instead of one small matrix product chain each.

For the pairs whose filter is a plain :class:`~autonomy.estimation.ekf.EKF` (one linearisation per update) and whose
detection has the scan's measurement size, each filter is predicted to the scan time and linearised at its prediction
(``h``, ``H`` and the angle-wrapped residual of its own detection model, per pair), then all of them are updated at
once with the same equations as :meth:`EKF.update_with` (``S = H P Hᵀ + R``, ``K = P Hᵀ S⁻¹``, ``x += K ν``, the
Joseph form, symmetrised) and written back with ``set_state``. The other pairs (UKF, CKF, SCIF, IMM, road-network
filters) take their own ``update``. The results equal the per-filter updates to round-off (a test holds them to 1e-9).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from autonomy.estimation.base import TIME_TOLERANCE
from autonomy.estimation.ekf import EKF
from autonomy.estimation.measurements import MeasurementLike, measurement_model

__all__ = ["update_pairs"]

_MIN_BATCH = 4  # below this many EKF pairs the per-filter path is as fast


def update_pairs(pairs: Sequence[tuple[object, MeasurementLike]], layout: tuple[str, ...],
                 target_height: float) -> None:
    """Update each ``(filter, detection)`` pair's filter with its detection (module docstring)."""
    batch, rest = [], []
    for f, det in pairs:
        (batch if type(f) is EKF and f.iterations == 1 else rest).append((f, det))
    if len(batch) < _MIN_BATCH or len({np.size(d.z) for _, d in batch}) != 1:
        rest, batch = list(pairs), []
    for f, det in rest:
        f.update(det)
    if not batch:
        return
    n = len(batch)
    x, P = _predicted(batch)
    models, key = [], None
    for _, det in batch:
        p_s = getattr(det, "p_sensor_W", None)
        this = None if p_s is None or getattr(det, "v_sensor_W", None) is not None else (
            id(det.model), np.asarray(p_s, dtype=float).tobytes())
        if this is None or this != key:  # one scan: one sensor pose, one model
            models.append(measurement_model(det, layout, target_height))
            key = this
        else:
            models.append(models[-1])
    Z = np.array([det.z for _, det in batch], dtype=float)
    R = np.array([det.R for _, det in batch], dtype=float)
    if all(m is models[0] for m in models):
        Z_pred, H = models[0].linearise_batch(x)
        nu = models[0].residual_batch(Z, Z_pred)
    else:
        lin = [m.linearise(xk) for m, xk in zip(models, x, strict=True)]
        H = np.array([h for _, h in lin])
        nu = np.array([m.residual(z, zp) for m, z, (zp, _) in zip(models, Z, lin, strict=True)])
    PHt = P @ np.transpose(H, (0, 2, 1))
    S = H @ PHt + R
    K = PHt @ np.linalg.inv(S)
    x = x + np.einsum("nij,nj->ni", K, nu)
    IKH = np.eye(x.shape[1])[None] - K @ H
    P = IKH @ P @ np.transpose(IKH, (0, 2, 1)) + K @ R @ np.transpose(K, (0, 2, 1))
    P = 0.5 * (P + np.transpose(P, (0, 2, 1)))
    for k in range(n):
        f, det = batch[k]
        f.set_state(x[k], P[k], det.t_meas)


def _predicted(batch: Sequence[tuple[EKF, MeasurementLike]]) -> tuple[np.ndarray, np.ndarray]:
    """Each filter's state and covariance predicted to its detection's time, batched over the filters that share a
    linear motion model and a time step (``x⁻ = F x``, ``P⁻ = F P Fᵀ + Q``, as :meth:`EKF._predict`)."""
    n = len(batch)
    x = np.empty((n, batch[0][0].x.size))
    P = np.empty((n, x.shape[1], x.shape[1]))
    groups: dict[tuple[int, float], list[int]] = {}
    for k, (f, det) in enumerate(batch):
        dt = float(det.t_meas) - f.t
        if f.model.is_linear and dt > TIME_TOLERANCE:
            groups.setdefault((id(f.model), dt), []).append(k)
        else:
            f.predict(det.t_meas)
            x[k], P[k] = f.x, f.P
    for (_, dt), ks in groups.items():
        F, Q = batch[ks[0]][0].model.matrices(dt)
        X = np.array([batch[k][0].x for k in ks])
        PP = np.array([batch[k][0].P for k in ks])
        x[ks] = X @ F.T
        P[ks] = F @ PP @ F.T + Q
    return x, P
