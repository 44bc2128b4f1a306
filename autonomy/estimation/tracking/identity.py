"""Which track is the designated target: a categorical belief over the hypotheses "track k is the target" and "the
target is in no track", kept by Bayes' rule.

Hypotheses ``H_k`` (the target is track k, one per confirmed track) and ``H_0`` (it is in none of them) carry weights
``w_k``, ``w_0`` that sum to 1. What changes them:

- **class readings** (:class:`~autonomy.sensing.measurement.ClassMeasurement`) on track k: a car's class is drawn
  once and every reading of it is conditionally independent given that class, so the track keeps per attribute the
  log-likelihood of its readings for every class, ``ℓ(c) = Σ_i log C_i[c, o_i]`` (the sensor's confusion ``C_i``,
  the reported class ``o_i``). Under ``H_k`` the readings have likelihood ``exp ℓ(c_T)`` (the target's known class
  ``c_T``); under every other hypothesis track k is a background car, of likelihood ``Σ_c π(c) exp ℓ(c)`` with the
  background population's class frequencies ``π``. The track's evidence is ``E_k = Σ_attributes [ℓ(c_T) −
  log Σ_c π(c) exp ℓ(c)]`` (:func:`track_evidence`) and ``w_k ∝ (continuity weight) · exp E_k``. Many readings of
  a look-alike's class therefore raise its weight by at most ``1 / π(c_T)``, however often it is seen. The car under a
  track may change (two cars pass within the sensors' resolution and the assignment swaps them): with probability
  ``ε`` (``swap_probability``) per reading the track's car is since its last reading a car drawn from the background,
  a hidden Markov chain over the car's class whose forward recursion is, per attribute,
  ``ℓₜ(c) = log C[c, oₜ] + log((1 − ε) e^{ℓₜ₋₁(c)} + ε Σ_c' π(c') e^{ℓₜ₋₁(c')})`` (:func:`accumulate_readings`;
  ``ℓ(c)`` is then the log-likelihood of the readings given the track's *current* car is of class ``c``, and ``ε = 0``
  gives the sum above). Old readings are discounted: a track that swapped from the target to a car of another colour
  loses its evidence after two or three readings of the new car instead of as many as it had of the old one. A teammate
  may add a track's evidence from the UAV's own sensors to its own belief;
- **a confirmed new track** j (position ``x_j``, covariance ``P_j``, evidence ``E_j``): under every existing
  hypothesis ``H_k`` (and under ``H_0`` too, if the target stays unseen) the new track is a background car, of
  likelihood ``ρ`` (the density of background cars that could start a track, cars per m²); under ``H_0`` it may
  instead be the target, of likelihood ``e^{E_j} p_T(x_j)``, where ``p_T = N(x_j; μ, Σ + P_j)`` is where the target
  is believed to be while in no track (the cue, or the last target track's estimate, with ``Σ`` grown by
  ``(search_speed · Δt)²`` per axis since then). So ``w_k ← w_k ρ``, ``w_j = w_0 e^{E_j} p_T(x_j)``,
  ``w_0 ← w_0 ρ``, normalised: a car that shows up nearer the cue later (the target was stopped, or hidden) takes
  the belief from one that showed up first but farther;
- **a radar scan that starts no new car near the search region**: under ``H_0`` the target is somewhere in the
  search region, unseen; a radar whose field of regard covers the region would have detected it with probability
  ``q`` (``search_detection_probability``: the radar's detection probability times the chance the target is in its
  line of sight, a property of the sensor and the town), and its detection would have started a track there. So every
  position-fixing scan none of whose unassigned detections falls in the search region's 99 % ellipse multiplies
  ``w_0`` by ``1 − q``: the target's no longer being in any track becomes implausible while every car in view is
  tracked, and a track that read the target's class (rather than one that only inherited the belief) takes it;
- **two tracks such a scan could not tell apart** (their estimates' difference inside the 99 % χ² gate of their
  summed covariances) may have swapped cars: each weight is a continuity part (from births, deaths and merges) times
  the class evidence ``e^{E_k}``, and the pair's continuity parts move towards each other by ``swap_probability``, so
  after two cars met, their own class readings decide which carries the target;
- **a deleted track** k: ``w_0 ← w_0 + w_k``; if ``H_k`` was the likelier of the two, the track's last estimate
  becomes where the target is believed to be (so a lost target is re-acquired from the tracks born near where it was
  last seen, with the search region growing with time).

The target track is the most probable track if its probability reaches ``min_probability`` (even while "the target
is in no track" is as likely: following the best candidate is what lets the UAV resolve the doubt, as its camera,
pointed at that track, reads its colour and type, which confirm it or move the belief to another track); otherwise
there is none and the target is believed to be near ``μ`` (the search centre).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

import numba
import numpy as np

__all__ = ["CHI2_2_99", "IdentityConfig", "SearchCentre", "TargetIdentity", "accumulate_readings",
           "background_frequencies", "class_evidence", "track_evidence"]

CHI2_2_99 = 9.2103
"""The 99 % quantile of χ² with 2 degrees of freedom: a search region's, or two tracks' difference's, gate."""


