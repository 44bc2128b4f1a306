"""Random search scenarios of set-membership search (Ibenenthal et al., section V): obstacles, targets, decoys.

Targets and decoys share one motion model (state ``(x, y, psi)`` at constant speed ``s``):
``psi_{k+1} = psi_k + v_k``, ``v_k ~ U[-v_max, v_max]``, ``p_{k+1} = p_k + s T (cos psi_{k+1}, sin psi_{k+1})``.
A move that would leave the free area is redrawn (up to ``max_redraws`` times, then the heading is reversed, and if
that fails too the target waits), so every step stays within the speed bound ``s`` and inside the free area.

A decoy is detected only from inside its visibility cone: vertex at the decoy, half aperture ``lambda`` with the
aperture ``2 lambda ~ U[pi/15, pi/5]``, axis ``a = (sin g cos b, sin g sin b, cos g)`` with the azimuth
``b ~ U[0, 2 pi)`` and the tilt from the vertical ``g = 2 lambda`` (the paper's "elevation equal to the aperture").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from autonomy.sensing.scene import TargetTruth
from worlds.geometry import Building

__all__ = ["GroundMovers", "MoverConfig", "random_cuboids", "random_free_points", "random_movers"]


@dataclass(frozen=True, kw_only=True)
class MoverConfig:
    """Motion of targets and decoys.

    Attributes
    ----------
    speed : float
        Constant ground speed ``s`` (m/s), > 0; the paper's 5 km/h is 1.389 m/s.
    max_turn : float
        Bound ``v_max`` of the random heading change per step (rad), >= 0; the paper uses pi/5.
    dt : float
        Step ``T`` (s), > 0.
    max_redraws : int
        Redraws of a move that leaves the free area before reversing, >= 0.
    aperture_range : tuple[float, float]
        Range of the decoys' full cone aperture ``2 lambda`` (rad), 0 < low <= high < pi / 2.
    """

    speed: float = 5.0 / 3.6
    max_turn: float = np.pi / 5
    dt: float = 1.0
    max_redraws: int = 8
    aperture_range: tuple[float, float] = (np.pi / 15, np.pi / 5)

    def __post_init__(self) -> None:
        if not (self.speed > 0):
            raise ValueError(f"MoverConfig.speed must be > 0 m/s, got {self.speed}")
        if not (self.max_turn >= 0):
            raise ValueError(f"MoverConfig.max_turn must be >= 0 rad, got {self.max_turn}")
        if not (self.dt > 0):
            raise ValueError(f"MoverConfig.dt must be > 0 s, got {self.dt}")
        if int(self.max_redraws) != self.max_redraws or self.max_redraws < 0:
            raise ValueError(f"MoverConfig.max_redraws must be an integer >= 0, got {self.max_redraws}")
        lo, hi = self.aperture_range
        if not (0 < lo <= hi < np.pi / 2):
            raise ValueError(
                f"MoverConfig.aperture_range must satisfy 0 < low <= high < pi/2, got {self.aperture_range}"
            )


def random_cuboids(rng: np.random.Generator, area: tuple[float, float, float, float], n: int,
                   side_range: tuple[float, float] = (30.0, 70.0), height: float = 100.0,
                   clearance: float = 10.0, max_tries: int = 1000) -> list[Building]:
    """``n`` axis-aligned cuboid buildings with sides ~ U[side_range] (m) inside ``area`` = (x0, y0, x1, y1) m,
    at least ``clearance`` m apart from each other and from the area's border."""
    x0, y0, x1, y1 = area
    out: list[Building] = []
    polys: list[BaseGeometry] = []
    for _ in range(max_tries):
        if len(out) == n:
            break
        sx, sy = rng.uniform(*side_range, size=2)
        cx = rng.uniform(x0 + clearance + sx / 2, x1 - clearance - sx / 2)
        cy = rng.uniform(y0 + clearance + sy / 2, y1 - clearance - sy / 2)
        b = Building.cuboid((cx, cy), (sx, sy, height), name=f"obstacle{len(out)}")
        p = shapely.Polygon(b.footprint)
        if all(p.distance(q) >= clearance for q in polys):
            out.append(b)
            polys.append(p)
    if len(out) < n:
        raise ValueError(f"could not place {n} obstacles of sides {side_range} m in {area}")
    return out


def random_free_points(rng: np.random.Generator, free_area: BaseGeometry, n: int, margin: float = 0.0,
                       max_tries: int = 100000) -> np.ndarray:
    """(n, 2) points (m) drawn uniformly in ``free_area`` at least ``margin`` m inside it."""
    region = free_area.buffer(-margin) if margin > 0 else free_area
    if region.is_empty:
        raise ValueError(f"no free point at margin {margin} m")
    x0, y0, x1, y1 = region.bounds
    pts: list[np.ndarray] = []
    for _ in range(max_tries):
        if len(pts) == n:
            break
        p = rng.uniform([x0, y0], [x1, y1])
        if shapely.contains_xy(region, p[0], p[1]):
            pts.append(p)
    if len(pts) < n:
        raise ValueError(f"could not draw {n} free points")
    return np.array(pts).reshape(n, 2)


