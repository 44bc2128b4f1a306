"""A tracker's class readings: what a scan's detections read into its tracks (autonomy/estimation/tracking/
class_readings.py)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from autonomy.estimation.tracking.class_readings import absorb, taken_readings, weighted_readings
from autonomy.estimation.tracking.identity import IdentityConfig, accumulate_readings, track_evidence
from autonomy.estimation.tracking.track import Track
from autonomy.sensing.measurement import ClassMeasurement

CONF2 = np.array([[0.9, 0.1], [0.2, 0.8]])
CONF3 = np.array([[0.7, 0.2, 0.1], [0.15, 0.7, 0.15], [0.1, 0.2, 0.7]])
IDENT = IdentityConfig(target_classes={"colour": 1, "length": 2},
                       background={"colour": np.array([0.9, 0.1]), "length": np.array([0.5, 0.3, 0.2])},
                       swap_probability=0.05, background_density=1e-5)


def _track() -> Track:
    return Track(filter=SimpleNamespace(t=0.0), last_update_t=0.0)


def _det(*classes: ClassMeasurement) -> SimpleNamespace:
    return SimpleNamespace(classes=tuple(classes))


def _colour(o: int) -> ClassMeasurement:
    return ClassMeasurement(attribute="colour", observed=o, confusion=CONF2)


def _length(o: int) -> ClassMeasurement:
    return ClassMeasurement(attribute="length", observed=o, confusion=CONF3)


def test_a_scan_s_taken_readings_group_by_attribute_in_scan_order():
    a, b, c = _track(), _track(), _track()
    by_attr, tracks = taken_readings([(a, _det(_colour(1), _length(2))), (b, _det()), (c, _det(_colour(0)))])
    assert tracks == [a, c]  # b read nothing
    assert [tr for tr, _ in by_attr["colour"]] == [a, c] and [tr for tr, _ in by_attr["length"]] == [a]
    np.testing.assert_array_equal(by_attr["colour"][1][1], CONF2[:, 0])  # P(observed 0 | each true class)
    assert taken_readings([(b, _det())]) == ({}, [])


def test_readings_that_cannot_be_read_together_are_refused():
    a, b = _track(), _track()
    assert taken_readings([(a, _det(_colour(1), _colour(0)))]) is None  # one attribute twice in a detection
    assert taken_readings([(a, _det(_colour(1))), (a, _det(_colour(0)))]) is None  # a track taking two detections
    assert taken_readings([(a, _det(_colour(1))), (b, _det(_colour(0)))]) is not None


def test_weighted_readings_are_the_scan_s_mixture():
    tr = _track()
    got = weighted_readings(tr, [(0.3, _det(_colour(1))), (0.5, _det(_colour(0), _length(1)))], none_weight=0.2)
    np.testing.assert_allclose(got["colour"][0][1], 0.2 + 0.3 * CONF2[:, 1] + 0.5 * CONF2[:, 0], rtol=1e-15)
    np.testing.assert_allclose(got["length"][0][1], 0.2 + 0.5 * CONF3[:, 1], rtol=1e-15)
    assert got["colour"][0][0] is tr
    whole = weighted_readings(tr, [(1.0, _det(_colour(1)))])  # taken whole: its own likelihood
    np.testing.assert_array_equal(whole["colour"][0][1], CONF2[:, 1])


def test_absorbing_a_scan_gives_each_track_the_bits_of_reading_it_alone():
    rng = np.random.default_rng(3)
    tracks = [_track() for _ in range(30)]
    alone = [_track() for _ in range(30)]
    for scan in range(6):
        pairs = []
        for k in range(30):
            classes = [_colour(int(rng.integers(2)))] if rng.random() < 0.8 else []
            if scan >= 2 and rng.random() < 0.5:
                classes.append(_length(int(rng.integers(3))))
            pairs.append((tracks[k], _det(*classes)))
        by_attr, read = taken_readings(pairs)
        absorb(by_attr, read, IDENT)
        for k, (_, det) in enumerate(pairs):  # the reference: one track at a time
            if not det.classes:
                continue
            for c in det.classes:
                alone[k].class_loglik[c.attribute] = accumulate_readings(
                    alone[k].class_loglik.get(c.attribute), np.log(np.maximum(c.likelihood(), 1e-300)),
                    IDENT.background.get(c.attribute), IDENT.swap_probability)
            alone[k].evidence = track_evidence(alone[k].class_loglik, IDENT)
    for tr, ref in zip(tracks, alone, strict=True):
        assert tr.class_loglik.keys() == ref.class_loglik.keys()
        for name in tr.class_loglik:
            np.testing.assert_array_equal(tr.class_loglik[name], ref.class_loglik[name])
        assert tr.evidence == ref.evidence
    assert sum(tr.evidence != 0.0 for tr in tracks) > 20
