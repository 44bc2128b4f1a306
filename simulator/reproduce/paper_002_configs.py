"""Paper 002's columns: which world, estimator, road-filter settings and guidance each campaign flies.

Primary columns (the paper's configuration) fly ``road_standoff_paper`` (the paper's geometry scaled to quadrotors, a
known curved arterial) with the paper's filters (:data:`PAPER_ROAD`) and Table I's NMPC (the world's own guidance
params); the LVFG baseline gets the same speed and turn limits as that NMPC (:data:`LVFG_TABLE_I`). Extra columns
(``paper_faithful=False``) carry our additions: the road filters' defaults (:data:`OURS_ROAD`) and our NMPC
(:data:`NMPC_OURS`), and the town world ``road_standoff`` as shipped.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import yaml

__all__ = ["Config", "CONFIGS", "PAPER_WORLD", "TOWN_WORLD", "PAPER_ROAD", "OURS_ROAD", "NMPC_OURS", "LVFG_TABLE_I",
           "PAPER_V0", "PAPER_RD", "SCALE"]

PAPER_WORLD = "road_standoff_paper"
TOWN_WORLD = "road_standoff"
UAV_COUNT = 2

SCALE = 15.0 / 40.0
"""Length scale of ``road_standoff_paper`` against the paper (UAV speed 15 m/s against 40 m/s; times kept)."""
PAPER_V0 = 15.0
PAPER_RD = 187.5

PAPER_ROAD: dict = {
    "ecukf_stage2": "pseudo",  # the paper's ECUKF: a sigma-point pseudo-measurement update, not a projection
    "constraint": {"follow_road_heading": False,  # the paper predicts with the Singer model alone
                   "switch_gate": 0.8,  # Table I's ε segment-switching gate
                   "velocity_update": "off"},  # the paper's pseudo-measurement constrains the position only
    "max_hypotheses": 1,  # one road hypothesis: the paper's known road, no junction filter
    "direction_weighting": False,
    "wrong_way_z": None,
}
"""The paper's MAEKF / ECUKF (``estimator.road`` of the world file): see :class:`RoadFilterConfig`."""

OURS_ROAD: dict = {}
"""The road filters' defaults (our additions: velocity turned with the road, projecting ECUKF, junction hypotheses,
no ε gate)."""

NMPC_OURS: dict = {"solver": "fatrop"}
"""Our NMPC: :class:`NmpcConfig`'s defaults (N = 20, our weights, chord phase term, speed v0 ± 6 m/s, ω ≤ 0.5 rad/s)
solved by Fatrop, as ``road_standoff`` flies it."""

LVFG_TABLE_I: dict = {"min_speed": PAPER_V0 - 10.0 * SCALE, "max_speed": PAPER_V0 + 10.0 * SCALE,
                      "max_heading_rate": 0.2}
"""The vector field under Table I's NMPC limits (|v − v0| ≤ 10 m/s scaled, |ω| ≤ 0.2 rad/s): like for like."""


def _flow(value: object) -> str:
    return yaml.safe_dump(value, default_flow_style=True, width=10**9).strip()


@dataclass(frozen=True)
class Config:
    """One campaign: ``world``, the estimator type of both UAVs, their guidance (``nmpc`` | ``vector_field``), the
    road-filter settings and the guidance params (None: the world's own, i.e. Table I's NMPC on the paper world)."""

    name: str
    world: str
    estimator: str
    guidance: str
    road: dict = field(default_factory=dict)
    guidance_params: dict | None = None
    paper_faithful: bool = True

    def overrides(self) -> tuple[str, ...]:
        sets = []
        for i in range(UAV_COUNT):
            sets += [f"uavs[{i}].autonomy.estimator.type={self.estimator}",
                     f"uavs[{i}].autonomy.guidance.type={self.guidance}"]
            if self.estimator in ("maekf", "ecukf") and self.road:
                sets.append(f"uavs[{i}].autonomy.estimator.road={_flow(self.road)}")
            if self.guidance_params is not None:
                sets.append(f"uavs[{i}].autonomy.guidance.params={_flow(self.guidance_params)}")
        return tuple(sets)


def _paper(name: str, est: str, guidance: str = "nmpc") -> Config:
    params = LVFG_TABLE_I if guidance == "vector_field" else None
    return Config(name, PAPER_WORLD, est, guidance, road=PAPER_ROAD, guidance_params=params)


CONFIGS = (
    _paper("ekf_nmpc", "ekf"), _paper("ukf_nmpc", "ukf"), _paper("maekf_nmpc", "maekf"),
    _paper("ecukf_nmpc", "ecukf"), _paper("ekf_lvfg", "ekf", "vector_field"),
    _paper("ecukf_lvfg", "ecukf", "vector_field"),
    # our additions on the paper world (extra columns)
    Config("ecukf_ours_nmpc", PAPER_WORLD, "ecukf", "nmpc", road=OURS_ROAD, paper_faithful=False),
    Config("ekf_nmpc_ours", PAPER_WORLD, "ekf", "nmpc", guidance_params=NMPC_OURS, paper_faithful=False),
    # the town world as shipped (our configuration: 150 m standoff, 12 m/s, our filters and NMPC)
    Config("town_ekf", TOWN_WORLD, "ekf", "nmpc", paper_faithful=False),
    Config("town_ukf", TOWN_WORLD, "ukf", "nmpc", paper_faithful=False),
    Config("town_maekf", TOWN_WORLD, "maekf", "nmpc", paper_faithful=False),
    Config("town_ecukf", TOWN_WORLD, "ecukf", "nmpc", paper_faithful=False),
)
"""Every campaign of the reproduction, run ``i`` of each with the same seed (``ctx.run_seeds()``)."""
