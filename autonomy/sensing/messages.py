"""Typed, timestamped messages exchanged over the radio :class:`~autonomy.sensing.channel.Channel`.

Every message names its sender, its receiver (``None`` for a broadcast) and the time it was sent; the channel wraps
it in an :class:`Envelope` that adds when and by which path it arrived.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from interfaces.state import TrackPicture

__all__ = ["Envelope", "EstimateMessage", "InformationMessage", "Message", "PlanMessage", "TrackListMessage"]


@dataclass(frozen=True, kw_only=True)
class Message:
    """Base of every radio message.

    Attributes
    ----------
    sender : str
        Node that sent it (a UAV name or the base station).
    receiver : str | None
        Addressee; ``None`` broadcasts to every other node in range.
    t_sent : float
        Send time (s).
    """

    sender: str
    receiver: str | None
    t_sent: float

    def __post_init__(self) -> None:
        if not self.sender:
            raise ValueError("Message.sender must be a non-empty node name")
        if self.receiver == self.sender:
            raise ValueError(f"Message.receiver must differ from the sender, got {self.receiver!r}")


@dataclass(frozen=True, kw_only=True)
class EstimateMessage(Message):
    """A local target estimate (state-vector fusion, covariance intersection, consensus).

    Attributes
    ----------
    target_id : int
        The sender's track label.
    x : np.ndarray
        (n,) state in the model's layout (SI units).
    P : np.ndarray
        (n, n) covariance.
    t_estimate : float
        Time the estimate refers to (s).
    """

    target_id: int
    x: np.ndarray
    P: np.ndarray
    t_estimate: float


@dataclass(frozen=True, kw_only=True)
class TrackListMessage(Message):
    """A multi-target tracker's confirmed tracks, with ids, target probabilities and class evidence, and the track
    the sender takes for the target (track-to-track association and fusion in a team among traffic).

    Attributes
    ----------
    picture : TrackPicture
        The tracks.
    """

    picture: TrackPicture


@dataclass(frozen=True, kw_only=True)
class InformationMessage(Message):
    """Measurement information ``(i, I) = (H^T R^-1 (z - h + H x), H^T R^-1 H)`` for information-filter fusion.

    Attributes
    ----------
    target_id : int
        The sender's track label.
    info_vector : np.ndarray
        (n,) information contribution ``i``.
    info_matrix : np.ndarray
        (n, n) information contribution ``I``.
    t_info : float
        Measurement time the contribution refers to (s).
    """

    target_id: int
    info_vector: np.ndarray
    info_matrix: np.ndarray
    t_info: float


@dataclass(frozen=True, kw_only=True)
class PlanMessage(Message):
    """A broadcast plan (sequential planning respects the plans already announced).

    Attributes
    ----------
    waypoints_W : np.ndarray
        (K, 3) planned positions (m).
    t_waypoints : np.ndarray
        (K,) times of the waypoints (s).
    """

    waypoints_W: np.ndarray
    t_waypoints: np.ndarray


@dataclass(frozen=True, kw_only=True)
class StateMessage(Message):
    """A UAV's own state, broadcast to its team (what teammates see of each other).

    Attributes
    ----------
    p_W, v_W : np.ndarray
        (3,) position (m) and velocity (m/s), world frame.
    yaw : float
        Yaw (rad).
    plan_p_W : np.ndarray | None
        (K, 2) or (K, 3) planned positions at ``t_sent + plan_dt·(k+1)`` (m), if the guidance law plans.
    plan_dt : float
        Step of the plan (s).
    """

    p_W: np.ndarray
    v_W: np.ndarray
    yaw: float
    plan_p_W: np.ndarray | None = None
    plan_dt: float = 1.0


@dataclass(frozen=True, kw_only=True)
class Envelope:
    """A delivered message.

    Attributes
    ----------
    message : Message
        The payload as sent.
    receiver : str
        Node that received it.
    tick_arrival : int
        Physics tick of arrival.
    t_arrival : float
        Arrival time (s).
    path : tuple[str, ...]
        Nodes from the sender to the receiver (two entries for a direct link).
    """

    message: Message
    receiver: str
    tick_arrival: int
    t_arrival: float
    path: tuple[str, ...]
