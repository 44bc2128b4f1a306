"""Paper 002's verdicts: a pure function of the aggregated per-run results (:func:`findings`).

Every rule is one of :mod:`simulator.reproduce.rules`, as strict as the paper's claim:

- road constraints cut the fused position error by the reduction of the paper's Table II (MAEKF 46.3 %, ECUKF 49.2 %
  against the fused EKF): :func:`~simulator.reproduce.rules.paired_reduction_at_least` with that fraction;
- fusion beats the better single UAV by Table II's 17.6 % (fused EKF against the UAV column with the lower mean, as
  the paper compares UAV2's column): the same rule;
- ECUKF below MAEKF, NMPC below LVFG (standoff and phase), NMPC + ECUKF below NMPC + EKF, and the ECUKF's gain larger
  under NMPC than under LVFG (a paired difference of differences): :func:`~simulator.reproduce.rules.paired_less`;
  the paper states these qualitatively (Section V), so the rule asks for the sign only. Guidance verdicts are judged in
  steady state (:mod:`simulator.reproduce.paper_002_steady`); the whole-run figures are in the tables.

Primary findings are judged on the paper's configuration (``paper_faithful=True``); the same claims judged on our
additions are extra rows (``paper_faithful=False``), and comparisons the paper does not make are ``paper_claim=False``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from simulator.reproduce import rules
from simulator.reproduce.report import Finding

__all__ = ["Results", "findings", "PAPER_TABLE_II", "PAPER_TABLE_III", "paper_reduction"]

PAPER_TABLE_II = {"EKF UAV1": (20.7141, 3.7757), "EKF UAV2": (17.5897, 3.4465), "EKF fused": (14.4868, 3.2418),
                  "UKF fused": (14.2238, 3.3099), "MAEKF fused, road": (7.7811, 2.1498),
                  "ECUKF fused, road": (7.3599, 2.0651)}
PAPER_TABLE_III = {"LVFG + EKF": (16.0767, 13.0413), "LVFG + ECUKF": (12.9999, 12.8627),
                   "NMPC + EKF": (13.4243, 12.5695), "NMPC + ECUKF": (9.5025, 11.1718)}


def paper_reduction(column: str, reference: str = "EKF fused") -> float:
    """Table II's relative reduction of ``column``'s position error against ``reference`` (fraction)."""
    return 1.0 - PAPER_TABLE_II[column][0] / PAPER_TABLE_II[reference][0]


@dataclass(frozen=True)
class Results:
    """Per-run figures (arrays in run order, paired across columns; NaN where a run has none).

    Attributes
    ----------
    pos : dict
        Mean fused position error (m) per Table II column on ``road_standoff_paper`` (``EKF UAV1``, ``EKF UAV2``,
        ``EKF fused``, ``UKF fused``, ``MAEKF fused, road``, ``ECUKF fused, road``) and our extra column
        ``ECUKF fused, road (ours)``.
    guidance : dict
        Per Table III column (``LVFG + EKF``, ``LVFG + ECUKF``, ``NMPC + EKF``, ``NMPC + ECUKF``, extras
        ``NMPC (ours) + EKF``, ``NMPC (ours) + ECUKF (ours)``): ``standoff`` / ``phase`` over the whole run and
        ``standoff_ss`` / ``phase_ss`` in steady state (m, deg).
    curve : dict
        Estimation only on the seeded curved roads (paper's radars at 500 m): fused error per filter
        (``ekf``, ``maekf_paper``, ``ecukf_paper``, ``maekf``, ``ecukf``).
    town : dict
        ``road_standoff`` as shipped (our configuration): ``EKF fused``, ``MAEKF fused, road``, ``ECUKF fused, road``.
    split : dict
        Per ``pos`` column, the mean over runs of the fused error's RMS along and across the road (``along_rms``,
        ``cross_rms``, m); empty when not computed.
    """

    pos: dict[str, np.ndarray]
    guidance: dict[str, dict[str, np.ndarray]]
    curve: dict[str, np.ndarray] = field(default_factory=dict)
    town: dict[str, np.ndarray] = field(default_factory=dict)
    split: dict[str, dict[str, float]] = field(default_factory=dict)


ROAD_COLUMNS = ("MAEKF fused, road", "ECUKF fused, road")


def _why_short(res: Results, col: str, verdict: str) -> str:
    """Why a road column falls short of the paper's reduction: where its error lies (the along / across split)."""
    if verdict != "not reproduced":
        return ""
    ref, con = res.split.get("EKF fused"), res.split.get(col)
    if not ref or not con:
        return ": below the paper's reduction"
    text = (f": below the paper's reduction. Across-road RMS {ref['cross_rms']:.1f} → {con['cross_rms']:.1f} m, "
            f"along-road RMS {ref['along_rms']:.1f} → {con['along_rms']:.1f} m")
    if con["along_rms"] > con["cross_rms"]:
        text += ": the constraint removes the across-road error; what is left lies along the road, where it does "\
                "not act"
    return text


