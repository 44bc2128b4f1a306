"""Compiled CasADi NLP solvers with an on-disk cache, and calls without argument conversion.

CasADi evaluates its symbolic functions in a virtual machine; for the NMPC's SQP the constraint Jacobian and the Hessian
evaluations are a third of a solve. :func:`compiled_nlpsol` builds the solver as usual, writes the C code of the
functions it calls (what ``generate_dependencies`` writes: ``nlp_fg``, ``nlp_jac_fg``, ``nlp_grad``, ``nlp_hess_l``, the
last the user's ``hess_lag`` when given), compiles them into a shared library and returns the same solver loading its
functions from that library. The library is cached under a key of the serialized problem and options, the CasADi
version, the machine, the compiler and its flags: the first construction of a problem on a machine pays the compiler
(a few seconds at ``-O1``), later ones — other runs, campaign workers, test processes — load it in milliseconds without
building the uncompiled solver first. Writers compile into a private temporary file and
publish it with an atomic rename, so concurrent processes never see a half-written library.

The cache is untrusted input: a library is loaded only when its size and SHA-256 equal those its writer recorded
in the sidecar ``<library>.json`` (written after the library was hashed, also by atomic rename). ``dlopen`` maps the
file into the process, so a truncated library (a full disk, a copy cut short) would not raise an error but kill the
process with SIGBUS on the first call into the missing pages; a library that does not match its sidecar, or has
none, is compiled again with a warning. The check reads the library once (2–6 ms for an NMPC's ≈ 0.6 MB).

:class:`BufferedCall` calls a CasADi function on numpy arrays through ``Function.buffer`` (zero copy): the usual
``solver(x0=..., p=...)`` converts every numpy argument to a ``DM`` through SWIG, ≈ 40–60 µs for each vector of 160
numbers, which made up ≈ 170 µs of a 1.1 ms NMPC solve.

Without a C compiler, or when compiling fails, the virtual-machine solver is returned and a warning logged: the
solutions are the same, only slower. ``SKYTRACK_CACHE_DIR`` moves the cache (default ``$XDG_CACHE_HOME/skytrack``
or ``~/.cache/skytrack``); ``CC`` picks the compiler (default ``cc``).
"""

from __future__ import annotations

import hashlib
import json
import logging
import os
import platform
import shlex
import shutil
import subprocess
import tempfile
from pathlib import Path

import casadi as ca
import numpy as np

from worlds.map_cache import cache_root

__all__ = ["BufferedCall", "cache_dir", "compiled_nlpsol"]

_LOG = logging.getLogger(__name__)
_FLAGS = ("-O1", "-fPIC", "-shared")
_KEY_FORMAT = "skytrack-nlpsol-3"  # bump when the key or the generated files change meaning
_warned: set[str] = set()


def cache_dir() -> Path:
    """Directory of the compiled libraries: ``casadi`` under skytrack's cache root (``SKYTRACK_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/skytrack``, else ``~/.cache/skytrack``)."""
    return cache_root() / "casadi"


def _warn_once(msg: str) -> None:
    if msg not in _warned:
        _warned.add(msg)
        _LOG.warning(msg)


def compiled_nlpsol(name: str, plugin: str, nlp: dict, opts: dict) -> tuple[ca.Function, bool]:
    """``ca.nlpsol(name, plugin, nlp, opts)`` with its functions compiled (see the module docstring).

    Returns
    -------
    solver : casadi.Function
        The solver, loading its functions from the cached library, or the virtual-machine solver on failure.
    compiled : bool
        Whether the compiled library is used.
    """
    compiler = shlex.split(os.environ.get("CC", "cc"))
    if not compiler or shutil.which(compiler[0]) is None:
        _warn_once(f"no C compiler ({' '.join(compiler) or 'CC empty'}): CasADi solvers run uncompiled (slower)")
        return ca.nlpsol(name, plugin, nlp, opts), False
    # the library holds nlp_hess_l already (the user's hess_lag when one was given)
    lib_opts = {k: v for k, v in opts.items() if k not in ("hess_lag", "jac_fg")}
    lib = cache_dir() / f"{name}_{_problem_key(plugin, nlp, opts, compiler)}.so"
    if lib.exists() and _verified(lib):  # cached: the virtual-machine solver is never built
        try:
            return ca.nlpsol(name, plugin, str(lib), lib_opts), True
        except RuntimeError as exc:  # a damaged library: compile it again
            _LOG.warning("cached CasADi library %s unusable (%s): compiling it again", lib, exc)
    solver = ca.nlpsol(name, plugin, nlp, opts)
    try:
        _compile(solver, name, compiler, lib)
        return ca.nlpsol(name, plugin, str(lib), lib_opts), True
    except (OSError, RuntimeError, subprocess.SubprocessError) as exc:
        _warn_once(f"compiling the CasADi solver {name!r} failed, it runs uncompiled (slower): {exc}")
        return solver, False


