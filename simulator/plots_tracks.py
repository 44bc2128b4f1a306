"""The plots of a multi-target tracking run (a ``tracks`` stream): ``plots/tracks.png`` and the ID-switch marks on
``plots/errors.png``.

``tracks.png`` has one column per UAV with a tracker: on the map, every track's path (thin, neutral), the segments
where the UAV took a track for the target (thick, in the UAV's colour), the designated target's true path (strong)
and every other ground vehicle's (light grey); below it, the target track's ``p_target`` over time, with the best
``p_target`` among the other tracks for comparison and the UAV's ID switches marked.

The target track of a UAV at an agent step is its row with ``is_target`` set (the one with the largest ``p_target``
should a step hold several); an *ID switch* is a step whose target track id differs from the last target track id
before it (the first acquisition is not a switch; a target lost and taken up again under the same id is not one
either, under a new id it is).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from simulator.runrecord import RunRecord

__all__ = ["TargetTrackSeries", "id_switch_times", "mark_id_switches", "target_track_series", "tracks_plot"]

_TRACK_RGB = (0.35, 0.4, 0.5)  # every track's path
_TARGET_TRUTH = "crimson"
_TRAFFIC_TRUTH = "0.78"
_ROAD = "0.88"


@dataclass(frozen=True)
class TargetTrackSeries:
    """One UAV's target track per agent step: times (N,) s, track id (N,) (-1: no track taken for the target),
    its ``p_target`` (N,) (NaN without one) and the largest ``p_target`` among the other live tracks (N,) (NaN
    without any)."""

    t: np.ndarray
    track: np.ndarray
    p_target: np.ndarray
    p_other: np.ndarray

    def switch_times(self) -> np.ndarray:
        """Times (K,) s of the steps whose target track id differs from the last one before them."""
        held = self.track >= 0
        ids, t = self.track[held], self.t[held]
        return t[1:][ids[1:] != ids[:-1]]


def _rows(stream: dict[str, np.ndarray], uav: int) -> dict[str, np.ndarray]:
    mask = stream["uav"] == uav
    return {k: v[mask] for k, v in stream.items()}


def target_track_series(tracks: dict[str, np.ndarray], uav: int) -> TargetTrackSeries:
    """UAV ``uav``'s :class:`TargetTrackSeries` from a ``tracks`` stream (the columns of
    :data:`simulator.streams.STREAMS`)."""
    d = _rows(tracks, uav)
    if d["tick"].size == 0:
        empty = np.zeros(0)
        return TargetTrackSeries(empty, np.zeros(0, dtype=np.int64), empty, empty)
    is_target = d["is_target"].astype(bool)
    p = d["p_target"].astype(float)
    # per tick: the rows taken for the target first, the largest p_target first among them
    order = np.lexsort((-np.nan_to_num(p, nan=-1.0), ~is_target, d["tick"]))
    tick, is_target, p = d["tick"][order], is_target[order], p[order]
    t, track = d["t"][order], d["track"][order].astype(np.int64)
    _, first = np.unique(tick, return_index=True)
    held = is_target[first]
    other_p = np.where(is_target, -np.inf, np.nan_to_num(p, nan=-np.inf))
    p_other = np.maximum.reduceat(other_p, first)
    return TargetTrackSeries(t=t[first], track=np.where(held, track[first], -1),
                             p_target=np.where(held, p[first], np.nan),
                             p_other=np.where(np.isfinite(p_other), p_other, np.nan))


def id_switch_times(tracks: dict[str, np.ndarray], uav: int) -> np.ndarray:
    """Times (K,) s at which UAV ``uav``'s target track id changed (see the module docstring)."""
    return target_track_series(tracks, uav).switch_times()


def mark_id_switches(ax: Any, rec: RunRecord, colors: Sequence[str]) -> int:
    """Vertical dotted lines on ``ax`` at every UAV's ID switches, in the UAV's colour; returns how many."""
    if "tracks" not in rec.streams:
        return 0
    tracks = rec.streams["tracks"]
    n = 0
    for u in np.unique(tracks["uav"]).astype(int).tolist():
        times = id_switch_times(tracks, u)
        for k, ts in enumerate(times):
            ax.axvline(float(ts), color=colors[u % len(colors)], ls=":", lw=1.0, alpha=0.9,
                       label=f"UAV {u} ID switch" if k == 0 else None)
        n += len(times)
    return n


def _segments(key: np.ndarray, t: np.ndarray, x: np.ndarray, y: np.ndarray,
              keep: np.ndarray | None = None) -> np.ndarray:
    """Line segments (M, 2, 2) m between consecutive samples in time of each ``key`` (a track or a vehicle);
    with ``keep`` (bool per sample), only those whose two ends are kept."""
    order = np.lexsort((t, key))
    key, x, y = key[order], x[order], y[order]
    same = key[1:] == key[:-1]
    if keep is not None:
        keep = keep[order]
        same &= keep[1:] & keep[:-1]
    a = np.c_[x[:-1], y[:-1]][same]
    b = np.c_[x[1:], y[1:]][same]
    return np.stack([a, b], axis=1) if len(a) else np.zeros((0, 2, 2))


