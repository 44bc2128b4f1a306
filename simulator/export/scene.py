"""A recorded run as the things an outside viewer draws, format-neutral: bodies, static geometry, detections, tracks
with covariance ellipses, radio links and scalar series, all on the run's simulation clock (``t``, s).

Everything is read with the readers a replay uses: :func:`simulator.runrecord.load_run` for the streams,
:func:`simulator.render.stage.load_geometry` for ``geometry.npz`` (buildings and road centre-lines),
:func:`simulator.render.world_view.read_world` for names, roles and body sizes, and the run's own channel model on
its recorded buildings for the links' delivery probabilities (:mod:`simulator.export.links`, the numbers
:class:`simulator.render.world_marks.RadioLinks` draws in a replay). A building whose footprint is not a rectangle
becomes its minimum rotated bounding box, so every building is one box. Times and values are the record's own:
nothing is resampled.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from simulator.plots_tracks import target_track_series
from simulator.render.timeline import hidden_when_free
from simulator.runrecord import RunRecord, load_run

__all__ = ["BoxShape", "Body", "DetectionScan", "Ellipse", "LinkSample", "RunScene", "Series", "TrackStep",
           "covariance_ellipse", "read_scene"]

ELLIPSE_SIGMA = 2.0  # covariance ellipses are drawn at 2 sigma
_ELLIPSE_POINTS = 32
_BEARING_RAY_M = 300.0  # length of a bearing ray that does not reach the ground
_SERIES_KEYS = {"uav": "uav", "vehicle": "vehicle"}  # entity columns of the streams, by which series split
_NOT_SERIES = {"tick", "t", "t_meas", "t_arrival", "uav", "vehicle", "track"}


@dataclass(frozen=True)
class Body:
    """A moving body: name, kind (``uav`` or ``vehicle``), role (a vehicle's ``target``/``decoy``/``traffic``, else
    ""), times (N,) s, positions (N, 3) m, attitudes (N, 4) (x, y, z, w) and box size (3,) m (UAV: its span)."""

    name: str
    kind: str
    role: str
    t: np.ndarray
    p_W: np.ndarray
    q_WB: np.ndarray
    size: np.ndarray


@dataclass(frozen=True)
class BoxShape:
    """A static box (a building): centre (3,) m, size (3,) m, yaw rad."""

    name: str
    center: np.ndarray
    size: np.ndarray
    yaw: float


@dataclass(frozen=True)
class DetectionScan:
    """One sensor's detections at one measurement time: world points (K, 3) m (radar, box), or rays (K, 2, 3) m from
    the UAV (bearing, camera), and whether each is a false alarm."""

    t: float
    sensor: str
    kind: str
    uav: int
    points_W: np.ndarray
    rays_W: np.ndarray
    clutter: np.ndarray


@dataclass(frozen=True)
class Ellipse:
    """A position estimate on the ground: label, centre (2,) m, its 2-sigma ellipse (K, 2) m, and flags."""

    label: str
    xy: np.ndarray
    outline: np.ndarray
    is_target: bool = False


@dataclass(frozen=True)
class TrackStep:
    """What one UAV held at one agent step: its tracks (``tracks`` stream) or its single estimate (``estimates`` /
    ``fused_estimates``)."""

    t: float
    uav: int
    ellipses: list[Ellipse]


@dataclass(frozen=True)
class LinkSample:
    """The radio links at one record time: per UAV pair (names), the two ends (3,) m and the delivery probability."""

    t: float
    links: list[tuple[str, str, np.ndarray, np.ndarray, float]]


@dataclass(frozen=True)
class Series:
    """A scalar time series: path parts (``("uav1", "uav_truth", "z")``), times (N,) s, values (N,)."""

    path: tuple[str, ...]
    t: np.ndarray
    v: np.ndarray


@dataclass
class RunScene:
    """A run directory, read for export (module docstring)."""

    title: str
    bodies: list[Body]
    buildings: list[BoxShape]
    roads: list[tuple[str, np.ndarray]]
    detections: list[DetectionScan]
    tracks: dict[str, list[TrackStep]]
    links: list[LinkSample]
    series: list[Series] = field(default_factory=list)

    @property
    def t_start(self) -> float:
        ts = [b.t[0] for b in self.bodies if len(b.t)]
        return float(min(ts)) if ts else 0.0


def covariance_ellipse(xy: np.ndarray, P: np.ndarray, sigma: float = ELLIPSE_SIGMA,
                       n: int = _ELLIPSE_POINTS) -> np.ndarray:
    """The ``sigma``-sigma ellipse (n, 2) m of a position ``xy`` (2,) m with covariance ``P`` (2, 2) m²; a point when
    ``P`` is not finite."""
    P = np.asarray(P, dtype=float)
    if not np.all(np.isfinite(P)):
        return np.repeat(np.asarray(xy, dtype=float)[None], n, axis=0)
    w, V = np.linalg.eigh(0.5 * (P + P.T))
    a = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    circle = np.c_[np.cos(a), np.sin(a)] * (sigma * np.sqrt(np.maximum(w, 0.0)))
    return np.asarray(xy, dtype=float) + circle @ V.T


def read_scene(run_dir: Path) -> RunScene:
    """Read the run directory ``run_dir`` for export (raises FileNotFoundError when it is not one)."""
    from simulator.render.stage import load_geometry
    from simulator.render.world_view import ReplayWorld, read_world

    run_dir = Path(run_dir)
    if not (run_dir / "run.json").exists() and not (run_dir / "timeseries").is_dir():
        raise FileNotFoundError(f"{run_dir} is not a run directory (no run.json or timeseries/)")
    rec = load_run(run_dir)
    world = ReplayWorld(read_world(run_dir))
    geometry = load_geometry(run_dir / "geometry.npz")
    name, seed = rec.run.get("world"), rec.run.get("seed")
    bodies = _bodies(rec, world)
    uav_names = {int(u): world.uav_name(int(u)) for u in np.unique(rec.streams.get("uav_truth", {}).get("uav", []))}
    scene = RunScene(
        title=f"{name} (seed {seed})" if name is not None else run_dir.name, bodies=bodies,
        buildings=[_box(f"building{k}", b) for k, b in enumerate(geometry.buildings)],
        roads=[(rid or f"road{k}", np.asarray(line, dtype=float)) for k, (rid, line) in
               enumerate(zip(geometry.road_ids, geometry.roads, strict=True))],
        detections=_detections(rec, {b.name: b for b in bodies}, uav_names),
        tracks=_tracks(rec, uav_names), links=_links(world, geometry, bodies))
    scene.series = _series(rec, world, uav_names) + _link_series(scene.links)
    return scene


def _bodies(rec: RunRecord, world: object) -> list[Body]:
    out = []
    ut = rec.streams.get("uav_truth") or {}
    span = 2.0 * world.uav_arm_length() if len(ut.get("t", ())) else 0.0
    for u, d in _group(ut, "uav").items():
        out.append(Body(world.uav_name(u), "uav", "", d["t"], np.c_[d["x"], d["y"], d["z"]],
                        np.c_[d["qx"], d["qy"], d["qz"], d["qw"]], np.array([span, span, 0.1 * span])))
    gv = world.world.ground_vehicles
    for v, d in _group(rec.streams.get("vehicle_truth") or {}, "vehicle").items():
        yaw = np.unwrap(d["yaw"])
        q = np.c_[np.zeros((len(yaw), 2)), np.sin(yaw / 2), np.cos(yaw / 2)]
        size = np.asarray(world.vehicle_size(v), dtype=float)
        p = hidden_when_free(d)  # a traffic source's free slots below the ground
        out.append(Body(gv[v].id if v < len(gv) else f"vehicle{v}", "vehicle", world.vehicle_role(v) or "",
                        d["t"], p, q, size))
    return out


def _group(stream: dict[str, np.ndarray], key: str) -> dict[int, dict[str, np.ndarray]]:
    if not len(stream.get(key, ())):
        return {}
    out = {}
    for value in np.unique(stream[key]):
        m = stream[key] == value
        order = np.argsort(stream["t"][m] if "t" in stream else stream["tick"][m], kind="stable")
        out[int(value)] = {k: v[m][order] for k, v in stream.items()}
    return out


def _box(name: str, b: object) -> BoxShape:
    if b.is_cuboid:
        c, size, yaw = b.cuboid_params
        return BoxShape(name, c, size, float(yaw))
    import shapely

    rect = np.asarray(shapely.Polygon(b.footprint).minimum_rotated_rectangle.exterior.coords)[:4]
    e0, e1 = rect[1] - rect[0], rect[2] - rect[1]
    centre = np.r_[rect.mean(axis=0), b.base_z + b.height / 2]
    return BoxShape(name, centre, np.array([np.linalg.norm(e0), np.linalg.norm(e1), b.height]),
                    float(np.arctan2(e0[1], e0[0])))


def _detections(rec: RunRecord, bodies: dict[str, Body], uav_names: dict[int, str]) -> list[DetectionScan]:
    d = rec.streams.get("detections") or {}
    if not len(d.get("t_meas", ())):
        return []
    scans = []
    keys = np.rec.fromarrays([d["sensor"], d["t_meas"]], names="sensor,t")
    for sensor, t in sorted({(str(s), float(t)) for s, t in zip(keys.sensor, keys.t, strict=True)},
                            key=lambda k: (k[1], k[0])):
        m = (d["sensor"] == sensor) & (d["t_meas"] == t)
        u, kind = int(d["uav"][m][0]), str(d["kind"][m][0])
        body = bodies.get(uav_names.get(u, ""))
        p_s = np.array([np.interp(t, body.t, body.p_W[:, k]) for k in range(3)]) if body else np.zeros(3)
        z0, z1, z2 = d["z0"][m], d["z1"][m], d["z2"][m]
        points, rays = np.zeros((0, 3)), np.zeros((0, 2, 3))
        if kind == "radar":
            points = p_s + z0[:, None] * np.c_[np.cos(z2) * np.cos(z1), np.cos(z2) * np.sin(z1), np.sin(z2)]
        elif kind == "box":
            points = np.c_[z0, z1, np.zeros_like(z0)]
        else:  # bearing / camera: azimuth z0, elevation z1 (NaN without one), a ray to the ground or of fixed length
            el = np.nan_to_num(z1, nan=0.0)
            u_W = np.c_[np.cos(el) * np.cos(z0), np.cos(el) * np.sin(z0), np.sin(el)]
            length = np.where(u_W[:, 2] < -1e-6, p_s[2] / np.maximum(-u_W[:, 2], 1e-6), _BEARING_RAY_M)
            length = np.minimum(length, 10.0 * _BEARING_RAY_M)
            rays = np.stack([np.broadcast_to(p_s, u_W.shape), p_s + length[:, None] * u_W], axis=1)
        scans.append(DetectionScan(t, sensor, kind, u, points, rays, d["truth_id"][m] < 0))
    return scans


def _tracks(rec: RunRecord, uav_names: dict[int, str]) -> dict[str, list[TrackStep]]:
    """Per layer (``tracks``, ``estimates``, ``fused_estimates``): every UAV's steps, in time order."""
    out: dict[str, list[TrackStep]] = {}
    tr = rec.streams.get("tracks") or {}
    if len(tr.get("t", ())):
        steps = []
        order = np.lexsort((tr["track"], tr["uav"], tr["tick"]))
        d = {k: v[order] for k, v in tr.items()}
        key = np.c_[d["tick"], d["uav"]]
        starts = np.flatnonzero(np.r_[True, np.any(key[1:] != key[:-1], axis=1)])
        for a, b in zip(starts, np.r_[starts[1:], len(key)], strict=True):
            ells = [Ellipse(f"track {int(d['track'][i])}", np.array([d["x"][i], d["y"][i]]),
                            covariance_ellipse([d["x"][i], d["y"][i]], [[d["pxx"][i], d["pxy"][i]],
                                                                        [d["pxy"][i], d["pyy"][i]]]),
                            bool(d["is_target"][i])) for i in range(a, b)]
            steps.append(TrackStep(float(d["t"][a]), int(d["uav"][a]), ells))
        out["tracks"] = steps
    for layer in ("estimates", "fused_estimates"):
        es = rec.streams.get(layer) or {}
        if not len(es.get("t", ())):
            continue
        steps = []
        for i in np.argsort(es["t"], kind="stable"):
            u = int(es["uav"][i])
            ells = []
            if bool(es["valid"][i]):
                xy = np.array([es["x"][i], es["y"][i]])
                P = [[es["pxx"][i], es["pxy"][i]], [es["pxy"][i], es["pyy"][i]]]
                ells = [Ellipse(uav_names.get(u, f"uav{u}"), xy, covariance_ellipse(xy, P), True)]
            steps.append(TrackStep(float(es["t"][i]), u, ells))
        out[layer] = steps
    return out


