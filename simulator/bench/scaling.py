"""How a run's cost grows with traffic and with the team: ``python -m simulator.bench.scaling --out docs/scaling``.

Runs ``helsinki_traffic_builtin`` (three radar UAVs with EKF, covariance intersection and vector-field standoff
tracking a physics car across the Helsinki extract) with 0 / 50 / 200 / 1000 built-in traffic cars, the same with SUMO
traffic (200 / 1000 vehicles, when SUMO is installed), and with 1 / 10 / 50 UAVs among 200 built-in cars, and writes
``scaling.md`` (the table: CPU real-time factor of the loop, setup excluded, and the wall seconds of each phase of the
tick per simulated second) and ``scaling.png`` beside it. Every figure comes from the runs of the command.
"""

from __future__ import annotations

import argparse
import copy
import json
import math
import tempfile
import time
from pathlib import Path
from typing import Any

import yaml

__all__ = ["ceiling_rtf", "loop_rtf", "main", "sweep"]

WORLD = "helsinki_traffic_builtin"
CARS = (0, 50, 200, 1000)
SUMO_CARS = (200, 1000)
UAVS = (1, 10, 50)
PHASES = ("vehicles", "physics", "sensors", "autonomy", "record", "other")
WARM_S = 2.0
"""Simulated seconds of the discarded runs that warm a sweep's process (:func:`sweep`)."""


def _world(cars: int, engine: str, uavs: int | None, duration_s: float) -> dict[str, Any]:
    from worlds.loader import shipped_worlds

    raw = yaml.safe_load(shipped_worlds()[WORLD].read_text(encoding="utf-8"))
    raw["traffic"] = {"engine": engine, "cars": cars, "rate_hz": 20 if engine == "builtin" else 5}
    if engine == "builtin":  # 1000 cars 12 m apart do not fit on the extract's 22 km of roads; 8 m apart they do
        raw["traffic"]["min_spacing_m"] = 8.0
    raw["sim"]["duration_s"] = duration_s
    if uavs is not None:
        base, out = raw["uavs"], []
        for k in range(uavs):
            u = copy.deepcopy(base[k % len(base)])
            a = 2 * math.pi * k / uavs
            z = 80.0 + 2.0 * (k % 15)
            u["id"] = f"uav{k + 1}"
            u["initial"] = {"position": [180.0 + 250.0 * math.cos(a), -360.0 + 250.0 * math.sin(a), z],
                            "yaw_deg": math.degrees(a) + 90.0}
            u["autonomy"]["guidance"]["altitude"] = z
            out.append(u)
        raw["uavs"] = out
    return raw


def loop_rtf(raw: dict[str, Any]) -> dict[str, float]:
    """One run of the world data ``raw`` (no plots): its CPU real-time factor from the first tick to the end of the
    run directory (setup left out) as ``cpu_rtf``, its wall twin as ``rtf``, the seconds behind them (``sim_s``,
    ``cpu_s``, ``wall_s``) and its phases' wall seconds per simulated second."""
    from simulator.engine import RunOptions, run_world
    from worlds.loader import load_world

    marks: dict[str, float] = {}

    def at_tick(tick: int) -> None:
        if tick == 1:
            marks["cpu"], marks["wall"] = time.process_time(), time.perf_counter()

    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "world.yaml"
        path.write_text(yaml.safe_dump(raw, sort_keys=False), encoding="utf-8")
        out = run_world(load_world(path), RunOptions(out_dir=Path(tmp) / "run", plots=False, on_tick=at_tick))
        cpu, wall = time.process_time() - marks["cpu"], time.perf_counter() - marks["wall"]
        if out.status != "completed":
            raise RuntimeError(f"the run of {raw.get('name', 'a world')} ended {out.status}: {out.error}")
        metrics = json.loads((Path(tmp) / "run" / "metrics.json").read_text(encoding="utf-8"))
    sim = float(raw["sim"]["duration_s"])
    row = {"cpu_rtf": sim / max(cpu, 1e-9), "rtf": sim / max(wall, 1e-9), "sim_s": sim, "cpu_s": cpu, "wall_s": wall}
    row.update({p: metrics["wall_time_breakdown_s"].get(p, 0.0) / sim for p in PHASES})
    return row


def ceiling_rtf(row: dict[str, Any], free: tuple[str, ...] = ("autonomy",)) -> float:
    """The wall real-time factor the loop of ``row`` (:func:`loop_rtf`) would have had if its phases ``free`` had
    cost nothing and the rest the same: its simulated seconds over its loop's wall seconds less those phases'. A
    ceiling measured in the same run: no speed-up of the ``free`` phases alone can bring the loop above it. The
    phases' seconds count the first tick, which the loop's window leaves out, so the ceiling errs high."""
    unknown = [p for p in free if p not in PHASES]
    if unknown:
        raise ValueError(f"ceiling_rtf: {unknown!r} are not phases of a run (expected some of {PHASES})")
    rest = row["wall_s"] - sum(row[p] for p in free) * row["sim_s"]
    if not rest > 0:
        raise ValueError(f"ceiling_rtf: the phases {free!r} take {row['wall_s'] - rest:.3f} s of a loop of "
                         f"{row['wall_s']:.3f} s wall; they must take less than the whole loop")
    return row["sim_s"] / rest


