"""OpenStreetMap import: tag handling on a hand-written extract, the shipped Helsinki extract, and error reporting."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import shapely
from shapely.geometry import LineString

from worlds.osm import (LocalTangentPlane, OsmEmptyError, OsmError, OsmFileNotFoundError, OsmFormatError, load_osm)
from worlds.roads.signals import JOIN_M, ON_ROAD_M, junctions, signalised_junctions

HELSINKI = Path(__file__).resolve().parents[2] / "assets" / "maps" / "helsinki.osm.pbf"
LON0, LAT0 = 24.94, 60.17
M_PER_DEG_LAT = 111_412.0  # approximate, only used to lay out the synthetic extract


def _lonlat(x: float, y: float) -> tuple[float, float]:
    return LON0 + x / (M_PER_DEG_LAT * np.cos(np.radians(LAT0))), LAT0 + y / M_PER_DEG_LAT


# node id -> (x, y) m around (LON0, LAT0)
NODES = {1: (0, 0), 2: (100, 0), 3: (200, 0), 4: (100, 100), 5: (0, 100), 6: (300, 0), 7: (300, 100), 8: (150, -50),
         9: (200, -60), 10: (230, -90), 11: (170, -90),
         # buildings
         20: (20, 20), 21: (40, 20), 22: (40, 40), 23: (20, 40), 30: (120, 20), 31: (140, 20), 32: (140, 40),
         40: (20, 120), 41: (40, 120), 42: (30, 135), 50: (-60, -60), 51: (-20, -60), 52: (-20, -20), 53: (-60, -20),
         54: (-50, -50), 55: (-30, -50), 56: (-40, -30), 13: (170, 70),
         60: (165, 35), 61: (185, 35), 62: (185, 65), 63: (165, 65)}
WAYS = [  # (id, node refs, tags)
    (100, [1, 2, 3], {"highway": "residential", "maxspeed": "40", "lanes": "2"}),
    (101, [2, 4], {"highway": "primary", "oneway": "yes", "lanes": "2", "maxspeed": "30 mph"}),
    (102, [5, 4], {"highway": "secondary", "oneway": "-1"}),
    (103, [5, 1], {"highway": "tertiary", "width": "8", "lanes:forward": "1", "lanes:backward": "1"}),
    (104, [3, 8], {"highway": "footway"}),
    (105, [6, 7], {"highway": "residential"}),  # a separate component: dropped
    (106, [3, 6], {"highway": "service", "tunnel": "yes"}),  # tunnels are left out
    (107, [3, 9], {"highway": "unclassified", "maxspeed": "FI:urban"}),
    (108, [9, 10, 11, 9], {"highway": "residential", "junction": "roundabout"}),
    (109, [3, 13], {"highway": "service"}),  # runs through building 205: dropped
    # buildings
    (200, [20, 21, 22, 23, 20], {"building": "yes", "height": "12 m"}),
    (201, [30, 31, 32, 30], {"building": "office", "building:levels": "5"}),
    (202, [40, 41, 42, 40], {"building": "house"}),
    (203, [50, 51, 52, 53, 50], {}),
    (204, [54, 55, 56, 54], {}),
    (205, [60, 61, 62, 63, 60], {"building": "garage"}),
]
RELATIONS = [(300, [(203, "outer"), (204, "inner")], {"type": "multipolygon", "building": "yes", "height": "40 ft"})]


def _write_osm(path: Path, node_tags: dict[int, dict[str, str]] | None = None) -> Path:
    lines = ['<?xml version="1.0" encoding="UTF-8"?>', '<osm version="0.6" generator="test">']
    for nid, (x, y) in NODES.items():
        lon, lat = _lonlat(x, y)
        tags = (node_tags or {}).get(nid, {})
        if not tags:
            lines.append(f'  <node id="{nid}" version="1" lat="{lat:.8f}" lon="{lon:.8f}"/>')
            continue
        lines.append(f'  <node id="{nid}" version="1" lat="{lat:.8f}" lon="{lon:.8f}">')
        lines += [f'    <tag k="{k}" v="{v}"/>' for k, v in tags.items()]
        lines.append("  </node>")
    for wid, refs, tags in WAYS:
        lines.append(f'  <way id="{wid}" version="1">')
        lines += [f'    <nd ref="{r}"/>' for r in refs]
        lines += [f'    <tag k="{k}" v="{v}"/>' for k, v in tags.items()]
        lines.append("  </way>")
    for rid, members, tags in RELATIONS:
        lines.append(f'  <relation id="{rid}" version="1">')
        lines += [f'    <member type="way" ref="{m}" role="{role}"/>' for m, role in members]
        lines += [f'    <tag k="{k}" v="{v}"/>' for k, v in tags.items()]
        lines.append("  </relation>")
    lines.append("</osm>")
    path.write_text("\n".join(lines))
    return path


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    return load_osm(_write_osm(tmp_path_factory.mktemp("osm") / "small.osm"), default_height=7.0)


def test_small_extract_network(small):
    net = small.network
    assert net.is_connected()
    # 6-7 is a separate component, footway and tunnel are skipped, 3-13 runs through a building
    assert set(net.nodes) == {"1", "2", "3", "4", "5", "9", "10"}
    # way 100 is cut at node 2 into two two-way streets
    assert {"w100_0.f", "w100_0.r", "w100_1.f", "w100_1.r"} <= set(net.roads)
    a = net.roads["w100_0.f"]
    assert (a.start_node, a.end_node, a.twin, a.lanes) == ("1", "2", "w100_0.r", 1)
    assert a.speed_limit == pytest.approx(40 / 3.6)
    assert a.length == pytest.approx(100.0, rel=0.01)
    # oneway=yes: only along the way; 2 lanes; mph
    assert "w101_0.r" not in net.roads
    b = net.roads["w101_0.f"]
    assert (b.start_node, b.end_node, b.twin, b.lanes) == ("2", "4", None, 2)
    assert b.speed_limit == pytest.approx(30 * 1.609344 / 3.6)
    # oneway=-1: only against the way
    assert "w102_0.f" not in net.roads
    c = net.roads["w102_0.r"]
    assert (c.start_node, c.end_node, c.twin) == ("4", "5", None)
    # width / total lanes
    assert net.roads["w103_0.f"].lane_width == pytest.approx(4.0)
    assert net.roads["w107_0.f"].speed_limit == pytest.approx(50 / 3.6)
    # the roundabout is one-way and cut into two pieces at its middle vertex: 9 -> 10 and 10 -> 11 -> 9
    ring = sorted(r for r in net.roads if r.startswith("w108"))
    assert ring == ["w108_0.f", "w108_1.f"]
    assert all(net.roads[r].twin is None for r in ring)
    assert net.route("9", "10") == ["w108_0.f"]
    assert net.route("10", "3") == ["w108_1.f", "w107_0.r"]


def test_small_extract_geometry(small):
    """Projected node positions match the metric layout to 0.2 %; the origin is the centre of the data."""
    net = small.network
    origin = np.array(net.nodes["1"]) - np.array(NODES[1])
    for nid in ("2", "3", "4", "5"):
        rel = np.array(net.nodes[nid]) - np.array(net.nodes["1"])
        np.testing.assert_allclose(rel, np.array(NODES[int(nid)], dtype=float), atol=0.5)
    assert np.all(np.abs(origin) < 400)


def test_small_extract_buildings(small):
    by_name = {b.name: b for b in small.buildings}
    assert set(by_name) == {"w200", "w201", "w202", "r300", "w205"}
    assert by_name["w200"].height == pytest.approx(12.0)
    assert by_name["w201"].height == pytest.approx(15.0)  # 5 levels x 3 m
    assert by_name["w202"].height == pytest.approx(7.0)  # default_height
    assert by_name["r300"].height == pytest.approx(40 * 0.3048)
    fp = by_name["w200"].footprint
    assert fp.shape == (4, 2)
    x, y = fp[:, 0], fp[:, 1]
    area = 0.5 * (np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))
    assert area == pytest.approx(400.0, rel=0.01)  # 20 m x 20 m, counter-clockwise
    assert by_name["r300"].footprint.shape == (4, 2)  # outer ring of the multipolygon


def test_bbox_crop(tmp_path):
    path = _write_osm(tmp_path / "crop.osm")
    lo, hi = _lonlat(-10, -10), _lonlat(110, 110)
    town = load_osm(path, bbox=(lo[0], lo[1], hi[0], hi[1]))
    assert set(town.network.nodes) == {"1", "2", "4", "5"}
    assert {b.name for b in town.buildings} == {"w200"}  # the others reach beyond x = 110 or y = 110 m
    assert town.origin_lonlat == pytest.approx(_lonlat(50, 50))
    with pytest.raises(OsmEmptyError, match="inside bbox"):
        far = _lonlat(5000, 5000)
        load_osm(path, bbox=(far[0], far[1], far[0] + 0.01, far[1] + 0.01))


def test_traffic_signals_are_read_and_control_their_junction(small, tmp_path):
    """Signal nodes (highway=traffic_signals, crossing=traffic_signals) become the town's signals at their nodes'
    positions; other node tags do not; bbox keeps those inside; the signal on node 2 (ways 100 and 101 meet there)
    lights that junction, the crossing on the footway's end (node 8, off the network) none."""
    assert small.signals.shape == (0, 2)  # the extract without node tags
    tags = {2: {"highway": "traffic_signals"}, 8: {"highway": "crossing", "crossing": "traffic_signals"},
            3: {"highway": "give_way"}, 1: {"crossing": "uncontrolled", "highway": "crossing"}}
    town = load_osm(_write_osm(tmp_path / "signals.osm", tags))
    assert town.signals.shape == (2, 2)
    proj = LocalTangentPlane(town.origin_lonlat)
    lonlat = np.array([_lonlat(*NODES[2]), _lonlat(*NODES[8])])
    np.testing.assert_allclose(town.signals, proj(lonlat[:, 0], lonlat[:, 1]), atol=0.01)  # OSM keeps 1e-7 deg
    np.testing.assert_allclose(town.signals[0], town.network.nodes["2"], atol=1e-9)
    assert signalised_junctions(town.network, town.signals) == ("2",)
    lo, hi = _lonlat(-10, -10), _lonlat(110, 110)
    cropped = load_osm(tmp_path / "signals.osm", bbox=(lo[0], lo[1], hi[0], hi[1]))
    assert cropped.signals.shape == (1, 2)


