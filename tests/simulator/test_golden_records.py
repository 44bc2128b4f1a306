"""The wiring may change; the numbers may not: every stream of a short run of every shipped world, two seeds each,
matches the digests in ``golden_records.json`` bit for bit (see :mod:`tests.simulator.golden`)."""

import pytest

from tests.simulator.golden import cases, load_golden, run_case


@pytest.mark.parametrize(("name", "seed"), cases())
def test_record_matches_golden(tmp_path, name, seed):
    want = load_golden()[f"{name}/{seed}"]
    got = run_case(name, seed, tmp_path)
    differs = sorted(k for k in set(want) | set(got) if want.get(k) != got.get(k))
    assert not differs, f"{name} seed {seed}: these digests changed: {differs}"