@dataclass(frozen=True, kw_only=True)
class IdentityConfig:
    """Target-identity settings.

    Attributes
    ----------
    target_classes : Mapping[str, int]
        The designated target's class per attribute (``worlds.catalog.car_classes``); readings of other attributes
        are ignored. Empty: identity by position and continuity alone.
    background : Mapping[str, np.ndarray]
        Per attribute, the (K,) class frequencies of the background cars (sum 1); an attribute of ``target_classes``
        missing here takes uniform frequencies.
    background_density : float
        Background cars per m² that could start a track (> 0), e.g. the traffic's car count over the road map's area.
    search_speed : float
        How fast the believed region of a target in no track grows (m/s per axis, > 0): a car's typical speed.
    min_probability : float
        Smallest probability in (0, 1] of the most probable track for it to be taken as the target.
    swap_probability : float
        Probability in [0, 1) that the car under a track changed since its last class reading (module docstring).
    search_detection_probability : float
        Probability in [0, 1) that one position-fixing scan detects a target in the search region (module docstring;
        0: the target's being in no track is never made less likely by scans that find nothing there).
    """

    target_classes: Mapping[str, int]
    background: Mapping[str, np.ndarray]
    background_density: float = 1e-4
    search_speed: float = 8.0
    min_probability: float = 0.2
    swap_probability: float = 0.02
    search_detection_probability: float = 0.0

    def __post_init__(self) -> None:
        if not self.background_density > 0:
            raise ValueError(f"IdentityConfig.background_density must be > 0 cars/m², got {self.background_density!r}")
        if not self.search_speed > 0:
            raise ValueError(f"IdentityConfig.search_speed must be > 0 m/s, got {self.search_speed!r}")
        if not 0 <= self.search_detection_probability < 1:
            raise ValueError(f"IdentityConfig.search_detection_probability must be in [0, 1), got "
                             f"{self.search_detection_probability!r}")
        if not 0 <= self.swap_probability < 1:
            raise ValueError(f"IdentityConfig.swap_probability must be in [0, 1), got {self.swap_probability!r}")
        if not 0 < self.min_probability <= 1:
            raise ValueError(f"IdentityConfig.min_probability must be in (0, 1], got {self.min_probability!r}")
        for name, freq in self.background.items():
            f = np.asarray(freq, dtype=float)
            if f.ndim != 1 or np.any(f < 0) or not math.isclose(float(f.sum()), 1.0, abs_tol=1e-9):
                raise ValueError(f"IdentityConfig.background[{name!r}] must be non-negative frequencies summing to 1")


@dataclass(frozen=True)
class SearchCentre:
    """Where the target is believed to be while it is in no track: ``N(p, var · I + growth)`` at time ``t``.

    Attributes
    ----------
    t : float
        Time of ``p`` (s).
    p : np.ndarray
        (2,) position (m).
    v : np.ndarray
        (2,) velocity it is predicted with (m/s).
    P : np.ndarray
        (2, 2) position covariance at ``t`` (m²).
    """

    t: float
    p: np.ndarray
    v: np.ndarray
    P: np.ndarray

    def at(self, t: float, search_speed: float) -> tuple[np.ndarray, np.ndarray]:
        """Mean (m) and covariance (m²) of the target's position at ``t`` (s): moved with ``v`` for up to 10 s, the
        covariance grown by ``(search_speed · Δt)²`` per axis."""
        dt = max(0.0, t - self.t)
        mean = self.p + self.v * min(dt, 10.0)
        return mean, self.P + np.eye(2) * (search_speed * dt) ** 2


