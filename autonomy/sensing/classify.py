"""Class readings of detected objects: a confusion matrix per attribute, and the draw of an observed class.

A :class:`Classifier` reads one class attribute (``"colour"``, ``"body"``, ``"length"``: the keys of
:attr:`~autonomy.sensing.scene.TargetTruth.attributes`, with the class lists of ``worlds.catalog``) with the
(K, K) row-stochastic confusion matrix ``C``, ``C[true, observed] = p(observed | true)``, given either as a full
matrix or by a scalar accuracy ``a`` (the symmetric channel)::

    C = a I + (1 - a) / (K - 1) (1 1^T - I),   1 / K < a <= 1

so the reading tells something about the class (``a > 1/K``). A detection whose object has no such attribute (a
false alarm, a static decoy: class ``-1``) is read as a uniformly drawn class; the reported confusion matrix stays
``C``, which is what a tracker must assume for an object it cannot tell from a car.

Sensors draw their class readings from their own generator, spawned from the scan's generator
(:func:`class_generator`) only when they classify something and after their other draws, so turning
classification on or off changes none of the other random numbers of a run.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from worlds.catalog import CAR_ATTRIBUTES

from .measurement import ClassMeasurement
from .scene import TargetTruth

__all__ = ["ROW_SUM_TOL", "Classifier", "class_generator", "check_classifiers", "read_classes"]

ROW_SUM_TOL = 1e-6
"""Largest ``|sum_j C[i, j] - 1|`` accepted of a configured confusion row (rows are renormalised after the check)."""


def symmetric_confusion(n_classes: int, accuracy: float) -> np.ndarray:
    """(K, K) confusion matrix with ``accuracy`` on the diagonal and ``(1 - accuracy) / (K - 1)`` elsewhere."""
    off = (1.0 - accuracy) / (n_classes - 1)
    return np.full((n_classes, n_classes), off) + (accuracy - off) * np.eye(n_classes)


@dataclass(frozen=True, kw_only=True)
class Classifier:
    """How a sensor reads one class attribute.

    Attributes
    ----------
    attribute : str
        The attribute read (a key of ``TargetTruth.attributes``).
    n_classes : int
        Number of classes K (>= 2).
    accuracy : float | None
        Probability of reporting the true class, in (1/K, 1]; the wrong classes share the rest equally. Give this or
        ``confusion``.
    confusion : np.ndarray | None
        (K, K) row-stochastic matrix, ``confusion[true, observed]``; non-negative rows summing to 1 within
        :data:`ROW_SUM_TOL`. Give this or ``accuracy``.
    matrix : np.ndarray
        (K, K) the confusion matrix in use (read-only; built from ``accuracy`` or ``confusion``).
    """

    attribute: str
    n_classes: int
    accuracy: float | None = None
    confusion: np.ndarray | None = None
    matrix: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.attribute, str) or not self.attribute:
            raise ValueError(f"Classifier.attribute must be a non-empty string, got {self.attribute!r}")
        k = self.n_classes
        if isinstance(k, bool) or not isinstance(k, int | np.integer) or k < 2:
            raise ValueError(f"Classifier.n_classes must be an integer >= 2, got {k!r}")
        if (self.accuracy is None) == (self.confusion is None):
            raise ValueError("Classifier needs exactly one of accuracy and confusion")
        if self.accuracy is not None:
            a = self.accuracy
            if not (isinstance(a, int | float) and 1.0 / k < a <= 1.0):
                raise ValueError(f"Classifier.accuracy must be in (1/{k}, 1] (better than a guess among {k} "
                                 f"classes), got {a!r}")
            C = symmetric_confusion(k, float(a))
        else:
            C = np.array(self.confusion, dtype=float)
            if C.shape != (k, k):
                raise ValueError(f"Classifier.confusion must be ({k}, {k}) for {k} classes of "
                                 f"{self.attribute!r}, got shape {C.shape}")
            if not np.all(np.isfinite(C)) or np.any(C < 0):
                raise ValueError("Classifier.confusion must have finite, non-negative entries")
            sums = C.sum(axis=1)
            bad = np.flatnonzero(np.abs(sums - 1.0) > ROW_SUM_TOL)
            if bad.size:
                raise ValueError(f"Classifier.confusion rows must sum to 1, row {int(bad[0])} sums to "
                                 f"{sums[bad[0]]:.9g}")
            C = C / sums[:, None]
            C.setflags(write=False)
            object.__setattr__(self, "confusion", C)
        C.setflags(write=False)
        object.__setattr__(self, "n_classes", int(k))
        object.__setattr__(self, "matrix", C)
        object.__setattr__(self, "_cdf", np.cumsum(C, axis=1))

    @classmethod
    def for_attribute(cls, attribute: str, *, accuracy: float | None = None,
                      confusion: np.ndarray | Sequence[Sequence[float]] | None = None) -> Classifier:
        """A classifier of a car attribute of ``worlds.catalog.CAR_ATTRIBUTES`` (K = the size of its class list)."""
        if attribute not in CAR_ATTRIBUTES:
            raise ValueError(f"Classifier attribute must be one of {', '.join(CAR_ATTRIBUTES)}, got {attribute!r}")
        return cls(attribute=attribute, n_classes=len(CAR_ATTRIBUTES[attribute]), accuracy=accuracy,
                   confusion=None if confusion is None else np.asarray(confusion, dtype=float))

    def read(self, true_class: int, rng: np.random.Generator) -> ClassMeasurement:
        """One reading of an object of class ``true_class`` (-1: none, read uniformly); one uniform draw of ``rng``.

        The observed class is ``j`` with probability ``matrix[true_class, j]`` (``1/K`` for ``true_class = -1``).
        """
        k = self.n_classes
        t = int(true_class)
        if not -1 <= t < k:
            raise ValueError(f"true_class of {self.attribute!r} must be in [-1, {k}), got {true_class!r}")
        u = rng.random()
        if t < 0:
            observed = min(int(u * k), k - 1)
        else:
            observed = min(int(np.searchsorted(self._cdf[t], u, side="right")), k - 1)
        return ClassMeasurement(attribute=self.attribute, observed=observed, confusion=self.matrix)


def check_classifiers(owner: str, classifiers: Sequence[Classifier], readable: Sequence[str]) -> tuple[Classifier, ...]:
    """``classifiers`` as a tuple, checked: each a :class:`Classifier` of one of the attributes ``readable`` (at most
    one per attribute) with the class count of ``worlds.catalog``. ``owner`` names the config in the errors."""
    out = tuple(classifiers)
    seen: set[str] = set()
    for c in out:
        if not isinstance(c, Classifier):
            raise ValueError(f"{owner}.classify must hold Classifier objects, got {type(c).__name__}")
        if c.attribute not in readable:
            raise ValueError(f"{owner}.classify reads only {', '.join(readable)}, got {c.attribute!r}")
        if c.attribute in seen:
            raise ValueError(f"{owner}.classify reads {c.attribute!r} twice")
        seen.add(c.attribute)
        k = len(CAR_ATTRIBUTES[c.attribute])
        if c.n_classes != k:
            raise ValueError(f"{owner}.classify: {c.attribute!r} has {k} classes, the classifier {c.n_classes}")
    return out


def class_generator(rng: np.random.Generator) -> np.random.Generator:
    """A generator for a scan's class readings, spawned from the scan's ``rng`` (its stream is not advanced)."""
    return rng.spawn(1)[0]


def read_classes(classifiers: Sequence[Classifier], truth_ids: Sequence[int], targets: TargetTruth,
                 rng: np.random.Generator) -> list[tuple[ClassMeasurement, ...]]:
    """The class readings of each detection: for detection ``n`` of target ``truth_ids[n]`` (-1: a false alarm),
    one :class:`ClassMeasurement` per classifier, drawn in detection order, then classifier order."""
    attrs = targets.attributes or {}
    row = {int(tid): r for r, tid in enumerate(targets.ids)}
    out = []
    for tid in truth_ids:
        r = row.get(int(tid))
        readings = []
        for c in classifiers:
            values = attrs.get(c.attribute)
            true = -1 if r is None or values is None else int(values[r])
            readings.append(c.read(true, rng))
        out.append(tuple(readings))
    return out
