"""Import an OpenStreetMap extract (``.osm.pbf`` or ``.osm`` XML) as a :class:`~worlds.town.Town`.

Reading uses pyosmium (``osmium``). What becomes what:

* **Roads.** Ways tagged ``highway`` = one of :data:`DRIVABLE` (motorway ... residential, service and the
  ``*_link`` roads), minus ``area=yes``, ``access=no``, time-dependent (``oneway=reversible|alternating``) ways and
  tunnels or covered ways (``tunnel=*``, ``covered=yes``: the world has no underground and cars must not drive through
  buildings). Each way is cut at every node it shares with another drivable way (and at missing nodes), giving
  streets between junctions; a closed piece is cut again at its middle vertex. ``oneway=yes|true|1`` (implied by
  ``junction=roundabout|circular`` and by ``highway=motorway|motorway_link``) gives one road along the way,
  ``oneway=-1`` one road against it, anything else a pair of twin roads. Lanes per direction come from
  ``lanes:forward`` / ``lanes:backward``, else ``lanes`` (split in half on two-way streets), else a per-class default;
  the lane width from ``width`` / total lanes (clipped to [2.5, 5] m), else a per-class default; the speed limit from
  ``maxspeed`` (km/h, ``mph``, ``FI:urban``-style zone codes, ``walk``), else a per-class default
  (:data:`CLASS_DEFAULTS`). Vertices closer than 0.5 m to the previous one are dropped. A road whose rightmost lane
  runs more than :data:`MAX_INSIDE_BUILDING` through building footprints is dropped (untagged driveways into garages
  and yards under buildings: in the simulated world cars would drive into walls). **Only the largest strongly
  connected component of the directed network is kept**, so every road can be reached from every other.
* **Traffic signals.** Nodes tagged ``highway=traffic_signals`` or ``crossing=traffic_signals`` (a signalised
  crossing, which in many cities is how the legs of a signalised junction are mapped), inside ``bbox`` if given, as
  the town's ``signals`` (positions); :func:`worlds.roads.signals.signalised_junctions` says which junctions they
  control.
* **Buildings.** Areas (closed ways and multipolygon relations) tagged ``building`` (not ``no``): each outer ring
  becomes a :class:`~worlds.geometry.Building` (inner rings, i.e. courtyards, are ignored). Height from ``height``
  (m, or ``ft``/``'``), else ``building:levels`` x :data:`LEVEL_HEIGHT`, else ``default_height``.

Projection
----------
Longitude / latitude (WGS84) are mapped to a local ENU frame whose origin is the centre of the ``bbox`` if given,
else of the file header's bounding box, else of the data: geodetic -> ECEF -> rotation into the origin's
east-north-up axes, keeping (east, north). This is the orthographic projection onto the tangent plane at the origin;
within a few kilometres it preserves distances and angles to better than 1 part in 10^5 (a point at distance d is
pulled in by about d^3 / 2R^2, and lies d^2 / 2R below the plane).

Errors
------
:class:`OsmFileNotFoundError` (a ``FileNotFoundError``) when the path does not exist; :class:`OsmFormatError` (a
``ValueError``) when the file cannot be read as OSM data; :class:`OsmEmptyError` (an ``OsmFormatError``) when it holds
no usable drivable roads. Every message names the file.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import shapely
from shapely.geometry import LineString

from worlds.geometry import Building
from worlds.roads.network import RoadNetwork
from worlds.roads.road import Road
from worlds.town import Town

__all__ = ["load_osm", "LocalTangentPlane", "OsmError", "OsmFileNotFoundError", "OsmFormatError", "OsmEmptyError",
           "DRIVABLE", "CLASS_DEFAULTS", "LEVEL_HEIGHT"]

LEVEL_HEIGHT = 3.0  # m per building storey
MIN_VERTEX_SPACING = 0.5  # m; closer consecutive road vertices are dropped
MAX_INSIDE_BUILDING = 1.0  # m; roads whose rightmost lane runs further through building footprints are dropped
_WGS84_A = 6378137.0  # m, semi-major axis
_WGS84_F = 1.0 / 298.257223563
_SUFFIXES = (".osm.pbf", ".pbf", ".osm", ".osm.bz2", ".osm.gz", ".o5m")


@dataclass(frozen=True, kw_only=True)
class ClassDefaults:
    """Defaults of one road class when tags are missing.

    Attributes
    ----------
    lanes : int
        Lanes per direction.
    lane_width : float
        m.
    speed_kmh : float
        km/h.
    """

    lanes: int
    lane_width: float
    speed_kmh: float


CLASS_DEFAULTS: dict[str, ClassDefaults] = {
    "motorway": ClassDefaults(lanes=2, lane_width=3.75, speed_kmh=100.0),
    "trunk": ClassDefaults(lanes=2, lane_width=3.5, speed_kmh=80.0),
    "primary": ClassDefaults(lanes=1, lane_width=3.5, speed_kmh=50.0),
    "secondary": ClassDefaults(lanes=1, lane_width=3.5, speed_kmh=50.0),
    "tertiary": ClassDefaults(lanes=1, lane_width=3.25, speed_kmh=40.0),
    "unclassified": ClassDefaults(lanes=1, lane_width=3.0, speed_kmh=40.0),
    "residential": ClassDefaults(lanes=1, lane_width=3.0, speed_kmh=30.0),
    "service": ClassDefaults(lanes=1, lane_width=3.0, speed_kmh=20.0),
}
CLASS_DEFAULTS.update({f"{k}_link": CLASS_DEFAULTS[k]
                       for k in ("motorway", "trunk", "primary", "secondary", "tertiary")})
DRIVABLE: frozenset[str] = frozenset(CLASS_DEFAULTS)
_ZONE_KMH = {"urban": 50.0, "rural": 80.0, "motorway": 120.0, "trunk": 100.0, "living_street": 20.0, "walk": 7.0}


class OsmError(Exception):
    """Base of the errors raised for unusable OpenStreetMap extracts."""


class OsmFileNotFoundError(OsmError, FileNotFoundError):
    """The extract does not exist."""


class OsmFormatError(OsmError, ValueError):
    """The extract cannot be read as OpenStreetMap data."""


class OsmEmptyError(OsmFormatError):
    """The extract holds no usable drivable roads."""


class LocalTangentPlane:
    """WGS84 longitude / latitude (deg) -> local (east, north) in m on the tangent plane at ``origin_lonlat``."""

    def __init__(self, origin_lonlat: tuple[float, float]) -> None:
        lon0, lat0 = (math.radians(v) for v in origin_lonlat)
        self.origin_lonlat = (float(origin_lonlat[0]), float(origin_lonlat[1]))
        self._ecef0 = _ecef(np.array([lon0]), np.array([lat0]))[0]
        sl, cl, sp, cp = math.sin(lon0), math.cos(lon0), math.sin(lat0), math.cos(lat0)
        self._R = np.array([[-sl, cl, 0.0], [-sp * cl, -sp * sl, cp]])  # rows: east, north in ECEF

    def __call__(self, lon: np.ndarray, lat: np.ndarray) -> np.ndarray:
        """(N, 2) east-north coordinates (m) of points given in degrees."""
        xyz = _ecef(np.radians(np.asarray(lon, dtype=float)), np.radians(np.asarray(lat, dtype=float)))
        return (xyz - self._ecef0) @ self._R.T


def _ecef(lon: np.ndarray, lat: np.ndarray) -> np.ndarray:
    e2 = _WGS84_F * (2.0 - _WGS84_F)
    n = _WGS84_A / np.sqrt(1.0 - e2 * np.sin(lat) ** 2)
    return np.stack([n * np.cos(lat) * np.cos(lon), n * np.cos(lat) * np.sin(lon), n * (1.0 - e2) * np.sin(lat)],
                    axis=-1)


@dataclass
class _RawWay:
    id: int
    tags: dict[str, str]
    refs: list[int]
    lonlat: np.ndarray  # (N, 2), NaN where the node is missing


@dataclass
class _RawBuilding:
    id: str
    tags: dict[str, str]
    rings: list[np.ndarray]  # outer rings (N, 2) lon/lat, not closed


def load_osm(path: str | Path, *, bbox: tuple[float, float, float, float] | None = None,
             default_height: float = 9.0) -> Town:
    """Load an OpenStreetMap extract as a :class:`Town` in a local ENU frame (see the module docstring).

    Parameters
    ----------
    path : str or Path
        ``.osm.pbf``, ``.osm`` (XML) or compressed ``.osm.bz2`` / ``.osm.gz`` file.
    bbox : (lon_min, lat_min, lon_max, lat_max), optional
        Degrees. Keep only road vertices inside (ways are cut where they leave) and buildings wholly inside.
    default_height : float
        Height of buildings without ``height`` or ``building:levels`` tags (m), > 0.

    Returns
    -------
    Town
        Its network is the largest strongly connected drivable component; ``origin_lonlat`` is the ENU origin.

    Raises
    ------
    OsmFileNotFoundError
        ``path`` does not exist (a ``FileNotFoundError``).
    OsmFormatError
        ``path`` is a directory, has an unknown suffix or cannot be parsed (a ``ValueError``).
    OsmEmptyError
        The file is empty or holds no usable drivable roads (inside ``bbox``) (an ``OsmFormatError``).
    """
    path = Path(path)
    if not default_height > 0:
        raise ValueError(f"load_osm: default_height must be > 0 m, got {default_height}")
    if bbox is not None:
        bbox = tuple(float(v) for v in bbox)
        if len(bbox) != 4 or not (bbox[0] < bbox[2] and bbox[1] < bbox[3]):
            raise ValueError(f"load_osm: bbox must be (lon_min, lat_min, lon_max, lat_max) with min < max, got {bbox}")
    ways, buildings, signals, header_box = _read(path)
    if bbox is not None:
        ways = [part for way in ways for part in _clip_way(way, bbox)]
        signals = signals[_inside(signals, bbox)]
    buildings = [b for b in buildings if bbox is None or all(_inside(r, bbox).all() for r in b.rings)]
    if not ways:
        raise OsmEmptyError(f"{path}: no drivable ways (highway={'|'.join(sorted(DRIVABLE))})"
                            + (f" inside bbox {bbox}" if bbox else ""))
    if bbox is not None:
        origin = ((bbox[0] + bbox[2]) / 2, (bbox[1] + bbox[3]) / 2)
    elif header_box is not None:
        origin = header_box
    else:
        allp = np.vstack([w.lonlat for w in ways])
        origin = tuple(float(v) for v in (np.nanmin(allp, axis=0) + np.nanmax(allp, axis=0)) / 2)
    proj = LocalTangentPlane(origin)
    blds = [b for raw in buildings for b in _buildings(raw, proj, default_height)]
    network = _largest_component(_clear_of_buildings(_build_network(ways, proj), blds))
    if not network.roads:
        raise OsmEmptyError(f"{path}: the drivable ways form no connected road network")
    return Town(network=network, buildings=blds, origin_lonlat=proj.origin_lonlat,
                signals=proj(signals[:, 0], signals[:, 1]).reshape(-1, 2))


def _read(path: Path) -> tuple[list[_RawWay], list[_RawBuilding], np.ndarray, tuple[float, float] | None]:
    """Drivable ways, building areas, traffic signals ((K, 2) lon/lat) and the header box centre (lon, lat) of
    ``path``."""
    if not path.exists():
        raise OsmFileNotFoundError(f"{path}: OpenStreetMap extract not found")
    if path.is_dir():
        raise OsmFormatError(f"{path}: is a directory, expected an .osm.pbf or .osm file")
    if not path.name.lower().endswith(_SUFFIXES):
        raise OsmFormatError(f"{path}: unsupported file type, expected one of {', '.join(_SUFFIXES)}")
    if path.stat().st_size == 0:
        raise OsmEmptyError(f"{path}: the file is empty")
    import osmium  # a heavy compiled dependency, needed only here

    ways: list[_RawWay] = []
    buildings: list[_RawBuilding] = []
    signals: list[tuple[float, float]] = []
    try:
        fp = (osmium.FileProcessor(str(path))
              .with_areas(osmium.filter.KeyFilter("building"))
              .with_filter(osmium.filter.KeyFilter("highway", "building", "crossing")))
        box = fp.header.box()
        header = None
        if box.valid():
            bl, tr = box.bottom_left, box.top_right
            header = ((bl.lon + tr.lon) / 2, (bl.lat + tr.lat) / 2)
        for obj in fp:
            if obj.is_node():
                if _is_signal(obj.tags) and obj.location.valid():
                    signals.append((obj.location.lon, obj.location.lat))
            elif obj.is_way() and obj.tags.get("highway") in DRIVABLE:
                tags = dict(obj.tags)
                if _excluded(tags):
                    continue
                ll = np.array([(n.lon, n.lat) if n.location.valid() else (np.nan, np.nan) for n in obj.nodes])
                ways.append(_RawWay(obj.id, tags, [n.ref for n in obj.nodes], ll.reshape(-1, 2)))
            elif obj.is_area() and obj.tags.get("building", "no") != "no":
                rings = [np.array([(n.lon, n.lat) for n in ring]) for ring in obj.outer_rings()]
                bid = f"{'w' if obj.from_way() else 'r'}{obj.orig_id()}"
                buildings.append(_RawBuilding(bid, dict(obj.tags), rings))
    except (RuntimeError, ValueError, OSError) as exc:
        raise OsmFormatError(f"{path}: cannot be read as OpenStreetMap data ({exc})") from exc
    return ways, buildings, np.array(signals, dtype=float).reshape(-1, 2), header


def _is_signal(tags) -> bool:
    """A node that is a traffic signal: ``highway=traffic_signals``, or a crossing with ``crossing=traffic_signals``."""
    return tags.get("highway") == "traffic_signals" or tags.get("crossing") == "traffic_signals"


def _excluded(tags: dict[str, str]) -> bool:
    """Drivable-class ways left out: areas, no access, time-dependent one-ways, tunnels and covered ways."""
    return (tags.get("area") == "yes" or tags.get("access") == "no" or tags.get("covered", "no") != "no"
            or tags.get("tunnel", "no") != "no" or tags.get("oneway") in ("reversible", "alternating"))


def _inside(lonlat: np.ndarray, bbox: tuple[float, float, float, float]) -> np.ndarray:
    lon, lat = lonlat[:, 0], lonlat[:, 1]
    return (lon >= bbox[0]) & (lon <= bbox[2]) & (lat >= bbox[1]) & (lat <= bbox[3])


def _clip_way(way: _RawWay, bbox: tuple[float, float, float, float]) -> list[_RawWay]:
    """The runs of ``way`` inside ``bbox`` (nodes outside become NaN, which cut the way later)."""
    ll = way.lonlat.copy()
    ll[~_inside(np.nan_to_num(ll, nan=np.inf), bbox)] = np.nan
    return [_RawWay(way.id, way.tags, way.refs, ll)] if np.isfinite(ll).all(axis=1).sum() >= 2 else []


def _build_network(ways: list[_RawWay], proj: LocalTangentPlane) -> RoadNetwork:
    """Cut ways at shared nodes and gaps, turn each piece into one or two roads."""
    uses: dict[int, int] = {}
    for w in ways:
        for ref in w.refs:
            uses[ref] = uses.get(ref, 0) + 1
    nodes: dict[str, np.ndarray] = {}
    roads: list[Road] = []
    for w in ways:
        xy = proj(w.lonlat[:, 0], w.lonlat[:, 1])
        ok = np.isfinite(xy).all(axis=1)
        for k, (i0, i1) in enumerate(_pieces(w.refs, ok, uses)):
            refs, pts = w.refs[i0:i1 + 1], xy[i0:i1 + 1]
            keep = _thin(pts)
            refs, pts = [refs[i] for i in keep], pts[keep]
            if len(pts) < 2:
                continue
            for ref, p in ((refs[0], pts[0]), (refs[-1], pts[-1])):
                nodes[str(ref)] = p
            roads += _roads_of_piece(f"w{w.id}_{k}", w.tags, str(refs[0]), str(refs[-1]), pts)
    return RoadNetwork(roads, nodes)


def _pieces(refs: list[int], ok: np.ndarray, uses: dict[int, int]) -> list[tuple[int, int]]:
    """Index ranges [i0, i1] of the way between consecutive junctions, skipping missing nodes; loops cut in two."""
    out: list[tuple[int, int]] = []
    start = None
    for i, ref in enumerate(refs):
        if not ok[i]:
            start = None
            continue
        if start is None:
            start = i
            continue
        if uses[ref] > 1 or i == len(refs) - 1 or not ok[i + 1] or ref in refs[start:i]:
            if refs[start] == ref:  # a closed piece: cut at its middle vertex
                if i - start < 3:
                    start = i
                    continue
                mid = (start + i) // 2
                out += [(start, mid), (mid, i)]
            else:
                out.append((start, i))
            start = i
    return out


def _thin(pts: np.ndarray) -> list[int]:
    """Indices of the vertices kept: each >= MIN_VERTEX_SPACING from the previous kept one; both ends kept."""
    keep = [0]
    for i in range(1, len(pts) - 1):
        if np.hypot(*(pts[i] - pts[keep[-1]])) >= MIN_VERTEX_SPACING:
            keep.append(i)
    last = len(pts) - 1
    if len(keep) > 1 and np.hypot(*(pts[last] - pts[keep[-1]])) < MIN_VERTEX_SPACING:
        keep.pop()
    if np.hypot(*(pts[last] - pts[keep[-1]])) > 1e-6:
        keep.append(last)
    return keep


def _roads_of_piece(pid: str, tags: dict[str, str], a: str, b: str, pts: np.ndarray) -> list[Road]:
    hw = tags["highway"]
    cls = CLASS_DEFAULTS[hw]
    oneway = tags.get("oneway", "")
    if oneway in ("yes", "true", "1"):
        direction = 1
    elif oneway in ("-1", "reverse"):
        direction = -1
    elif oneway in ("no", "false", "0"):
        direction = 0
    else:
        implied = tags.get("junction") in ("roundabout", "circular") or hw in ("motorway", "motorway_link")
        direction = 1 if implied else 0
    total = _first_number(tags.get("lanes"))
    if direction == 0:
        fwd = _first_number(tags.get("lanes:forward")) or (max(1.0, total // 2) if total else cls.lanes)
        bwd = _first_number(tags.get("lanes:backward")) or (max(1.0, total - total // 2) if total else cls.lanes)
    else:
        fwd = bwd = total or cls.lanes
    fwd, bwd = max(1, int(fwd)), max(1, int(bwd))
    width = _length_m(tags.get("width"))
    n_total = fwd + bwd if direction == 0 else fwd
    lane_width = float(np.clip(width / n_total, 2.5, 5.0)) if width else cls.lane_width
    speed = _speed_ms(tags.get("maxspeed")) or cls.speed_kmh / 3.6
    common = dict(lane_width=lane_width, speed_limit=speed)
    if direction == 1:
        return [Road(id=f"{pid}.f", vertices=pts, start_node=a, end_node=b, lanes=fwd, **common)]
    if direction == -1:
        return [Road(id=f"{pid}.r", vertices=pts[::-1], start_node=b, end_node=a, lanes=fwd, **common)]
    road = Road(id=f"{pid}.f", vertices=pts, start_node=a, end_node=b, lanes=fwd, twin=f"{pid}.r", **common)
    return [road, road.reversed(id=f"{pid}.r", lanes=bwd)]


def _clear_of_buildings(net: RoadNetwork, buildings: list[Building]) -> RoadNetwork:
    """``net`` without the streets (both directions) where a rightmost lane runs more than MAX_INSIDE_BUILDING m
    through building footprints."""
    if not buildings:
        return net
    polys = shapely.make_valid(np.array([shapely.Polygon(b.footprint) for b in buildings]))
    tree = shapely.STRtree(polys)
    drop: set[str] = set()
    for road in net.roads.values():
        s = np.linspace(0.0, road.length, max(2, int(np.ceil(road.length / 2.0)) + 1))
        lane = LineString(road.point(s, road.lane_offset(0)))
        hits = tree.query(lane, predicate="intersects")
        if len(hits) and shapely.length(shapely.intersection(lane, polys[hits])).sum() > MAX_INSIDE_BUILDING:
            drop |= {road.id, road.twin} - {None}
    return RoadNetwork([r for r in net.roads.values() if r.id not in drop], net.nodes)


def _largest_component(net: RoadNetwork) -> RoadNetwork:
    """The sub-network on the largest strongly connected set of nodes (ties: the one met first)."""
    _, labels = net.strong_components()
    used = {r.start_node for r in net.roads.values()}
    counts: dict[int, int] = {}
    for nid in net.nodes:
        if nid in used:
            counts[labels[nid]] = counts.get(labels[nid], 0) + 1
    if not counts:
        return RoadNetwork([], {})
    best = max(counts, key=lambda c: counts[c])
    keep = {n for n, c in labels.items() if c == best}
    roads = [r for r in net.roads.values() if r.start_node in keep and r.end_node in keep]
    return RoadNetwork(roads, {n: net.nodes[n] for n in net.nodes if n in keep})


def _buildings(raw: _RawBuilding, proj: LocalTangentPlane, default_height: float) -> list[Building]:
    height = _length_m(raw.tags.get("height"))
    if not height:
        levels = _first_number(raw.tags.get("building:levels"))
        height = levels * LEVEL_HEIGHT if levels else default_height
    out = []
    for k, ring in enumerate(raw.rings):
        xy = proj(ring[:, 0], ring[:, 1])
        if len(xy) > 1 and np.allclose(xy[0], xy[-1]):
            xy = xy[:-1]
        xy = xy[np.r_[True, np.hypot(*np.diff(xy, axis=0).T) > 1e-3]]
        try:
            out.append(Building(footprint=xy, height=float(height), name=raw.id + (f"_{k}" if k else "")))
        except ValueError:
            continue  # degenerate ring (fewer than 3 distinct vertices or zero area)
    return out


def _first_number(text: str | None) -> float:
    """First decimal number in ``text`` (``"2;3"`` -> 2.0), 0.0 if none."""
    m = re.search(r"\d+(?:\.\d+)?", text or "")
    return float(m.group()) if m else 0.0


def _length_m(text: str | None) -> float:
    """A length tag in metres: ``"12"``, ``"12 m"``, ``"40 ft"``, ``"40'"``; 0.0 if unreadable."""
    value = _first_number((text or "").replace(",", "."))
    return value * 0.3048 if re.search(r"ft|'", text or "") else value


def _speed_ms(text: str | None) -> float:
    """A ``maxspeed`` tag in m/s (km/h by default, ``mph``, zone codes like ``FI:urban``); 0.0 if unreadable."""
    if not text:
        return 0.0
    t = text.strip().lower()
    if t in ("none", "signals", "variable"):
        return 0.0
    kmh = _first_number(t)
    if kmh and "mph" in t:
        kmh *= 1.609344
    if not kmh:
        kmh = next((v for k, v in _ZONE_KMH.items() if t.endswith(k)), 0.0)
    return kmh / 3.6
