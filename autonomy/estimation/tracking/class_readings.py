"""A multi-target tracker's class readings: the class measurements of the detections that updated its tracks, into
each track's per-class log-likelihoods and class evidence (:mod:`.identity`).

A GNN scan's tracks each take one detection whole (:func:`taken_readings`); a JPDA track takes every detection of its
scan with its association probability (:func:`weighted_readings`). Either way :func:`absorb` reads them: per
attribute, every listed track's discounted log-likelihoods (:func:`.identity.accumulate_readings`) and then each
track's evidence (:func:`.identity.class_evidence`) are computed as the rows of one array where the tracks' arrays
share a shape, each row the same numbers as that track alone. The tracker hands the evidence of its confirmed tracks
to the identity belief (:meth:`.identity.TargetIdentity.read_many`).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from autonomy.estimation.measurements import MeasurementLike

from .identity import IdentityConfig, accumulate_readings, class_evidence
from .track import Track

__all__ = ["Readings", "absorb", "taken_readings", "weighted_readings"]

Readings = dict[str, list[tuple[Track, np.ndarray]]]
"""Per attribute, each track with the per-class likelihood of its new readings."""

def weighted_readings(track: Track, weighted: Sequence[tuple[float, MeasurementLike]],
                      none_weight: float = 0.0) -> Readings:
    """The readings of the detections that updated ``track`` with the weights ``weighted`` (association
    probabilities): per attribute, the per-class likelihood of the scan being the mixture ``β₀ + Σ βⱼ C_j[c, o_j]``
    (``β₀`` = ``none_weight``); a detection taken whole (weight 1, no miss) gives its own likelihood."""
    by_attr: dict[str, np.ndarray] = {}
    for w, det in weighted:
        for c in getattr(det, "classes", ()):
            lik = np.asarray(c.likelihood(), dtype=float)
            prev = by_attr.get(c.attribute)
            if prev is None and w == 1.0 and none_weight == 0.0:  # one detection taken whole: 0 + 1 · lik
                by_attr[c.attribute] = lik
            else:
                by_attr[c.attribute] = (np.full(lik.size, none_weight) if prev is None else prev) + w * lik
    return {name: [(track, lik)] for name, lik in by_attr.items()}


def taken_readings(pairs: Sequence[tuple[Track, MeasurementLike]]) -> tuple[Readings, list[Track]] | None:
    """The readings of a GNN scan, each track with the one detection it took whole, and the tracks that read any, in
    the scan's order; None where they cannot be read together (a detection reading one attribute twice, or a track
    taking two detections): then each is :func:`weighted_readings` of its own."""
    reads = [(tr, det.classes) for tr, det in pairs if getattr(det, "classes", ())]
    if (any(len({c.attribute for c in classes}) != len(classes) for _, classes in reads)
            or len({id(tr) for tr, _ in reads}) != len(reads)):
        return None
    by_attr: Readings = {}
    for track, classes in reads:
        for c in classes:
            by_attr.setdefault(c.attribute, []).append((track, c.likelihood()))
    return by_attr, [tr for tr, _ in reads]


def absorb(by_attr: Readings, tracks: Sequence[Track], ident: IdentityConfig) -> None:
    """Per attribute, each listed track's likelihood of its new readings (per class) into its per-class
    log-likelihoods (:func:`.identity.accumulate_readings`); then the class evidence of ``tracks`` (each once; that
    of :func:`.identity.track_evidence`, within ±50). Arrays of one shape are computed as the
    rows of one array, each row the same numbers as alone."""
    for name, items in by_attr.items():
        bg = ident.background.get(name)
        liks = [lik for _, lik in items]
        prev = [tr.class_loglik.get(name) for tr, _ in items]
        before = [k for k, ell in enumerate(prev) if ell is not None]
        if _alike(liks) and _alike([prev[k] for k in before]):
            step = np.log(np.maximum(np.array(liks, dtype=float), 1e-300))
            ells = list(step)  # a first reading: its step
            if before:
                new = accumulate_readings(np.array([prev[k] for k in before], dtype=float), step[before], bg,
                                          ident.swap_probability)
                for k, ell in zip(before, new, strict=True):
                    ells[k] = ell
        else:
            ells = [accumulate_readings(ell, np.log(np.maximum(lik, 1e-300)), bg, ident.swap_probability)
                    for ell, lik in zip(prev, liks, strict=True)]
        for (track, _), ell in zip(items, ells, strict=True):
            track.class_loglik[name] = ell
    total = np.zeros(len(tracks))
    for name, c_t in ident.target_classes.items():
        has = [k for k, tr in enumerate(tracks) if tr.class_loglik.get(name) is not None]
        if not has:
            continue
        ells = [tracks[k].class_loglik[name] for k in has]
        bg = ident.background.get(name)
        total[has] += (class_evidence(np.array(ells, dtype=float), c_t, bg) if _alike(ells)
                       else [class_evidence(ell, c_t, bg) for ell in ells])
    for track, evidence in zip(tracks, np.clip(total, -50.0, 50.0).tolist(), strict=True):
        track.evidence = evidence


def _alike(arrays: Sequence[np.ndarray]) -> bool:
    """Whether ``arrays`` all have one shape (and so stack into the rows of one array)."""
    return len({np.shape(a) for a in arrays}) <= 1