def _problem_key(plugin: str, nlp: dict, opts: dict, compiler: list[str]) -> str:
    """Cache key of a solver's library: the serialized problem (x, p -> f, g), the options (functions among them
    serialized), the CasADi version, the machine and the compiler with its flags. ``nlpsol`` derives the functions it
    calls deterministically from these, so equal keys mean equal C; serializing is ≈ 10× cheaper than generating the
    C, and a cached solver is loaded without building its virtual-machine twin first."""

    def text(v: object) -> str:
        if isinstance(v, ca.Function):
            return v.serialize()
        if isinstance(v, dict):
            return "{" + ",".join(f"{k!r}:{text(v[k])}" for k in sorted(v)) + "}"
        return repr(v)

    args = [nlp["x"]] + ([nlp["p"]] if "p" in nlp else [])
    problem = ca.Function("nlp", args, [nlp.get("f", 0), nlp.get("g", ca.DM.zeros(0, 1))])
    parts = [_KEY_FORMAT, plugin, problem.serialize(), text(opts), ca.__version__, platform.machine(),
             " ".join(compiler + list(_FLAGS))]
    return hashlib.sha256("\0".join(parts).encode()).hexdigest()[:20]


def _compile(solver: ca.Function, name: str, compiler: list[str], lib: Path) -> None:
    """Write the C of ``solver``'s functions, compile it and publish it as ``lib`` (atomic rename)."""
    with tempfile.TemporaryDirectory() as tmp:
        # what solver.generate_dependencies writes, but into our own directory (it takes a bare file name only)
        gen = ca.CodeGenerator(f"{name}.c", {"with_header": False})
        gen.add(solver.oracle())
        for fname in solver.get_function():
            gen.add(solver.get_function(fname))
        src = Path(gen.generate(f"{tmp}{os.sep}"))
        out = Path(tmp) / lib.name
        proc = subprocess.run([*compiler, *_FLAGS, str(src), "-o", str(out)], capture_output=True, text=True,
                              check=False)
        if proc.returncode != 0:
            raise RuntimeError(f"{' '.join(compiler)} exited with {proc.returncode}: {proc.stderr.strip()[:500]}")
        lib.parent.mkdir(parents=True, exist_ok=True)
        _publish(out, lib)


def _sidecar(lib: Path) -> Path:
    """The file recording ``lib``'s size and SHA-256 (``<library>.json``)."""
    return lib.with_name(lib.name + ".json")


def _digest(path: Path) -> tuple[int, str]:
    """(size in bytes, SHA-256 hex) of a file's contents."""
    with path.open("rb") as f:
        return os.fstat(f.fileno()).st_size, hashlib.file_digest(f, "sha256").hexdigest()


