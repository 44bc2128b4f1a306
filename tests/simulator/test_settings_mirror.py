"""Every world-file setting of an estimator or guidance law has the name and the default of the component field it
feeds (worlds/ cannot import the components' configurations, so the world's settings models declare the names once
more; this test is what keeps the two from drifting apart)."""

import dataclasses
import inspect
import math

import pytest
from pydantic import BaseModel

from autonomy.estimation.road.config import RoadFilterConfig
from autonomy.estimation.road.constraint import RoadConstraintParams
from autonomy.estimation.setmem.estimator import SetMembershipConfig
from autonomy.estimation.tracker import TrackerConfig
from autonomy.guidance.fast_mpc import FastMpcConfig
from autonomy.guidance.formation.guidance import FormationConfig
from autonomy.guidance.formation.jacobi import JacobiGains
from autonomy.guidance.infoplan.config import InfoPlannerConfig
from autonomy.guidance.nmpc_config import NmpcConfig, NmpcWeights
from autonomy.guidance.pdip import PdipOptions
from autonomy.guidance.search.guidance import SetMembershipSearchGuidance
from autonomy.guidance.search.planner import SearchConfig
from autonomy.guidance.unicycle import UnicycleParams
from autonomy.guidance.vector_field import VectorFieldConfig
from autonomy.guidance.waypoints import WaypointConfig
from simulator.builders.common import in_radians
from simulator.builders.guidance import MISSION_FIELDS
from simulator.registry import ESTIMATOR_BUILDERS, GUIDANCE_BUILDERS
from worlds import schema_settings as ss
from worlds import variants
from worlds.schema import FormationSpec, GuidanceSpec, ImmSpec, InfoPlanSpec, JacobiGainsSpec, SearchSpec

# settings model -> (component config, config fields a builder fills from elsewhere: the type, the team, the world)
PARAMS = [
    (ss.TrackerSettings, TrackerConfig, {"filter", "model", "stack_scans"} | {  # imm_*: the estimator's imm block
        f.name for f in dataclasses.fields(TrackerConfig) if f.name.startswith("imm_")}),
    (ss.RoadSettings, RoadFilterConfig, {"variant"}),
    (ss.RoadConstraintSettings, RoadConstraintParams, set()),
    (ss.SetMembershipSettings, SetMembershipConfig, {"max_target_speed"}),
    (ss.WaypointSettings, WaypointConfig, {"waypoints", "speed"}),
    (ss.VectorFieldSettings, VectorFieldConfig, {"standoff_radius", "nominal_speed", "altitude", "team_size"}),
    (ss.NmpcSettings, NmpcConfig, {"standoff_radius", "nominal_speed", "altitude", "team_size", "fallback"}),
    (ss.UnicycleSettings, UnicycleParams, set()),
    (ss.NmpcWeightsSettings, NmpcWeights, set()),
    (ss.FastMpcSettings, FastMpcConfig, {"altitude"}),
    (ss.PdipSettings, PdipOptions, set()),
    (ss.InfoPlanSettings, InfoPlannerConfig, set(InfoPlanSpec.model_fields) - {"routing"} | {
        "routing", "base_p_W", "dt", "speed", "altitude", "sigma_range", "sigma_bearing", "channel",
        "max_heading_rate", "n_heading_rates"}),
]


def config_defaults(cls) -> dict:
    out = {}
    for f in dataclasses.fields(cls):
        if f.default is not dataclasses.MISSING:
            out[f.name] = f.default
        elif f.default_factory is not dataclasses.MISSING:
            out[f.name] = f.default_factory()
        else:
            out[f.name] = dataclasses.MISSING
    return out


def same(setting, component) -> bool:
    if isinstance(setting, BaseModel):  # a nested settings model against the nested dataclass
        return all(same(v, getattr(component, k)) for k, v in setting)
    if isinstance(setting, float) or isinstance(component, float):
        return setting == pytest.approx(component, rel=1e-12, abs=0)
    return setting == component


