"""PNG plots of a run, made from its run directory alone (so they can be redrawn from any record, even a partial one).

- ``plots/trajectories.png``: top-down map — buildings, roads, UAV tracks, the target's true path and the estimates;
- ``plots/errors.png``: each UAV's position error against truth over time, with the filter's own 2σ bound;
- ``plots/altitude.png``: UAV altitudes over time;
- ``plots/standoff.png``: with standoff guidance, each UAV's standoff-distance error and the team's phase-keeping error
  over time (paper 002's Table III quantities, :mod:`autonomy.metrics.standoff`);
- ``plots/links.png``: with a lossy radio, each UAV pair's delivery probability over time under the run's channel model;
- ``plots/search.png``: with a set-membership search team, the set areas over time and the sets on the map
  (:mod:`simulator.plots_search`);
- ``plots/tracks.png``: with a multi-target tracker (a ``tracks`` stream), every track, the one taken for the target
  and every vehicle's truth per UAV, with the target track's ``p_target`` over time (:mod:`simulator.plots_tracks`);
  ``errors.png`` then marks the ID switches;
- ``plots/relay.png``: with fusion at a base station, the routes to it (each UAV's next hop, drawn every 10 s over the
  flown paths) and each UAV's route probability β over time with the packets lost.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from simulator.plots_search import search_plot
from simulator.plots_tracks import mark_id_switches, tracks_plot
from simulator.runrecord import RunRecord, load_run

__all__ = ["write_geometry", "write_plots"]

_COLORS = ["tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink", "tab:olive", "tab:cyan"]


def write_geometry(out_dir: Path, buildings: list, network: object | None) -> None:
    """Store building footprints and road centre-lines in ``geometry.npz`` for plots and renderers."""
    fps = [np.asarray(b.footprint) for b in buildings]
    roads, road_ids = [], []
    if network is not None:
        for rid, road in network.roads.items():
            s = np.linspace(0.0, road.length, max(2, int(road.length / 5.0) + 1))
            roads.append(np.asarray(road.point(s)))
            road_ids.append(str(rid))
    def pack(polys: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        if not polys:
            return np.zeros((0, 2)), np.zeros(1, dtype=int)
        return np.concatenate(polys), np.cumsum([0] + [len(q) for q in polys])
    bv, bo = pack(fps)
    rv, ro = pack(roads)
    np.savez(Path(out_dir) / "geometry.npz", building_xy=bv, building_offsets=bo, road_xy=rv, road_offsets=ro,
             road_ids=np.array(road_ids, dtype=str), building_height=np.array([b.height for b in buildings]))


def _unpack(xy: np.ndarray, offsets: np.ndarray) -> list[np.ndarray]:
    return [xy[offsets[i]:offsets[i + 1]] for i in range(len(offsets) - 1)]


def _by(stream: dict[str, np.ndarray], column: str, value: int) -> dict[str, np.ndarray]:
    mask = stream[column] == value
    return {k: v[mask] for k, v in stream.items()}


def write_plots(run_dir: str | Path) -> list[Path]:
    """Draw every plot the record allows; returns the files written."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    run_dir = Path(run_dir)
    rec = load_run(run_dir)
    plots = run_dir / "plots"
    plots.mkdir(exist_ok=True)
    written = []

    fig, ax = plt.subplots(figsize=(8, 8), dpi=110)
    geo = run_dir / "geometry.npz"
    if geo.exists():
        with np.load(geo) as g:
            roads = _unpack(g["road_xy"], g["road_offsets"])
            blds = _unpack(g["building_xy"], g["building_offsets"])
        for r in roads:
            ax.plot(r[:, 0], r[:, 1], color="0.55", lw=2.5, solid_capstyle="round", zorder=1)
        if blds:
            ax.add_collection(PolyCollection(blds, facecolor="0.8", edgecolor="0.5", lw=0.5, zorder=2))
    _draw_tracks(ax, rec)
    ax.set_aspect("equal")
    ax.set_xlabel("x east (m)")
    ax.set_ylabel("y north (m)")
    ax.set_title(f"{rec.run.get('world', '')} — seed {rec.run.get('seed', '')} — {rec.status}")
    ax.legend(loc="upper right", fontsize=8)
    _zoom_to_tracks(ax, rec)
    fig.tight_layout()
    written.append(plots / "trajectories.png")
    fig.savefig(written[-1])
    plt.close(fig)

    if "estimates" in rec.streams and "vehicle_truth" in rec.streams:
        target = int(rec.metrics.get("target_index", 0) or 0)
        fig, ax = plt.subplots(figsize=(9, 4), dpi=110)
        truth = _by(rec.streams["vehicle_truth"], "vehicle", target)
        est = rec.streams["estimates"]
        for u in np.unique(est["uav"]):
            e = _by(est, "uav", int(u))
            ok = e["valid"].astype(bool)
            if not ok.any() or truth["t"].size == 0:
                continue
            tx = np.interp(e["t"][ok], truth["t"], truth["x"])
            ty = np.interp(e["t"][ok], truth["t"], truth["y"])
            err = np.hypot(e["x"][ok] - tx, e["y"][ok] - ty)
            c = _COLORS[int(u) % len(_COLORS)]
            ax.plot(e["t"][ok], err, color=c, lw=1.2, label=f"UAV {int(u)} error")
            sig = 2 * np.sqrt(np.clip(e["pxx"][ok] + e["pyy"][ok], 0, None))
            if np.isfinite(sig).any():
                ax.plot(e["t"][ok], sig, color=c, lw=0.8, ls="--", label=f"UAV {int(u)} 2σ")
        mark_id_switches(ax, rec, _COLORS)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("position error (m)")
        ax.set_title("target position error against truth")
        ax.grid(alpha=0.3)
        if ax.lines:
            ax.legend(fontsize=8)
        fig.tight_layout()
        written.append(plots / "errors.png")
        fig.savefig(written[-1])
        plt.close(fig)

    if "uav_truth" in rec.streams:
        fig, ax = plt.subplots(figsize=(9, 3), dpi=110)
        ut = rec.streams["uav_truth"]
        for u in np.unique(ut["uav"]):
            d = _by(ut, "uav", int(u))
            ax.plot(d["t"], d["z"], color=_COLORS[int(u) % len(_COLORS)], label=f"UAV {int(u)}")
        ax.set_xlabel("time (s)")
        ax.set_ylabel("altitude (m)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        written.append(plots / "altitude.png")
        fig.savefig(written[-1])
        plt.close(fig)
    world = _world(run_dir)
    for draw in (_standoff_plot, _links_plot, _relay_plot, search_plot):
        path = draw(plt, rec, world, plots)
        if path is not None:
            written.append(path)
    path = tracks_plot(plt, rec, world, plots, _COLORS)
    if path is not None:
        written.append(path)
    return written


def _world(run_dir: Path) -> object | None:
    """The run's validated world, or None when ``world.yaml`` is missing or from another schema version."""
    try:
        from worlds.loader import load_world

        return load_world(run_dir / "world.yaml").world
    except Exception:  # noqa: BLE001 - plots that need the world are skipped
        return None


def _uav_xy_on(ut: dict[str, np.ndarray], uavs: list[int], t: np.ndarray) -> np.ndarray:
    """(T, N, 2) positions of ``uavs`` interpolated to times ``t``."""
    cols = []
    for u in uavs:
        d = _by(ut, "uav", u)
        cols.append(np.c_[np.interp(t, d["t"], d["x"]), np.interp(t, d["t"], d["y"])])
    return np.stack(cols, axis=1)


def _standoff_plot(plt: object, rec: RunRecord, world: object | None, plots: Path) -> Path | None:
    from autonomy.metrics.standoff import phase_errors, standoff_errors

    if world is None or "uav_truth" not in rec.streams or "vehicle_truth" not in rec.streams:
        return None
    trackers = [i for i, u in enumerate(world.uavs) if u.autonomy.guidance.type in ("vector_field", "nmpc")]
    ut = rec.streams["uav_truth"]
    trackers = [i for i in trackers if np.any(ut["uav"] == i)]
    truth = _by(rec.streams["vehicle_truth"], "vehicle", int(rec.metrics.get("target_index", 0) or 0))
    if not trackers or truth["t"].size < 2:
        return None
    t = truth["t"]
    xy = _uav_xy_on(ut, trackers, t)
    target = np.c_[truth["x"], truth["y"]]
    radii = np.array([world.uavs[i].autonomy.guidance.standoff_m for i in trackers])
    err = standoff_errors(xy, target, radii)
    two = len(trackers) >= 2
    fig, axes = plt.subplots(2 if two else 1, 1, figsize=(9, 5.5 if two else 3), dpi=110, sharex=True, squeeze=False)
    ax = axes[0, 0]
    for k, i in enumerate(trackers):
        ax.plot(t, err[:, k], color=_COLORS[i % len(_COLORS)], lw=1.1,
                label=f"UAV {i} (r_d = {radii[k]:g} m, mean {err[:, k].mean():.1f} m)")
    ax.set_ylabel("standoff error (m)")
    ax.set_title("standoff distance error |‖p − p_T‖ − r_d| (truth)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    if two:
        ph = np.degrees(phase_errors(xy, target))
        ax = axes[1, 0]
        ax.plot(t, ph, color="k", lw=1.1, label=f"mean {ph.mean():.1f}°")
        ax.set_ylabel("phase error (deg)")
        ax.set_title(f"phase-keeping error (commanded separation {360 / len(trackers):.0f}°)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axes[-1, 0].set_xlabel("time (s)")
    return _save(plt, fig, plots / "standoff.png")


def _links_plot(plt: object, rec: RunRecord, world: object | None, plots: Path) -> Path | None:
    if world is None or world.comms.model == "perfect" or len(world.uavs) < 2 or "uav_truth" not in rec.streams:
        return None
    from simulator.render.stage import load_geometry
    from simulator.render.world_marks import RadioLinks

    geo = plots.parent / "geometry.npz"
    links = RadioLinks(world, load_geometry(geo).buildings if geo.exists() else [])
    ut = rec.streams["uav_truth"]
    uavs = list(range(len(world.uavs)))
    if not all(np.any(ut["uav"] == u) for u in uavs):
        return None
    t = np.unique(ut["t"])
    z = np.stack([np.interp(t, _by(ut, "uav", u)["t"], _by(ut, "uav", u)["z"]) for u in uavs], axis=1)
    pos = np.concatenate([_uav_xy_on(ut, uavs, t), z[..., None]], axis=2)
    pr = links.series(t, pos)
    names = [u.id for u in world.uavs]
    pairs = [(i, j) for i in uavs for j in uavs if i < j]
    fig, ax = plt.subplots(figsize=(9, 3.2), dpi=110)
    for k, (i, j) in enumerate(pairs):
        ax.plot(t, pr[:, k], lw=1.1, label=f"{names[i]}–{names[j]} (mean {pr[:, k].mean():.2f})")
    _probability_axis(ax, "delivery probability",
                      "radio links: delivery probability of the channel model at the flown geometry")
    return _save(plt, fig, plots / "links.png")


def _probability_axis(ax: object, ylabel: str, title: str) -> None:
    """A probability over time: [0, 1] with a margin, labels, grid, legend."""
    ax.set_ylim(-0.03, 1.03)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)


def _save(plt: object, fig: object, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def _relay_plot(plt: object, rec: RunRecord, world: object | None, plots: Path, every_s: float = 10.0) -> Path | None:
    if world is None or world.comms.base_station is None or "routing" not in rec.streams \
            or "uav_truth" not in rec.streams:
        return None
    ro, ut = rec.streams["routing"], rec.streams["uav_truth"]
    base = np.asarray(world.comms.base_station[:2], dtype=float)
    uavs = sorted(int(u) for u in np.unique(ut["uav"]))
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(13, 5.5), dpi=110, gridspec_kw={"width_ratios": [1, 1.2]})
    if "vehicle_truth" in rec.streams:
        vt = rec.streams["vehicle_truth"]
        ax.plot(vt["x"], vt["y"], "k-", lw=1.5, label="target")
    for u in uavs:
        d = _by(ut, "uav", u)
        ax.plot(d["x"], d["y"], color=_COLORS[u % len(_COLORS)], lw=1.0, label=world.uavs[u].id)
    ax.plot(*base, "ks", ms=9, label="base station")
    times = np.unique(ro["t"])
    for tk in times[np.isclose(np.mod(times, every_s), 0.0) | (times == times[0])]:
        at = ro["t"] == tk
        xy = _uav_xy_on(ut, uavs, np.array([tk]))[0]
        for u, par in zip(ro["uav"][at], ro["parent"][at], strict=True):
            if par == -2:
                continue
            end = base if par == -1 else xy[uavs.index(int(par))]
            ax.annotate("", xy=end, xytext=xy[uavs.index(int(u))],
                        arrowprops={"arrowstyle": "->", "color": _COLORS[int(u) % len(_COLORS)], "lw": 0.8,
                                    "alpha": 0.7})
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title(f"routes to the base station ({world.comms.routing}), every {every_s:g} s")
    for u in sorted(int(k) for k in np.unique(ro["uav"])):
        d = _by(ro, "uav", u)
        c = _COLORS[u % len(_COLORS)]
        lost = d["sent"].astype(bool) & ~d["delivered"].astype(bool)
        bx.plot(d["t"], d["beta"], color=c, lw=1.1, label=f"{world.uavs[u].id} β (mean {d['beta'].mean():.2f})")
        bx.plot(d["t"][lost], d["beta"][lost], "x", color=c, ms=5)
    _probability_axis(bx, "route probability β", "route probability to the base (×: packet lost)")
    return _save(plt, fig, plots / "relay.png")


def _draw_tracks(ax: object, rec: RunRecord) -> None:
    if "vehicle_truth" in rec.streams:
        vt = rec.streams["vehicle_truth"]
        for v in np.unique(vt["vehicle"]):
            d = _by(vt, "vehicle", int(v))
            ax.plot(d["x"], d["y"], color="k", lw=1.5, zorder=4, label="vehicle truth" if v == 0 else None)
            ax.plot(d["x"][-1:], d["y"][-1:], "ks", ms=5, zorder=5)
    if "uav_truth" in rec.streams:
        ut = rec.streams["uav_truth"]
        for u in np.unique(ut["uav"]):
            d = _by(ut, "uav", int(u))
            c = _COLORS[int(u) % len(_COLORS)]
            ax.plot(d["x"], d["y"], color=c, lw=1.0, zorder=3, label=f"UAV {int(u)}")
            ax.plot(d["x"][-1:], d["y"][-1:], "^", color=c, ms=7, zorder=5)
    if "estimates" in rec.streams:
        est = rec.streams["estimates"]
        for u in np.unique(est["uav"]):
            e = _by(est, "uav", int(u))
            ok = e["valid"].astype(bool)
            ax.plot(e["x"][ok], e["y"][ok], ".", color=_COLORS[int(u) % len(_COLORS)], ms=2, zorder=4,
                    label=f"UAV {int(u)} estimate")


def _zoom_to_tracks(ax: object, rec: RunRecord) -> None:
    xs, ys = [], []
    for name in ("uav_truth", "vehicle_truth"):
        if name in rec.streams:
            xs.append(rec.streams[name]["x"])
            ys.append(rec.streams[name]["y"])
    if not xs:
        return
    x, y = np.concatenate(xs), np.concatenate(ys)
    pad = max(50.0, 0.1 * max(np.ptp(x), np.ptp(y)))
    ax.set_xlim(x.min() - pad, x.max() + pad)
    ax.set_ylim(y.min() - pad, y.max() + pad)
