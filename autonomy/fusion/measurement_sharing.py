"""Raw measurement sharing across a team (paper 003's centralised augmented measurement, decentralised).

Every detection a UAV's sensor produces is also sent to its teammates over the radio. A teammate's copy keeps what
the detection says (``z``, ``R``, the sensor's id and position, ``t_meas``) and arrives when the sensor delivered it
plus the radio's delay; the receiving tracker stacks it with its own detections of the same ``t_meas``
(:class:`~autonomy.estimation.tracker.TrackerConfig` ``stack_scans``). A copy that arrives after the tracker has
moved past its scan time (an update of a newer scan, or an agent step after it) is dropped there like any
out-of-sequence measurement: with the agents stepping at the sensors' rate, a copy delayed by up to one agent period
still updates the track at its scan time (after the own bearing of that time, sequentially), and a longer radio delay
leaves each UAV its own bearings only.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

from autonomy.sensing.measurement import Detection
from autonomy.sensing.messages import Message

__all__ = ["DetectionMessage", "relayed"]


@dataclass(frozen=True, kw_only=True)
class DetectionMessage(Message):
    """A UAV's detections of one scan, for its teammates.

    Attributes
    ----------
    detections : tuple[Detection, ...]
        As its sensor produced them (sensor position and ``t_meas`` included).
    """

    detections: tuple[Detection, ...]


def relayed(detections: Sequence[Detection], delay_s: float) -> list[Detection]:
    """Teammates' copies of ``detections``: the same measurements, arriving ``delay_s`` (s, >= 0) after their
    sensor delivered them."""
    if not delay_s >= 0:
        raise ValueError(f"delay_s must be >= 0 s, got {delay_s}")
    return [replace(d, t_arrival=d.t_arrival + delay_s) for d in detections]
