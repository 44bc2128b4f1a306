"""Classification-aided association: a detection's class readings as a factor of its association likelihood.

A detection ``j`` that reports classes (a camera's colour and body type, a radar's length class:
:class:`~autonomy.sensing.measurement.ClassMeasurement`, each with its likelihood vector ``L_j(c) = C[c, o_j]`` over
the true class ``c``) is evidence of *which* car it comes from, beside where it is. Under "``j`` is track ``i``'s car"
the reading has probability ``Σ_c p̃_i(c) L_j(c)``, with ``p̃_i = (1 − ε) p_i + ε π`` the track's predicted class
distribution: its posterior ``p_i(c) ∝ π(c) e^{ℓ_i(c)}`` from the readings it took (``ℓ_i`` the per-class
log-likelihood :func:`~.identity.accumulate_readings` keeps, ``π`` the background cars' class frequencies), mixed
with the chance ``ε`` (``swap_probability``) that the car under the track changed since. Under "``j`` is a car of no
track" (a new car, or clutter) it has probability ``Σ_c π(c) L_j(c)``. The association likelihood of the pair is
multiplied by their ratio (Bar-Shalom, Willett and Tian, *Tracking and Data Fusion*, 2011, §3.4 "feature-aided
association"), per attribute the detection reports (readings of attributes independent given the car):

    log λᵢⱼ = Σ_a log( p̃ᵢᵃ · Lⱼᵃ / πᵃ · Lⱼᵃ )

so a track that has read a red sedan again and again is unlikely to take a detection that reads a blue van where two
cars pass within the sensors' resolution, and a track without readings (``p_i = π``) is indifferent (``λ = 1``). GNN
subtracts ``2 log λ`` from the pair's cost ``−2 log N(ν; 0, S)``; JPDA adds ``log λ`` to the pair's log-likelihood
ratio.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

__all__ = ["ClassAffinity"]


class ClassAffinity:
    """``log λ`` of gated (track, detection) pairs from class readings (module docstring).

    Parameters
    ----------
    background : Mapping[str, np.ndarray]
        Per attribute, the (K,) class frequencies ``π`` of the cars (an attribute missing here: uniform).
    swap_probability : float
        ``ε`` in [0, 1): the chance that the car under a track changed since its last reading.
    """

    def __init__(self, background: Mapping[str, np.ndarray], swap_probability: float) -> None:
        if not 0.0 <= swap_probability < 1.0:
            raise ValueError(f"ClassAffinity.swap_probability must be in [0, 1), got {swap_probability!r}")
        self.background = {k: np.asarray(v, dtype=float) for k, v in background.items()}
        self.swap_probability = float(swap_probability)

    def log_ratios(self, tracks: Sequence[object], detections: Sequence[object], rows: np.ndarray,
                   cols: np.ndarray) -> np.ndarray | None:
        """``log λ`` of each pair ``(tracks[rows[k]], detections[cols[k]])``; None when no detection of the pairs
        reports a class (every ratio would be 1)."""
        readings: dict[str, dict[int, np.ndarray]] = {}  # attribute -> detection index -> likelihood vector
        for j in np.unique(cols).tolist():
            for c in getattr(detections[j], "classes", ()):
                readings.setdefault(c.attribute, {})[j] = np.asarray(c.likelihood(), dtype=float)
        if not readings:
            return None
        out = np.zeros(len(rows))
        for name, by_det in readings.items():
            k = next(iter(by_det.values())).size
            prior = self.background.get(name)
            prior = np.full(k, 1.0 / k) if prior is None or prior.size != k else prior
            sel = np.flatnonzero(np.isin(cols, np.fromiter(by_det, dtype=np.int64)))
            if not sel.size:
                continue
            L = np.stack([by_det[j] for j in cols[sel].tolist()])                    # (pairs, K)
            uniq, at = np.unique(rows[sel], return_inverse=True)
            predicted = self._predicted_many([tracks[i] for i in uniq.tolist()], name, prior)[at]  # once per track
            num = np.einsum("pk,pk->p", predicted, L)
            den = L @ prior
            out[sel] += np.log(np.maximum(num, 1e-300)) - np.log(np.maximum(den, 1e-300))
        return out

    def _predicted_many(self, tracks: Sequence[object], name: str, prior: np.ndarray) -> np.ndarray:
        """(T, K) ``p̃`` of every track for attribute ``name`` (``prior`` = π; a track without readings of it: π),
        those with readings computed together."""
        out = np.tile(prior, (len(tracks), 1))
        ells = [getattr(tr, "class_loglik", {}).get(name) for tr in tracks]
        read = [k for k, ell in enumerate(ells) if ell is not None and np.size(ell) == prior.size]
        if read:
            E = np.array([ells[k] for k in read], dtype=float).reshape(len(read), prior.size)
            w = prior * np.exp(E - E.max(axis=1, keepdims=True))
            post = w / w.sum(axis=1, keepdims=True)
            out[read] = (1.0 - self.swap_probability) * post + self.swap_probability * prior
        return out
