"""The registry of builders: world-file settings reach the components' configurations field by field, nested ones
as their own dataclasses."""

import numpy as np
import pytest

from autonomy.estimation.road.constraint import RoadConstraintParams
from autonomy.guidance.fast_mpc import FastMpcConfig
from autonomy.guidance.nmpc_config import NmpcConfig, NmpcWeights
from autonomy.guidance.pdip import PdipOptions
from autonomy.guidance.vector_field import VectorFieldConfig
from simulator.builders.common import config_from
from simulator.registry import SENSOR_BUILDERS, build_estimator, build_guidance, build_sensor
from worlds.loader import load_world

U0 = "uavs[0].autonomy"


def test_nested_settings_become_the_nested_dataclasses():
    world = load_world("road_standoff", [f"{U0}.guidance.params.weights={{q_r: 5000}}",
                                         f"{U0}.guidance.params.model={{tau_v: 0.5}}"]).world
    g = world.uavs[0].autonomy.guidance
    cfg = config_from(NmpcConfig, g.settings.given(), team_size=2)
    assert cfg.weights == NmpcWeights(q_r=5000.0) and cfg.model.tau_v == 0.5 and cfg.solver == "fatrop"
    fast = load_world("consensus_fmpc", [f"{U0}.guidance.params.pdip={{max_iter: 12}}"]).world.uavs[0]
    fcfg = config_from(FastMpcConfig, fast.autonomy.guidance.settings.given())
    assert fcfg.pdip == PdipOptions(max_iter=12) and fcfg.v_max == 15


def test_lists_become_tuples():
    world = load_world("demo", [f"{U0}.guidance.params.relative_speed_bounds=[0.6, 1.4]"]).world
    law = build_guidance(world.uavs[0], 0, 2, ())
    assert isinstance(law.config, VectorFieldConfig) and law.config.relative_speed_bounds == (0.6, 1.4)
    assert (law.config.standoff_radius, law.config.nominal_speed, law.config.team_size) == (100.0, 12.0, 2)


def test_the_road_constraint_settings_reach_the_filter():
    loaded = load_world("road_standoff", [f"{U0}.estimator.type=maekf",
                                          f"{U0}.estimator.road={{constraint: {{sigma_keep: 0.7}}}}"])
    from worlds.build import build_geometry

    geometry = build_geometry(loaded.world, loaded.path, np.random.default_rng(0))
    est = build_estimator(loaded.world.uavs[0], 0, geometry.network)
    assert est.road_config.road.constraint == RoadConstraintParams(sigma_keep=0.7)
    assert (est.config.filter, est.config.singer_alpha) == ("ekf", 0.6)


def test_the_fusion_method_declares_the_stacked_scans():
    world = load_world("formation_imm").world
    assert build_estimator(world.uavs[0], 0).config.stack_scans is True
    for method in ("none", "convex"):
        demo = load_world("demo", [f"{U0}.fusion.method={method}"]).world
        assert build_estimator(demo.uavs[0], 0).config.stack_scans is False


def test_every_sensor_type_has_a_builder():
    world = load_world("helsinki_chase").world
    for spec in world.uavs[0].sensors:
        assert spec.type in SENSOR_BUILDERS
        assert build_sensor(spec, "s").sensor_id == "s"
    with pytest.raises(TypeError, match="unknown sensor spec"):
        build_sensor(object(), "s")
