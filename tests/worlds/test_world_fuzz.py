"""World-file fuzzing: mutate one value of a shipped world; whatever the loader accepts must then run.

A mutant replaces the value at a random key path of a shipped world's YAML (or adds an unknown key to a mapping) with
one from a pool of troublemakers: not-a-number, infinities, zero, negative, tiny and huge numbers, wrong types, empty
containers, unknown names; or, at a number, with a nearby one (doubled, halved, plus one, negated), which the loader
accepts more often, so that more mutants run. The loader may refuse it (``WorldError``: the file, the key path, the
value and what was expected); if it accepts it, a short run of it must end ``completed``: no world the loader
accepts is rejected by the run, and no mistake surfaces only after the physics engine has started.
"""

from __future__ import annotations

import copy
from pathlib import Path

import yaml
from yaml_paths import key_paths
from hypothesis import HealthCheck, given, note, settings
from hypothesis import strategies as st

from simulator.engine import RunOptions, run_world
from worlds.errors import WorldError
from worlds.loader import load_world, shipped_worlds

FUZZ_WORLDS = ("consensus_fmpc", "demo", "formation_imm", "relay_tracking", "road_standoff", "search_decoys")
"""Every shipped world but the two Helsinki ones (their roads and buildings come from an OpenStreetMap extract)."""

POOL = (float("nan"), float("inf"), float("-inf"), 0, -1, 1e-300, 1e9, 2**70, -(2**70), 0.5, True, None, "truck",
        [], {}, [1e9, 1e9, 1e9], [float("nan"), 0.0, 0.0], {"bogus": 1})
"""Replacement values."""

FREE_TEXT = ("name", "description")
"""Top-level keys whose value is free text: any string is fine there."""

RUN_S = 0.2
"""Simulated seconds each accepted mutant runs."""


def _raw(name: str) -> dict:
    return yaml.safe_load(shipped_worlds()[name].read_text(encoding="utf-8"))




RAW = {name: _raw(name) for name in FUZZ_WORLDS}
PATHS = {name: [p for p in key_paths(raw) if p[0] not in FREE_TEXT] for name, raw in RAW.items()}


@st.composite
def mutants(draw: st.DrawFn) -> tuple[str, tuple, object, dict]:
    """(world name, key path, new value, mutated raw world)."""
    name = draw(st.sampled_from(FUZZ_WORLDS))
    raw = copy.deepcopy(RAW[name])
    loc = draw(st.sampled_from(PATHS[name]))
    node = raw
    for key in loc[:-1]:
        node = node[key]
    old = node[loc[-1]]
    if isinstance(old, int | float) and not isinstance(old, bool) and draw(st.booleans()):
        value = draw(st.sampled_from((old * 2, old / 2, old + 1, -old)))
    else:
        value = copy.deepcopy(draw(st.sampled_from(POOL)))
    if isinstance(node[loc[-1]], dict) and draw(st.booleans()):
        node[loc[-1]]["bogus_key"] = value  # an unknown key
        loc = loc + ("bogus_key",)
    else:
        node[loc[-1]] = value
    return name, loc, value, raw


STATS = {"tried": 0, "accepted": 0}


@settings(max_examples=60, derandomize=True, deadline=None, database=None,
          suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
@given(mutant=mutants())
def test_every_world_the_loader_accepts_runs(mutant: tuple, tmp_path: Path) -> None:
    name, loc, value, raw = mutant
    note(f"{name}: {loc} = {value!r}")
    STATS["tried"] += 1
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(raw), encoding="utf-8")
    try:
        loaded = load_world(path)
    except WorldError:
        return
    STATS["accepted"] += 1
    out = tmp_path / f"run{STATS['tried']}"
    try:
        outcome = run_world(loaded, RunOptions(duration_s=RUN_S, out_dir=out, plots=False))
    except WorldError as exc:
        raise AssertionError(f"{name}: {loc} = {value!r} loaded, then refused by the run: {exc}") from None
    assert outcome.status == "completed", f"{name}: {loc} = {value!r} loaded, then the run failed: {outcome.error}"