def accumulate_readings(previous: np.ndarray | None, step: np.ndarray, frequencies: np.ndarray | None,
                        swap_probability: float) -> np.ndarray:
    """A track's per-class log-likelihood after one more reading of log-likelihood ``step`` (per class), from
    ``previous`` (None: the first reading): ``ℓₜ(c) = step(c) + log((1 − ε) e^{ℓₜ₋₁(c)} + ε Σ_c' π(c') e^{ℓₜ₋₁(c')})``
    with ``ε = swap_probability`` and ``π = frequencies`` (uniform if None), module docstring. ``previous`` and
    ``step`` may be (n, K): n tracks' readings at once, each row as alone."""
    step = np.asarray(step, dtype=float)
    if previous is None:
        return step.copy()
    prev = np.asarray(previous, dtype=float)
    if swap_probability == 0.0:
        return prev + step
    k = prev.shape[-1]
    freq = np.full(k, 1.0 / k) if frequencies is None else np.asarray(frequencies, dtype=float)
    top = prev.max(axis=-1, keepdims=True)
    e = np.exp(prev - top)
    mixed = (1.0 - swap_probability) * e + swap_probability * _weighted_sum(e, freq)[..., None]
    return step + top + np.log(mixed)


def class_evidence(loglik: np.ndarray, target_class: int, frequencies: np.ndarray | None) -> np.ndarray:
    """One attribute's term of :func:`track_evidence`, ``ℓ(c_T) − log Σ_c π(c) exp ℓ(c)``, of per-class
    log-likelihoods ``loglik`` (K,), or of (n, K) rows at once; ``π = frequencies`` (uniform if None)."""
    ell = np.asarray(loglik, dtype=float)
    k = ell.shape[-1]
    freq = np.full(k, 1.0 / k) if frequencies is None else np.asarray(frequencies, dtype=float)
    top = ell.max(axis=-1)
    return ell[..., target_class] - (top + np.log(_weighted_sum(np.exp(ell - top[..., None]), freq)))


def track_evidence(loglik: Mapping[str, np.ndarray], config: IdentityConfig) -> float:
    """``E = Σ_a [ℓ_a(c_T) − log Σ_c π_a(c) exp ℓ_a(c)]`` over the attributes the target has a class for, from a
    track's per-class log-likelihoods ``loglik[attribute]`` of its readings (module docstring), within ±50."""
    total = 0.0
    for name, c_t in config.target_classes.items():
        ell = loglik.get(name)
        if ell is not None:
            total += float(class_evidence(ell, c_t, config.background.get(name)))
    return max(min(total, 50.0), -50.0)


