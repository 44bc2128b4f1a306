"""The plot of a set-membership search run (paper 004): ``plots/search.png``.

Left: each UAV's normalised areas ``φ(X)/φ(X_s)`` and ``φ(X̄)/φ(X_s)`` over time and the team's mean (the paper's
Fig. 6), with the steps at which a true target lay outside some UAV's ``X ∪ X̄`` marked (there should be none).
Right: the last snapshot of UAV 0's sets (``search_sets.jsonl.gz``) on the map with the buildings, the UAVs' tracks, the
cars' paths and the decoys.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from simulator.runrecord import RunRecord, load_search_sets

__all__ = ["search_plot"]

_X_RGBA = (0.85, 0.1, 0.1, 0.55)
_XBAR_RGBA = (0.2, 0.45, 0.9, 0.25)


def _draw_set(ax: Any, wkt: str, rgba: tuple[float, ...], label: str) -> None:
    import shapely
    from matplotlib.patches import PathPatch
    from matplotlib.path import Path as MplPath

    geom = shapely.from_wkt(wkt)
    first = True
    for poly in shapely.get_parts(geom):
        if poly.geom_type != "Polygon" or poly.is_empty:
            continue
        rings = [np.asarray(poly.exterior.coords)] + [np.asarray(r.coords) for r in poly.interiors]
        verts = np.concatenate(rings)
        codes = np.concatenate([[MplPath.MOVETO] + [MplPath.LINETO] * (len(r) - 2) + [MplPath.CLOSEPOLY]
                                for r in rings])
        ax.add_patch(PathPatch(MplPath(verts, codes), facecolor=rgba, edgecolor="none", zorder=2,
                               label=label if first else None))
        first = False


def search_plot(plt: Any, rec: RunRecord, world: Any, plots: Path) -> Path | None:
    """Draw ``plots/search.png`` when the run has a ``search`` stream (module docstring)."""
    if "search" not in rec.streams:
        return None
    from matplotlib.collections import PolyCollection

    s = rec.streams["search"]
    fig, (ax, mp) = plt.subplots(1, 2, figsize=(14, 6), dpi=100)
    uavs = np.unique(s["uav"])
    for u in uavs:
        m = s["uav"] == u
        ax.plot(s["t"][m], s["area_Xbar"][m], color="tab:blue", lw=0.6, alpha=0.5)
        ax.plot(s["t"][m], s["area_X"][m], color="tab:red", lw=0.6, alpha=0.5)
    t = np.unique(s["t"])
    for col, color, name in (("area_Xbar", "tab:blue", "φ(X̄)/φ(X_s)"), ("area_X", "tab:red", "φ(X)/φ(X_s)")):
        mean = np.array([s[col][s["t"] == tk].mean() for tk in t])
        ax.plot(t, mean, color=color, lw=2.0, label=f"{name}, team mean (thin: each UAV)")
    bad = s["targets_inside"] < s["targets"]
    if bad.any():
        ax.plot(s["t"][bad], np.zeros(bad.sum()), "kx", ms=8, label="a target outside X ∪ X̄")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("normalised area")
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title("set areas")

    geo = plots.parent / "geometry.npz"
    if geo.exists():
        with np.load(geo) as g:
            xy, off = g["building_xy"], g["building_offsets"]
        blds = [xy[off[i]:off[i + 1]] for i in range(len(off) - 1)]
        if blds:
            mp.add_collection(PolyCollection(blds, facecolor="0.6", edgecolor="0.3", lw=0.5, zorder=3))
    snaps = load_search_sets(plots.parent)
    title = "map"
    if snaps and snaps[-1].sets:
        snap = snaps[-1]
        first = min(snap.sets)
        X, Xbar = snap.sets[first]
        _draw_set(mp, Xbar, _XBAR_RGBA, "X̄ (undetected targets)")
        _draw_set(mp, X, _X_RGBA, "X (detected targets)")
        title = f"sets of UAV {first} at t = {snap.t:.0f} s"
    if "uav_truth" in rec.streams:
        ut = rec.streams["uav_truth"]
        for u in np.unique(ut["uav"]):
            m = ut["uav"] == u
            mp.plot(ut["x"][m], ut["y"][m], lw=0.5, alpha=0.7, zorder=4)
    if "vehicle_truth" in rec.streams:
        vt = rec.streams["vehicle_truth"]
        for v in np.unique(vt["vehicle"]):
            m = vt["vehicle"] == v
            mp.plot(vt["x"][m], vt["y"][m], "k-", lw=1.5, zorder=5)
            mp.plot(vt["x"][m][-1:], vt["y"][m][-1:], "ks", ms=6, zorder=6, label="car" if v == 0 else None)
    if world is not None and world.decoys:
        d = np.array([dc.position for dc in world.decoys])
        mp.plot(d[:, 0], d[:, 1], "D", color="tab:orange", ms=7, zorder=6, label="decoy")
    mp.set_aspect("equal")
    mp.autoscale_view()
    mp.set_xlabel("x east (m)")
    mp.set_ylabel("y north (m)")
    mp.set_title(title)
    mp.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    path = plots / "search.png"
    fig.savefig(path)
    plt.close(fig)
    return path
