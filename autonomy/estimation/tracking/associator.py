"""Nearest-neighbour association of a scan's detections to tracks.

Each track takes, from each sensor of the scan, the detection of the smallest NIS inside its gate (a scan holds the
detections of one time: one sensor's, or all sensors' when scans are stacked). Tracks choose independently: with
several tracks two may take the same detection (a global assignment over all tracks resolves that).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from autonomy.estimation.base import Filter
from autonomy.estimation.measurements import MeasurementLike

from .gate import ChiSquareGate
from .track import Track

__all__ = ["Association", "NearestNeighbourAssociator"]


@dataclass(frozen=True, eq=False)
class Association:
    """What one track takes from one scan.

    Attributes
    ----------
    track : Track
        The track.
    detections : tuple
        Its detections, at most one per sensor, in scan order (empty: the scan missed it).
    gated_out : int
        Detections of the sensors that had none inside the track's gate.
    """

    track: Track
    detections: tuple[MeasurementLike, ...]
    gated_out: int


class NearestNeighbourAssociator:
    """Per track and sensor, the detection of the smallest distance inside the gate (module docstring).

    Parameters
    ----------
    gate : ChiSquareGate
        The validation gate.
    distance : callable
        ``distance(filter, detection)``: the NIS of the detection against the track's filter
        (:class:`~.gate.PredictedNis`).
    """

    def __init__(self, gate: ChiSquareGate, distance: Callable[[Filter, MeasurementLike], float]) -> None:
        self.gate = gate
        self.distance = distance

    def associate(self, tracks: Sequence[Track], scan: Sequence[MeasurementLike]) -> list[Association]:
        """One :class:`Association` per track, in the order of ``tracks``."""
        by_sensor: dict[object, list] = {}
        for d in scan:
            by_sensor.setdefault(d.sensor_id, []).append(d)
        out = []
        for track in tracks:
            chosen, gated_out = [], 0
            for group in by_sensor.values():
                best, best_nis = None, np.inf
                for d in group:
                    nis = self.distance(track.filter, d)
                    if self.gate.accepts(nis, np.size(d.z)) and nis < best_nis:
                        best, best_nis = d, nis
                if best is None:
                    gated_out += len(group)
                else:
                    chosen.append(best)
            out.append(Association(track=track, detections=tuple(chosen), gated_out=gated_out))
        return out
