"""Compiled CasADi solvers (on-disk cache, fallback without a compiler) and buffered calls."""

from __future__ import annotations

import hashlib
import json
import logging

import casadi as ca
import numpy as np
import pytest

from autonomy.guidance import codegen
from autonomy.guidance.codegen import BufferedCall, compiled_nlpsol
from autonomy.guidance.nmpc import NmpcStandoffGuidance
from autonomy.guidance.nmpc_config import NmpcConfig
from interfaces.state import OwnState, TargetEstimate

_QUIET = {"print_header": False, "print_iteration": False, "print_status": False, "print_time": False,
          "qpsol": "qrqp", "qpsol_options": {"print_iter": False, "print_header": False, "print_info": False}}


def _rosenbrock() -> dict:
    """min (x0 − p)² + 10 (x1 − x0²)² s.t. x0 + x1 ≤ 1.5: the constraint binds, optimum depends on p."""
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p")
    return {"x": x, "p": p, "f": (x[0] - p) ** 2 + 10 * (x[1] - x[0] ** 2) ** 2, "g": x[0] + x[1]}


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("SKYTRACK_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("CC", raising=False)
    codegen._warned.clear()
    return tmp_path / "casadi"


def _solve(solver, p: float) -> np.ndarray:
    sol = BufferedCall(solver)(x0=[0.0, 0.0], p=p, lbx=[-np.inf] * 2, ubx=[np.inf] * 2, lbg=-np.inf, ubg=1.5)
    return sol["x"]


def test_compiled_solver_matches_the_virtual_machine_and_is_cached(cache):
    ref = ca.nlpsol("ref", "sqpmethod", _rosenbrock(), _QUIET)
    solver, ok = compiled_nlpsol("rb", "sqpmethod", _rosenbrock(), _QUIET)
    assert ok
    libs = sorted(cache.glob("rb_*.so"))
    assert len(libs) == 1
    for p in (1.0, 0.3, -0.5):
        np.testing.assert_allclose(_solve(solver, p), _solve(ref, p), rtol=0, atol=1e-12)
    # x0 + x1 = 1.5 binds at p = 1 (the unconstrained optimum (1, 1) is infeasible)
    assert sum(_solve(solver, 1.0)) == pytest.approx(1.5, abs=1e-8)
    mtime = libs[0].stat().st_mtime_ns
    _, ok2 = compiled_nlpsol("rb", "sqpmethod", _rosenbrock(), _QUIET)  # same problem: loaded, not recompiled
    assert ok2 and sorted(cache.glob("rb_*.so")) == libs and libs[0].stat().st_mtime_ns == mtime
    nlp = _rosenbrock()
    other = dict(nlp, g=nlp["x"][0] - nlp["x"][1])
    compiled_nlpsol("rb", "sqpmethod", other, _QUIET)  # another problem: another library
    assert len(list(cache.glob("rb_*.so"))) == 2
    left = sorted(p.name for p in cache.iterdir())
    assert all(n.endswith((".so", ".so.json")) and not n.startswith(".tmp") for n in left), left  # nothing else
    assert len(left) == 4  # two libraries, each with its checksum file


def test_a_damaged_cached_library_is_compiled_again(cache):
    compiled_nlpsol("rb", "sqpmethod", _rosenbrock(), _QUIET)
    (lib,) = cache.glob("rb_*.so")
    lib.write_bytes(b"not a shared library")
    solver, ok = compiled_nlpsol("rb", "sqpmethod", _rosenbrock(), _QUIET)
    assert ok and lib.stat().st_size > 1000  # replaced by a real library
    ref = ca.nlpsol("ref", "sqpmethod", _rosenbrock(), _QUIET)
    np.testing.assert_allclose(_solve(solver, 0.3), _solve(ref, 0.3), rtol=0, atol=1e-12)


def test_a_user_hessian_is_what_the_library_evaluates(cache):
    """hess_lag = 0 turns the SQP into steepest descent-like steps on a (regularised) zero Hessian: a different
    iteration count than the exact Hessian, identical between compiled and uncompiled."""
    nlp = _rosenbrock()
    x, p, lf, lg = nlp["x"], nlp["p"], ca.SX.sym("lam_f"), ca.SX.sym("lam_g")
    hess = ca.Function("nlp_hess_l", [x, p, lf, lg], [lf * 2 * ca.SX.eye(2)], ["x", "p", "lam_f", "lam_g"],
                       ["hess_gamma_x_x"])
    opts = dict(_QUIET, hess_lag=hess, max_iter=200)
    ref = BufferedCall(ca.nlpsol("ref", "sqpmethod", nlp, opts))
    comp, ok = compiled_nlpsol("rbh", "sqpmethod", nlp, opts)
    comp = BufferedCall(comp)
    exact = BufferedCall(ca.nlpsol("ex", "sqpmethod", nlp, _QUIET))
    args = {"x0": [0.0, 0.0], "p": 1.0, "lbx": [-np.inf] * 2, "ubx": [np.inf] * 2, "lbg": -np.inf, "ubg": 1.5}
    out_ref, out_comp = ref(**args), comp(**args)
    it_ref, it_comp = ref.stats()["iter_count"], comp.stats()["iter_count"]
    exact(**args)
    assert ok and it_ref == it_comp != exact.stats()["iter_count"]
    np.testing.assert_allclose(out_comp["x"], out_ref["x"], rtol=0, atol=1e-12)


@pytest.mark.parametrize("cc", ["/nonexistent/cc", "false"], ids=["no-compiler", "compiler-fails"])
def test_without_a_working_compiler_the_uncompiled_solver_is_used(cache, monkeypatch, caplog, cc):
    monkeypatch.setenv("CC", cc)
    with caplog.at_level(logging.WARNING, logger="autonomy.guidance.codegen"):
        solver, ok = compiled_nlpsol("rbf", "sqpmethod", _rosenbrock(), _QUIET)
    assert not ok and "uncompiled" in caplog.text
    assert sum(_solve(solver, 1.0)) == pytest.approx(1.5, abs=1e-8)
    assert not list(cache.glob("*.so"))


def test_buffered_call_equals_the_casadi_call_and_zeroes_missing_inputs():
    a, b = ca.SX.sym("a", 3), ca.SX.sym("b", 2)
    f = ca.Function("f", [a, b], [ca.sumsqr(a) + b[0], ca.vertcat(a * b[1], b)], ["a", "b"], ["s", "v"])
    call = BufferedCall(f)
    out = call(a=np.array([1.0, 2.0, 3.0]), b=[4.0, 5.0])
    ref = f(a=[1.0, 2.0, 3.0], b=[4.0, 5.0])
    np.testing.assert_allclose(out["s"], np.asarray(ref["s"]).ravel())
    np.testing.assert_allclose(out["v"], np.asarray(ref["v"]).ravel())
    kept = out["v"]
    out2 = call(a=[1.0, 1.0, 1.0])  # b missing: zero
    np.testing.assert_allclose(out2["v"], [0, 0, 0, 0, 0])
    np.testing.assert_allclose(kept, [5, 10, 15, 4, 5])  # earlier outputs are copies, not overwritten
    with pytest.raises(ValueError, match="no input"):  # a misspelt name is an error, not a silent zero
        call(a=[1.0, 1.0, 1.0], bb=[1.0, 2.0])
    with pytest.raises(ValueError, match="takes 2 numbers"):
        call(a=[1.0, 1.0, 1.0], b=[1.0, 2.0, 3.0])
    np.testing.assert_allclose(call(a=2.0, b=[0.0, 1.0])["v"], [2, 2, 2, 0, 1])  # a scalar fills its input
    with pytest.raises(ValueError, match="sparse"):
        BufferedCall(ca.Function("g", [ca.SX.sym("m", ca.Sparsity.diag(2))], [ca.SX(1)]))


def test_compiled_nmpc_commands_equal_the_uncompiled_ones(cache):
    own = OwnState(t=0.0, p_W=[90.0, 20.0, 60.0], v_W=[0.0, 10.0, 0.0], yaw=1.5)
    commands = {}
    for compiled in (True, False):
        g = NmpcStandoffGuidance(NmpcConfig(team_size=1, horizon=8, compiled=compiled), 0)
        assert g.compiled is compiled
        out = []
        for k in range(4):  # a cold start, then warm solves by the compiled SQP
            t = 0.5 * k
            tgt = TargetEstimate(t=t, p_W=np.array([3.0 * t, 0.0, 0.0]), v_W=np.array([3.0, 0.0, 0.0]))
            sp = g.command(own, tgt, [], t)
            out.append([sp.speed, sp.heading_rate])
        assert g.stats.failures == 0
        commands[compiled] = np.array(out)
    np.testing.assert_allclose(commands[True], commands[False], rtol=0, atol=1e-9)
    assert list(cache.glob("nmpc_*.so"))


_LOAD_AND_SOLVE = """
import logging, sys
import casadi as ca
import numpy as np
from autonomy.guidance.codegen import BufferedCall, compiled_nlpsol
logging.basicConfig(level=logging.WARNING, format="%(levelname)s %(message)s")
x, p = ca.SX.sym("x", 2), ca.SX.sym("p")
nlp = {"x": x, "p": p, "f": (x[0] - p) ** 2 + 10 * (x[1] - x[0] ** 2) ** 2, "g": x[0] + x[1]}
opts = {"print_header": False, "print_iteration": False, "print_status": False, "print_time": False,
        "qpsol": "qrqp", "qpsol_options": {"print_iter": False, "print_header": False, "print_info": False}}
solver, ok = compiled_nlpsol("rbs", "sqpmethod", nlp, opts)
sol = BufferedCall(solver)(x0=[0.0, 0.0], p=1.0, lbx=[-np.inf] * 2, ubx=[np.inf] * 2, lbg=-np.inf, ubg=1.5)
print("compiled", ok, "x0+x1 %.9f" % sum(sol["x"]))
"""


def _load_in_subprocess(cache_root):
    """Build or load the cached library in a fresh process: a library that crashes the loader must not take the
    test session down, and must not be mapped into it either."""
    import os
    import subprocess
    import sys
    from pathlib import Path

    env = dict(os.environ, SKYTRACK_CACHE_DIR=str(cache_root))
    env.pop("CC", None)
    root = Path(__file__).resolve().parents[2]
    return subprocess.run([sys.executable, "-c", _LOAD_AND_SOLVE], cwd=root, env=env, capture_output=True, text=True,
                          timeout=300, check=False)


def _truncate(lib):
    with lib.open("r+b") as f:  # in place, as a copy cut short or a full disk leaves it
        f.truncate(lib.stat().st_size // 2)


def _flip_middle(lib):
    data = bytearray(lib.read_bytes())
    mid = len(data) // 2
    data[mid:mid + 64] = bytes(b ^ 0xFF for b in data[mid:mid + 64])
    with lib.open("r+b") as f:
        f.write(data)


def _drop_sidecar(lib):
    lib.with_name(lib.name + ".json").unlink()


@pytest.mark.parametrize("damage, says", [(_truncate, "is damaged"), (_flip_middle, "is damaged"),
                                          (_drop_sidecar, "has no checksum file")],
                         ids=["truncated", "corrupted", "no-sidecar"])
def test_a_damaged_cached_library_is_rebuilt_instead_of_crashing_the_process(tmp_path, damage, says):
    first = _load_in_subprocess(tmp_path)
    assert first.returncode == 0, first.stderr
    assert "compiled True x0+x1 1.500000000" in first.stdout
    (lib,) = (tmp_path / "casadi").glob("rbs_*.so")
    side = json.loads(lib.with_name(lib.name + ".json").read_text())
    assert side["size"] == lib.stat().st_size
    assert side["sha256"] == hashlib.sha256(lib.read_bytes()).hexdigest()
    damage(lib)
    again = _load_in_subprocess(tmp_path)
    assert again.returncode == 0, f"exit {again.returncode}: {again.stderr}"  # SIGBUS was -7 (a shell's 135)
    assert "compiled True x0+x1 1.500000000" in again.stdout
    assert f"cached CasADi library {lib} {says}" in again.stderr
    assert hashlib.sha256(lib.read_bytes()).hexdigest() == json.loads(
        lib.with_name(lib.name + ".json").read_text())["sha256"]  # republished whole, with a matching sidecar
    third = _load_in_subprocess(tmp_path)
    assert third.returncode == 0 and "WARNING" not in third.stderr  # loaded from the cache, verified
