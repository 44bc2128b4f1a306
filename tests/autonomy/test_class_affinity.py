"""Classification-aided association: the class readings' likelihood ratio by hand, its neutrality for a track that
has read nothing, and its effect on GNN (two crossing cars of different colours keep their tracks) and on JPDA's
joint events."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
import pytest

from autonomy.estimation.factory import make_filter
from autonomy.estimation.measurements import Measurement, PositionDetectionModel
from autonomy.estimation.models import ConstantVelocity
from autonomy.estimation.tracking.assignment import GlobalNearestNeighbourAssociator
from autonomy.estimation.tracking.class_affinity import ClassAffinity
from autonomy.estimation.tracking.gate import ChiSquareGate, PredictedNis
from autonomy.estimation.tracking.identity import accumulate_readings
from autonomy.estimation.tracking.jpda import JointProbabilisticAssociator
from autonomy.estimation.tracking.track import Track
from autonomy.sensing.measurement import ClassMeasurement

MODEL = ConstantVelocity(q=0.5)
BOX = PositionDetectionModel(dim=2)
C = np.array([[0.9, 0.1], [0.2, 0.8]])  # confusion of a two-colour reading: C[true, observed]
PI = np.array([0.5, 0.5])


@dataclass(frozen=True, kw_only=True)
class Classed(Measurement):
    """A position detection that also reports classes."""

    classes: tuple = ()


def box(x, y, colour=None, t=0.0) -> Measurement:
    classes = () if colour is None else (ClassMeasurement(attribute="colour", observed=colour, confusion=C),)
    return Classed(z=np.array([x, y], dtype=float), R=np.eye(2), t_meas=t, model=BOX, sensor_id=0, classes=classes)


def track_at(x, y, readings=(), sp2=4.0) -> Track:
    tr = Track(make_filter("ekf", MODEL, np.array([x, 0.0, y, 0.0]), np.diag([sp2, 1.0, sp2, 1.0])), 0.0)
    for o in readings:
        tr.class_loglik["colour"] = accumulate_readings(tr.class_loglik.get("colour"), np.log(C[:, o]), PI, 0.0)
    return tr


def test_the_likelihood_ratio_by_hand():
    """One reading of colour 0 on the track: posterior (0.5·0.9, 0.5·0.2)/0.55 = (9/11, 2/11). A detection reading
    colour 1: (9/11·0.1 + 2/11·0.8) / (0.5·0.1 + 0.5·0.8) = (2.5/11) / 0.45; reading colour 0: (8.5/11) / 0.55.
    With ε = 0.1 the track's distribution is first mixed with the background: 0.9·post + 0.1·π."""
    tracks, dets = [track_at(0, 0, readings=[0])], [box(0, 0, colour=1), box(0, 0, colour=0)]
    rows, cols = np.array([0, 0]), np.array([0, 1])
    got = ClassAffinity({"colour": PI}, 0.0).log_ratios(tracks, dets, rows, cols)
    np.testing.assert_allclose(got, [math.log(2.5 / 11 / 0.45), math.log(8.5 / 11 / 0.55)], rtol=1e-12)
    mixed = 0.9 * np.array([9 / 11, 2 / 11]) + 0.1 * PI
    got = ClassAffinity({"colour": PI}, 0.1).log_ratios(tracks, dets, rows, cols)
    np.testing.assert_allclose(got, [math.log(mixed @ C[:, 1] / 0.45), math.log(mixed @ C[:, 0] / 0.55)], rtol=1e-12)


def test_many_tracks_and_pairs_in_any_order_match_the_formula_pair_by_pair():
    """Tracks with and without readings, each in several pairs listed out of order: every pair's log λ is the
    module docstring's formula for that pair alone."""
    rng = np.random.default_rng(7)
    eps, prior = 0.05, np.array([0.7, 0.3])
    tracks = [track_at(3.0 * i, 0.0, readings=rng.integers(0, 2, size=i % 4).tolist()) for i in range(12)]
    dets = [box(0, 0, colour=int(c)) for c in rng.integers(0, 2, size=9)] + [box(0, 0)]
    rows, cols = rng.integers(0, 12, size=60), rng.integers(0, 10, size=60)
    got = ClassAffinity({"colour": prior}, eps).log_ratios(tracks, dets, rows, cols)
    want = []
    for i, j in zip(rows.tolist(), cols.tolist(), strict=True):
        if not dets[j].classes:
            want.append(0.0)
            continue
        ell = tracks[i].class_loglik.get("colour")
        post = prior if ell is None else prior * np.exp(ell) / (prior * np.exp(ell)).sum()
        L = C[:, dets[j].classes[0].observed]
        want.append(math.log(((1 - eps) * post + eps * prior) @ L / (prior @ L)))
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-15)