def _verified(lib: Path) -> bool:
    """Whether ``lib`` is the library its writer published: same size and SHA-256 as in its sidecar. Logs why not."""
    side = _sidecar(lib)
    try:
        record = json.loads(side.read_text(encoding="utf-8"))
        want = (int(record["size"]), str(record["sha256"]))
        if record.get("format") != _KEY_FORMAT:
            raise ValueError(f"format {record.get('format')!r}, expected {_KEY_FORMAT!r}")
    except FileNotFoundError:
        _LOG.warning("cached CasADi library %s has no checksum file %s: compiling it again", lib, side.name)
        return False
    except (OSError, ValueError, KeyError, TypeError, AttributeError) as exc:
        _LOG.warning("checksum file %s of the cached CasADi library unreadable (%s): compiling it again", side, exc)
        return False
    try:
        have = _digest(lib)
    except OSError as exc:
        _LOG.warning("cached CasADi library %s unreadable (%s): compiling it again", lib, exc)
        return False
    if have != want:
        _LOG.warning("cached CasADi library %s is damaged (%d bytes, SHA-256 %s…; its writer recorded %d bytes, %s…): "
                     "compiling it again", lib, have[0], have[1][:12], want[0], want[1][:12])
        return False
    return True


def _publish(built: Path, lib: Path) -> None:
    """Copy ``built`` into the cache as ``lib`` with its sidecar: the copy is hashed (what readers will check is what
    landed on disk) and renamed into place, then the sidecar is written and renamed. A reader between the two renames
    sees a library whose sidecar is missing or stale and compiles again: it never loads unverified bytes."""
    lib.parent.mkdir(parents=True, exist_ok=True)
    fd, staged_name = tempfile.mkstemp(dir=lib.parent, prefix=".tmp-", suffix=".so")
    os.close(fd)
    staged = Path(staged_name)
    side_fd, side_name = tempfile.mkstemp(dir=lib.parent, prefix=".tmp-", suffix=".json")
    os.close(side_fd)
    try:
        shutil.copyfile(built, staged)
        with staged.open("rb+") as f:
            os.fsync(f.fileno())
        size, sha = _digest(staged)
        with open(side_name, "w", encoding="utf-8") as f:
            json.dump({"format": _KEY_FORMAT, "size": size, "sha256": sha}, f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(staged, lib)  # atomic: a concurrent reader sees no library or a whole one
        os.replace(side_name, _sidecar(lib))
    except BaseException:
        staged.unlink(missing_ok=True)
        Path(side_name).unlink(missing_ok=True)
        raise


class BufferedCall:
    """Call a CasADi function on numpy arrays by input name without converting them (``Function.buffer``).

    Inputs not given are zero (CasADi's default for the solvers' multiplier guesses and bounds is not used: pass
    every bound). Outputs are returned as fresh dense arrays keyed by output name.
    """

    def __init__(self, fun: ca.Function) -> None:
        self.fun = fun
        for i in range(fun.n_in()):
            if not fun.sparsity_in(i).is_dense():
                raise ValueError(f"BufferedCall needs dense inputs; {fun.name()}.{fun.name_in(i)} is sparse")
        self._in = {name: np.zeros(fun.nnz_in(i)) for i, name in enumerate(fun.name_in())}
        self._out = [np.zeros(fun.nnz_out(i)) for i in range(fun.n_out())]
        self._buf, self._trigger = fun.buffer()
        for i, name in enumerate(fun.name_in()):
            self._buf.set_arg(i, memoryview(self._in[name]))
        for i, a in enumerate(self._out):
            self._buf.set_res(i, memoryview(a))

    def __call__(self, **args: np.ndarray | float) -> dict[str, np.ndarray]:
        """Evaluate with the given inputs (missing ones zero); raises ``RuntimeError`` as CasADi does, ``ValueError``
        for an input name the function does not have or an input of the wrong size (a scalar fills its input)."""
        unknown = set(args) - set(self._in)
        if unknown:
            raise ValueError(f"{self.fun.name()} has no input {sorted(unknown)}; inputs: {list(self._in)}")
        for name, a in self._in.items():
            v = args.get(name)
            if v is None:
                a.fill(0.0)
                continue
            v = np.asarray(v, dtype=float).reshape(-1)
            if v.size not in (1, a.size):
                raise ValueError(f"{self.fun.name()}.{name} takes {a.size} numbers, got {v.size}")
            np.copyto(a, v)
        self._trigger()
        return {name: a.copy() for name, a in zip(self.fun.name_out(), self._out, strict=True)}

    def stats(self) -> dict:
        """Statistics of the last call (the wrapped function's ``stats()``; a buffer keeps its own memory)."""
        return self._buf.stats()
