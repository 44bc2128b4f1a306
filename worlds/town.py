"""Procedural towns: a two-way street grid with some curved arterials, blocks filled with set-back buildings.

Layout (world ENU, metres, centred on the origin)
-------------------------------------------------
Junctions sit on a regular grid of pitch ``block_size`` covering ``extent``. Every ``arterial_every``-th grid line
(rows and columns, counted from the first) is an arterial with ``arterial_lanes`` lanes per direction; the others are
local streets with ``lanes``. A fraction ``curved_fraction`` of the arterials (drawn with the generator) meander as the
sine wave :math:`\\delta(u) = A \\sin(\\pi u / B)` across their line, with :math:`B` the block size and
:math:`A` = ``curve_amplitude`` :math:`\\cdot B`: it crosses zero at every junction, so junctions stay on the grid and
the curve is smooth through them.

Each block (the polygon bounded by the four centre-lines around a grid cell) minus its streets' carriageways grown by
``setback`` is the lot. The lot's bounding box is cut into parcels of about ``footprint_range[1] + building_gap``; each
parcel receives one axis-aligned box with sides drawn uniformly from ``footprint_range`` (capped by the parcel) at a
uniform position keeping ``building_gap / 2`` from the parcel's edges, and a height uniform in ``height_range``; a box
is kept only if the lot contains it. So buildings never touch a carriageway (they keep ``setback``) nor each other
(they keep ``building_gap``). With ``max_buildings`` set, a uniformly drawn subset of that size is kept.

Everything random comes from the generator passed in: the same config and seed give the same town.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np
import shapely
from shapely.geometry import Polygon
from shapely.ops import unary_union

from worlds.geometry import Building
from worlds.roads.mesh import road_polygons
from worlds.roads.network import RoadNetwork, street_road_ids
from worlds.roads.road import Road

__all__ = ["TownConfig", "Town", "generate_town", "town_road_ids"]

_CURVE_VIA = 12  # intermediate vertices per block of a curved arterial


@dataclass(frozen=True, kw_only=True)
class TownConfig:
    """Parameters of a procedural town.

    Attributes
    ----------
    extent : tuple[float, float]
        Size (x, y) of the street grid (m), each >= ``block_size``; rounded down to whole blocks.
    block_size : float
        Distance between neighbouring parallel street centre-lines (m), > 0.
    lanes : int
        Lanes per direction on local streets (>= 1).
    arterial_lanes : int
        Lanes per direction on arterials (>= 1).
    arterial_every : int
        Every n-th grid line is an arterial (>= 1; 1 makes every street an arterial).
    lane_width : float
        Lane width (m), > 0.
    speed_limit : float
        Local-street speed limit (m/s), > 0.
    arterial_speed_limit : float
        Arterial speed limit (m/s), > 0.
    curved_fraction : float
        Fraction of arterials that meander, in [0, 1].
    curve_amplitude : float
        Meander amplitude as a fraction of ``block_size``, in [0, 0.25].
    setback : float
        Minimum distance from a carriageway edge to a building (m), >= 0.
    building_gap : float
        Minimum distance between buildings (m), >= 0.
    footprint_range : tuple[float, float]
        Range of building side lengths (m), 0 < min <= max.
    height_range : tuple[float, float]
        Range of building heights (m), 0 < min <= max.
    max_buildings : int | None
        Keep at most this many buildings (a uniform random subset), or all when None.
    """

    extent: tuple[float, float] = (600.0, 600.0)
    block_size: float = 100.0
    lanes: int = 1
    arterial_lanes: int = 2
    arterial_every: int = 3
    lane_width: float = 3.5
    speed_limit: float = 13.9
    arterial_speed_limit: float = 16.7
    curved_fraction: float = 0.5
    curve_amplitude: float = 0.12
    setback: float = 3.0
    building_gap: float = 4.0
    footprint_range: tuple[float, float] = (10.0, 25.0)
    height_range: tuple[float, float] = (6.0, 40.0)
    max_buildings: int | None = None

    def __post_init__(self) -> None:
        for name in ("extent", "footprint_range", "height_range"):
            val = tuple(float(v) for v in getattr(self, name))
            if len(val) != 2:
                raise ValueError(f"TownConfig.{name} must have 2 values, got {getattr(self, name)!r}")
            object.__setattr__(self, name, val)
        if not self.block_size > 0:
            raise ValueError(f"TownConfig.block_size must be > 0 m, got {self.block_size}")
        if min(self.extent) < self.block_size:
            raise ValueError(f"TownConfig.extent must be >= block_size ({self.block_size} m) in x and y, "
                             f"got {self.extent}")
        for name in ("lanes", "arterial_lanes", "arterial_every"):
            if not (isinstance(getattr(self, name), int) and getattr(self, name) >= 1):
                raise ValueError(f"TownConfig.{name} must be an integer >= 1, got {getattr(self, name)!r}")
        for name in ("lane_width", "speed_limit", "arterial_speed_limit"):
            if not getattr(self, name) > 0:
                raise ValueError(f"TownConfig.{name} must be > 0, got {getattr(self, name)}")
        if not 0.0 <= self.curved_fraction <= 1.0:
            raise ValueError(f"TownConfig.curved_fraction must be in [0, 1], got {self.curved_fraction}")
        if not 0.0 <= self.curve_amplitude <= 0.25:
            raise ValueError(f"TownConfig.curve_amplitude must be in [0, 0.25], got {self.curve_amplitude}")
        for name in ("setback", "building_gap"):
            if not getattr(self, name) >= 0:
                raise ValueError(f"TownConfig.{name} must be >= 0 m, got {getattr(self, name)}")
        for name in ("footprint_range", "height_range"):
            lo, hi = getattr(self, name)
            if not 0 < lo <= hi:
                raise ValueError(f"TownConfig.{name} must satisfy 0 < min <= max, got {getattr(self, name)}")
        if self.max_buildings is not None and not (isinstance(self.max_buildings, int) and self.max_buildings >= 0):
            raise ValueError(f"TownConfig.max_buildings must be None or an integer >= 0, got {self.max_buildings!r}")

    @classmethod
    def from_mapping(cls, data: dict) -> "TownConfig":
        """Build from plain data (a world file's ``town`` section); unknown keys raise ``ValueError`` naming them."""
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ValueError(f"TownConfig: unknown field(s) {unknown}; known: {sorted(known)}")
        return cls(**data)


@dataclass(frozen=True)
class Town:
    """A world's static layout: its road network and buildings.

    Attributes
    ----------
    network : RoadNetwork
        The drivable roads.
    buildings : list[Building]
        Building footprints and heights (m).
    origin_lonlat : tuple[float, float] | None
        (longitude, latitude) in degrees of the local ENU origin for imported maps; None for synthetic towns.
    signals : np.ndarray
        (K, 2) positions (m) of the traffic signals the map marks (OpenStreetMap ``highway=traffic_signals`` and
        signalised crossings); (0, 2) when it marks none, as in synthetic towns. Which junctions they control:
        :func:`worlds.roads.signals.signalised_junctions`.
    """

    network: RoadNetwork
    buildings: list[Building] = field(default_factory=list)
    origin_lonlat: tuple[float, float] | None = None
    signals: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))

    def bounds(self) -> tuple[float, float, float, float]:
        """(x_min, y_min, x_max, y_max) over road samples and building footprints (m)."""
        pts = [r.samples for r in self.network.roads.values()] + [b.footprint for b in self.buildings]
        if not pts:
            raise ValueError("Town.bounds: the town is empty")
        allp = np.vstack(pts)
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        return float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])


