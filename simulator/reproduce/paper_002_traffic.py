"""Paper 002 among traffic: what traffic costs the team, beside the paper (which assumes the target is given).

Campaigns of ``road_standoff_traffic`` (the flagship's UAVs and target car among 24 kinematic traffic cars), paired
by seed (run ``i`` of every campaign has the same seed, so the same town, routes and noise):

- ``traffic``: the world as shipped (radars reading a length class, gimballed cameras reading colour and body type,
  multi-target tracking, track association and fusion);
- ``alone``: the same world and team with the traffic cars removed (the same multi-target tracker): the like-for-like
  "without traffic" reference;
- ``same_look``: every car a red sedan, so no class reading tells the target apart: what identity remains from the
  cue and track continuity alone;
- Table II's columns among traffic (``radar_ekf``, ``radar_ukf``, ``radar_maekf``, ``radar_ecukf``): the paper's
  radar-only team (cameras removed; ``road_standoff``'s start and altitudes, where the shipped traffic world flies
  higher for its cameras), beside the same columns without traffic (``road_standoff``, single-target).

Verdict rules (the issue's acceptance, each as strict as stated): the fused position error and the NMPC standoff
error with traffic are within 1.5× of ``alone``: the upper end of the 95 % interval of the per-seed ratio is at most
1.5; every UAV keeps the target: the mean over seeds of each UAV's fused ``identity_fraction`` is at least 0.9, and
of its own (unfused) one too.
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import yaml

from simulator.reproduce.report import Finding, MeanCI, PaperReport, ReproContext, Table, mean_ci, write_paper_report
from simulator.reproduce.seeds import EVAL_SEED

if TYPE_CHECKING:
    from simulator.campaign.config import RunReport

__all__ = ["CAMPAIGNS", "ratio_within", "reproduce_traffic", "traffic_section"]

WORLD = "road_standoff_traffic"
NO_TRAFFIC_WORLD = "road_standoff"
UAVS = ("uav1", "uav2")
QUICK_DURATION_S = 12.0
MAX_RATIO = 1.5
MIN_IDENTITY = 0.9


def _flow(value: object) -> str:
    """``value`` as one line of YAML flow (a ``--set`` value)."""
    return yaml.safe_dump(value, default_flow_style=True, width=10**9).strip()


def _world_overrides(kind: str) -> tuple[str, ...]:
    """The ``--set`` overrides of campaign ``kind`` on ``road_standoff_traffic``."""
    from worlds.loader import load_world

    world = load_world(WORLD).world
    if kind == "traffic":
        return ()
    if kind == "alone":
        target = next(g for g in world.ground_vehicles if g.role == "target")
        sets = [f"ground_vehicles={_flow([target.model_dump(exclude_defaults=True)])}"]
        return tuple(sets + [f"uavs[{i}].autonomy.estimator.tracking.mode=multi" for i in range(len(world.uavs))])
    if kind == "same_look":
        return tuple(s for k in range(len(world.ground_vehicles))
                     for s in (f"ground_vehicles[{k}].colour=red", f"ground_vehicles[{k}].type=sedan"))
    if kind.startswith("radar_"):  # Table II's columns: the paper's radars and estimator settings (Table I)
        est = kind.removeprefix("radar_")
        paper = load_world(NO_TRAFFIC_WORLD).world
        sets = []
        for i, u in enumerate(world.uavs):
            radars = [s.model_dump(exclude_defaults=True) for s in u.sensors if s.type == "radar"]
            params = paper.uavs[i].autonomy.estimator.params
            sets += [f"uavs[{i}].sensors={_flow(radars)}", f"uavs[{i}].autonomy.estimator.type={est}",
                     f"uavs[{i}].autonomy.estimator.params={_flow(params)}",
                     f"uavs[{i}].initial={_flow(paper.uavs[i].initial.model_dump(mode='json'))}",
                     f"uavs[{i}].autonomy.guidance.altitude={paper.uavs[i].autonomy.guidance.altitude}"]
        return tuple(sets)
    raise ValueError(f"unknown traffic campaign {kind!r}")


@dataclass(frozen=True)
class Campaign:
    """One campaign: its name, world and overrides."""

    name: str
    world: str
    overrides: tuple[str, ...]


def _campaigns() -> tuple[Campaign, ...]:
    out = [Campaign(k, WORLD, _world_overrides(k)) for k in ("traffic", "alone", "same_look")]
    out += [Campaign(f"radar_{e}", WORLD, _world_overrides(f"radar_{e}")) for e in ("ekf", "ukf", "maekf", "ecukf")]
    out += [Campaign(f"paper_{e}", NO_TRAFFIC_WORLD, tuple(f"uavs[{i}].autonomy.estimator.type={e}" for i in range(2)))
            for e in ("ekf", "ukf", "maekf", "ecukf")]
    return tuple(out)


CAMPAIGNS = ("traffic", "alone", "same_look", "radar_ekf", "radar_ukf", "radar_maekf", "radar_ecukf",
             "paper_ekf", "paper_ukf", "paper_maekf", "paper_ecukf")


def _run(ctx: ReproContext, c: Campaign) -> dict[int, RunReport]:
    from simulator.campaign.runner import CampaignConfig

    res = ctx.campaign(CampaignConfig(world=c.world, runs=ctx.runs, out_dir=ctx.out_dir / "campaigns" / c.name,
                                      seed=ctx.seed, duration_s=QUICK_DURATION_S if ctx.quick else None,
                                      overrides=c.overrides, workers=ctx.workers, progress=ctx.progress))
    return {r.index: r for r in res.reports if r.status == "completed"}


def _col(runs: dict[int, dict], keys: tuple[str, ...], idx: list[int]) -> np.ndarray:
    vals = [[runs[i].get(k) for k in keys] for i in idx]
    return np.array([np.nan if None in v else float(np.mean(v)) for v in vals])


def ratio_within(num: np.ndarray, den: np.ndarray, limit: float) -> tuple[bool, MeanCI]:
    """Whether the per-seed ratio ``num / den`` is within ``limit``: the upper end of its 95 % interval (with one
    seed, the ratio itself) is at most ``limit``; and that interval."""
    ok = np.isfinite(num) & np.isfinite(den) & (den > 0)
    ci = mean_ci(num[ok] / den[ok])
    return bool(ok.any() and np.isfinite(ci.mean) and ci.mean + (ci.half or 0.0) <= limit), ci


def identity_kept(fractions: dict[str, np.ndarray], minimum: float) -> bool:
    """Whether every UAV's mean identity fraction over the seeds is at least ``minimum`` (a UAV without a value
    fails)."""
    return bool(fractions) and all(v.size and np.all(np.isfinite(v)) and float(np.mean(v)) >= minimum
                                   for v in fractions.values())


def traffic_section(ctx: ReproContext, paper_runs: dict[str, dict[int, dict]] | None = None
                    ) -> tuple[tuple[Table, ...], tuple[Finding, ...], int]:
    """Run the traffic campaigns (the ``paper_*`` ones only when ``paper_runs`` does not hold road_standoff's runs
    of those estimators, keyed ``ekf`` ...) and return the tables, findings and paired run count."""
    campaigns = {c.name: c for c in _campaigns()}
    have = dict(paper_runs or {})
    runs: dict[str, dict[int, dict]] = {}
    for name, c in campaigns.items():
        if name.startswith("paper_") and name.removeprefix("paper_") in have:
            runs[name] = have[name.removeprefix("paper_")]
            continue
        runs[name] = {i: r.metrics for i, r in _run(ctx, c).items()}
    idx = sorted(set.intersection(*(set(r) for r in runs.values())))
    if not idx:
        raise RuntimeError("no seed completed in every traffic campaign; see the campaigns' summary.md")
    car = "car1"
    pos = lambda u: f"targets.{car}.{u}.position_error_mean_m"  # noqa: E731
    ident = lambda u: f"targets.{car}.{u}.identity_fraction"  # noqa: E731
    fused = tuple(pos(f"{u}_fused") for u in UAVS)
    standoff = tuple(f"uavs.{u}.standoff_error_mean_m" for u in UAVS)

    names = ("EKF UAV1", "EKF UAV2", "EKF fused", "UKF fused", "MAEKF fused, road", "ECUKF fused, road")
    keys = ((pos("uav1"),), (pos("uav2"),), fused, fused, fused, fused)
    est = ("ekf", "ekf", "ekf", "ukf", "maekf", "ecukf")
    rows = []
    for n, k, e in zip(names, keys, est, strict=True):
        alone, traffic = _col(runs[f"paper_{e}"], k, idx), _col(runs[f"radar_{e}"], k, idx)
        ok, ratio = ratio_within(traffic, alone, np.inf)
        idf = _col(runs[f"radar_{e}"], tuple(ident(f"{u}_fused") for u in UAVS) if "fused" in n
                   else (ident(n.split()[-1].lower()),), idx)
        rows.append((n, mean_ci(alone).text(), mean_ci(traffic).text(), ratio.text(2), mean_ci(idf).text(2)))
    t_paper = Table(title="Table II's columns among traffic: mean position error (m), radar-only team",
                    columns=("column", "road_standoff (no traffic)", "with 24 traffic cars", "ratio (per seed)",
                             "identity fraction"),
                    rows=tuple(rows),
                    note=f"Mean ± 95 % CI over {len(idx)} seeds, paired. Without traffic: `{NO_TRAFFIC_WORLD}` with "
                         "the single-target trackers (the paper assumes the target is given); with traffic: "
                         f"`{WORLD}` with its cameras removed (radars only, as in the paper; each radar reads a "
                         "length class), multi-target tracking and track association. The identity fraction is the "
                         "share of agent steps whose estimate lies on the target car (nearest car within 50 m).")

    tr, al, sl = runs["traffic"], runs["alone"], runs["same_look"]
    e_tr, e_al = _col(tr, fused, idx), _col(al, fused, idx)
    s_tr, s_al = _col(tr, standoff, idx), _col(al, standoff, idx)
    err_ok, err_ratio = ratio_within(e_tr, e_al, MAX_RATIO)
    st_ok, st_ratio = ratio_within(s_tr, s_al, MAX_RATIO)
    id_fused = {u: _col(tr, (ident(f"{u}_fused"),), idx) for u in UAVS}
    id_local = {u: _col(tr, (ident(u),), idx) for u in UAVS}
    id_same = {u: _col(sl, (ident(f"{u}_fused"),), idx) for u in UAVS}
    mot = {u: _col(tr, (f"uavs.{u}.mot.mota",), idx) for u in UAVS}
    idf1 = {u: _col(tr, (f"uavs.{u}.mot.idf1",), idx) for u in UAVS}
    t_acc = Table(
        title=f"`{WORLD}` as shipped (radars + gimballed cameras) against the same team without traffic",
        columns=("quantity", "without traffic", "with traffic", "ratio (per seed)"),
        rows=(("fused position error (m)", mean_ci(e_al).text(), mean_ci(e_tr).text(), err_ratio.text(2)),
              ("standoff error (m)", mean_ci(s_al).text(), mean_ci(s_tr).text(), st_ratio.text(2)),
              *((f"{u} identity fraction, fused / own", "", f"{mean_ci(id_fused[u]).text(2)} / "
                 f"{mean_ci(id_local[u]).text(2)}", "") for u in UAVS),
              *((f"{u} identity fraction, all cars red sedans (fused)", "", mean_ci(id_same[u]).text(2), "")
                for u in UAVS),
              *((f"{u} MOTA / IDF1 over all cars", "", f"{mean_ci(mot[u]).text(2)} / {mean_ci(idf1[u]).text(2)}",
                 "") for u in UAVS)),
        note="Without traffic: the shipped world with its traffic cars removed and the same multi-target tracker. "
             "All cars red sedans: no class reading tells the target apart, so identity rests on the cue and track "
             "continuity (reported, no verdict).")
    ext = dict(paper="— (the paper assumes the target is given)", runs=len(idx), paper_faithful=False,
               paper_claim=False)
    ratio_rule = f"upper end of the 95 % interval of the per-seed ratio ≤ {MAX_RATIO}"
    id_ours = ("fused: " + ", ".join(f"{u} {mean_ci(v).text(2)}" for u, v in id_fused.items())
               + "; own: " + ", ".join(f"{u} {mean_ci(v).text(2)}" for u, v in id_local.items()))
    findings = (
        Finding(claim=f"Among 24 traffic cars the fused position error stays within {MAX_RATIO}× of the same seeds "
                      "without traffic",
                verdict="reproduced" if err_ok else "not reproduced", rule=ratio_rule,
                ours=f"per-seed ratio {err_ratio.text(2)}", why=f"per-seed ratio {err_ratio.text(2)}", **ext),
        Finding(claim=f"Every UAV keeps the target's identity at least {MIN_IDENTITY:.0%} of the time",
                verdict="reproduced" if identity_kept(id_fused, MIN_IDENTITY) and identity_kept(id_local,
                                                                                              MIN_IDENTITY)
                else "not reproduced", rule=f"every UAV's mean over seeds ≥ {MIN_IDENTITY}, fused and own",
                ours=id_ours, why=id_ours, **ext),
        Finding(claim=f"The NMPC standoff error stays within {MAX_RATIO}× of the same seeds without traffic",
                verdict="reproduced" if st_ok else "not reproduced", rule=ratio_rule,
                ours=f"per-seed ratio {st_ratio.text(2)}", why=f"per-seed ratio {st_ratio.text(2)}", **ext),
    )
    return (t_acc, t_paper), findings, len(idx)


def reproduce_traffic(ctx: ReproContext) -> PaperReport:
    """The traffic section alone, as a report of its own."""
    tables, findings, n = traffic_section(ctx)
    return PaperReport(
        paper="002-traffic", title="Paper 002's standoff tracking among traffic (our extension)", runs=n,
        setup=f"Campaigns of `{WORLD}` and `{NO_TRAFFIC_WORLD}`, paired by seed; "
              f"{'quick: ' + str(QUICK_DURATION_S) + ' s runs' if ctx.quick else '120 s runs'}. "
              "See simulator/reproduce/paper_002_traffic.py for every campaign's overrides.",
        tables=tables, findings=findings,
        deviations=("The paper assumes the target is given; this section is ours: the target among 24 kinematic "
                    "traffic cars that drive the same roads with the same driver.",
                    "The shipped traffic world adds a gimballed camera per UAV and flies its UAVs at 110 m and 120 m "
                    "(road_standoff: 60 m and 70 m), so that the cameras see down the town's streets; the Table II "
                    "columns among traffic remove the cameras (radar only) and fly road_standoff's altitudes.",
                    "The shipped traffic world's target model brakes harder (Singer σa = 2 m/s², not Table I's "
                    "0.66) and its EKF iterates its camera updates (3 linearisations); its comparison without traffic "
                    "keeps both. The Table II columns among traffic use Table I's settings, as without traffic."))


def main(argv: list[str] | None = None) -> int:
    """``python -m simulator.reproduce.paper_002_traffic --runs N --out DIR``."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=int, default=10)
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--seed", type=int, default=EVAL_SEED,
                    help=f"base seed (default {EVAL_SEED}; 1 is the tuning base)")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", type=Path, required=True)
    a = ap.parse_args(argv)
    a.out.mkdir(parents=True, exist_ok=True)
    ctx = ReproContext(out_dir=a.out, runs=a.runs, workers=a.workers, seed=a.seed, quick=a.quick)
    rep = reproduce_traffic(ctx)
    args = sys.argv[1:] if argv is None else argv
    rep = replace(rep, seeds=ctx.seeds_text())
    write_paper_report(rep, a.out, "python -m simulator.reproduce.paper_002_traffic " + " ".join(args))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