def _roads(run_dir: Path) -> list[np.ndarray]:
    geo = run_dir / "geometry.npz"
    if not geo.exists():
        return []
    with np.load(geo) as g:
        xy, off = g["road_xy"], g["road_offsets"]
    return [xy[off[i]:off[i + 1]] for i in range(len(off) - 1)]


def _draw_map(ax: Any, rec: RunRecord, d: dict[str, np.ndarray], target: int | None, roads: list[np.ndarray],
              colour: str) -> None:
    from matplotlib.collections import LineCollection

    if roads:
        ax.add_collection(LineCollection(roads, colors=_ROAD, linewidths=3.0, zorder=1))
    xs, ys = [d["x"]], [d["y"]]
    if "vehicle_truth" in rec.streams:
        vt = rec.streams["vehicle_truth"]
        veh = vt["vehicle"].astype(int)
        is_target = veh == (-1 if target is None else target)
        on = np.asarray(vt["active"], dtype=bool) if "active" in vt else np.ones(len(veh), dtype=bool)
        traffic = _segments(veh, vt["t"], vt["x"], vt["y"], ~is_target & on)  # free traffic slots hold no car
        ax.add_collection(LineCollection(traffic, colors=_TRAFFIC_TRUTH, linewidths=0.8, zorder=2,
                                         label="other vehicles (truth)"))
        if is_target.any():
            ax.plot(vt["x"][is_target], vt["y"][is_target], color=_TARGET_TRUTH, lw=1.4, zorder=5,
                    label="target (truth)")
        xs.append(vt["x"][on])
        ys.append(vt["y"][on])
    track = d["track"].astype(np.int64)
    ax.add_collection(LineCollection(_segments(track, d["t"], d["x"], d["y"]), colors=[_TRACK_RGB],
                                     linewidths=0.6, alpha=0.7, zorder=3, label="tracks"))
    held = _segments(track, d["t"], d["x"], d["y"], d["is_target"].astype(bool))
    ax.add_collection(LineCollection(held, colors=colour, linewidths=3.5, alpha=0.85, zorder=4,
                                     label="track taken for target"))
    x, y = np.concatenate(xs), np.concatenate(ys)
    ok = np.isfinite(x) & np.isfinite(y)
    if ok.any():
        x, y = x[ok], y[ok]
        pad = max(30.0, 0.05 * max(np.ptp(x), np.ptp(y)))
        ax.set_xlim(x.min() - pad, x.max() + pad)
        ax.set_ylim(y.min() - pad, y.max() + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x east (m)")
    ax.set_ylabel("y north (m)")
    ax.legend(loc="upper right", fontsize=7)


def _draw_strip(ax: Any, series: TargetTrackSeries, colour: str) -> None:
    ax.plot(series.t, series.p_target, color=colour, lw=1.2, label="target track")
    if np.isfinite(series.p_other).any():
        ax.plot(series.t, series.p_other, color="0.6", lw=0.8, label="best other track")
    for k, ts in enumerate(series.switch_times()):
        ax.axvline(float(ts), color="k", ls=":", lw=1.0, label="ID switch" if k == 0 else None)
    ax.set_ylim(-0.03, 1.03)
    ax.set_xlabel("time (s)")
    ax.set_ylabel("p_target")
    ax.grid(alpha=0.3)
    ax.legend(loc="lower right", fontsize=7)


def tracks_plot(plt: Any, rec: RunRecord, world: Any, plots: Path, colors: Sequence[str]) -> Path | None:
    """Draw ``plots/tracks.png`` when the record has a ``tracks`` stream (None otherwise); ``colors`` per UAV index.

    ``world`` (the run's validated world, or None) names the UAVs; the designated target is the metrics'
    ``target_index``.
    """
    tracks = rec.streams.get("tracks")
    if not tracks or not len(tracks.get("tick", ())):
        return None
    uavs = np.unique(tracks["uav"]).astype(int).tolist()
    target = rec.metrics.get("target_index")
    target = None if target is None else int(target)
    roads = _roads(plots.parent)
    n = len(uavs)
    fig, axes = plt.subplots(2, n, figsize=(6.5 * n, 8.5), dpi=110, squeeze=False,
                             gridspec_kw={"height_ratios": [3.2, 1.0]})
    for k, u in enumerate(uavs):
        colour = colors[u % len(colors)]
        d = _rows(tracks, u)
        name = world.uavs[u].id if world is not None and u < len(world.uavs) else f"UAV {u}"
        series = target_track_series(tracks, u)
        _draw_map(axes[0, k], rec, d, target, roads, colour)
        axes[0, k].set_title(f"{name}: {np.unique(d['track']).size} tracks, "
                             f"{series.switch_times().size} ID switches")
        _draw_strip(axes[1, k], series, colour)
    fig.tight_layout()
    path = plots / "tracks.png"
    fig.savefig(path)
    plt.close(fig)
    return path