def _road(res: Results) -> list[Finding]:
    out = []
    for col in ROAD_COLUMNS:
        f = paper_reduction(col)
        j = rules.paired_reduction_at_least(res.pos[col], res.pos["EKF fused"], f, names=(col.split()[0], "EKF"))
        out.append(Finding.judged(
            f"Road constraints cut the fused position error by Table II's {100 * f:.1f} % ({col} vs EKF fused; "
            "paper's filters, Table I's NMPC, closed loop)", j,
            paper=f"{PAPER_TABLE_II[col][0]:.2f} vs {PAPER_TABLE_II['EKF fused'][0]:.2f} m ({100 * f:.1f} % lower)",
            why=j.ours + _why_short(res, col, j.verdict)))
    if res.curve:
        for kind, col in (("maekf_paper", "MAEKF fused, road"), ("ecukf_paper", "ECUKF fused, road")):
            f = paper_reduction(col)
            j = rules.paired_reduction_at_least(res.curve[kind], res.curve["ekf"], f, names=(kind, "ekf"))
            out.append(Finding.judged(
                f"Road constraints cut the fused position error by Table II's {100 * f:.1f} % ({col.split()[0]} "
                "vs EKF; estimation only, the paper's radars at 500 m, seeded curved roads)", j,
                paper=f"{100 * f:.1f} % lower"))
    return out


def _fusion(res: Results) -> Finding:
    singles = ("EKF UAV1", "EKF UAV2")
    means = {c: float(np.nanmean(res.pos[c])) if np.isfinite(res.pos[c]).any() else np.inf for c in singles}
    best = min(singles, key=means.__getitem__)
    f = paper_reduction("EKF fused", "EKF UAV2")
    j = rules.paired_reduction_at_least(res.pos["EKF fused"], res.pos[best], f, names=("fused", best))
    return Finding.judged(f"Fusing the two UAVs' estimates cuts the error by Table II's {100 * f:.1f} % against the "
                          "better single UAV", j,
                          paper=f"EKF fused {PAPER_TABLE_II['EKF fused'][0]:.2f} vs UAV2 "
                                f"{PAPER_TABLE_II['EKF UAV2'][0]:.2f} m", why=f"{j.ours} (better single: {best})")


def _ecukf_vs_maekf(res: Results) -> Finding:
    j = rules.paired_less(res.pos["ECUKF fused, road"], res.pos["MAEKF fused, road"], " m", ("ECUKF", "MAEKF"))
    return Finding.judged("ECUKF is more accurate than MAEKF (paper's filters)", j,
                          paper=f"{PAPER_TABLE_II['ECUKF fused, road'][0]:.2f} vs "
                                f"{PAPER_TABLE_II['MAEKF fused, road'][0]:.2f} m")


