"""The wiring may change; the numbers may not: every stream of a short run of every shipped world, two seeds each,
matches ``golden_records.json``: bit for bit on the machine that wrote it, to a relative 1e-6 on any other (see
:mod:`tests.simulator.golden`)."""

import pytest

from tests.simulator.golden import cases, compare, load_golden, run_case


@pytest.mark.parametrize(("name", "seed"), cases())
def test_record_matches_golden(tmp_path, name, seed):
    digests, values = run_case(name, seed, tmp_path)
    how, differs = compare(load_golden(), f"{name}/{seed}", digests, values)
    if how == "unchecked":
        pytest.skip(f"{name}: checked only on the machine that wrote golden_records.json (golden.BITS_ONLY)")
    assert not differs, f"{name} seed {seed}: these changed ({how}): {differs}"