def _weighted_sum(e: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``Σ_c w(c) e(c)`` along the last axis of ``e``, the products added one after another in class order (as a
    dot product of so few terms is), so that a row gives the same bits alone or among others."""
    total = e[..., 0] * w[0]
    for c in range(1, e.shape[-1]):
        total = total + e[..., c] * w[c]
    return total


class TargetIdentity:
    """The belief over which confirmed track is the designated target (module docstring).

    Parameters
    ----------
    config : IdentityConfig
        Settings.
    """

    def __init__(self, config: IdentityConfig) -> None:
        self.config = config
        # the weights of the hypotheses "track k is the target", in the order the tracks were taken: an array, so
        # that renormalising after each of a scan's hundreds of class readings is one vector operation
        self._ids: list[int] = []
        self._at: dict[int, int] = {}  # track id -> index in _ids and _w
        self._w = np.zeros(0)
        self.evidence: dict[int, float] = {}
        self.w_none = 1.0
        self.centre: SearchCentre | None = None

    @property
    def weights(self) -> dict[int, float]:
        """A copy of the probabilities of the tracks the belief holds (track id → probability), in the order the
        tracks were taken."""
        return dict(zip(self._ids, self._w.tolist(), strict=True))

    @property
    def held(self) -> int:
        """How many tracks the belief holds."""
        return len(self._ids)

    def holds(self, track_id: int) -> bool:
        """Whether the belief holds track ``track_id``."""
        return track_id in self._at

    def cue(self, t: float, p: np.ndarray, sigma_m: float) -> None:
        """The hand-off: the target is near ``p`` (m) at ``t`` (s) with standard deviation ``sigma_m`` (m) per axis."""
        self.centre = SearchCentre(t=float(t), p=np.asarray(p, dtype=float)[:2].copy(), v=np.zeros(2),
                                   P=np.eye(2) * float(sigma_m) ** 2)

    def probability(self, track_id: int) -> float:
        """Probability that track ``track_id`` is the target (0 for a track the belief does not hold)."""
        i = self._at.get(track_id)
        return 0.0 if i is None else float(self._w[i])

    def target(self) -> int | None:
        """Id of the most probable track (of equally probable ones, the smallest id) if its probability reaches
        ``min_probability``, else None."""
        if not self._ids:
            return None
        top = self._w.max()
        k = min(self._ids[i] for i in np.flatnonzero(self._w == top).tolist())
        return k if top >= self.config.min_probability else None

    def confirmed(self, track_id: int, t: float, p: np.ndarray, P: np.ndarray, evidence: float) -> None:
        """Track ``track_id`` was confirmed at ``t`` (s) at position ``p`` (m) with covariance ``P`` (2×2, m²) and
        class evidence ``evidence`` (log-likelihood ratio): it takes its share of ``H_0``."""
        if self.centre is None:  # no cue: every new track is as likely the target as any background car
            density = self.config.background_density
        else:
            mean, S = self.centre.at(t, self.config.search_speed)
            S = S + np.asarray(P, dtype=float)[:2, :2]
            d = np.asarray(p, dtype=float)[:2] - mean
            maha = float(d @ np.linalg.solve(S, d))
            density = math.exp(-0.5 * maha) / (2.0 * math.pi * math.sqrt(max(np.linalg.det(S), 1e-300)))
        odds = math.exp(min(evidence, 50.0)) * density / self.config.background_density  # relative to ρ
        self._set(track_id, self.w_none * odds)  # every other hypothesis keeps its weight × ρ / ρ
        self.evidence[track_id] = min(evidence, 50.0)
        self._normalise()

    def read(self, track_id: int, evidence: float,
             where: Callable[[], tuple[float, np.ndarray, np.ndarray, np.ndarray]] | None = None) -> None:
        """Track ``track_id``'s class evidence is now ``evidence`` (:func:`track_evidence` of all its readings): its
        weight changes by ``exp(evidence − previous evidence)``. If that takes the track from likelier the target than
        ``H_0`` to less likely (its readings turned: it swapped onto another car), the target is believed to be near
        where the track is, ``where()`` = (t, p, v, P) as for :meth:`deleted`, and searched for from there."""
        self.read_many([track_id], [evidence], None if where is None else lambda _: where())

    def read_many(self, track_ids: Sequence[int], evidences: Sequence[float],
                  where: Callable[[int], tuple[float, np.ndarray, np.ndarray, np.ndarray]] | None = None) -> None:
        """:meth:`read` of each track of ``track_ids`` with its evidence, one after another (a scan's readings):
        the same floating-point operations, the belief renormalised after each, in one compiled loop. Of the tracks
        whose readings turned, the last one's ``where(k)`` (k its place in ``track_ids``) becomes the search centre,
        as reading them one by one leaves it."""
        at, idx, factor, place = self._at, [], [], []
        for k, (track_id, evidence) in enumerate(zip(track_ids, evidences, strict=True)):
            i = at.get(track_id)
            if i is None:
                continue
            new = max(min(float(evidence), 50.0), -50.0)
            change = new - self.evidence.get(track_id, 0.0)
            self.evidence[track_id] = new
            if change != 0.0:
                idx.append(i)
                factor.append(math.exp(change))
                place.append(k)
        if not idx:
            return
        self.w_none, turned = _reweigh(self._w, self.w_none, np.array(idx, dtype=np.int64), np.array(factor))
        if turned >= 0 and where is not None:
            t, p, v, P = where(place[turned])
            self.centre = SearchCentre(t=float(t), p=np.asarray(p, dtype=float)[:2].copy(),
                                       v=np.asarray(v, dtype=float)[:2].copy(),
                                       P=np.asarray(P, dtype=float)[:2, :2].copy())

    def deleted(self, track_id: int, t: float, p: np.ndarray, v: np.ndarray, P: np.ndarray) -> None:
        """Track ``track_id`` was dropped at ``t`` (s) with last estimate ``p`` (m), ``v`` (m/s), position
        covariance ``P`` (m²): its weight joins ``H_0``, and if it was likelier the target than ``H_0`` was, the
        search centre moves to its estimate."""
        w = self._pop(track_id)
        self.evidence.pop(track_id, None)
        if w is None:
            return
        if w > self.w_none:
            self.centre = SearchCentre(t=float(t), p=np.asarray(p, dtype=float)[:2].copy(),
                                       v=np.asarray(v, dtype=float)[:2].copy(),
                                       P=np.asarray(P, dtype=float)[:2, :2].copy())
        self.w_none += w
        self._normalise()

    def scanned(self, t: float, unassigned: Sequence[np.ndarray], unresolved: Sequence[tuple[int, int]] = ()) -> None:
        """A position-fixing scan at ``t`` (s) whose detections that no confirmed track took fixed the ground
        positions ``unassigned`` (m): the pairs of tracks it could not tell apart (``unresolved``) may have swapped
        (:meth:`_forget_continuity`), and unless one of ``unassigned`` lies in the search region's 99 % ellipse,
        ``H_0`` is less likely by ``1 − q`` (module docstring)."""
        if not self._ids:
            return
        self._forget_continuity(self.config.swap_probability, unresolved)
        q = self.config.search_detection_probability
        if q <= 0.0:
            return
        if self.centre is not None and len(unassigned):
            mean, S = self.centre.at(t, self.config.search_speed)
            d = np.asarray(unassigned, dtype=float)[:, :2] - mean
            maha = np.einsum("ni,ij,nj->n", d, np.linalg.inv(S), d)
            if np.any(maha <= CHI2_2_99):
                return
        self.w_none *= 1.0 - q
        self._normalise()

    def _forget_continuity(self, delta: float, unresolved: Sequence[tuple[int, int]]) -> None:
        """One scan of the chance ``delta`` that two unresolved tracks (``unresolved``: pairs of track ids whose
        estimates the scan could not tell apart) swapped their cars: each weight is its continuity part
        ``c_k = w_k e^{−E_k}`` times its class evidence ``e^{E_k}``; the pair's continuity parts move by ``delta``
        towards each other (``c_i ← c_i + δ Σ_j (c_j − c_i)`` over the pairs of ``i``, all pairs at once, with δ at
        most one over the most pairs a track is in), the evidence parts stay. So a
        track that passed close to the target's while the belief was on the other is not held down for ever by that
        history, and its own class readings can take the belief; tracks that never met keep their continuity."""
        if delta <= 0.0 or not unresolved:
            return
        c = {k: w * math.exp(-self.evidence.get(k, 0.0)) for k, w in zip(self._ids, self._w.tolist(), strict=True)}
        pairs = [(a, b) for a, b in unresolved if a in c and b in c]
        if not pairs:
            return
        degree: dict[int, int] = {}
        for a, b in pairs:
            degree[a], degree[b] = degree.get(a, 0) + 1, degree.get(b, 0) + 1
        delta = min(delta, 1.0 / max(degree.values()))  # every part stays non-negative
        new = dict(c)
        for a, b in pairs:  # all pairs at once, from the scan's parts: the order of the pairs does not matter
            new[a] += delta * (c[b] - c[a])
            new[b] += delta * (c[a] - c[b])
        self._w = np.array([ck * math.exp(self.evidence.get(k, 0.0)) for k, ck in new.items()], dtype=float)
        self._normalise()

    def merged(self, kept: int, dropped: int) -> None:
        """Track ``dropped`` was found to be a duplicate of ``kept``: ``kept`` takes its weight."""
        w = self._pop(dropped)
        w = 0.0 if w is None else w
        self.evidence.pop(dropped, None)
        i = self._at.get(kept)
        if i is not None:
            self._w[i] += w
        else:
            self.w_none += w
        self._normalise()

    def teammates(self, log_ratios: Mapping[int, float]) -> dict[int, float]:
        """The probabilities each track would have with the teammates' class evidence ``log_ratios`` (per own track
        id) added, without changing this belief (evidence from other UAVs' sensors is used, never stored, so it is
        never counted twice)."""
        w = {k: v * math.exp(max(min(log_ratios.get(k, 0.0), 50.0), -50.0))
             for k, v in zip(self._ids, self._w.tolist(), strict=True)}
        total = sum(w.values()) + self.w_none
        return {k: v / total for k, v in w.items()}

    def _normalise(self) -> None:
        # the weights summed one after another in their order (np.cumsum, as Python's sum of floats before 3.12), then
        # each divided by the total: the same floating-point operations as on a dict of them
        total = (float(np.cumsum(self._w)[-1]) if self._ids else 0.0) + self.w_none
        if not total > 0:
            self._w = np.zeros(len(self._ids))
            self.w_none = 1.0
            return
        self._w /= total
        self.w_none /= total

    def _set(self, track_id: int, weight: float) -> None:
        """Track ``track_id``'s (unnormalised) weight: a new track's is appended after those held."""
        i = self._at.get(track_id)
        if i is not None:
            self._w[i] = weight
            return
        self._at[track_id] = len(self._ids)
        self._ids.append(track_id)
        self._w = np.append(self._w, weight)

    def _pop(self, track_id: int) -> float | None:
        """Remove track ``track_id`` from the belief; its weight, or None if it was not held."""
        i = self._at.pop(track_id, None)
        if i is None:
            return None
        w = float(self._w[i])
        del self._ids[i]
        self._w = np.delete(self._w, i)
        for j in range(i, len(self._ids)):
            self._at[self._ids[j]] = j
        return w

    def search_estimate(self, t: float) -> tuple[np.ndarray, np.ndarray] | None:
        """Mean and covariance of where the target is believed to be at ``t`` (s) while in no track; None without a
        cue or a lost target track."""
        if self.centre is None:
            return None
        return self.centre.at(t, self.config.search_speed)


@numba.njit(cache=True)
def _reweigh(w: np.ndarray, w_none: float, idx: np.ndarray, factor: np.ndarray) -> tuple[float, int]:
    """``w[idx[k]] *= factor[k]`` for each k in turn, each followed by :meth:`TargetIdentity._normalise`'s arithmetic
    (the weights summed in order, plus ``w_none``; all divided by the total, or reset when it is not positive), in
    place. Returns the new ``w_none`` and the last k whose track went from likelier than ``H_0`` to not (-1: none)."""
    turned = -1
    for k in range(idx.size):
        i = idx[k]
        was_likelier = w[i] > w_none
        w[i] *= factor[k]
        total = 0.0
        if w.size:
            total = w[0]
            for j in range(1, w.size):
                total += w[j]
        total += w_none
        if not total > 0.0:
            w[:] = 0.0
            w_none = 1.0
        else:
            for j in range(w.size):
                w[j] /= total
            w_none /= total
        if was_likelier and w[i] <= w_none:
            turned = k
    return w_none, turned


def background_frequencies(classes: Sequence[Mapping[str, int]], sizes: Mapping[str, int]) -> dict[str, np.ndarray]:
    """Per attribute, the class frequencies of the cars ``classes`` (one mapping attribute → class each) with one
    pseudo-count per class (so no class is impossible), for attributes with ``sizes[attr]`` classes."""
    out = {}
    for name, k in sizes.items():
        counts = np.ones(k)
        for c in classes:
            if name in c and 0 <= c[name] < k:
                counts[c[name]] += 1.0
        out[name] = counts / counts.sum()
    return out
