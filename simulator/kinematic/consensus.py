"""Closed loop of paper 000 on kinematic UAVs: square-root cubature information filters fused by HCMCI consensus over
a switching ring, and fast MPC guidance with separation between same-altitude UAVs.

Each step of ``T`` seconds

1. the target moves along a scripted stop-and-go drive with turns (:data:`STOP_AND_GO`; the paper shows its path only
   in a figure);
2. every UAV measures (slant range, azimuth, angle from nadir) with its own noise ``R_j`` (paper 000's nadir radar);
3. the four SCIF nodes predict, compute their measurement information and run ``L`` HCMCI iterations over the ring
   1–3–2–4–1 with the links of the current step (case 2 cuts 1–3 for steps 150–200 and 1–4 for steps 300–350);
4. every UAV plans with its fast MPC on its own node's estimate, seeing the other UAVs' positions, and flies the
   first input for one step (Euler unicycle, the paper's model).

Each node starts from its own first measurement (the paper's ``h = 0`` start puts the estimate at the origin, km
away: see the notes) with position σ 5 m, velocity σ 2 m/s and acceleration σ 1 m/s².
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from autonomy.estimation.measurements import Measurement, NadirRadarModel
from autonomy.estimation.models import Singer
from autonomy.estimation.scif import SCIF
from autonomy.fusion.consensus import hcmci_step, ring_adjacency, without_links
from autonomy.guidance.fast_mpc import FastMpcConfig, FastMpcGuidance
from interfaces.state import OwnState, TargetEstimate, TeammateState

__all__ = ["STOP_AND_GO", "ConsensusLoopConfig", "ConsensusLoopResult", "target_drive", "run_consensus_loop"]

_D2R = np.pi / 180.0

STOP_AND_GO: tuple[tuple[float, float, float], ...] = (
    (10.0, 0.6, 0.0), (25.0, 0.0, 0.0), (15.0, 0.0, np.pi / 30), (20.0, 0.0, 0.0), (8.0, -0.75, 0.0),
    (12.0, 0.0, 0.0), (10.0, 0.8, 0.0), (15.0, 0.0, -np.pi / 30), (30.0, 0.0, 0.0), (15.0, 0.0, np.pi / 45),
    (40.0, 0.0, 0.0))
"""(duration s, along-track acceleration m/s², turn rate rad/s) pieces of the target's drive (200 s): pull away to
6 m/s, turns of 90° and 60°, a stop of 12 s, a pull-away to 8 m/s."""


def target_drive(steps: int, dt: float, p0: tuple[float, float] = (4500.0, -8.0), heading0: float = 0.0,
                 substeps: int = 10) -> np.ndarray:
    """(steps + 1, 6) Singer-layout states ``(x, vx, ax, y, vy, ay)`` every ``dt`` s along :data:`STOP_AND_GO`
    (speed never below 0; integrated with ``substeps`` sub-steps per ``dt``)."""
    h = dt / substeps
    x, y, psi, v = p0[0], p0[1], heading0, 0.0
    bounds = np.cumsum([s[0] for s in STOP_AND_GO])
    out = []
    for k in range(steps + 1):
        t = k * dt
        i = min(int(np.searchsorted(bounds, t, side="right")), len(STOP_AND_GO) - 1)
        a, w = STOP_AND_GO[i][1], STOP_AND_GO[i][2]
        if v <= 0.0 and a < 0:
            a = 0.0
        c, s = np.cos(psi), np.sin(psi)
        out.append([x, v * c, a * c - v * w * s, y, v * s, a * s + v * w * c])
        for _ in range(substeps):
            x += v * np.cos(psi) * h
            y += v * np.sin(psi) * h
            psi += w * h
            v = max(0.0, v + a * h)
    return np.array(out)


@dataclass(frozen=True, kw_only=True)
class ConsensusLoopConfig:
    """A run of paper 000 (defaults: case 1).

    Attributes
    ----------
    case : {1, 2}
        Case 2 changes UAV 1 and 3's tracking weights and cuts links 1–3 (steps 150–200) and 1–4 (steps 300–350).
    outages : bool
        Whether case 2 cuts its links (False: case 2's weights on the full ring, the paired control that isolates the
        outages' effect from the rest of case 2).
    steps : int
        Number of steps, >= 1 (the paper: 400).
    dt : float
        Step T, s.
    consensus_iterations : int
        HCMCI iterations L, >= 1.
    ring : tuple of int
        Ring order (0-based) of the consensus graph.
    altitudes : tuple of float
        UAV altitudes, m.
    initial : tuple of (x, y, θ)
        UAV start states, m and rad.
    noise : tuple of (σ²_r, σ²_az, σ²_ϕ)
        Diagonals of the radars' R_j as printed (m², rad², rad²).
    singer_alpha, singer_sigma_a : float
        Target model (1/s, m/s²).
    mpc : FastMpcConfig
        Shared fast MPC settings; the per-UAV weights come from ``weights``.
    weights : tuple of (w_v, w_o, w_x, w_y)
        Per UAV, case 1.
    """

    case: Literal[1, 2] = 1
    outages: bool = True
    steps: int = 400
    dt: float = 0.5
    consensus_iterations: int = 3
    ring: tuple[int, ...] = (0, 2, 1, 3)
    altitudes: tuple[float, ...] = (100.0, 100.0, 110.0, 110.0)
    initial: tuple[tuple[float, float, float], ...] = ((4510.0, -8.0, 2.0), (4490.0, -8.0, 2.0),
                                                      (4509.0, -8.0, 2.0), (4491.0, -8.0, 2.0))
    noise: tuple[tuple[float, float, float], ...] = ((1.0, 0.5 * _D2R, 0.5 * _D2R), (2.5, 0.3 * _D2R, 0.6 * _D2R),
                                                     (1.5, 0.1 * _D2R, 0.5 * _D2R), (1.0, 0.1 * _D2R, 0.5 * _D2R))
    singer_alpha: float = 0.6
    singer_sigma_a: float = 0.67
    mpc: FastMpcConfig = field(default_factory=lambda: FastMpcConfig(v_max=40.0, omega_max=5.0,
                                                                     separation_distance=10.0))
    weights: tuple[tuple[float, float, float, float], ...] = ((5, 180, 0.5, 0.5), (4, 180, 0.4, 0.5),
                                                              (5, 180, 0.5, 0.5), (4, 180, 0.4, 0.5))

    def __post_init__(self) -> None:
        if self.case not in (1, 2):
            raise ValueError(f"ConsensusLoopConfig.case must be 1 or 2, got {self.case!r}")
        if self.steps < 1 or self.consensus_iterations < 1:
            raise ValueError(f"ConsensusLoopConfig.steps and consensus_iterations must be >= 1, got {self.steps}, "
                             f"{self.consensus_iterations}")
        n = len(self.initial)
        if not (len(self.altitudes) == len(self.noise) == len(self.weights) == n == len(self.ring)):
            raise ValueError("ConsensusLoopConfig: altitudes, noise, weights, initial and ring need one entry per UAV")

    def outage_links(self, step: int) -> list[tuple[int, int]]:
        """Links (0-based) down at ``step`` (1-based)."""
        if self.case != 2 or not self.outages:
            return []
        return [link for link, lo, hi in (((0, 2), 150, 200), ((0, 3), 300, 350)) if lo <= step < hi]

    def uav_weights(self, j: int) -> tuple[float, float, float, float]:
        """(w_v, w_o, w_x, w_y) of UAV ``j`` in this case."""
        if self.case == 2 and j in (0, 2):
            return (5, 180, 0.2, 0.2)
        return self.weights[j]


@dataclass(frozen=True, kw_only=True)
class ConsensusLoopResult:
    """Time series of a run (K steps, N UAVs).

    Attributes
    ----------
    t : np.ndarray
        (K,) times, s.
    target : np.ndarray
        (K, 2) true target positions, m.
    estimates : np.ndarray
        (K, N, 2) each node's position estimate after consensus, m.
    error : np.ndarray
        (K, N) position errors ‖p̂_j − p‖, m.
    consensus_error : np.ndarray
        (K, N) distance of each node's estimate from the mean of all nodes' estimates, m.
    uav : np.ndarray
        (K + 1, N, 3) UAV states (x, y, θ).
    inputs : np.ndarray
        (K, N, 2) applied (v, ω).
    separation : np.ndarray
        (K + 1, P) distances of the same-altitude pairs, m.
    pairs : tuple of (int, int)
        The same-altitude pairs of ``separation``.
    outage : np.ndarray
        (K,) bool, a link was down.
    step_time_s : np.ndarray
        (K, N) wall time per UAV and step of its fast MPC, its SCIF information step and its share of the consensus, s.
    """

    t: np.ndarray
    target: np.ndarray
    estimates: np.ndarray
    error: np.ndarray
    consensus_error: np.ndarray
    uav: np.ndarray
    inputs: np.ndarray
    separation: np.ndarray
    pairs: tuple[tuple[int, int], ...]
    outage: np.ndarray
    step_time_s: np.ndarray


def _fix(z: np.ndarray, p: np.ndarray) -> np.ndarray:
    """Ground position (2,) from a nadir radar measurement ``z = (r, az, ϕ)`` taken at ``p`` (3,)."""
    rho = z[0] * np.sin(z[2])
    return p[:2] + rho * np.array([np.cos(z[1]), np.sin(z[1])])


def run_consensus_loop(cfg: ConsensusLoopConfig, rng: np.random.Generator) -> ConsensusLoopResult:
    """Run ``cfg`` with measurement noise from ``rng``."""
    n, dt = len(cfg.initial), cfg.dt
    truth = target_drive(cfg.steps, dt)
    model = Singer(alpha=cfg.singer_alpha, sigma_a=cfg.singer_sigma_a, discretisation="euler")
    guides = []
    for j in range(n):
        w_v, w_o, w_x, w_y = cfg.uav_weights(j)
        mpc = FastMpcConfig(**{**{f: getattr(cfg.mpc, f) for f in cfg.mpc.__dataclass_fields__},
                               "w_v": w_v, "w_o": w_o, "w_x": w_x, "w_y": w_y, "altitude": cfg.altitudes[j]})
        guides.append(FastMpcGuidance(mpc))
    R = [np.diag(r) for r in cfg.noise]
    R_chol = [np.sqrt(np.asarray(r, dtype=float)) for r in cfg.noise]
    ring = ring_adjacency(cfg.ring)
    pairs = tuple((a, b) for a in range(n) for b in range(a + 1, n) if cfg.altitudes[a] == cfg.altitudes[b])
    X = np.array(cfg.initial, dtype=float)
    speed = np.zeros(n)
    nodes: list[SCIF] | None = None
    rows: dict[str, list] = {k: [] for k in ("t", "tgt", "est", "err", "cons", "uav", "u", "sep", "out", "time")}
    rows["uav"].append(X.copy())
    rows["sep"].append([float(np.hypot(*(X[a, :2] - X[b, :2]))) for a, b in pairs])
    for k in range(1, cfg.steps + 1):
        t = k * dt
        xt = truth[k]
        times = np.zeros(n)
        meas, models = [], []
        for j in range(n):
            p = np.array([X[j, 0], X[j, 1], cfg.altitudes[j]])
            mm = NadirRadarModel(model.layout, p)
            z = mm.h(xt) + R_chol[j] * rng.normal(size=3)
            meas.append(Measurement(z=z, R=R[j], t_meas=t, sensor_id=j, p_sensor_W=p))
            models.append(mm)
        down = cfg.outage_links(k)
        if nodes is None:
            P0 = np.diag([25.0, 4.0, 1.0, 25.0, 4.0, 1.0])
            nodes = []
            for j in range(n):
                xy = _fix(meas[j].z, meas[j].p_sensor_W)
                nodes.append(SCIF(model, np.array([xy[0], 0.0, 0.0, xy[1], 0.0, 0.0]), P0, t))
        else:
            t0 = time.perf_counter()
            hcmci_step(nodes, meas, without_links(ring, down), cfg.consensus_iterations, models=models)
            times += (time.perf_counter() - t0) / n
        est = np.array([nd.x[[0, 3]] for nd in nodes])
        p_true = xt[[0, 3]]
        rows["t"].append(t)
        rows["tgt"].append(p_true)
        rows["est"].append(est)
        rows["err"].append(np.linalg.norm(est - p_true, axis=1))
        rows["cons"].append(np.linalg.norm(est - est.mean(axis=0), axis=1))
        rows["out"].append(bool(down))
        # guidance: each UAV on its own node's estimate, seeing the others' current states
        U = np.zeros((n, 2))
        for j in range(n):
            nd = nodes[j]
            v_vec = np.array([speed[j] * np.cos(X[j, 2]), speed[j] * np.sin(X[j, 2]), 0.0])
            own = OwnState(t=t, p_W=np.array([X[j, 0], X[j, 1], cfg.altitudes[j]]), v_W=v_vec, yaw=float(X[j, 2]))
            target = TargetEstimate(t=t, p_W=nd.x[[0, 3]], v_W=nd.x[[1, 4]])
            mates = [TeammateState(id=m, t=t, p_W=np.array([X[m, 0], X[m, 1], cfg.altitudes[m]]),
                                   v_W=np.array([speed[m] * np.cos(X[m, 2]), speed[m] * np.sin(X[m, 2]), 0.0]),
                                   yaw=float(X[m, 2]), plan_p_W=guides[m].planned_path(), plan_dt=dt)
                     for m in range(n) if m != j]
            t0 = time.perf_counter()
            sp = guides[j].command(own, target, mates, t)
            times[j] += time.perf_counter() - t0
            U[j] = sp.speed, sp.heading_rate
        X = X + dt * np.column_stack([U[:, 0] * np.cos(X[:, 2]), U[:, 0] * np.sin(X[:, 2]), U[:, 1]])
        speed = U[:, 0].copy()
        rows["u"].append(U)
        rows["uav"].append(X.copy())
        rows["sep"].append([float(np.hypot(*(X[a, :2] - X[b, :2]))) for a, b in pairs])
        rows["time"].append(times)
    return ConsensusLoopResult(
        t=np.array(rows["t"]), target=np.array(rows["tgt"]), estimates=np.array(rows["est"]),
        error=np.array(rows["err"]), consensus_error=np.array(rows["cons"]), uav=np.array(rows["uav"]),
        inputs=np.array(rows["u"]), separation=np.array(rows["sep"]).reshape(len(rows["sep"]), len(pairs)),
        pairs=pairs, outage=np.array(rows["out"]), step_time_s=np.array(rows["time"]))
