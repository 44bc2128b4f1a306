"""skytrack's road graph as a SUMO network: plain XML nodes and edges through eclipse-sumo's ``netconvert``.

Every skytrack road becomes one SUMO edge between the same junction nodes, with the road's centre-line sampled as the
edge's ``shape``, its lanes per direction, lane width and speed limit, so that SUMO drives on skytrack's geometry.

Where the lanes lie
-------------------
A skytrack road with a twin (one direction of a two-way street) has its lanes on its right of the centre-line, the
street's dividing line, filling lateral offsets ``[-lanes * lane_width, 0]``; SUMO's ``spreadType="right"`` (its
default) puts an edge's lanes on the right of the edge shape in the same way, lane 0 rightmost in both. A road
without a twin (one-way) has its lanes centred on its centre-line, which is SUMO's ``spreadType="center"``. SUMO cuts
every lane short where it enters a junction's polygon and joins the lanes across the junction with internal lanes
(ids beginning ``":"``); outside junctions its lane centres lie on skytrack's (tested to 1 cm on straight roads).

Traffic lights: junctions listed in ``signals`` get one (``type="traffic_light"``; a world's are the junctions its
map's signals control, :func:`worlds.roads.signals.signalised_junctions`), and those within 20 m of each other run
one program (``--tls.join``: the carriageways of a divided road crossing a street); with ``tls="guess"`` netconvert
also guesses lights at the other junctions by its own rule (``--tls.guess``: junctions of fast roads); with
``tls="none"`` the rest are priority junctions (right before left between equal roads).

Coordinates: ``--offset.disable-normalization`` keeps SUMO's x-y equal to skytrack's world x-y (no shift).
"""

from __future__ import annotations

import hashlib
import os
import re
import subprocess
import uuid
import xml.etree.ElementTree as ET
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from vehicles.car.road_protocol import sample_road
from vehicles.sumo._runtime import sumo_binary
from worlds.roads.network import RoadNetwork

__all__ = ["NetConfig", "SumoNet", "build_sumo_net", "read_lane_shapes"]

_SAFE_ID = re.compile(r"[^A-Za-z0-9_.\-]")


@dataclass(frozen=True, kw_only=True)
class NetConfig:
    """How skytrack's roads are turned into a SUMO network.

    Attributes
    ----------
    shape_spacing : float
        Spacing of the centre-line samples written as a curved road's edge shape (m); straight roads get their two
        end points only.
    tls : str
        ``"guess"``: netconvert guesses traffic lights (``--tls.guess``) at junctions without one;
        ``"none"``: only the junctions in ``signals`` get lights.
    signals : tuple[str, ...]
        Node ids that have traffic lights (e.g. from OSM signals).
    no_turnarounds : bool
        No U-turns at junctions except at dead ends, as skytrack's drivers (``RoadNetwork.successors``).
    timeout_s : float
        Longest netconvert may run (s).
    """

    shape_spacing: float = 2.0
    tls: str = "guess"
    signals: tuple[str, ...] = ()
    no_turnarounds: bool = True
    timeout_s: float = 300.0

    def __post_init__(self) -> None:
        if not self.shape_spacing > 0:
            raise ValueError(f"NetConfig.shape_spacing must be > 0 m, got {self.shape_spacing}")
        if self.tls not in ("guess", "none"):
            raise ValueError(f"NetConfig.tls must be 'guess' or 'none', got {self.tls!r}")
        object.__setattr__(self, "signals", tuple(str(s) for s in self.signals))


@dataclass(frozen=True)
class SumoNet:
    """A SUMO network file made from a skytrack road network, and how its ids map back.

    Attributes
    ----------
    net_file : Path
        The ``.net.xml`` netconvert wrote.
    edge_to_road : dict[str, str]
        SUMO edge id -> skytrack road id (every normal edge; internal edges ``":..."`` are junction paths).
    road_to_edge : dict[str, str]
        skytrack road id -> SUMO edge id.
    """

    net_file: Path
    edge_to_road: dict[str, str]
    road_to_edge: dict[str, str] = field(repr=False)

    def road_of(self, edge_id: str) -> str:
        """skytrack road id of SUMO edge (or lane) ``edge_id``; ``""`` for a junction's internal edge."""
        if edge_id.startswith(":"):
            return ""
        return self.edge_to_road.get(edge_id, "")


def _sumo_ids(ids: Iterable[str]) -> dict[str, str]:
    """A SUMO-safe id per skytrack id (letters, digits, ``_ . -`` kept; the rest become ``_``), unique."""
    out: dict[str, str] = {}
    used: set[str] = set()
    for sid in ids:
        base = _SAFE_ID.sub("_", sid) or "_"
        if base.startswith(":"):
            base = "_" + base[1:]
        cand, k = base, 1
        while cand in used:
            cand, k = f"{base}~{k}", k + 1
        used.add(cand)
        out[sid] = cand
    return out