class GroundMovers:
    """Targets and decoys moving at random in the free area (module docstring).

    Parameters
    ----------
    config : MoverConfig
        Motion parameters.
    free_area : BaseGeometry
        Where they may be (m).
    p_xy : np.ndarray
        (M, 2) initial positions (m), inside ``free_area``.
    heading : np.ndarray
        (M,) initial headings (rad).
    kind : tuple[str, ...]
        ``"car"`` or ``"decoy"`` per mover.
    cone_axis_W : np.ndarray | None
        (M, 3) unit cone axes (decoys; any unit vector for cars).
    cone_half_angle : np.ndarray | None
        (M,) half apertures (rad); cars get ``pi`` (seen from everywhere).
    """

    def __init__(self, config: MoverConfig, free_area: BaseGeometry, p_xy: np.ndarray, heading: np.ndarray,
                 kind: tuple[str, ...], cone_axis_W: np.ndarray | None = None,
                 cone_half_angle: np.ndarray | None = None):
        self.config = config
        self.free_area = free_area
        shapely.prepare(self.free_area)
        self.p_xy = np.array(p_xy, dtype=float).reshape(-1, 2)
        self.heading = np.array(heading, dtype=float).reshape(-1)
        self.kind = tuple(kind)
        m = len(self.p_xy)
        if len(self.heading) != m or len(self.kind) != m:
            raise ValueError(f"GroundMovers needs {m} headings and kinds, got {len(self.heading)}, {len(self.kind)}")
        if not np.all(shapely.contains_xy(free_area, self.p_xy[:, 0], self.p_xy[:, 1])):
            raise ValueError("GroundMovers initial positions must lie inside the free area")
        self.cone_axis_W = None if cone_axis_W is None else np.array(cone_axis_W, dtype=float).reshape(m, 3)
        self.cone_half_angle = None if cone_half_angle is None else np.array(cone_half_angle, dtype=float).reshape(m)

    @property
    def is_target(self) -> np.ndarray:
        """(M,) bool: true targets (cars)."""
        return np.array([k == "car" for k in self.kind], dtype=bool)

    def step(self, rng: np.random.Generator) -> None:
        """Move every mover by one step (module docstring)."""
        cfg = self.config
        d = cfg.speed * cfg.dt
        for i in range(len(self.p_xy)):
            draws = list(rng.uniform(-cfg.max_turn, cfg.max_turn, size=cfg.max_redraws + 1)) + [np.pi]
            for v in draws:
                psi = self.heading[i] + v
                q = self.p_xy[i] + d * np.array([np.cos(psi), np.sin(psi)])
                if shapely.contains_xy(self.free_area, q[0], q[1]):
                    self.p_xy[i] = q
                    self.heading[i] = psi
                    break

    def truth(self) -> TargetTruth:
        """The movers as :class:`~autonomy.sensing.scene.TargetTruth` on the ground (z = 0)."""
        m = len(self.p_xy)
        v = self.config.speed * np.column_stack([np.cos(self.heading), np.sin(self.heading), np.zeros(m)])
        return TargetTruth(
            ids=np.arange(m), p_W=np.column_stack([self.p_xy, np.zeros(m)]), v_W=v, kind=self.kind,
            yaw=self.heading.copy(), cone_axis_W=self.cone_axis_W, cone_half_angle=self.cone_half_angle,
        )


def random_movers(rng: np.random.Generator, config: MoverConfig, free_area: BaseGeometry, n_targets: int,
                  n_decoys: int, margin: float = 2.0) -> GroundMovers:
    """Targets then decoys at uniform free positions with uniform headings and random decoy cones."""
    m = n_targets + n_decoys
    p = random_free_points(rng, free_area, m, margin=margin)
    heading = rng.uniform(-np.pi, np.pi, size=m)
    kind = ("car",) * n_targets + ("decoy",) * n_decoys
    axis = np.tile([0.0, 0.0, 1.0], (m, 1))
    half = np.full(m, np.pi)
    lo, hi = config.aperture_range
    for j in range(n_targets, m):
        lam = 0.5 * rng.uniform(lo, hi)
        beta = rng.uniform(0.0, 2.0 * np.pi)
        gamma = 2.0 * lam
        axis[j] = [np.sin(gamma) * np.cos(beta), np.sin(gamma) * np.sin(beta), np.cos(gamma)]
        half[j] = lam
    return GroundMovers(config, free_area, p, heading, kind, cone_axis_W=axis, cone_half_angle=half)