def test_a_track_that_read_nothing_and_a_detection_that_reads_nothing_are_neutral():
    aff = ClassAffinity({"colour": np.array([0.7, 0.3])}, 0.02)
    tracks = [track_at(0, 0), track_at(5, 0, readings=[1, 1])]
    got = aff.log_ratios(tracks, [box(0, 0, colour=1), box(1, 0)], np.array([0, 0, 1]), np.array([0, 1, 1]))
    np.testing.assert_allclose(got, [0.0, 0.0, 0.0], atol=1e-15)
    assert aff.log_ratios(tracks, [box(0, 0)], np.array([0, 1]), np.array([0, 0])) is None
    with pytest.raises(ValueError, match="swap_probability"):
        ClassAffinity({}, 1.0)


def test_gnn_keeps_two_crossing_cars_of_different_colours_on_their_tracks():
    """Tracks at x = 0 (three readings of colour 0) and x = 4 (three of colour 1) meet detections at x = 2.5
    (colour 0: the first track's car, which has moved on) and x = 1.5 (colour 1). By position alone the tracks
    take the nearer detections, a swap: cost 2·1.5²/5 against 2·2.5²/5. The readings' ratios reverse it."""
    gate = ChiSquareGate(0.9999)
    tracks = [track_at(0, 0, readings=[0, 0, 0]), track_at(4, 0, readings=[1, 1, 1])]
    dets = [box(2.5, 0, colour=0), box(1.5, 0, colour=1)]
    plain = GlobalNearestNeighbourAssociator(gate, PredictedNis(MODEL, 0.0))
    aided = GlobalNearestNeighbourAssociator(gate, PredictedNis(MODEL, 0.0),
                                             affinity=ClassAffinity({"colour": PI}, 0.02))
    assert plain.assign(tracks, dets).pairs == ((0, 1), (1, 0))
    assert aided.assign(tracks, dets).pairs == ((0, 0), (1, 1))
    # readings that do not tell the cars apart leave the kinematic assignment
    same = [box(2.5, 0, colour=0), box(1.5, 0, colour=0)]
    neutral = [track_at(0, 0), track_at(4, 0)]
    assert aided.assign(neutral, same).pairs == plain.assign(neutral, same).pairs == ((0, 1), (1, 0))


def test_jpda_joint_events_carry_the_readings_ratio():
    """The hand-enumerated two-track, two-detection events of the JPDA test, each pair's likelihood times its
    class ratio λᵢⱼ."""
    pd, pg, lam = 0.8, 0.9999, 1e-3
    tracks = [track_at(0.0, 0.0, readings=[0, 0]), track_at(6.0, 0.0, readings=[1])]
    dets = [box(2.0, 1.0, colour=1), box(4.0, -1.0, colour=0)]
    aff = ClassAffinity({"colour": PI}, 0.02)
    jpda = JointProbabilisticAssociator(ChiSquareGate(pg), PredictedNis(MODEL, 0.0), pd, lam, affinity=aff)
    a = jpda.assign(tracks, dets)
    rows, cols = np.array([0, 0, 1, 1]), np.array([0, 1, 0, 1])
    ratio = dict(zip(zip(rows.tolist(), cols.tolist(), strict=True),
                     np.exp(aff.log_ratios(tracks, dets, rows, cols)).tolist(), strict=True))
    s = 5.0

    def N(track_xy, z):
        nu = np.subtract(z, track_xy)
        return math.exp(-0.5 * float(nu @ nu) / s) / (2.0 * math.pi * s)

    L = {(i, j): pd * N(t, z) / lam * ratio[i, j] for i, t in enumerate([(0.0, 0.0), (6.0, 0.0)])
         for j, z in enumerate([(2.0, 1.0), (4.0, -1.0)])}
    m = 1.0 - pd * pg
    expected = np.zeros((2, 3))
    total = 0.0
    for choice in itertools.product(range(-1, 2), repeat=2):
        if choice[0] >= 0 and choice[0] == choice[1]:
            continue
        w = math.prod(L[i, j] if j >= 0 else m for i, j in enumerate(choice))
        total += w
        for i, j in enumerate(choice):
            expected[i, j + 1] += w
    np.testing.assert_allclose(a.weights, expected / total, rtol=0.0, atol=1e-12)
    assert ratio[0, 1] > 1.0 > ratio[0, 0] and ratio[1, 0] > 1.0 > ratio[1, 1]