def test_local_tangent_plane_closed_form():
    """1e-3 deg steps from the origin map to the WGS84 meridian and parallel radii of curvature (to 1e-6)."""
    a, f = 6378137.0, 1 / 298.257223563
    e2 = f * (2 - f)
    lat = np.radians(LAT0)
    M = a * (1 - e2) / (1 - e2 * np.sin(lat) ** 2) ** 1.5  # meridian radius of curvature
    N = a / np.sqrt(1 - e2 * np.sin(lat) ** 2)  # prime vertical radius
    proj = LocalTangentPlane((LON0, LAT0))
    d = 1e-3
    xy = proj(np.array([LON0, LON0, LON0 + d]), np.array([LAT0, LAT0 + d, LAT0]))
    np.testing.assert_allclose(xy[0], [0.0, 0.0], atol=1e-9)
    assert xy[1, 1] == pytest.approx(M * np.radians(d), rel=1e-5) and abs(xy[1, 0]) < 1e-6
    assert xy[2, 0] == pytest.approx(N * np.cos(lat) * np.radians(d), rel=1e-5)


# ---------------------------------------------------------------- the shipped Helsinki extract
@pytest.fixture(scope="module")
def helsinki():
    return load_osm(HELSINKI)


def test_helsinki_network(helsinki):
    net = helsinki.network
    assert net.is_connected()
    assert 15_000 < net.street_length() < 40_000  # about 23 km of streets in the 1 x 1.7 km centre
    assert 25_000 < net.total_length() < 60_000
    assert len(net.roads) > 1000 and len(net.nodes) > 500
    assert any(r.twin is None for r in net.roads.values())  # one-way streets exist
    x0, y0, x1, y1 = helsinki.bounds()
    assert -600 < x0 and x1 < 600 and -900 < y0 and y1 < 900
    assert helsinki.origin_lonlat == pytest.approx(((24.9351762 + 24.9534145) / 2, (60.1641550 + 60.1791130) / 2))


