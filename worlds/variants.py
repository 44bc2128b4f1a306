"""The open sets of estimator types, guidance types and fusion methods a world file may name, each with its typed
settings.

A world file picks a variant by its tag (``estimator.type``, ``guidance.type``, ``fusion.method``); the schema
(:mod:`worlds.schema_autonomy`) looks the tag up here, refuses an unknown one listing the known tags, and validates
the variant's ``params`` (and an estimator's ``road``) against the variant's settings model at load. The simulator's
registry (:mod:`simulator.registry`) maps the same tags to builders; a new mode registers its settings here and its
builder there in one call (:func:`simulator.registry.register_guidance`).

Switching a type needs no reset of ``params``: a key that the chosen type does not know but another registered type
of the same family does is dropped with a :class:`WorldNote` warning (so ``--set uavs[0].autonomy.guidance.type=
vector_field`` on a world whose NMPC has ``params: {solver: fatrop}`` flies the vector field with its defaults); a key
no type of the family knows is an error naming its path.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

from pydantic import BaseModel

from worlds.schema_settings import (FastMpcSettings, FormationSettings, InfoPlanSettings, NmpcSettings, NoSettings,
                                    RoadSettings, SearchSettings, SetMembershipSettings, TrackerSettings,
                                    VectorFieldSettings, WaypointSettings)

__all__ = [
    "ESTIMATORS",
    "FUSIONS",
    "GUIDANCES",
    "EstimatorVariant",
    "FusionVariant",
    "GuidanceVariant",
    "WorldNote",
    "check_tag",
    "known_tags",
    "register_estimator",
    "register_fusion",
    "register_guidance",
    "settings_models",
    "split_params",
]


class WorldNote(UserWarning):
    """A world-file setting that the loader dropped (a setting of another type than the one chosen)."""


@dataclass(frozen=True, kw_only=True)
class EstimatorVariant:
    """An estimator type.

    Attributes
    ----------
    settings : type[BaseModel] | None
        Model of its ``params`` (None: unchecked keyword arguments of a plugin class).
    road : type[BaseModel] | None
        Model of its ``road`` settings (None: it takes none).
    """

    settings: type[BaseModel] | None
    road: type[BaseModel] | None = None


@dataclass(frozen=True, kw_only=True)
class GuidanceVariant:
    """A guidance type.

    Attributes
    ----------
    settings : type[BaseModel] | None
        Model of its ``params`` (None: unchecked keyword arguments of a plugin class).
    """

    settings: type[BaseModel] | None


@dataclass(frozen=True, kw_only=True)
class FusionVariant:
    """A fusion method.

    Attributes
    ----------
    stacked_scans : bool
        The UAV's tracker stacks the detections of one time (its own and the teammates' shared ones) into one update.
    """

    stacked_scans: bool = False


_TRACKER = EstimatorVariant(settings=TrackerSettings)
ESTIMATORS: dict[str, EstimatorVariant] = {
    "ekf": _TRACKER,
    "ukf": _TRACKER,
    "ckf": _TRACKER,
    "scif": _TRACKER,
    "imm": _TRACKER,
    "maekf": EstimatorVariant(settings=TrackerSettings, road=RoadSettings),
    "ecukf": EstimatorVariant(settings=TrackerSettings, road=RoadSettings),
    "set_membership": EstimatorVariant(settings=SetMembershipSettings),
    "plugin": EstimatorVariant(settings=None),
}
"""Estimator types by tag."""

GUIDANCES: dict[str, GuidanceVariant] = {
    "hold": GuidanceVariant(settings=WaypointSettings),
    "waypoints": GuidanceVariant(settings=WaypointSettings),
    "vector_field": GuidanceVariant(settings=VectorFieldSettings),
    "nmpc": GuidanceVariant(settings=NmpcSettings),
    "fast_mpc": GuidanceVariant(settings=FastMpcSettings),
    "formation": GuidanceVariant(settings=FormationSettings),
    "search": GuidanceVariant(settings=SearchSettings),
    "infoplan": GuidanceVariant(settings=InfoPlanSettings),
    "plugin": GuidanceVariant(settings=None),
}
"""Guidance types by tag."""

FUSIONS: dict[str, FusionVariant] = {
    "none": FusionVariant(),
    "convex": FusionVariant(),
    "covariance_intersection": FusionVariant(),
    "hcmci": FusionVariant(),
    "measurements": FusionVariant(stacked_scans=True),
    "sets": FusionVariant(),
    "base_station": FusionVariant(),
}
"""Fusion methods by tag."""


def _register(table: dict[str, Any], family: str, tag: str, variant: Any) -> None:
    if tag in table and table[tag] != variant:
        raise ValueError(f"{family} {tag!r} is registered already")
    table[tag] = variant


def register_estimator(tag: str, variant: EstimatorVariant) -> None:
    """Add an estimator type (its builder goes into :mod:`simulator.registry`)."""
    _register(ESTIMATORS, "estimator type", tag, variant)


def register_guidance(tag: str, variant: GuidanceVariant) -> None:
    """Add a guidance type (its builder goes into :mod:`simulator.registry`)."""
    _register(GUIDANCES, "guidance type", tag, variant)


def register_fusion(tag: str, variant: FusionVariant) -> None:
    """Add a fusion method."""
    _register(FUSIONS, "fusion method", tag, variant)


def known_tags(table: dict[str, Any]) -> str:
    """The registered tags of a family, for error messages: ``'ekf', 'ukf' or 'plugin'``."""
    tags = [repr(t) for t in table]
    return tags[0] if len(tags) == 1 else ", ".join(tags[:-1]) + " or " + tags[-1]


def check_tag(table: dict[str, Any], tag: str) -> str:
    """``tag`` if it is registered in ``table``, else a ValueError listing the known tags."""
    if tag not in table:
        raise ValueError(f"one of {known_tags(table)}")
    return tag


def split_params(params: dict[str, Any], model: type[BaseModel], others: list[type[BaseModel]],
                 where: str) -> dict[str, Any]:
    """``params`` less the keys that ``model`` does not know and one of the ``others`` (settings of the family's other
    types) does: those are dropped with a :class:`WorldNote` naming them (``where``: the section, e.g. ``guidance
    type 'vector_field'``). Keys no model knows stay, for ``model`` to refuse."""
    own = set(model.model_fields)
    foreign = set().union(*(set(m.model_fields) for m in others if m is not model)) if others else set()
    dropped = sorted(k for k in params if k not in own and k in foreign)
    if dropped:
        # shown as "world:0: WorldNote: ..." (no source line: the note is about the world file, not this code)
        warnings.warn_explicit(f"{where}: ignoring {', '.join(dropped)} (settings of another type)", WorldNote,
                               filename="world", lineno=0, module="worlds.variants")
    return {k: v for k, v in params.items() if k not in dropped}


def settings_models(table: dict[str, Any], attribute: str = "settings") -> list[type[BaseModel]]:
    """The distinct settings models of a family's types (``attribute``: ``settings`` or ``road``)."""
    models: list[type[BaseModel]] = []
    for variant in table.values():
        model = getattr(variant, attribute, None)
        if model is not None and model is not NoSettings and model not in models:
            models.append(model)
    return models
