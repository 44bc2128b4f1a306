"""Sequential distributed one-step MPC for set-membership search (Ibenenthal et al., section IV).

UAVs fly at constant speed ``V`` and altitude; UAV ``i`` turns its heading by ``u`` every step ``T``:
``psi_{k+1} = psi_k + u``, ``p_{k+1} = p_k + V T (cos psi_{k+1}, sin psi_{k+1})``. Over the horizon ``h`` the
control is held (``u_{k+1} = ... = u_{k+h} = u``) and ``u`` is chosen on a grid of ``n_controls`` values in
``[-u_max, u_max]`` (the paper's gradient search over a one-dimensional, non-smooth cost is replaced by an
exhaustive grid, which finds the same or a better minimum). The cost is (eq. 19)

    J(u) = J_m(u) + alpha_d J_d(u) + alpha_s J_s(u),

with every area normalised by ``phi(X_s)`` and every distance by ``L = sqrt(phi(X_s))`` so the terms are
comparable:

- ``J_m = [phi(X^P_{k+h}) + alpha_m phi(Xbar^P_{k+h})] / phi(X_s)`` (eq. 20), the sets predicted without new
  detections (only ``S_3``): dilated by ``v_max T`` and stripped of the regions observed by this UAV and by the
  neighbours that decided earlier in this step;
- ``J_d = [phi(X_j) d(X_j, p_{k+h}) + phi(Xbar) d(Xbar, p_{k+h})] / (phi(X_s) L)`` (eq. 21), ``d`` the distance from
  the point to the set (0 inside). The paper selects ``j = argmin_l phi(X_l) d(p_k, X_l)``, which favours *small*
  components; its stated intent (drive the UAV to the closest set with a large area) is implemented here as
  ``j = argmin_l d(p_k, X_l) / phi(X_l)`` (``SearchConfig.component_choice = "near_large"``, the default;
  ``"paper"`` takes the paper's formula as printed);
- ``J_s = 1/2 [1 - tanh((d_obs(p_{k+h}) - alpha_s1) / alpha_s2)]`` (eq. 22), ``d_obs`` the horizontal distance to
  the nearest obstacle footprint.

Predicted sets (fast form). With ``D_k = (S (+) B(r)) n X_s`` and ``r = v_max T``, one step of the prediction is
``S_{k+1} = D_k \\ F_{k+1}``, and ``(D \\ F) (+) B(r) c (D (+) B(r)) \\ (F (-) B(r))`` (a point at distance <= r from
``D \\ F`` cannot have its whole r-disc inside ``F``). So the two-step prediction is over-approximated by
``D_2 \\ ((F_1 (-) B(r)) U F_2)`` with ``D_2`` the twice-dilated set, computed once per UAV and step: each
candidate costs a single difference against small polygons. All work is clipped to a window around the UAV that
contains every region any candidate can observe, grown by the dilations, so area differences between candidates
are exact up to the over-approximation above.

Beyond the paper, ``SearchConfig.tail_steps > 0`` measures the candidate's remaining sets ``tail_steps`` steps
later, grown without new observations, which charges a candidate for the frontier it leaves behind (the paper's
cost is ``tail_steps = 0``, the default).

Beyond the paper, obstacle clearance holds by construction (``SearchConfig.loiter_safety``, on by default; the
cost above is unchanged). The soft term ``J_s`` only discourages the end of the held-control rollout from
approaching an obstacle; with a bounded turn a UAV can still reach a state from which every admissible turn
sequence hits one (the reproduction measured approaches to 0 m with ``J_s`` alone). So only candidates whose
*next* state — the one actually flown, ``(p_{k+1}, psi + u)`` — is safe in the sense of
:mod:`autonomy.guidance.search.safety` are admissible: the full-left or the full-right maximum-turn loiter from
that state keeps ``d_col + clearance_margin`` from every obstacle footprint. The cost is still evaluated on the
held-control rollout; admissibility only filters which grid values may win. If the current state is safe, its
own loiter turn ``+-u_max`` (always on the grid) is admissible, so by induction every flown chord keeps the
clearance for all time from a safe start (the simulator's kinematic search mission draws its
starts until safe). From an unsafe start with no admissible candidate the planner takes the candidate of largest
clearance and flags the decision (``SearchDecision.safe`` is False).

Team order (section IV-B): within each connected component of the communication graph the lowest index decides
first, then the others in breadth-first order, each one using the plans of its direct neighbours that decided
before it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Literal, Protocol

import numpy as np
import shapely
from shapely.geometry.base import BaseGeometry

from autonomy.estimation.setmem import polygons as pg
from autonomy.estimation.setmem.estimator import SetEstimate
from autonomy.guidance.search.safety import LoiterSafety
from autonomy.sensing.scene import SensorPose
from worlds.geometry import Building

__all__ = ["PlannedPath", "RegionModel", "SearchConfig", "SearchDecision", "SearchPlanner", "decision_order",
           "yaw_quaternion"]


class RegionModel(Protocol):
    """What the planner needs of the sensor: the ground region observed from a pose."""

    def observed_region(self, pose: SensorPose) -> BaseGeometry:
        """Observed ground region (m)."""
        ...


@dataclass(frozen=True, kw_only=True)
class SearchConfig:
    """Parameters of the search MPC (defaults: the paper's section V).

    Attributes
    ----------
    speed : float
        Constant horizontal speed ``V`` (m/s), > 0; the paper's 60 km/h is 16.67 m/s.
    altitude : float
        Flight altitude (m), > 0.
    dt : float
        Decision step ``T`` (s), > 0.
    max_turn : float
        Bound ``u_max`` on the heading change per step (rad), in (0, pi].
    n_controls : int
        Number of grid values of ``u``, odd, >= 3.
    horizon : int
        Prediction horizon ``h`` (steps), >= 1.
    max_target_speed : float
        Bound on the targets' speed used in the prediction (m/s), > 0.
    alpha_m, alpha_d, alpha_s : float
        Weights of the undetected-set area, the distance term and the obstacle risk (dimensionless), >= 0.
    alpha_s1, alpha_s2 : float
        Centre and width of the obstacle-risk transition (m); ``alpha_s1 - alpha_s2 >= d_col`` and ``alpha_s2 > 0``.
    d_col : float
        Distance to an obstacle counted as a collision (m), >= 0.
    window_margin : float
        Extra margin of the planning window (m), >= 0.
    tail_steps : int
        Extra steps, >= 0, over which the predicted sets keep growing *without* new observations before their area
        is measured (0: the paper's ``J_m`` at ``k + h``). A positive value charges a candidate for the regrowth
        of the frontier it leaves behind: ``phi((S_{k+h} (+) B(tail r)) n X_s)``.
    altitude_gain : float
        Proportional gain of the vertical velocity set-point on the altitude error (1/s), >= 0.
    loiter_safety : bool
        Admit only controls whose next state has a safe maximum-turn loiter (module docstring; beyond the paper).
        False: the paper's planner, clearance left to ``J_s``.
    clearance_margin : float
        Margin over ``d_col`` the safe loiters keep from every obstacle (m), >= 0.
    component_choice : {"near_large", "paper"}
        Which component of ``X`` the distance term ``J_d`` pulls towards: ``argmin d / phi`` (the paper's stated
        intent, the default) or ``argmin phi d`` (its formula as printed); module docstring.
    """

    speed: float = 60.0 / 3.6
    altitude: float = 100.0
    dt: float = 1.0
    max_turn: float = np.pi / 4
    n_controls: int = 7
    horizon: int = 2
    max_target_speed: float = 5.0 / 3.6
    alpha_m: float = 1.3
    alpha_d: float = 4.5
    alpha_s: float = 3500.0
    alpha_s1: float = 10.0
    alpha_s2: float = 3.0
    d_col: float = 5.0
    window_margin: float = 10.0
    tail_steps: int = 0
    altitude_gain: float = 1.0
    loiter_safety: bool = True
    clearance_margin: float = 1.0
    component_choice: Literal["near_large", "paper"] = "near_large"

    def __post_init__(self) -> None:
        for name in ("speed", "altitude", "dt", "max_target_speed", "alpha_s2"):
            if not (getattr(self, name) > 0):
                raise ValueError(f"SearchConfig.{name} must be > 0, got {getattr(self, name)}")
        for name in ("alpha_m", "alpha_d", "alpha_s", "d_col", "window_margin", "altitude_gain",
                     "clearance_margin"):
            if not (getattr(self, name) >= 0):
                raise ValueError(f"SearchConfig.{name} must be >= 0, got {getattr(self, name)}")
        if not (0 < self.max_turn <= np.pi):
            raise ValueError(f"SearchConfig.max_turn must be in (0, pi] rad, got {self.max_turn}")
        if int(self.n_controls) != self.n_controls or self.n_controls < 3 or self.n_controls % 2 == 0:
            raise ValueError(f"SearchConfig.n_controls must be an odd integer >= 3, got {self.n_controls}")
        if self.component_choice not in ("near_large", "paper"):
            raise ValueError(f"SearchConfig.component_choice must be near_large|paper, got {self.component_choice!r}")
        if int(self.tail_steps) != self.tail_steps or self.tail_steps < 0:
            raise ValueError(f"SearchConfig.tail_steps must be an integer >= 0, got {self.tail_steps}")
        if int(self.horizon) != self.horizon or self.horizon < 1:
            raise ValueError(f"SearchConfig.horizon must be an integer >= 1, got {self.horizon}")
        if self.alpha_s1 - self.alpha_s2 < self.d_col:
            raise ValueError(
                f"SearchConfig needs alpha_s1 - alpha_s2 >= d_col, got {self.alpha_s1} - {self.alpha_s2} < {self.d_col}"
            )

    def controls(self) -> np.ndarray:
        """Grid of heading changes (rad), ordered by increasing ``|u|`` so ties keep the heading."""
        u = np.linspace(-self.max_turn, self.max_turn, self.n_controls)
        return u[np.argsort(np.abs(u), kind="stable")]


@dataclass(frozen=True, kw_only=True)
class PlannedPath:
    """Positions and headings a UAV will have at steps ``k+1 .. k+h``.

    Attributes
    ----------
    p_xy : np.ndarray
        (h, 2) horizontal positions (m).
    yaw : np.ndarray
        (h,) headings (rad).
    """

    p_xy: np.ndarray
    yaw: np.ndarray

    def __post_init__(self) -> None:
        p = np.array(self.p_xy, dtype=float).reshape(-1, 2)
        y = np.array(self.yaw, dtype=float).reshape(-1)
        if len(y) != len(p) or not (np.all(np.isfinite(p)) and np.all(np.isfinite(y))):
            raise ValueError(f"PlannedPath needs finite (h, 2) positions and (h,) headings, got {p.shape}, {y.shape}")
        object.__setattr__(self, "p_xy", p)
        object.__setattr__(self, "yaw", y)


@dataclass(frozen=True, kw_only=True)
class SearchDecision:
    """The heading change chosen by one UAV and what it was chosen on.

    Attributes
    ----------
    u : float
        Heading change for the next step (rad).
    path : PlannedPath
        Resulting positions and headings over the horizon.
    cost : float
        ``J(u)`` of the chosen control (dimensionless).
    terms : dict[str, float]
        ``"J_m"``, ``"J_d"``, ``"J_s"`` of the chosen control.
    costs : np.ndarray
        ``J`` of every candidate, in the order of ``controls``.
    controls : np.ndarray
        The candidate heading changes (rad).
    admissible : np.ndarray
        (n_controls,) bool: the candidate's next state is safe (all True without ``loiter_safety``).
    clearance : float
        Loiter clearance of the chosen next state (m); ``inf`` without obstacles or without ``loiter_safety``.
    safe : bool
        The chosen candidate is admissible; False only when none was (possible only from an unsafe state).
    """

    u: float
    path: PlannedPath
    cost: float
    terms: dict[str, float]
    costs: np.ndarray
    controls: np.ndarray
    admissible: np.ndarray
    clearance: float = np.inf
    safe: bool = True


def yaw_quaternion(yaw: float) -> np.ndarray:
    """Quaternion (x, y, z, w) of a rotation by ``yaw`` rad about +z."""
    return np.array([0.0, 0.0, np.sin(yaw / 2.0), np.cos(yaw / 2.0)])


def rollout(p_xy: np.ndarray, heading: float, u: float, config: SearchConfig) -> PlannedPath:
    """Unicycle positions and headings over the horizon with ``u`` held (module docstring)."""
    k = np.arange(1, config.horizon + 1)
    yaw = heading + k * u
    step = config.speed * config.dt * np.column_stack([np.cos(yaw), np.sin(yaw)])
    return PlannedPath(p_xy=np.asarray(p_xy, dtype=float)[:2] + np.cumsum(step, axis=0), yaw=yaw)


def decision_order(adjacency: np.ndarray) -> list[int]:
    """Order of decision: per connected component, lowest index first, then breadth-first over the links."""
    A = np.asarray(adjacency, dtype=bool)
    n = A.shape[0]
    seen = np.zeros(n, dtype=bool)
    order: list[int] = []
    for root in range(n):
        if seen[root]:
            continue
        queue = [root]
        seen[root] = True
        while queue:
            i = queue.pop(0)
            order.append(i)
            for j in np.flatnonzero(A[i] & ~seen):
                seen[j] = True
                queue.append(int(j))
    return order


class SearchPlanner:
    """Sequential one-step MPC of the search (module docstring).

    Parameters
    ----------
    config : SearchConfig
        Parameters.
    sensor : RegionModel
        Gives the observed region of a pose (e.g. a :class:`~autonomy.sensing.box_sensor.BoxSensor`).
    free_area : BaseGeometry
        ``X_s`` (m).
    obstacles : Sequence[Building]
        Obstacles of the risk term and of the safe-loiter constraint.
    footprint_radius : float
        Radius (m) of a disc around the UAV containing every region it can observe; with the box sensor this is
        the half-diagonal of the footprint, ``sqrt(2) h tan(opening / 2)``.
    keep_in : BaseGeometry | None
        Area the UAVs must stay inside (m), enforced by the safe-loiter constraint like an obstacle; ``None``
        (the paper's missions) leaves them free to fly beyond the search area.
    """

    def __init__(self, config: SearchConfig, sensor: RegionModel, free_area: BaseGeometry,
                 obstacles: Sequence[Building] = (), footprint_radius: float = 60.0,
                 keep_in: BaseGeometry | None = None):
        if not (footprint_radius > 0):
            raise ValueError(f"SearchPlanner.footprint_radius must be > 0 m, got {footprint_radius}")
        self.config = config
        self.sensor = sensor
        self.free_area = pg.as_polygonal(free_area)
        self.area0 = pg.area(self.free_area)
        self.length0 = float(np.sqrt(self.area0))
        self.footprint_radius = float(footprint_radius)
        self._obstacles = (
            shapely.union_all([shapely.Polygon(b.footprint) for b in obstacles]) if obstacles else pg.EMPTY
        )
        shapely.prepare(self.free_area)
        self.safety = LoiterSafety(
            speed=config.speed, dt=config.dt, max_turn=config.max_turn, required=config.d_col + config.clearance_margin,
            obstacles=self._obstacles, keep_in=keep_in,
        ) if config.loiter_safety else None
        self._memo: dict[tuple[float, float, float], BaseGeometry] | None = None

    def region(self, p_xy: np.ndarray, yaw: float) -> BaseGeometry:
        """Observed region from a horizontal position (m) and heading (rad) at the flight altitude.

        Within :meth:`plan_team` the regions are remembered by pose: a UAV that decides after a neighbour reuses the
        regions of the neighbour's chosen path, computed when the neighbour scored it (the same geometry)."""
        key = (float(p_xy[0]), float(p_xy[1]), float(yaw))
        if self._memo is not None and key in self._memo:
            return self._memo[key]
        pose = SensorPose(p_W=np.array([p_xy[0], p_xy[1], self.config.altitude]), q_WB=yaw_quaternion(yaw))
        out = pg.as_polygonal(self.sensor.observed_region(pose))
        if self._memo is not None:
            self._memo[key] = out
        return out

    def obstacle_risk(self, p_xy: np.ndarray) -> np.ndarray:
        """``J_s`` (eq. 22) at points (N, 2) m; 0 without obstacles."""
        p = np.asarray(p_xy, dtype=float).reshape(-1, 2)
        if self._obstacles.is_empty:
            return np.zeros(len(p))
        d = pg.distance_to(self._obstacles, p)
        cfg = self.config
        return 0.5 * (1.0 - np.tanh((d - cfg.alpha_s1) / cfg.alpha_s2))

    def _distance_term(self, est: SetEstimate, p_now: np.ndarray, p_end: np.ndarray) -> np.ndarray:
        a0, L = self.area0, self.length0
        out = np.zeros(len(p_end))
        comps = pg.components(est.X)
        if comps:
            d_now = np.array([float(c.distance(shapely.Point(p_now))) for c in comps])
            areas = np.array([c.area for c in comps])
            if self.config.component_choice == "paper":
                j = int(np.argmin(areas * d_now))
            else:
                j = int(np.argmin(d_now / np.maximum(areas, 1e-9)))
            out += areas[j] * pg.distance_to(comps[j], p_end) / (a0 * L)
        if not est.Xbar.is_empty:
            out += est.area_Xbar * pg.distance_to(est.Xbar, p_end) / (a0 * L)
        return out

    def _remaining_area(self, D: BaseGeometry, G: BaseGeometry) -> float:
        """Area (m^2) of ``D \\ G``, grown over ``tail_steps`` more steps when asked (config docstring)."""
        if D.is_empty:
            return 0.0
        tail = self.config.tail_steps
        if tail == 0:
            return pg.area(D) - pg.area(shapely.intersection(D, G))
        r = tail * self.config.max_target_speed * self.config.dt
        S = pg.as_polygonal(shapely.difference(D, G))
        return pg.area(pg.intersection_all([pg.dilate(S, r, 1), self.free_area]))

    def decide(self, p_xy: np.ndarray, heading: float, estimate: SetEstimate,
               decided: Sequence[PlannedPath] = ()) -> SearchDecision:
        """Heading change minimising ``J`` for a UAV at ``p_xy`` (m) with ``heading`` (rad), given its sets and the
        plans of the neighbours that already decided this step."""
        cfg = self.config
        p0 = np.asarray(p_xy, dtype=float)[:2]
        h = cfg.horizon
        r = cfg.max_target_speed * cfg.dt
        reach = cfg.speed * cfg.dt * h + self.footprint_radius
        half = reach + (h + 1 + 2 * cfg.tail_steps) * r / np.cos(np.pi / 8) + cfg.window_margin
        window = shapely.box(p0[0] - half, p0[1] - half, p0[0] + half, p0[1] + half)
        # candidate-independent parts: the h-times dilated local sets and the neighbours' erased regions
        D = {}
        for name, S in (("X", estimate.X), ("Xbar", estimate.Xbar)):
            S = pg.intersection_all([S, window])
            for _ in range(h):
                S = pg.intersection_all([pg.dilate(S, r), self.free_area])
            D[name] = S
        erased_nb = []
        for path in decided:
            for k in range(min(h, len(path.yaw))):
                F = self.region(path.p_xy[k], float(path.yaw[k]))
                erased_nb.append(F.buffer(-r * (h - 1 - k), quad_segs=2) if k < h - 1 else F)
        G_nb = pg.union_all(erased_nb)
        if not G_nb.is_empty:
            D = {name: pg.as_polygonal(shapely.difference(S, G_nb)) for name, S in D.items()}
        controls = cfg.controls()
        paths = [rollout(p0, heading, float(u), cfg) for u in controls]
        Jm = np.zeros(len(controls))
        for c, path in enumerate(paths):
            erased = []
            for k in range(h):
                F = self.region(path.p_xy[k], float(path.yaw[k]))
                erased.append(F.buffer(-r * (h - 1 - k), quad_segs=2) if k < h - 1 else F)
            G = pg.union_all(erased)
            aX, aXb = (self._remaining_area(D[name], G) for name in ("X", "Xbar"))
            Jm[c] = (aX + cfg.alpha_m * aXb) / self.area0
        p_end = np.array([path.p_xy[-1] for path in paths])
        Jd = self._distance_term(estimate, p0, p_end)
        Js = self.obstacle_risk(p_end)
        J = Jm + cfg.alpha_d * Jd + cfg.alpha_s * Js
        clearance = np.full(len(controls), np.inf)
        if self.safety is not None and self.safety.active:
            clearance = self.safety.clearance(np.array([path.p_xy[0] for path in paths]),
                                              np.array([path.yaw[0] for path in paths]))
        admissible = self.safety.admits(clearance) if self.safety is not None else np.ones(len(J), dtype=bool)
        safe = bool(admissible.any())
        best = int(np.argmin(np.where(admissible, J, np.inf))) if safe else int(np.argmax(clearance))
        return SearchDecision(
            u=float(controls[best]), path=paths[best], cost=float(J[best]),
            terms={"J_m": float(Jm[best]), "J_d": float(Jd[best]), "J_s": float(Js[best])},
            costs=J, controls=controls, admissible=admissible, clearance=float(clearance[best]), safe=safe,
        )

    def plan_team(self, p_xy: np.ndarray, headings: np.ndarray, estimates: Sequence[SetEstimate],
                  adjacency: np.ndarray) -> list[SearchDecision]:
        """Decisions of every UAV (positions (N, 2) m, headings (N,) rad, each UAV's own sets, (N, N) links),
        taken sequentially in :func:`decision_order`; returned in UAV index order."""
        P = np.asarray(p_xy, dtype=float).reshape(-1, 2)
        A = np.asarray(adjacency, dtype=bool)
        n = len(P)
        if A.shape != (n, n) or len(estimates) != n or len(headings) != n:
            raise ValueError(
                f"plan_team needs matching sizes, got {P.shape}, {A.shape}, {len(estimates)}, {len(headings)}"
            )
        out: list[SearchDecision | None] = [None] * n
        self._memo = {}
        try:
            for i in decision_order(A):
                decided = [out[j].path for j in range(n) if j != i and A[i, j] and out[j] is not None]
                out[i] = self.decide(P[i], float(headings[i]), estimates[i], decided)
        finally:
            self._memo = None
        return [d for d in out if d is not None]
