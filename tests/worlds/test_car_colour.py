"""A car's paint colour and the sensors' ``classify`` blocks in world files: defaults, what reaches the truth and the
sensor models, and the refusals, each naming its key path."""

from __future__ import annotations

import numpy as np
import pytest

from simulator.registry import build_sensor
from simulator.truth import car_attributes
from worlds.catalog import CAR_COLOURS, CAR_TYPES, LENGTH_CLASSES
from worlds.errors import WorldError
from worlds.loader import load_world

RADAR = "uavs[0].sensors[0]"


def test_colour_defaults_to_white_and_reaches_the_truth_attributes():
    world = load_world("road_standoff").world  # its car names no colour
    assert world.ground_vehicles[0].colour == "white"
    world = load_world("demo", ["ground_vehicles[0].colour=green", "ground_vehicles[0].type=van"]).world
    g = world.ground_vehicles[0]
    attrs = car_attributes([g.type], [g.colour])
    assert attrs == {"colour": [CAR_COLOURS.index("green")], "body": [CAR_TYPES.index("van")],
                     "length": [LENGTH_CLASSES.index("long")]}
    assert world.model_dump()["ground_vehicles"][0]["colour"] == "green"


def test_every_catalogue_colour_loads():
    for colour in CAR_COLOURS:
        assert load_world("demo", [f"ground_vehicles[0].colour={colour}"]).world.ground_vehicles[0].colour == colour


def test_sensor_entries_without_classify_build_sensors_that_classify_nothing():
    world = load_world("road_standoff").world  # its radars name no classify block
    assert build_sensor(world.uavs[0].sensors[0], "r").config.classify == ()


def test_classify_blocks_reach_the_sensor_models():
    world = load_world("demo", [f"{RADAR}.classify={{length: {{confusion: [[0.7, 0.3], [0.1, 0.9]]}}}}",
                                "uavs[1].sensors[0]={type: camera, rate_hz: 10, classify: {colour: {accuracy: 0.6},"
                                " body: {accuracy: 0.95}}}"]).world
    (length,) = build_sensor(world.uavs[0].sensors[0], "r").config.classify
    np.testing.assert_array_equal(length.matrix, [[0.7, 0.3], [0.1, 0.9]])
    colour, body = build_sensor(world.uavs[1].sensors[0], "c").config.classify
    assert (colour.attribute, colour.accuracy, body.attribute, body.accuracy) == ("colour", 0.6, "body", 0.95)
    assert colour.matrix.shape == (len(CAR_COLOURS),) * 2


@pytest.mark.parametrize("override, path, expected", [
    ("ground_vehicles[0].colour=pink", "ground_vehicles[0].colour",
     f"one of the car colours ({', '.join(CAR_COLOURS)})"),
    (f"{RADAR}.classify={{length: {{accuracy: 0.5}}}}", f"{RADAR}.classify.length.accuracy", "in (1/2, 1]"),
    (f"{RADAR}.classify={{length: {{confusion: [[0.9, 0.2], [0.1, 0.9]]}}}}", f"{RADAR}.classify.length.confusion",
     "row 0 sums to 1.1"),
    (f"{RADAR}.classify={{length: {{confusion: [[1.5, -0.5], [0, 1]]}}}}", f"{RADAR}.classify.length.confusion",
     "non-negative"),
    (f"{RADAR}.classify={{length: {{confusion: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]}}}}",
     f"{RADAR}.classify.length.confusion", "a 2 x 2 matrix, one row and one column per class of length (short, long)"),
    (f"{RADAR}.classify={{length: {{}}}}", f"{RADAR}.classify.length", "exactly one of accuracy and confusion"),
    (f"{RADAR}.classify={{colour: {{accuracy: 0.9}}}}", f"{RADAR}.classify.colour", "no such key here"),
    ("uavs[1].sensors[0]={type: camera, rate_hz: 10, classify: {colour: {confusion: [[1, 0], [0, 1]]}}}",
     "uavs[1].sensors[0].classify.colour.confusion", "a 7 x 7 matrix"),
    ("uavs[1].sensors[0]={type: camera, rate_hz: 10, classify: {body: {accuracy: 0.2}}}",
     "uavs[1].sensors[0].classify.body.accuracy", "in (1/2, 1]"),
], ids=["colour", "accuracy", "row-sum", "negative", "shape", "neither", "radar-colour", "camera-shape",
        "camera-body-accuracy"])
def test_refusals_name_the_key_path(override, path, expected):
    with pytest.raises(WorldError) as info:
        load_world("demo", [override])
    (issue,) = info.value.issues
    assert issue.path == path and expected in issue.expected, str(info.value)


def test_truth_carries_the_car_attributes_and_minus_one_for_static_decoys():
    from simulator.decoys import StaticDecoys
    from simulator.fake_engine import ScriptedCars
    from simulator.truth import Truth

    cars = ScriptedCars(lambda tick: np.array([[0.0, 0.0, 0.7], [20.0, 0.0, 0.7]]), 240)
    decoys = StaticDecoys(p_W=np.array([[50.0, 0.0, 0.7]]), yaw=np.zeros(1), cone_axis_W=np.array([[0.0, 0.0, 1.0]]),
                          cone_half_angle=np.array([0.5]), body_ids=np.array([9]))
    attrs = car_attributes(["van", "sedan"], ["red", "black"])
    targets = Truth(None, cars, ("car", "decoy"), decoys, attrs).targets()
    assert targets.attributes["colour"].tolist() == [CAR_COLOURS.index("red"), CAR_COLOURS.index("black"), -1]
    assert targets.attributes["body"].tolist() == [CAR_TYPES.index("van"), CAR_TYPES.index("sedan"), -1]
    assert targets.attributes["length"].tolist() == [LENGTH_CLASSES.index("long"), LENGTH_CLASSES.index("short"), -1]
    assert Truth(None, cars, ("car", "car"), None).targets().attributes is None
    with pytest.raises(ValueError, match="one entry per car"):
        Truth(None, cars, ("car",), None, attrs)
