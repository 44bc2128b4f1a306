"""Estimator, guidance and fusion variants: each type's settings (``params``, an estimator's ``road``) are checked at
load against its typed settings, an unknown tag is refused with the known ones, and switching a type by ``--set``
needs no ``params={}`` reset."""

import warnings

import pytest

from worlds.errors import WorldError
from worlds.loader import load_world, shipped_worlds
from worlds.schema import World
from worlds.variants import WorldNote

U0 = "uavs[0].autonomy"


def refused(world: str, overrides: list[str]):
    with pytest.raises(WorldError) as info:
        load_world(world, overrides)
    return info.value.issues[0]


@pytest.mark.parametrize("world, overrides, path, value, expected", [
    ("demo", [f"{U0}.guidance.params.bogus=1"], f"{U0}.guidance.params.bogus", 1, "no such key"),
    ("demo", [f"{U0}.guidance.params.max_heading_rate=-1"], f"{U0}.guidance.params.max_heading_rate", -1,
     "greater than 0"),
    ("demo", [f"{U0}.guidance.params.relative_speed_bounds=fast"], f"{U0}.guidance.params.relative_speed_bounds",
     "fast", "tuple"),
    ("demo", [f"{U0}.estimator.params.q=-2"], f"{U0}.estimator.params.q", -2, "greater than 0"),
    ("demo", [f"{U0}.estimator.params.qq=2"], f"{U0}.estimator.params.qq", 2, "no such key"),
    ("demo", [f"{U0}.estimator.params.confirm_fixes=4"], f"{U0}.estimator.params.confirm_fixes", 4, "2 or 3"),
    ("helsinki_chase", [f"{U0}.estimator.road.spawn_distance=0"], f"{U0}.estimator.road.spawn_distance", 0,
     "greater than 0"),
    ("helsinki_chase", [f"{U0}.estimator.road.constraint.velocity_update=sideways"],
     f"{U0}.estimator.road.constraint.velocity_update", "sideways", "'auto'"),
    ("road_standoff", [f"{U0}.guidance.params.weights.q_r=-1"], f"{U0}.guidance.params.weights.q_r", -1,
     "greater than or equal to 0"),
    ("road_standoff", [f"{U0}.guidance.params.solver=snopt"], f"{U0}.guidance.params.solver", "snopt", "'fatrop'"),
    ("search_decoys", [f"{U0}.estimator.params.max_vertices=2"], f"{U0}.estimator.params.max_vertices", 2,
     "greater than or equal to 3"),
    ("consensus_fmpc", [f"{U0}.guidance.params.pdip.tol=0"], f"{U0}.guidance.params.pdip.tol", 0, "greater than 0"),
    ("formation_imm", [f"{U0}.guidance.params.bogus=1"], f"{U0}.guidance.params.bogus", 1, "no such key"),
])
def test_bad_settings_are_refused_at_load_with_their_path(world, overrides, path, value, expected):
    issue = refused(world, overrides)
    assert (issue.path, issue.value) == (path, value)
    assert expected in issue.expected


@pytest.mark.parametrize("key, tag, known", [
    ("estimator.type", "kalman", ["'ekf'", "'set_membership'", "'plugin'"]),
    ("guidance.type", "orbit", ["'vector_field'", "'nmpc'", "'infoplan'"]),
    ("fusion.method", "average", ["'convex'", "'hcmci'", "'base_station'"]),
])
def test_an_unknown_tag_lists_the_known_ones(key, tag, known):
    issue = refused("demo", [f"{U0}.{key}={tag}"])
    assert (issue.path, issue.value) == (f"{U0}.{key}", tag)
    assert all(k in issue.expected for k in known)


def test_switching_the_guidance_type_needs_no_params_reset():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        world = load_world("road_standoff", [f"{U0}.guidance.type=vector_field"]).world
    g = world.uavs[0].autonomy.guidance
    assert g.params == {} and g.settings.max_speed == 20.0  # the NMPC's solver is dropped, the field's defaults kept
    notes = [w for w in caught if issubclass(w.category, WorldNote)]
    assert len(notes) == 1 and "solver" in str(notes[0].message) and "'vector_field'" in str(notes[0].message)
    assert world.uavs[1].autonomy.guidance.params == {"solver": "fatrop"}


def test_switching_keeps_the_settings_both_types_know_and_refuses_unknown_ones():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", WorldNote)
        world = load_world("road_standoff", [f"{U0}.guidance.params.max_heading_rate=0.4",
                                             f"{U0}.guidance.type=vector_field"]).world
        assert world.uavs[0].autonomy.guidance.params == {"max_heading_rate": 0.4}
        issue = refused("road_standoff", [f"{U0}.guidance.type=vector_field", f"{U0}.guidance.params.sover=sqp"])
    assert issue.path == f"{U0}.guidance.params.sover"


def test_switching_the_estimator_to_sets_drops_the_trackers_settings():
    from worlds.schema import EstimatorSpec

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        spec = EstimatorSpec(type="set_membership", params={"q": 2.0, "quad_segs": 4})
    assert spec.params == {"quad_segs": 4} and spec.settings.quad_segs == 4
    notes = [str(w.message) for w in caught if issubclass(w.category, WorldNote)]
    assert notes == ["estimator type 'set_membership': ignoring q (settings of another type)"]


def test_the_typed_settings_are_the_given_params():
    world = load_world("demo").world
    assert world.uavs[0].autonomy.estimator.params == {"q": 2.0}
    settings = world.uavs[0].autonomy.estimator.settings
    assert settings.q == 2.0 and settings.given() == {"q": 2.0}
    assert world.uavs[0].autonomy.fusion.variant.stacked_scans is False
    assert load_world("formation_imm").world.uavs[0].autonomy.fusion.variant.stacked_scans is True


@pytest.mark.parametrize("name", sorted(shipped_worlds()))
def test_a_resolved_world_reloads_to_the_same_world(name):
    world = load_world(name).world
    again = World.model_validate(world.model_dump(mode="json"))
    assert again == world