@pytest.mark.parametrize("model, config, elsewhere", PARAMS, ids=[m.__name__ for m, _, _ in PARAMS])
def test_params_settings_mirror_their_config(model, config, elsewhere):
    defaults = config_defaults(config)
    for name, field in model.model_fields.items():
        assert name in defaults, f"{model.__name__}.{name}: {config.__name__} has no field {name!r}"
        default = field.get_default(call_default_factory=True)
        assert same(default, defaults[name]), (f"{model.__name__}.{name} defaults to {default!r}, "
                                               f"{config.__name__}.{name} to {defaults[name]!r}")
    missing = set(defaults) - set(model.model_fields) - elsewhere
    assert not missing, f"{config.__name__} fields neither in {model.__name__} nor filled by the builder: {missing}"


def block_defaults(spec: type[BaseModel], skip: set[str] = frozenset()) -> dict:
    """A settings block's defaults by the component field each feeds (``*_deg`` in radians, suffix dropped)."""
    values = {k: f.get_default(call_default_factory=True) for k, f in spec.model_fields.items() if k not in skip}
    return in_radians(values)


LAG_DEFAULT = inspect.signature(SetMembershipSearchGuidance).parameters["velocity_lag_s"].default
BLOCKS = [
    # block, component defaults it feeds (prefix: the tracker's imm_ fields), block keys whose default is
    # "take it from elsewhere" (None: the UAV's bearing sensor, the radio's routing)
    (ImmSpec, {k.removeprefix("imm_"): v for k, v in config_defaults(TrackerConfig).items() if k.startswith("imm_")},
     set()),
    (JacobiGainsSpec, config_defaults(JacobiGains), set()),
    (FormationSpec, config_defaults(FormationConfig), {"sigma_bearing_deg"}),
    (SearchSpec, {**config_defaults(SearchConfig), "velocity_lag_s": LAG_DEFAULT}, set()),
    (InfoPlanSpec, {**config_defaults(InfoPlannerConfig), "heading_rates": config_defaults(InfoPlannerConfig)[
        "n_heading_rates"]}, {"routing"}),  # the config's heading_rates is the grid, n_heading_rates its size
]


@pytest.mark.parametrize("block, component, from_elsewhere", BLOCKS, ids=[b.__name__ for b, _, _ in BLOCKS])
def test_settings_blocks_feed_fields_of_their_own_names_and_defaults(block, component, from_elsewhere):
    for name, default in block_defaults(block, from_elsewhere).items():
        assert name in component, f"{block.__name__}: no component field {name!r}"
        assert same(default, component[name]), f"{block.__name__}.{name}: {default!r} against {component[name]!r}"
    for name in from_elsewhere:
        assert block.model_fields[name].default is None


@pytest.mark.parametrize("tag", sorted(MISSION_FIELDS))
def test_the_mission_keys_feed_fields_the_law_has(tag):
    configs = {"hold": WaypointConfig, "waypoints": WaypointConfig, "vector_field": VectorFieldConfig,
               "nmpc": NmpcConfig, "fast_mpc": FastMpcConfig, "formation": FormationConfig, "search": SearchConfig,
               "infoplan": InfoPlannerConfig}
    fields = config_defaults(configs[tag])
    for key, field in MISSION_FIELDS[tag].items():
        assert key in GuidanceSpec.model_fields and field in fields


def test_every_tag_has_a_builder_and_every_builder_a_tag():
    assert set(variants.ESTIMATORS) == set(ESTIMATOR_BUILDERS)
    assert set(variants.GUIDANCES) == set(GUIDANCE_BUILDERS)
    # every built-in law (other modules, e.g. a test's, may have registered more) has its mission fields
    assert set(MISSION_FIELDS) == {"hold", "waypoints", "vector_field", "nmpc", "fast_mpc", "formation", "search",
                                   "infoplan"} and set(MISSION_FIELDS) <= set(GUIDANCE_BUILDERS)


def test_the_imm_default_is_the_trackers():
    assert math.radians(ImmSpec().turn_rate_deg_s) == TrackerConfig().imm_turn_rate