def _guidance(res: Results) -> list[Finding]:
    g = res.guidance
    out = []
    j = rules.paired_less(g["NMPC + EKF"]["standoff_ss"], g["LVFG + EKF"]["standoff_ss"], " m", ("NMPC", "LVFG"))
    out.append(Finding.judged("NMPC keeps the standoff distance better than LVFG (EKF; steady state, LVFG under the "
                              "NMPC's speed and turn limits)", j, paper="13.42 vs 16.08 m"))
    j = rules.paired_less(g["NMPC + ECUKF"]["standoff_ss"], g["NMPC + EKF"]["standoff_ss"], " m", ("ECUKF", "EKF"))
    out.append(Finding.judged("With NMPC, the ECUKF lowers the standoff error against the EKF (steady state)", j,
                              paper="9.50 vs 13.42 m"))
    gain_n = g["NMPC + ECUKF"]["standoff_ss"] - g["NMPC + EKF"]["standoff_ss"]
    gain_l = g["LVFG + ECUKF"]["standoff_ss"] - g["LVFG + EKF"]["standoff_ss"]
    j = rules.paired_less(gain_n, gain_l, " m", ("NMPC gain", "LVFG gain"))
    out.append(Finding.judged("Better estimation (ECUKF) lowers the standoff error more under NMPC than under LVFG "
                              "(steady state)", j, paper="−3.92 vs −3.08 m"))
    j = rules.paired_less(g["NMPC + EKF"]["phase_ss"], g["LVFG + EKF"]["phase_ss"], "°", ("NMPC", "LVFG"))
    out.append(Finding.judged("NMPC keeps the 180° phase separation better than LVFG (EKF; steady state)", j,
                              paper="12.57 vs 13.04°"))
    return out


def _road_cut(a: np.ndarray, b: np.ndarray, base: str, names: tuple[str, str], what: str) -> Finding:
    """One of our road filters (``a``) against the EKF (``b``), judged at Table II's reduction for ``base``."""
    f = paper_reduction(base)
    j = rules.paired_reduction_at_least(a, b, f, names=names)
    return Finding.judged(f"Road constraints cut the fused position error by {100 * f:.1f} % ({what})", j,
                          paper=f"{100 * f:.1f} % lower", paper_faithful=False)


def _extras(res: Results) -> list[Finding]:
    out = []
    col = "ECUKF fused, road (ours)"
    if col in res.pos:
        out.append(_road_cut(res.pos[col], res.pos["EKF fused"], "ECUKF fused, road", ("ECUKF (ours)", "EKF"),
                             "our ECUKF: velocity turned with the road, projected sigma points, junction hypotheses, "
                             "no ε gate; Table I's NMPC"))
    for kind, base in (("maekf", "MAEKF fused, road"), ("ecukf", "ECUKF fused, road")):
        if res.curve and kind in res.curve:
            out.append(_road_cut(res.curve[kind], res.curve["ekf"], base, (kind, "ekf"),
                                 f"our {kind.upper()}; estimation only, seeded curved roads"))
        if res.town and base in res.town:
            out.append(_road_cut(res.town[base], res.town["EKF fused"], base, (kind, "ekf"),
                                 f"our {kind.upper()} and NMPC in the town world, 150 m standoff"))
    g = res.guidance
    if "NMPC (ours) + EKF" in g:
        j = rules.paired_less(g["NMPC (ours) + EKF"]["standoff_ss"], g["NMPC + EKF"]["standoff_ss"], " m",
                              ("ours", "Table I"))
        out.append(Finding.judged("Our NMPC (N = 20, our weights, chord phase term, v0 ± 6 m/s, ω ≤ 0.5 rad/s) keeps "
                                  "the standoff better than Table I's (EKF; steady state)", j, paper="—",
                                  paper_faithful=False, paper_claim=False))
    return out


def findings(res: Results) -> tuple[Finding, ...]:
    """Every verdict of paper 002 from the aggregated results (module docstring)."""
    return (*_road(res), _fusion(res), _ecukf_vs_maekf(res), *_guidance(res), *_extras(res))