def test_helsinki_signals_light_junctions_near_them(helsinki):
    """The extract maps some 470 signals (132 highway=traffic_signals nodes, the rest signalised crossings); the
    junctions they control are junctions, each with a signal within reach."""
    assert 400 < len(helsinki.signals) < 550
    lit = signalised_junctions(helsinki.network, helsinki.signals)
    joints = junctions(helsinki.network)
    assert 30 < len(lit) < len(joints) and set(lit) <= set(joints)
    for node in lit:
        assert np.min(np.hypot(*(helsinki.signals - helsinki.network.nodes[node]).T)) <= JOIN_M + ON_ROAD_M


def test_helsinki_centre_lines_follow_the_map(helsinki):
    """Every smooth centre-line stays within 2 m of the mapped polyline (no spline overshoot at corners)."""
    worst = 0.0
    for road in helsinki.network.roads.values():
        if road.vertices.shape[0] > 2:
            pts = road.point(np.linspace(0.0, road.length, 200))
            worst = max(worst, float(shapely.distance(LineString(road.vertices), shapely.points(pts)).max()))
    assert worst < 2.0


def test_helsinki_lanes_clear_buildings(helsinki):
    """No rightmost lane runs more than 1 m through a building footprint (such driveways are dropped on import)."""
    polys = shapely.make_valid(np.array([shapely.Polygon(b.footprint) for b in helsinki.buildings]))
    tree = shapely.STRtree(polys)
    for road in helsinki.network.roads.values():
        lane = LineString(road.point(np.linspace(0.0, road.length, 50), road.lane_offset(0)))
        hits = tree.query(lane, predicate="intersects")
        assert shapely.length(shapely.intersection(lane, polys[hits])).sum() <= 1.0