def sweep(duration_s: float = 15.0, uav_duration_s: float = 10.0) -> list[dict[str, Any]]:
    """Every configuration of the module docstring, one run each (seed of the world file), after a short discarded
    run of each engine."""
    from vehicles.sumo import sumo_available

    # the first run of a process loads compiled kernels (numba's cache) and modules inside its loop, once per process
    # and engine: a short run of each, discarded, so that no row of the table pays it
    loop_rtf(_world(CARS[0], "builtin", None, WARM_S))
    if sumo_available():
        loop_rtf(_world(SUMO_CARS[0], "sumo", None, WARM_S))
    rows = []
    for n in CARS:
        rows.append({"sweep": "cars", "engine": "builtin", "cars": n, "uavs": 3, **loop_rtf(_world(n, "builtin", None,
                                                                                                 duration_s))})
    if sumo_available():
        for n in SUMO_CARS:
            rows.append({"sweep": "cars", "engine": "sumo", "cars": n, "uavs": 3,
                         **loop_rtf(_world(n, "sumo", None, duration_s))})
    for k in UAVS:
        rows.append({"sweep": "uavs", "engine": "builtin", "cars": 200, "uavs": k,
                     **loop_rtf(_world(200, "builtin", k, uav_duration_s))})
    return rows


def _table(rows: list[dict[str, Any]]) -> str:
    head = ("| traffic | cars | UAVs | CPU real-time factor | autonomy free | "
            + " | ".join(f"{p} s/s" for p in PHASES) + " |")
    rule = "|---|---:|---:|---:|---:|" + "---:|" * len(PHASES)
    body = [f"| {r['engine']} | {r['cars']} | {r['uavs']} | {r['cpu_rtf']:.2f}x | {ceiling_rtf(r):.2f}x | "
            + " | ".join(f"{r[p]:.3f}" for p in PHASES) + " |" for r in rows]
    return "\n".join([head, rule, *body])


def _plot(rows: list[dict[str, Any]], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 4))
    for engine, style in (("builtin", "o-"), ("sumo", "s--")):
        sel = [r for r in rows if r["sweep"] == "cars" and r["engine"] == engine]
        if sel:
            a.plot([max(r["cars"], 1) for r in sel], [r["cpu_rtf"] for r in sel], style, label=engine)
    a.set(xscale="log", yscale="log", xlabel="traffic cars (0 drawn at 1)", ylabel="CPU real-time factor",
          title="3 radar UAVs, Helsinki")
    a.axhline(1.0, color="grey", lw=0.8)
    a.legend()
    sel = [r for r in rows if r["sweep"] == "uavs"]
    b.plot([r["uavs"] for r in sel], [r["cpu_rtf"] for r in sel], "o-")
    b.set(xscale="log", yscale="log", xlabel="UAVs", ylabel="CPU real-time factor", title="among 200 built-in cars")
    b.axhline(1.0, color="grey", lw=0.8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=Path("docs/scaling"))
    ap.add_argument("--duration", type=float, default=15.0, help="simulated seconds of each traffic run")
    args = ap.parse_args(argv)
    rows = sweep(args.duration)
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "scaling.json").write_text(json.dumps(rows, indent=1), encoding="utf-8")
    _plot(rows, args.out / "scaling.png")
    (args.out / "scaling.md").write_text(
        "# How cost grows with traffic and with the team\n\n"
        f"Made by `python -m simulator.bench.scaling --out {args.out}` ({time.strftime('%Y-%m-%d')}, "
        "2-core machine): helsinki_traffic_builtin (three radar UAVs, EKF, covariance intersection, vector field, "
        f"one physics target car) for {args.duration:g} s per traffic run and 10 s per team run, one run each, "
        f"after a discarded {WARM_S:g} s run of each engine (the first run of a process loads compiled kernels "
        "inside its loop). CPU real-time factor: simulated time over the loop's CPU time (setup left out). "
        "Autonomy free: the wall real-time factor of the same run without its autonomy phase (`ceiling_rtf`), what "
        "no speed-up of the tracking, fusion and guidance alone can pass. The phase columns are the tick's wall "
        "seconds per simulated second (`wall_time_breakdown_s`).\n\n"
        + _table(rows) + "\n\n![real-time factor against cars and UAVs](scaling.png)\n", encoding="utf-8")
    print(_table(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
