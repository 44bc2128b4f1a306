"""Multi-target tracking for a UAV: when its tracker holds every car, and what it is told about the target.

:func:`tracking_mode` resolves ``estimator.tracking.mode`` (``auto``: multi when the world has more than one ground
vehicle that is not a decoy). :func:`multi_target` turns the estimator the registry built into its multi-target
form: a built-in tracker (any filter, the road-constrained ones too) becomes a
:class:`~autonomy.estimation.tracking.multi.MultiTargetTracker` with the same filters, gate and loss settings; a
user's single-target estimator is fed the target track's detections
(:class:`~autonomy.estimation.tracking.gated.TargetGatedEstimator`); an estimator that is already multi-target (it
has ``track_reports``) or holds sets is left as it is.

What the team knows of the target (:func:`identity_config`): its classes (colour, body type, length class, from its
world-file entry: the hand-off describes the car), the class frequencies of the other cars (the traffic census) and
their density where tracks start: the other cars over the streets' length times a band of ``TRACK_BAND_M`` (tracks
of cars lie within tens of metres of their road), or over the terrain without roads.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from autonomy.estimation.tracker import SingleTargetTracker, TrackerConfig
from autonomy.estimation.tracking.gated import TargetGatedEstimator
from autonomy.estimation.tracking.identity import IdentityConfig, background_frequencies
from autonomy.estimation.tracking.multi import MultiTargetTracker, MultiTrackerConfig
from worlds.catalog import CAR_ATTRIBUTES, car_classes
from worlds.schema import GroundVehicleSpec, UavSpec, World

__all__ = ["TRACK_BAND_M", "identity_config", "multi_target", "tracking_mode"]

TRACK_BAND_M = 100.0
"""Width of the band around the streets where the tracks of cars start (m): about twice the largest radar range
noise of the shipped worlds on either side of the road."""


def tracking_mode(world: World, uav: UavSpec) -> str:
    """``single`` or ``multi`` for ``uav``'s estimator (module docstring)."""
    est = uav.autonomy.estimator
    if est.type == "set_membership":
        return "single"
    mode = est.tracking.mode
    if mode != "auto":
        return mode
    return "multi" if sum(g.role != "decoy" for g in world.ground_vehicles) > 1 else "single"


def _classes(g: GroundVehicleSpec) -> dict[str, int]:
    return car_classes(g.type, g.colour)


def identity_config(world: World, uav: UavSpec, network: Any = None) -> IdentityConfig:
    """What ``uav``'s tracker knows of the (first) designated target and of the other cars (module docstring)."""
    spec = uav.autonomy.estimator.tracking
    targets = world.target_ids()
    by_id = {g.id: g for g in world.ground_vehicles}
    target = by_id.get(targets[0]) if targets else None
    others = [g for g in world.ground_vehicles if g.role != "decoy" and g.id not in targets]
    area = float(np.prod(world.terrain.size))
    if network is not None and network.street_length() > 0:
        area = min(area, float(network.street_length()) * TRACK_BAND_M)
    return IdentityConfig(
        target_classes=_classes(target) if target is not None else {},
        background=background_frequencies([_classes(g) for g in others],
                                          {k: len(v) for k, v in CAR_ATTRIBUTES.items()}),
        background_density=max(len(others), 1) / area,
        search_speed=spec.search_speed, min_probability=spec.min_target_probability,
        swap_probability=spec.swap_probability, search_detection_probability=search_detection_probability(uav))


SEARCH_DETECTION_PROBABILITY = 0.3
"""``tracking.search_detection_probability: auto`` for a UAV whose radars see a target anywhere around, stopped or
not: a radar's detection probability (0.9-0.95 in the shipped worlds) times about a third for the chance that a car
in a town is in its line of sight from a UAV's altitude and standoff."""


def search_detection_probability(uav: UavSpec) -> float:
    """The UAV's ``tracking.search_detection_probability``, ``auto`` resolved (its schema description)."""
    value = uav.autonomy.estimator.tracking.search_detection_probability
    if value != "auto":
        return float(value)
    radars = [s for s in uav.sensors if s.type == "radar"]
    sees_all = radars and all(s.min_detectable_velocity == 0 and s.fov is None for s in radars)
    return SEARCH_DETECTION_PROBABILITY if sees_all else 0.0


def _multi_config(uav: UavSpec) -> MultiTrackerConfig:
    spec = uav.autonomy.estimator.tracking
    return MultiTrackerConfig(associator=spec.associator, confirm_m=spec.confirm_m, confirm_n=spec.confirm_n,
                              detection_probability=spec.detection_probability,
                              clutter_density=spec.clutter_density, merge_distance_m=spec.merge_distance_m,
                              merge_speed_mps=spec.merge_speed_mps, max_tracks=spec.max_tracks,
                              class_aided=spec.class_aided,
                              camera_detection_probability=spec.camera_detection_probability)


def multi_target(estimator: Any, world: World, uav: UavSpec, network: Any = None) -> Any:
    """``estimator`` in its multi-target form when :func:`tracking_mode` says multi (module docstring)."""
    if tracking_mode(world, uav) != "multi" or hasattr(estimator, "track_reports"):
        return estimator
    identity = identity_config(world, uav, network)
    multi = _multi_config(uav)
    if isinstance(estimator, SingleTargetTracker):
        return MultiTargetTracker(estimator.config, multi, identity, model=estimator.model,
                                  filters=estimator.initiator.filters,
                                  gating_filter=estimator.associator.distance.gating_filter)
    if uav.autonomy.estimator.type == "set_membership":
        return estimator
    return TargetGatedEstimator(estimator, MultiTargetTracker(TrackerConfig(), multi, identity))