def _links(world: object, geometry: object, bodies: list[Body]) -> list[LinkSample]:
    from simulator.export.links import link_samples

    uavs = [b for b in bodies if b.kind == "uav"]
    if len(uavs) < 2 or len({len(b.t) for b in uavs}) != 1:
        return []
    try:
        samples = link_samples(world.world, geometry.buildings, [b.name for b in uavs], uavs[0].t,
                               np.stack([b.p_W for b in uavs], axis=1))
    except Exception:  # noqa: BLE001 - links are an addition: an export must not fail for them (as in a replay)
        return []
    return [LinkSample(t, links) for t, links in samples]


def _series(rec: RunRecord, world: object, uav_names: dict[int, str]) -> list[Series]:
    """Every numeric column of every stream, split by its UAV or vehicle; the target track's ``p_target`` per UAV."""
    gv = world.world.ground_vehicles
    out = []
    for name, cols in sorted(rec.streams.items()):
        if name in ("detections", "tracks") or not len(cols.get("t", ())):
            continue
        key = next((k for k in _SERIES_KEYS if k in cols), None)
        groups = _group(cols, key) if key else {-1: {k: v[np.argsort(cols["t"], kind="stable")]
                                                     for k, v in cols.items()}}
        for ent, d in groups.items():
            who = (uav_names.get(ent, f"uav{ent}") if key == "uav" else
                   (gv[ent].id if ent < len(gv) else f"vehicle{ent}") if key == "vehicle" else "run")
            for col, v in d.items():
                if col in _NOT_SERIES or v.dtype.kind not in "biuf" or not np.isfinite(v.astype(float)).any():
                    continue  # ids, text, and columns never set for this entity (a unicycle UAV's vx)
                out.append(Series((who, name, col), d["t"].astype(float), v.astype(float)))
    tr = rec.streams.get("tracks") or {}
    for u in (np.unique(tr["uav"]).astype(int).tolist() if len(tr.get("t", ())) else []):
        s = target_track_series(tr, u)
        out.append(Series((uav_names.get(u, f"uav{u}"), "target_track", "p_target"), s.t.astype(float), s.p_target))
        out.append(Series((uav_names.get(u, f"uav{u}"), "target_track", "track"), s.t.astype(float),
                          s.track.astype(float)))
    return out


def _link_series(links: list[LinkSample]) -> list[Series]:
    if not links:
        return []
    t = np.array([s.t for s in links])
    return [Series(("links", f"{a}-{b}", "delivery_probability"), t, np.array([s.links[k][4] for s in links]))
            for k, (a, b, *_rest) in enumerate(links[0].links)]
