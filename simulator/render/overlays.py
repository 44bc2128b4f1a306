"""What the autonomy believes, drawn over a rendered frame with OpenCV from world coordinates.

Every world-space mark (the true and estimated target positions, the estimate's 2σ covariance ellipse, the standoff
circle, UAV trails, radar detections) is projected with the frame's own :class:`CameraView`, so it lands where the
3D renderer drew the scene. Lines are drawn with 4 fractional bits (``shift=4``) for sub-pixel placement.

A multi-target tracker's live tracks are drawn per UAV as small rings with their ids; the track the UAV takes for the
target as a filled dot with its id and ``p_target``. Ground vehicles other than the target (traffic) get small grey
corner brackets, the target the white ones.

Ground regions (the search's sets) are filled translucently: each is cut to the part of the ground plane in front of
the camera (:func:`_in_front`), projected (a plane seen through a pinhole maps straight edges to straight edges
there), cut to the image in pixels and filled, holes included.

The 2σ ellipse of a position covariance ``P = V diag(l1, l2) V^T`` is
``x + 2 V diag(sqrt(l1), sqrt(l2)) [cos a, sin a]``; for a Gaussian it holds 1 - exp(-2) ≈ 86 % of the
probability mass in 2D.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import cv2
import numpy as np
import shapely

from simulator.render.projection import CameraView
from simulator.render.timeline import RadarScan
from simulator.render.world_marks import probability_rgb

__all__ = ["LEGEND", "SEARCH_LEGEND", "TRACKS_LEGEND", "EstimateMark", "GroundRegion", "OverlayFrame", "TrackMark",
           "covariance_ellipse", "draw_hud", "draw_overlays", "rgb255"]

_SHIFT = 4
_ONE = 1 << _SHIFT
_LIMIT = 1e5  # px: keeps far off-screen points inside cv2's fixed-point range
_TRUTH_RGB = (255, 255, 255)
_CLUTTER_RGB = (255, 230, 0)
_TRAFFIC_RGB = (150, 150, 150)
_TRACK_FONT = 0.3  # text scale of track labels per unit line scale
_CIRCLE_POINTS = 72
_FRONT_MARGIN = 1.0  # m beyond the near plane: regions are cut there before they are projected
_IMAGE_MARGIN = 16  # px around the image kept when a projected region is cut to it


def rgb255(rgb: Sequence[float]) -> tuple[int, int, int]:
    """An RGB colour in [0, 1] as 0–255 integers."""
    return tuple(int(round(255 * c)) for c in rgb[:3])


def covariance_ellipse(xy: np.ndarray, P: np.ndarray, n_sigma: float = 2.0, n: int = _CIRCLE_POINTS) -> np.ndarray:
    """Points (n, 2) m of the ``n_sigma`` ellipse of the 2x2 covariance ``P`` (m²) around ``xy``."""
    lam, V = np.linalg.eigh(0.5 * (P + P.T))
    a = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return xy + n_sigma * (np.c_[np.cos(a), np.sin(a)] * np.sqrt(np.clip(lam, 0.0, None))) @ V.T


@dataclass(frozen=True)
class EstimateMark:
    """One UAV's belief about the target: its colour (RGB in [0, 1]), position xy m, covariance P (2, 2) m²,
    standoff radius m (None: no circle)."""

    uav: int
    rgb: tuple[float, float, float]
    xy: np.ndarray
    P: np.ndarray
    standoff_m: float | None


@dataclass(frozen=True)
class TrackMark:
    """One UAV's live tracks: its colour (RGB in [0, 1]), track ids (K,), positions xy (K, 2) m, ``p_target`` (K,)
    and which the UAV takes for the target (K,) bool."""

    uav: int
    rgb: tuple[float, float, float]
    track: np.ndarray
    xy: np.ndarray
    p_target: np.ndarray
    is_target: np.ndarray


@dataclass(frozen=True)
class GroundRegion:
    """A region of the ground to fill: its colour (RGB in [0, 1]), opacity in [0, 1] and shape (a shapely polygon or
    multipolygon in world x, y, m)."""

    rgb: tuple[float, float, float]
    alpha: float
    geom: Any


@dataclass(frozen=True)
class OverlayFrame:
    """The world-space marks of one frame.

    ``target_W`` is the true target (3,) m; ``trails`` (colour, points (K, 3) m) per UAV; ``scan_rgb`` the colour of
    each UAV's detections; ``uavs`` (colour, name, p_W (3,) m) ringed and labelled; ``ground_z`` the height (m) at
    which the 2D estimates, ellipses and standoff circles are drawn; ``regards`` (colour, closed ground outline
    (K, 3) m) the radars' fields of regard; ``links`` (p_a, p_b, delivery probability) the radio links;
    ``constrained_roads`` (colour, centre-line (K, 3) m) the road each road-constrained estimator holds the target on;
    ``regions`` ground regions filled at ``ground_z`` under every other mark, in order; ``tracks`` every UAV's live
    tracks (drawn at ``ground_z``); ``traffic_W`` the true positions (M, 3) m of the ground vehicles other than the
    target.
    """

    target_W: np.ndarray | None
    estimates: list[EstimateMark] = field(default_factory=list)
    trails: list[tuple[tuple[float, float, float], np.ndarray]] = field(default_factory=list)
    scans: list[RadarScan] = field(default_factory=list)
    scan_rgb: dict[int, tuple[float, float, float]] = field(default_factory=dict)
    uavs: list[tuple[tuple[float, float, float], str, np.ndarray]] = field(default_factory=list)
    ground_z: float = 0.0
    regards: list[tuple[tuple[float, float, float], np.ndarray]] = field(default_factory=list)
    constrained_roads: list[tuple[tuple[float, float, float], np.ndarray]] = field(default_factory=list)
    links: list[tuple[np.ndarray, np.ndarray, float]] = field(default_factory=list)
    regions: list[GroundRegion] = field(default_factory=list)
    tracks: list[TrackMark] = field(default_factory=list)
    traffic_W: np.ndarray | None = None


def _pixels(view: CameraView, pts_W: np.ndarray, w: int, h: int) -> tuple[np.ndarray, np.ndarray]:
    uv, front = view.project(pts_W, w, h)
    return np.clip(np.nan_to_num(uv * _ONE), -_LIMIT * _ONE, _LIMIT * _ONE).astype(np.int64), front


def _polyline(img: np.ndarray, view: CameraView, pts_W: np.ndarray, rgb: tuple[int, int, int], thickness: int,
              closed: bool) -> None:
    h, w = img.shape[:2]
    if closed:
        pts_W = np.vstack([pts_W, pts_W[:1]])
    px, front = _pixels(view, pts_W, w, h)
    # split into runs of consecutive points in front of the camera
    runs, start = [], None
    for k, ok in enumerate(front):
        if ok and start is None:
            start = k
        if (not ok or k == len(front) - 1) and start is not None:
            end = k + 1 if ok else k
            if end - start >= 2:
                runs.append(px[start:end].astype(np.int32).reshape(-1, 1, 2))
            start = None
    if runs:
        cv2.polylines(img, runs, False, rgb, thickness, cv2.LINE_AA, _SHIFT)


def _at_ground(xy: np.ndarray, z: float) -> np.ndarray:
    xy = np.atleast_2d(xy)
    return np.c_[xy, np.full(len(xy), z)]


def _circle_W(centre: np.ndarray, radius: float) -> np.ndarray:
    a = np.linspace(0.0, 2.0 * np.pi, _CIRCLE_POINTS, endpoint=False)
    return centre + radius * np.c_[np.cos(a), np.sin(a)]


def _in_front(view: CameraView, z: float, depth: float) -> Any:
    """The part of the ground plane at height ``z`` m at least ``depth`` m in front of the camera along its optical
    axis, as a polygon reaching past the far plane; ``None`` when the whole plane is in front.

    A ground point p = (x, y, z) is in front when (p − eye)·f ≥ depth, f the unit optical axis: the half-plane
    f_xy·(x, y) ≥ depth + eye·f − f_z z.
    """
    f = view.target_W - view.eye_W
    f = f / np.linalg.norm(f)
    c = depth + float(view.eye_W @ f) - f[2] * z
    n = float(np.hypot(f[0], f[1]))
    if n < 1e-9:  # looking straight up or down: all of the plane or none of it
        return None if c <= 0.0 else shapely.Polygon()
    u = f[:2] / n
    base, side = u * (c / n), np.array([-u[1], u[0]])
    reach = 2.0 * (view.far + float(np.hypot(*view.eye_W[:2])) + abs(c / n))
    return shapely.Polygon([base + reach * side, base - reach * side, base - reach * side + reach * u,
                            base + reach * side + reach * u])


def _region_pixels(view: CameraView, geom: Any, z: float, w: int, h: int) -> list[np.ndarray]:
    """The rings, in fixed-point pixels (K, 1, 2) int32, of the ground region ``geom`` at height ``z`` m cut to the
    part in front of the camera and to the image (with a margin)."""
    front = _in_front(view, z, view.near + _FRONT_MARGIN)
    if front is not None:
        geom = shapely.intersection(geom, front)
    image = shapely.box(-_IMAGE_MARGIN, -_IMAGE_MARGIN, w + _IMAGE_MARGIN, h + _IMAGE_MARGIN)
    rings = []
    for poly in shapely.get_parts(geom):
        if poly.geom_type != "Polygon" or poly.is_empty:
            continue
        px = []
        for ring in (poly.exterior, *poly.interiors):
            uv, ok = view.project(_at_ground(np.asarray(ring.coords)[:, :2], z), w, h)
            if not ok.all():
                break
            px.append(uv)
        else:
            cut = shapely.intersection(shapely.make_valid(shapely.Polygon(px[0], px[1:])), image)
            for part in shapely.get_parts(cut):
                if part.geom_type == "Polygon" and not part.is_empty:
                    for ring in (part.exterior, *part.interiors):
                        rings.append(np.round(np.asarray(ring.coords) * _ONE).astype(np.int32).reshape(-1, 1, 2))
    return rings


def _fill_region(img: np.ndarray, view: CameraView, region: GroundRegion, z: float,
                 ground_visible: np.ndarray | None) -> None:
    """Fill ``region`` translucently and outline it, on the pixels of ``ground_visible`` only (all when ``None``)."""
    h, w = img.shape[:2]
    rings = _region_pixels(view, region.geom, z, w, h)
    if not rings:
        return
    col = rgb255(region.rgb)
    mask = np.zeros((h, w), np.uint8)
    cv2.fillPoly(mask, rings, 255, cv2.LINE_8, _SHIFT)  # even-odd over all rings: holes stay open
    if ground_visible is not None:
        mask[~ground_visible] = 0
    a = float(region.alpha)
    layer = cv2.add(cv2.multiply(img, (1.0 - a,) * 3 + (0.0,)), tuple(a * c for c in col) + (0.0,))
    cv2.polylines(layer, rings, True, col, 1, cv2.LINE_AA, _SHIFT)
    cv2.copyTo(layer, mask, img)


def draw_overlays(img: np.ndarray, view: CameraView, frame: OverlayFrame,
                  ground_visible: np.ndarray | None = None) -> None:
    """Draw ``frame``'s marks on ``img`` (H, W, 3) RGB uint8 in place, as seen through ``view``; ground regions only
    on the pixels of ``ground_visible`` (H, W) bool, where the ground or a road is seen (all pixels when ``None``)."""
    h, w = img.shape[:2]
    s = max(1, int(round(h / 360)))  # line scale for the image size
    for region in frame.regions:
        _fill_region(img, view, region, frame.ground_z, ground_visible)
    for rgb, pts in frame.regards:
        _polyline(img, view, pts, rgb255(tuple(0.55 * c + 0.45 for c in rgb)), 1, closed=True)
    for rgb, pts in frame.constrained_roads:
        _polyline(img, view, pts, rgb255(rgb), 3 * s, closed=False)
    for a_W, b_W, pr in frame.links:
        _polyline(img, view, np.vstack([a_W, b_W]), rgb255(probability_rgb(pr)), s, closed=False)
    for rgb, pts in frame.trails:
        if len(pts) >= 2:
            _polyline(img, view, pts, rgb255(rgb), s, closed=False)
    for est in frame.estimates:
        col = rgb255(est.rgb)
        if est.standoff_m is not None:
            _polyline(img, view, _at_ground(_circle_W(est.xy, est.standoff_m), frame.ground_z), col, s, closed=True)
        ell = covariance_ellipse(est.xy, est.P)
        _polyline(img, view, _at_ground(ell, frame.ground_z), col, s + 1, closed=True)
        px, front = _pixels(view, _at_ground(est.xy, frame.ground_z), w, h)
        if front[0]:
            c = tuple(int(v) for v in px[0])
            d = 4 * s * _ONE
            cv2.line(img, (c[0] - d, c[1] - d), (c[0] + d, c[1] + d), col, s, cv2.LINE_AA, _SHIFT)
            cv2.line(img, (c[0] - d, c[1] + d), (c[0] + d, c[1] - d), col, s, cv2.LINE_AA, _SHIFT)
    for scan in frame.scans:
        px, front = _pixels(view, scan.points_W, w, h)
        col = rgb255(frame.scan_rgb.get(scan.uav, (1.0, 1.0, 1.0)))
        for k in np.flatnonzero(front):
            c = tuple(int(v) for v in px[k])
            if scan.clutter[k]:
                cv2.circle(img, c, 3 * s * _ONE, _CLUTTER_RGB, s, cv2.LINE_AA, _SHIFT)
            else:
                cv2.circle(img, c, 2 * s * _ONE, col, -1, cv2.LINE_AA, _SHIFT)
                cv2.circle(img, c, 2 * s * _ONE, (0, 0, 0), 1, cv2.LINE_AA, _SHIFT)
    if frame.traffic_W is not None and len(frame.traffic_W):
        _traffic_brackets(img, view, frame.traffic_W, s)
    for k, mark in enumerate(frame.tracks):
        _draw_tracks(img, view, mark, frame.ground_z, s, k)
    for rgb, name, p_W in frame.uavs:
        px, front = _pixels(view, p_W, w, h)
        if front[0]:
            c = tuple(int(v) for v in px[0])
            cv2.circle(img, c, 7 * s * _ONE, rgb255(rgb), s, cv2.LINE_AA, _SHIFT)
            org = (c[0] // _ONE + 8 * s, c[1] // _ONE - 4 * s)
            cv2.putText(img, name, org, cv2.FONT_HERSHEY_SIMPLEX, 0.35 * s, rgb255(rgb), max(1, s // 2), cv2.LINE_AA)
    if frame.target_W is not None:
        _brackets(img, view, frame.target_W, s)


def _bracket_corners(c: np.ndarray, r: int, k: int) -> list[np.ndarray]:
    """The four corner polylines (3 points each, fixed-point pixels) of brackets of half-size ``r`` and arm ``k``
    around each centre of ``c`` (N, 2)."""
    out = []
    for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
        corner = c + np.array([sx * r, sy * r])
        pts = np.stack([corner - np.array([sx * k, 0]), corner, corner - np.array([0, sy * k])], axis=1)
        out.extend(pts.astype(np.int32))
    return out


def _traffic_brackets(img: np.ndarray, view: CameraView, p_W: np.ndarray, s: int) -> None:
    """Small grey corner brackets around every traffic car (one polyline call for all of them)."""
    h, w = img.shape[:2]
    px, front = _pixels(view, p_W, w, h)
    if front.any():
        cv2.polylines(img, _bracket_corners(px[front], 7 * s * _ONE, 3 * s * _ONE), False, _TRAFFIC_RGB, s,
                      cv2.LINE_AA, _SHIFT)


def _draw_tracks(img: np.ndarray, view: CameraView, mark: TrackMark, z: float, s: int, row: int) -> None:
    """One UAV's tracks: a ring and the id per track; the target track filled, with its id and ``p_target``.
    ``row`` (the UAV's place among those drawn) puts its labels below the marks (even rows) or above them (odd rows),
    further out every second row, so that two UAVs' labels of one car do not overlap."""
    if not len(mark.track):
        return
    h, w = img.shape[:2]
    px, front = _pixels(view, _at_ground(mark.xy, z), w, h)
    col = rgb255(mark.rgb)
    scale, thick = _TRACK_FONT * s, max(1, s // 2)
    out = row // 2
    dy = (10 + 12 * out) * s if row % 2 == 0 else -(4 + 12 * out) * s
    for k in np.flatnonzero(front & ~mark.is_target):
        c = (int(px[k, 0]), int(px[k, 1]))
        cv2.circle(img, c, 3 * s * _ONE, col, 1, cv2.LINE_AA, _SHIFT)
        org = (c[0] // _ONE + 4 * s, c[1] // _ONE + dy)
        _shadowed_text(img, str(int(mark.track[k])), org, scale, col, thick, s)
    for k in np.flatnonzero(front & mark.is_target):
        c = (int(px[k, 0]), int(px[k, 1]))
        cv2.circle(img, c, 4 * s * _ONE, col, -1, cv2.LINE_AA, _SHIFT)
        cv2.circle(img, c, 4 * s * _ONE, (0, 0, 0), 1, cv2.LINE_AA, _SHIFT)
        org = (c[0] // _ONE + 6 * s, c[1] // _ONE + dy)
        text = f"{int(mark.track[k])} p={float(mark.p_target[k]):.2f}"
        _shadowed_text(img, text, org, 1.3 * scale, col, thick, s)


def _shadowed_text(img: np.ndarray, text: str, org: tuple[int, int], scale: float, rgb: tuple[int, int, int],
                   thick: int, shift: int) -> None:
    """Text in ``rgb`` over a black copy of itself shifted by ``shift`` px down and right (readable on any ground)."""
    font = cv2.FONT_HERSHEY_SIMPLEX
    cv2.putText(img, text, (org[0] + shift, org[1] + shift), font, scale, (0, 0, 0), thick, cv2.LINE_AA)
    cv2.putText(img, text, org, font, scale, rgb, thick, cv2.LINE_AA)


def _brackets(img: np.ndarray, view: CameraView, p_W: np.ndarray, s: int) -> None:
    """Corner brackets around the true target, leaving the car itself visible."""
    h, w = img.shape[:2]
    px, front = _pixels(view, p_W, w, h)
    if not front[0]:
        return
    cx, cy = (int(v) for v in px[0])
    r, k = 11 * s * _ONE, 5 * s * _ONE
    for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
        corner = (cx + sx * r, cy + sy * r)
        for end in ((corner[0] - sx * k, corner[1]), (corner[0], corner[1] - sy * k)):
            cv2.line(img, corner, end, (0, 0, 0), 3 * s, cv2.LINE_AA, _SHIFT)
            cv2.line(img, corner, end, _TRUTH_RGB, s, cv2.LINE_AA, _SHIFT)


LEGEND = (("white brackets: true target   x: estimate   ellipse around it: 2-sigma   wide circle: standoff",
           (0.9, 0.9, 0.9)),
          ("filled dots: radar detections of the last scan   yellow rings: clutter   lines: UAV trails",
           (0.9, 0.9, 0.9)),
          ("pale outline: radar field of regard   UAV-to-UAV line: radio link, red (Pr 0) to green (Pr 1)   "
           "thick road line: road the filter is constrained to",
           (0.9, 0.9, 0.9)))


TRACKS_LEGEND = (("small rings + numbers: a UAV's tracks   filled dot: the track it takes for the target, with "
                  "p(target)   grey brackets: other cars (truth)", (0.9, 0.9, 0.9)),)


SEARCH_LEGEND = (("blue fill: X-bar, where an undetected target may be   red fill: X, where a detected target may be "
                  "(sets of the UAV named in the HUD)", (0.9, 0.9, 0.9)),)


def draw_hud(img: np.ndarray, lines: Sequence[tuple[str, tuple[float, float, float]]], corner: str = "left",
             size: float = 1.0) -> None:
    """Text lines (text, RGB in [0, 1]) on a translucent dark box in the top-left (``corner="left"``) or
    bottom-left (``"bottom"``) corner, in place; ``size`` scales the text."""
    if not lines:
        return
    h, w = img.shape[:2]
    scale = 0.5 * h / 720 * 1.3 * size
    thick = max(1, int(round(h / 720 * 1.5 * size)))
    font = cv2.FONT_HERSHEY_SIMPLEX
    sizes = [cv2.getTextSize(text, font, scale, thick)[0] for text, _ in lines]
    line_h = int(max(sz[1] for sz in sizes) * 1.8)
    pad = line_h // 2
    box_w = min(w, max(sz[0] for sz in sizes) + 2 * pad)
    box_h = min(h, line_h * len(lines) + pad)
    y0 = 0 if corner == "left" else h - box_h
    roi = img[y0:y0 + box_h, 0:box_w]
    roi[:] = (roi.astype(np.uint16) * 2 // 5).astype(np.uint8)  # darken to 40 %
    for k, (text, rgb) in enumerate(lines):
        cv2.putText(img, text, (pad, y0 + (k + 1) * line_h), font, scale, rgb255(rgb), thick, cv2.LINE_AA)
