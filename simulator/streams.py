"""The time-series streams of a run record: one declaration of each stream's columns, in their order.

The recorder (:class:`simulator.record.RunRecorder`) checks each stream's first row against its schema (later rows
must repeat the first row's columns), so a writer that drops, renames or reorders a column fails at once instead of
leaving a record its readers cannot load. The writers (:mod:`simulator.recording`, :mod:`simulator.search_team`,
:mod:`simulator.base_station`) build their rows from :meth:`StreamSchema.blank` or in the declared order.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = ["STREAMS", "StreamSchema"]


@dataclass(frozen=True, kw_only=True)
class StreamSchema:
    """One stream: its name, its columns in order and what a row is.

    Attributes
    ----------
    name : str
        Folder name under ``timeseries/``.
    columns : tuple[str, ...]
        Column names, in the order of the stored structured array's fields.
    doc : str
        What one row is.
    """

    name: str
    columns: tuple[str, ...]
    doc: str

    def blank(self, **values: Any) -> dict[str, Any]:
        """A row with every column NaN but ``values`` (in the declared order); raises KeyError on an unknown column."""
        unknown = set(values) - set(self.columns)
        if unknown:
            raise KeyError(f"stream {self.name}: no columns {sorted(unknown)}")
        return {c: values.get(c, np.nan) for c in self.columns}

    def check(self, columns: tuple[str, ...]) -> None:
        """Raise KeyError unless ``columns`` are this stream's, in order."""
        if columns != self.columns:
            raise KeyError(f"stream {self.name}: columns {list(columns)} differ from its schema {list(self.columns)}")


_ESTIMATE = ("tick", "t", "uav", "valid", "x", "y", "vx", "vy", "pxx", "pxy", "pyy", "pvxvx", "pvyvy", "detections",
             "road")

_SCHEMAS = (
    StreamSchema(name="uav_truth", doc="per UAV per record tick: position (m), attitude quaternion, velocity (m/s)",
                 columns=("tick", "t", "uav", "x", "y", "z", "qx", "qy", "qz", "qw", "vx", "vy", "vz")),
    StreamSchema(name="vehicle_truth", doc="per ground vehicle per record tick: pose, velocity, acceleration, speed, "
                 "road coordinates (road id, arc length s and lateral offset, m) and whether it is on the road (false "
                 "for a traffic source's free slot, which holds no vehicle: its other columns are stale)",
                 columns=("tick", "t", "vehicle", "x", "y", "z", "yaw", "vx", "vy", "vz", "ax", "ay", "az", "speed",
                          "road", "s", "lateral", "active")),
    StreamSchema(name="detections", doc="per detection: when taken and delivered (s), the UAV and sensor, its kind, "
                 "the truth behind it (-1 false alarm) and its first four measurement components (NaN-padded)",
                 columns=("tick", "t_meas", "t_arrival", "uav", "sensor", "kind", "truth_id", "z0", "z1", "z2", "z3")),
    StreamSchema(name="estimates", columns=_ESTIMATE, doc="per agent step: the UAV's own estimate (position m, "
                 "velocity m/s, covariance entries), the detections it used and the road it holds the target on"),
    StreamSchema(name="fused_estimates", columns=_ESTIMATE, doc="per agent step of a fusing UAV: the fused estimate"),
    StreamSchema(name="tracks", doc="per agent step of a UAV with a multi-target tracker, per live track: its id, "
                 "estimate (position m, velocity m/s, covariance entries), the probability that it is the designated "
                 "target, its own class evidence (log-likelihood ratio), whether it is confirmed and whether the UAV "
                 "takes it for the target",
                 columns=("tick", "t", "uav", "track", "x", "y", "vx", "vy", "pxx", "pxy", "pyy", "p_target",
                          "evidence", "confirmed", "is_target")),
    StreamSchema(name="commands", doc="per agent step: the set-point's kind and values (NaN where not that kind)",
                 columns=("tick", "t", "uav", "kind", "speed", "heading_rate", "altitude", "vx", "vy", "vz")),
    StreamSchema(name="measurement_sharing", doc="per agent step of a UAV taking its teammates' detections: those "
                 "delivered so far, and those its track used so far from its own and its teammates' sensors",
                 columns=("tick", "t", "uav", "received", "own_used", "mates_used")),
    StreamSchema(name="search", doc="per search-team step per UAV (simulator.search_team)",
                 columns=("tick", "t", "uav", "area_X", "area_Xbar", "targets_inside", "targets", "decoys_in_X",
                          "fused_with", "links", "safe", "clearance", "u", "plan_x", "plan_y", "deviation",
                          "vertices_X", "vertices_Xbar")),
    StreamSchema(name="routing", doc="per base-station step per reporting UAV (simulator.base_station)",
                 columns=("tick", "t", "uav", "parent", "hops", "beta", "sent", "delivered")),
    StreamSchema(name="base_station", doc="per base-station step: the base's estimate and packets "
                 "(simulator.base_station)",
                 columns=("tick", "t", "valid", "x", "y", "vx", "vy", "pxx", "pxy", "pyy", "pvxvx", "pvyvy",
                          "info_trace", "received", "lost", "late", "received_total", "lost_total")),
)

STREAMS: dict[str, StreamSchema] = {s.name: s for s in _SCHEMAS}
"""Every stream a run may write, by name."""