def _shape(road, spacing: float) -> np.ndarray:
    """Points of ``road``'s centre-line for the SUMO edge shape: its ends if straight, else every ``spacing`` m."""
    if road.vertices.shape[0] == 2 or road.total_turn < 1e-9:
        s = np.array([0.0, road.length])
    else:
        s = np.linspace(0.0, road.length, max(2, int(np.ceil(road.length / spacing))) + 1)
    xy, _, _ = sample_road(road, s, 0.0)
    return xy


def _fmt(xy: np.ndarray) -> str:
    return " ".join(f"{x:.4f},{y:.4f}" for x, y in xy)


def plain_xml(network: RoadNetwork, config: NetConfig) -> tuple[str, str, dict[str, str], dict[str, str]]:
    """(nodes XML, edges XML, node id map, road id map) of ``network`` in SUMO's plain format."""
    node_ids = _sumo_ids(network.nodes)
    road_ids = _sumo_ids(network.roads)
    unknown = [s for s in config.signals if s not in network.nodes]
    if unknown:
        raise ValueError(f"NetConfig.signals: {unknown!r} are not nodes of the network")
    nodes = ET.Element("nodes")
    for nid, p in network.nodes.items():
        attrs = {"id": node_ids[nid], "x": f"{p[0]:.4f}", "y": f"{p[1]:.4f}"}
        if nid in config.signals:
            attrs["type"] = "traffic_light"
        ET.SubElement(nodes, "node", attrs)
    edges = ET.Element("edges")
    for rid, road in network.roads.items():
        ET.SubElement(edges, "edge", {
            "id": road_ids[rid], "from": node_ids[road.start_node], "to": node_ids[road.end_node],
            "numLanes": str(road.lanes), "speed": f"{road.speed_limit:.4f}", "width": f"{road.lane_width:.4f}",
            "spreadType": "right" if road.twin is not None else "center",
            "shape": _fmt(_shape(road, config.shape_spacing)),
        })
    return (ET.tostring(nodes, encoding="unicode"), ET.tostring(edges, encoding="unicode"), node_ids, road_ids)


def build_sumo_net(network: RoadNetwork, work_dir: str | Path, config: NetConfig | None = None) -> SumoNet:
    """Write ``network`` as SUMO plain XML into ``work_dir`` and convert it with netconvert (cached by content).

    The files are named by a hash of the plain XML and the options, so a second call with the same network reuses
    the ``.net.xml`` already there.

    Raises
    ------
    SumoUnavailable
        eclipse-sumo is not installed.
    RuntimeError
        netconvert failed (its error output is in the message).
    """
    config = config or NetConfig()
    nodes_xml, edges_xml, _, road_ids = plain_xml(network, config)
    turn = ["--no-turnarounds.except-deadend", "true"] if config.no_turnarounds else []
    join = ["--tls.join", "true"] if config.signals else []  # lights of junctions within 20 m run one program
    args = ["--offset.disable-normalization", "true", *turn, "--tls.guess", str(config.tls == "guess").lower(),
            *join, "--junctions.corner-detail", "5", "--no-warnings", "true"]
    digest = hashlib.sha256("\n".join([nodes_xml, edges_xml, *args]).encode()).hexdigest()[:16]
    work = Path(work_dir)
    work.mkdir(parents=True, exist_ok=True)
    net_file = work / f"skytrack_{digest}.net.xml"
    edge_to_road = {e: r for r, e in road_ids.items()}
    if not net_file.is_file():
        own = f"{os.getpid()}_{uuid.uuid4().hex[:8]}"  # runs in parallel (a campaign's workers) never share a file
        nod, edg = work / f"skytrack_{digest}.{own}.nod.xml", work / f"skytrack_{digest}.{own}.edg.xml"
        nod.write_text(nodes_xml)
        edg.write_text(edges_xml)
        tmp = work / f"skytrack_{digest}.{own}.tmp.net.xml"
        cmd = [str(sumo_binary("netconvert")), "--node-files", str(nod), "--edge-files", str(edg),
               "--output-file", str(tmp), *args]
        try:
            res = subprocess.run(cmd, capture_output=True, text=True, timeout=config.timeout_s, check=False)
            if res.returncode != 0 or not tmp.is_file():
                raise RuntimeError(f"netconvert failed (exit {res.returncode}): "
                                   f"{res.stderr.strip() or res.stdout.strip()}")
            tmp.replace(net_file)  # atomic: a half-written file is never taken for a cached network
        finally:
            for f in (nod, edg, tmp):
                f.unlink(missing_ok=True)
    return SumoNet(net_file=net_file, edge_to_road=edge_to_road, road_to_edge=dict(road_ids))


def read_lane_shapes(net_file: str | Path) -> dict[str, np.ndarray]:
    """Lane id -> (K, 2) lane centre polyline (m) of every lane in a ``.net.xml``, internal lanes included."""
    out: dict[str, np.ndarray] = {}
    for _, el in ET.iterparse(str(net_file)):
        if el.tag == "lane":
            pts = [tuple(map(float, p.split(",")[:2])) for p in el.get("shape", "").split()]
            out[el.get("id")] = np.array(pts, dtype=float).reshape(-1, 2)
    return out