def generate_town(cfg: TownConfig, rng: np.random.Generator) -> Town:
    """Generate a town from ``cfg`` with randomness drawn only from ``rng`` (see the module docstring)."""
    nx = int(cfg.extent[0] // cfg.block_size) + 1
    ny = int(cfg.extent[1] // cfg.block_size) + 1
    B = cfg.block_size
    x0, y0 = -(nx - 1) * B / 2.0, -(ny - 1) * B / 2.0
    xs, ys = x0 + B * np.arange(nx), y0 + B * np.arange(ny)
    rows_art = [j for j in range(ny) if j % cfg.arterial_every == 0]  # horizontal lines y = ys[j]
    cols_art = [i for i in range(nx) if i % cfg.arterial_every == 0]  # vertical lines x = xs[i]
    lines = [("row", j) for j in rows_art] + [("col", i) for i in cols_art]
    n_curved = int(round(cfg.curved_fraction * len(lines)))
    curved = {lines[k] for k in rng.choice(len(lines), size=n_curved, replace=False)} if n_curved else set()

    nodes = {_nid(i, j): (float(xs[i]), float(ys[j])) for i in range(nx) for j in range(ny)}
    amp = cfg.curve_amplitude * B
    roads: list[Road] = []
    for j in range(ny):
        for i in range(nx - 1):
            bulge = amp * (-1) ** i if ("row", j) in curved else 0.0
            roads += _street(cfg, f"h{i}_{j}", _nid(i, j), _nid(i + 1, j), nodes, bulge, j in rows_art)
    for i in range(nx):
        for j in range(ny - 1):
            bulge = -amp * (-1) ** j if ("col", i) in curved else 0.0
            roads += _street(cfg, f"v{i}_{j}", _nid(i, j), _nid(i, j + 1), nodes, bulge, i in cols_art)
    network = RoadNetwork(roads, nodes)
    polys = road_polygons(network)
    boxes = np.vstack([_fill_block(cfg, rng, network, polys, i, j) for i in range(nx - 1) for j in range(ny - 1)])
    if cfg.max_buildings is not None and len(boxes) > cfg.max_buildings:
        boxes = boxes[np.sort(rng.choice(len(boxes), size=cfg.max_buildings, replace=False))]
    buildings = [Building.cuboid((cx, cy), (sx, sy, h), name=f"b{k}") for k, (cx, cy, sx, sy, h) in enumerate(boxes)]
    return Town(network=network, buildings=buildings)


def town_road_ids(cfg: TownConfig) -> list[str]:
    """Ids of every road :func:`generate_town` builds from ``cfg`` (they depend on the grid only, not on the random
    draws), so that a world's routes can be checked at load: ``h{i}_{j}`` and ``v{i}_{j}`` streets, each a ``.f`` and
    ``.r`` road."""
    nx = int(cfg.extent[0] // cfg.block_size) + 1
    ny = int(cfg.extent[1] // cfg.block_size) + 1
    sids = [f"h{i}_{j}" for j in range(ny) for i in range(nx - 1)] + [f"v{i}_{j}" for i in range(nx)
                                                                      for j in range(ny - 1)]
    return [rid for sid in sids for rid in street_road_ids(sid)]


def _nid(i: int, j: int) -> str:
    return f"n{i}_{j}"


def _street(cfg: TownConfig, sid: str, a: str, b: str, nodes: dict, bulge: float, arterial: bool) -> list[Road]:
    """The twin roads of street ``sid`` from junction ``a`` to ``b``, bowed ``bulge`` m to the left by a half sine."""
    pa, pb = np.array(nodes[a]), np.array(nodes[b])
    if bulge == 0.0:
        verts = np.vstack([pa, pb])
    else:
        u = np.linspace(0.0, 1.0, _CURVE_VIA + 2)
        d = pb - pa
        n = np.array([-d[1], d[0]]) / np.hypot(*d)
        verts = pa + u[:, None] * d + (bulge * np.sin(np.pi * u))[:, None] * n
    lanes = cfg.arterial_lanes if arterial else cfg.lanes
    speed = cfg.arterial_speed_limit if arterial else cfg.speed_limit
    fwd, rev = street_road_ids(sid)
    common = dict(lanes=lanes, lane_width=cfg.lane_width, speed_limit=speed)
    road = Road(id=fwd, vertices=verts, start_node=a, end_node=b, twin=rev, **common)
    return [road, road.reversed(id=rev)]


def _fill_block(cfg: TownConfig, rng: np.random.Generator, network: RoadNetwork, polys: dict[str, Polygon], i: int,
                j: int) -> np.ndarray:
    """Buildings of block (i, j) as rows (centre x, centre y, size x, size y, height) in m."""
    sides = [(f"h{i}_{j}", False), (f"v{i + 1}_{j}", False), (f"h{i}_{j + 1}", True), (f"v{i}_{j}", True)]
    ring = []
    for sid, backwards in sides:
        pts = network.roads[street_road_ids(sid)[0]].samples
        ring.append((pts[::-1] if backwards else pts)[:-1])
    block = Polygon(np.vstack(ring))
    streets = unary_union([polys[rid] for sid, _ in sides for rid in street_road_ids(sid)])
    lot = block.difference(streets.buffer(cfg.setback))
    if lot.is_empty:
        return np.empty((0, 5))
    fmin, fmax = cfg.footprint_range
    gap = cfg.building_gap
    minx, miny, maxx, maxy = lot.bounds
    cells = []
    for lo, hi in ((minx, maxx), (miny, maxy)):
        n = max(1, int((hi - lo) // (fmax + gap)))
        cells.append(lo + (hi - lo) * np.arange(n + 1) / n)
    gx, gy = np.meshgrid(np.arange(len(cells[0]) - 1), np.arange(len(cells[1]) - 1), indexing="ij")
    gx, gy = gx.ravel(), gy.ravel()
    x0, x1 = cells[0][gx], cells[0][gx + 1]
    y0, y1 = cells[1][gy], cells[1][gy + 1]
    u = rng.random((len(gx), 5))
    smax_x, smax_y = np.minimum(fmax, x1 - x0 - gap), np.minimum(fmax, y1 - y0 - gap)
    sx, sy = fmin + u[:, 0] * (smax_x - fmin), fmin + u[:, 1] * (smax_y - fmin)
    cx = x0 + gap / 2 + sx / 2 + u[:, 2] * (x1 - x0 - gap - sx)
    cy = y0 + gap / 2 + sy / 2 + u[:, 3] * (y1 - y0 - gap - sy)
    h = cfg.height_range[0] + u[:, 4] * (cfg.height_range[1] - cfg.height_range[0])
    ok = (smax_x >= fmin) & (smax_y >= fmin)
    shapely.prepare(lot)
    ok &= shapely.contains(lot, shapely.box(cx - sx / 2, cy - sy / 2, cx + sx / 2, cy + sy / 2))
    return np.stack([cx, cy, sx, sy, h], axis=1)[ok]
