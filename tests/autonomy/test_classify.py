"""Class readings: the confusion matrix of a Classifier, the statistics of its draws, and the radar's and camera's
readings, which leave every other number of a scan as it was with classification off."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from autonomy.sensing.camera import CAR_RGBA, Camera, CameraConfig
from autonomy.sensing.classify import ROW_SUM_TOL, Classifier, read_classes
from autonomy.sensing.fake_scene import FakeScene, SceneBox
from autonomy.sensing.radar import Radar, RadarConfig
from autonomy.sensing.scene import SensorPose, TargetTruth
from simulator.builders.sensors import build_radar
from simulator.truth import car_attributes
from worlds.catalog import CAR_ATTRIBUTES, CAR_COLOURS, LENGTH_CLASSES, car_classes
from worlds.schema import CONFUSION_ROW_TOL, CameraClassifySpec, RadarClassifySpec, RadarSpec

FAMILY_LEVEL = 0.999
"""Every cell of an empirical confusion matrix lies in its binomial band, Bonferroni-corrected so that all the
cells of a test together hold with this probability."""


def binomial_band(n: int, p: np.ndarray, cells: int) -> tuple[np.ndarray, np.ndarray]:
    lo, hi = stats.binom.interval(1.0 - (1.0 - FAMILY_LEVEL) / cells, n, p)
    return lo, hi


def test_accuracy_gives_the_symmetric_channel():
    c = Classifier.for_attribute("colour", accuracy=0.7)
    k = len(CAR_COLOURS)
    assert c.n_classes == k and c.matrix.shape == (k, k)
    np.testing.assert_allclose(np.diag(c.matrix), 0.7, rtol=0, atol=1e-15)
    np.testing.assert_allclose(c.matrix[~np.eye(k, dtype=bool)], 0.3 / 6, rtol=0, atol=1e-15)
    np.testing.assert_allclose(c.matrix.sum(axis=1), 1.0, rtol=0, atol=1e-15)
    assert not c.matrix.flags.writeable


@pytest.mark.parametrize("kwargs, message", [
    ({"accuracy": 0.5}, r"accuracy must be in \(1/2, 1\]"),
    ({"accuracy": 1.01}, r"accuracy must be in \(1/2, 1\]"),
    ({}, "exactly one of accuracy and confusion"),
    ({"accuracy": 0.9, "confusion": np.eye(2)}, "exactly one of accuracy and confusion"),
    ({"confusion": np.eye(3)}, r"must be \(2, 2\)"),
    ({"confusion": [[0.9, 0.2], [0.1, 0.9]]}, "row 0 sums to 1.1"),
    ({"confusion": [[1.2, -0.2], [0.0, 1.0]]}, "non-negative"),
], ids=["accuracy-a-guess", "accuracy-over-1", "neither", "both", "shape", "row-sum", "negative"])
def test_classifier_refuses(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Classifier.for_attribute("length", **kwargs)


def test_sensor_configs_refuse_attributes_they_cannot_read():
    with pytest.raises(ValueError, match="reads only length"):
        RadarConfig(sigma_range=1.0, sigma_azimuth=0.01, classify=(Classifier.for_attribute("colour", accuracy=0.9),))
    with pytest.raises(ValueError, match="reads only colour, body"):
        CameraConfig(classify=(Classifier.for_attribute("length", accuracy=0.9),))
    twice = (Classifier.for_attribute("body", accuracy=0.9), Classifier.for_attribute("body", accuracy=0.8))
    with pytest.raises(ValueError, match="twice"):
        CameraConfig(classify=twice)
    with pytest.raises(ValueError, match="'length' has 2 classes, the classifier 3"):
        RadarConfig(sigma_range=1.0, sigma_azimuth=0.01,
                    classify=(Classifier(attribute="length", n_classes=3, accuracy=0.9),))


def test_schema_blocks_name_the_readable_attributes_and_the_tolerance():
    from autonomy.sensing.camera import CAMERA_ATTRIBUTES
    from autonomy.sensing.radar import RADAR_ATTRIBUTES

    assert tuple(RadarClassifySpec.model_fields) == RADAR_ATTRIBUTES
    assert tuple(CameraClassifySpec.model_fields) == CAMERA_ATTRIBUTES
    assert set(RADAR_ATTRIBUTES + CAMERA_ATTRIBUTES) == set(CAR_ATTRIBUTES)
    assert CONFUSION_ROW_TOL == ROW_SUM_TOL


def test_empirical_confusion_lies_in_binomial_bands():
    k = len(CAR_COLOURS)
    C = np.random.default_rng(7).dirichlet(np.full(k, 0.8), size=k)
    C[np.arange(k), np.arange(k)] += 2.0  # a confusion matrix that favours the true class, rows normalised below
    C /= C.sum(axis=1, keepdims=True)
    c = Classifier.for_attribute("colour", confusion=C)
    rng = np.random.default_rng(11)
    n = 3000
    counts = np.zeros((k + 1, k), dtype=int)  # last row: false alarms (no true class), read uniformly
    for true in [*range(k), -1]:
        for _ in range(n):
            m = c.read(true, rng)
            assert m.attribute == "colour" and np.array_equal(m.confusion, c.matrix)
            counts[true, m.observed] += 1
    P = np.vstack([C, np.full(k, 1.0 / k)])
    lo, hi = binomial_band(n, P, P.size)
    assert np.all((counts >= lo) & (counts <= hi)), (counts, lo, hi)
    # not a vacuous band: a symmetric channel of the same mean accuracy falls outside it
    sym = Classifier.for_attribute("colour", accuracy=float(np.mean(np.diag(C)))).matrix
    assert np.any((n * sym < lo[:k]) | (n * sym > hi[:k]))


def test_read_classes_follows_the_truth_ids():
    targets = TargetTruth(ids=[4, 9], p_W=np.zeros((2, 3)), v_W=np.zeros((2, 3)), kind=("car", "decoy"),
                          yaw=[0.0, 0.0], attributes={"length": [1, -1]})
    sure = Classifier.for_attribute("length", confusion=np.eye(2))
    readings = read_classes((sure,), [4, 4, 9, -1], targets, np.random.default_rng(0))
    assert [r[0].observed for r in readings[:2]] == [1, 1]
    # the decoy (-1) and the false alarm read uniformly: each class about half of many reads
    rng = np.random.default_rng(1)
    n = 2000
    for tid in (9, -1):
        ones = sum(r[0].observed for r in read_classes((sure,), [tid] * n, targets, rng))
        lo, hi = binomial_band(n, np.array(0.5), 2)
        assert lo <= ones <= hi


# --- radar -----------------------------------------------------------------------------------------------------

POSE = SensorPose(p_W=[0.0, 0.0, 200.0])
RADAR = dict(sigma_range=5.0, sigma_azimuth=np.deg2rad(1.0), sigma_elevation=np.deg2rad(1.0), sigma_range_rate=0.5,
             clutter_rate=3.0, max_range=3000.0)


def traffic(types=("van", "sedan", "van"), colours=("red", "white", "blue")) -> TargetTruth:
    n = len(types)
    x = 300.0 + 150.0 * np.arange(n)
    return TargetTruth(ids=np.arange(n) + 10, p_W=np.column_stack([x, 0.3 * x, np.zeros(n)]),
                       v_W=np.tile([12.0, 0.0, 0.0], (n, 1)), kind=("car",) * n, yaw=np.zeros(n),
                       attributes=car_attributes(types, colours))


def scans(sensor, targets: TargetTruth, scene, n: int, seed: int = 3, pose: SensorPose = POSE):
    rng = np.random.default_rng(seed)
    return [sensor.measure(0.5 * k, pose, targets, scene, rng) for k in range(n)], rng


def test_radar_classification_changes_no_other_number():
    targets, scene = traffic(), FakeScene()
    off, rng_off = scans(Radar(RadarConfig(**RADAR)), targets, scene, 40)
    reads = (Classifier.for_attribute("length", accuracy=0.8),)
    on, rng_on = scans(Radar(RadarConfig(**RADAR, classify=reads)), targets, scene, 40)
    assert rng_off.bit_generator.state == rng_on.bit_generator.state  # the scans' stream is not advanced
    n_dets = 0
    for a, b in zip(off, on, strict=True):
        np.testing.assert_array_equal(a.truth_ids, b.truth_ids)
        assert len(a.detections) == len(b.detections)
        for da, db in zip(a.detections, b.detections, strict=True):
            np.testing.assert_array_equal(da.z, db.z)
            np.testing.assert_array_equal(da.R, db.R)
            assert (da.t_meas, da.t_arrival) == (db.t_meas, db.t_arrival)
            assert da.classes == () and len(db.classes) == 1 and db.classes[0].attribute == "length"
            n_dets += 1
    assert n_dets > 100  # cars and clutter were seen


def test_radar_on_a_van_reads_long_with_the_configured_accuracy():
    accuracy = 0.8
    spec = RadarSpec(type="radar", rate_hz=2.0, sigma_range=5.0, sigma_azimuth_deg=1.0, sigma_elevation_deg=1.0,
                     max_range=3000.0, classify={"length": {"accuracy": accuracy}})
    radar = build_radar(spec, "radar")
    van = traffic(types=("van",), colours=("white",))
    assert van.attributes["length"][0] == LENGTH_CLASSES.index("long") == car_classes("van", "white")["length"]
    outs, _ = scans(radar, van, FakeScene(), 3000, seed=5)
    readings = [d.classes for o in outs for d in o.detections]
    assert all(o.truth_ids.tolist() in ([], [10]) for o in outs)
    n = len(readings)
    long_ = sum(LENGTH_CLASSES[c[0].observed] == "long" for c in readings)
    lo, hi = binomial_band(n, np.array(accuracy), 1)
    assert n > 2500 and lo <= long_ <= hi, (n, long_, lo, hi)
    np.testing.assert_allclose(readings[0][0].confusion, [[0.8, 0.2], [0.2, 0.8]], rtol=0, atol=1e-15)


# --- camera ----------------------------------------------------------------------------------------------------

CAR_RGB = tuple(round(255 * c) for c in CAR_RGBA[:3])


def test_camera_classification_changes_no_other_number_and_reads_colour_and_body():
    targets = traffic(types=("van", "sedan"), colours=("red", "white"))
    targets = TargetTruth(ids=targets.ids, p_W=[[40.0, -4.0, 1.0], [40.0, 4.0, 0.75]], v_W=targets.v_W,
                          kind=targets.kind, yaw=targets.yaw, seg_ids=[70, 71], attributes=targets.attributes)
    boxes = [SceneBox(center_W=(40.0, -4.0, 1.0), size=(5.9, 2.0, 2.0), rgb=CAR_RGB, seg_id=70),
             SceneBox(center_W=(40.0, 4.0, 0.75), size=(4.8, 1.8, 1.5), rgb=CAR_RGB, seg_id=71)]
    scene = FakeScene(boxes=boxes)
    pose = SensorPose(p_W=[0.0, 0.0, 30.0])
    base = dict(pixel_sigma=0.7, gimbal_pitch=np.arctan2(30.0, 40.0))
    off, rng_off = scans(Camera(CameraConfig(**base)), targets, scene, 30, pose=pose)
    sure = (Classifier.for_attribute("colour", confusion=np.eye(len(CAR_COLOURS))),
            Classifier.for_attribute("body", accuracy=0.9))
    on, rng_on = scans(Camera(CameraConfig(**base, classify=sure)), targets, scene, 30, pose=pose)
    assert rng_off.bit_generator.state == rng_on.bit_generator.state
    for a, b in zip(off, on, strict=True):
        assert sorted(a.truth_ids.tolist()) == [10, 11]
        np.testing.assert_array_equal(a.truth_ids, b.truth_ids)
        for da, db, tid in zip(a.detections, b.detections, b.truth_ids, strict=True):
            np.testing.assert_array_equal(da.z, db.z)
            np.testing.assert_array_equal(da.R, db.R)
            np.testing.assert_array_equal(da.pixel_box, db.pixel_box)
            assert da.classes == ()
            colour, body = db.classes
            assert (colour.attribute, body.attribute) == ("colour", "body")
            assert CAR_COLOURS[colour.observed] == {10: "red", 11: "white"}[int(tid)]  # identity confusion


def test_a_reading_checks_a_confusion_matrix_it_has_not_seen_and_keeps_a_writable_one_unchecked():
    from autonomy.sensing.measurement import ClassMeasurement

    clf = Classifier.for_attribute("colour", accuracy=0.9)
    rng = np.random.default_rng(3)
    first, second = clf.read(2, rng), clf.read(2, rng)
    assert second.confusion is clf.matrix  # checked once, then handed on as it is
    np.testing.assert_array_equal(first.confusion, clf.matrix)
    bad = np.array([[0.5, 0.6], [0.5, 0.5]])
    with pytest.raises(ValueError, match="sum to 1"):
        ClassMeasurement(attribute="colour", observed=0, confusion=bad)
    good = np.array([[0.9, 0.1], [0.2, 0.8]])  # writable: copied at each reading, never taken on trust
    m = ClassMeasurement(attribute="colour", observed=1, confusion=good)
    good[0, 0] = 5.0
    assert m.confusion[0, 0] == 0.9
    with pytest.raises(ValueError, match="sum to 1"):
        ClassMeasurement(attribute="colour", observed=1, confusion=good)