def test_helsinki_buildings(helsinki):
    assert 400 <= len(helsinki.buildings) <= 520
    heights = np.array([b.height for b in helsinki.buildings])
    assert np.all(heights > 0) and heights.max() < 120
    assert np.sum(heights != 9.0) > 100  # many carry height or level tags
    ateneum = next(b for b in helsinki.buildings if b.name == "w8033120")  # building:levels = 3.5
    assert ateneum.height == pytest.approx(10.5)
    assert sum(b.name.startswith("r") for b in helsinki.buildings) > 20  # multipolygon relations


def test_helsinki_random_route_is_continuous(helsinki):
    net = helsinki.network
    rng = np.random.default_rng(42)
    start = sorted(net.roads)[int(rng.integers(len(net.roads)))]
    route = net.random_route(start, 400, rng)
    assert len(route) == 400
    for a, b in zip(route[:-1], route[1:], strict=True):
        ra, rb = net.roads[a], net.roads[b]
        assert ra.end_node == rb.start_node
        np.testing.assert_allclose(ra.point(ra.length), rb.point(0.0), atol=1e-9)
    assert sum(net.roads[r].length for r in route) > 5_000


def test_helsinki_shortest_route(helsinki):
    net = helsinki.network
    nodes = sorted(net.nodes)
    route = net.route(nodes[0], nodes[-1])
    assert net.roads[route[0]].start_node == nodes[0] and net.roads[route[-1]].end_node == nodes[-1]
    length = sum(net.roads[r].length for r in route)
    straight = np.hypot(*(net.nodes[nodes[-1]] - net.nodes[nodes[0]]))
    assert straight <= length < 3 * straight + 200


# ---------------------------------------------------------------- errors
def test_missing_file(tmp_path):
    path = tmp_path / "nowhere.osm.pbf"
    with pytest.raises(OsmFileNotFoundError, match="nowhere.osm.pbf.*not found") as err:
        load_osm(path)
    assert isinstance(err.value, FileNotFoundError) and isinstance(err.value, OsmError)


def test_corrupt_files(tmp_path):
    bad_pbf = tmp_path / "bad.osm.pbf"
    bad_pbf.write_bytes(np.random.default_rng(0).bytes(4096))
    with pytest.raises(OsmFormatError, match="bad.osm.pbf: cannot be read") as err:
        load_osm(bad_pbf)
    assert isinstance(err.value, ValueError)
    bad_xml = tmp_path / "bad.osm"
    bad_xml.write_text("<osm><node id=")
    with pytest.raises(OsmFormatError, match="bad.osm: cannot be read"):
        load_osm(bad_xml)
    wrong = tmp_path / "map.txt"
    wrong.write_text("hello")
    with pytest.raises(OsmFormatError, match="map.txt: unsupported file type"):
        load_osm(wrong)
    with pytest.raises(OsmFormatError, match="is a directory"):
        load_osm(tmp_path)


def test_empty_extracts(tmp_path):
    empty = tmp_path / "empty.osm.pbf"
    empty.write_bytes(b"")
    with pytest.raises(OsmEmptyError, match="empty.osm.pbf: the file is empty"):
        load_osm(empty)
    no_roads = tmp_path / "noroads.osm"
    no_roads.write_text('<?xml version="1.0"?>\n<osm version="0.6">\n'
                        '<node id="1" version="1" lat="60.1" lon="24.9"/>\n</osm>\n')
    with pytest.raises(OsmEmptyError, match="noroads.osm: no drivable ways"):
        load_osm(no_roads)


def test_bad_arguments():
    with pytest.raises(ValueError, match="default_height"):
        load_osm(HELSINKI, default_height=0.0)
    with pytest.raises(ValueError, match="bbox"):
        load_osm(HELSINKI, bbox=(25.0, 60.0, 24.0, 61.0))
