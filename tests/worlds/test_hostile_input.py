"""Hostile input to the world loader: files that are not UTF-8 text, YAML that explodes when read (alias bombs, deep
nesting, recursive aliases), oversized files, ``--set`` lines that are not YAML, names that would leave ``runs/``,
physics no airframe can fly. Each is a :class:`WorldError` naming the file, the key path (or the ``--set`` line) and
what was expected, within a few seconds and a few hundred MB: :func:`_bounded` turns a hang into a failure (an
interval timer) and measures the memory the load allocates (tracemalloc). Property tests then mutate the shipped
worlds (their values and their text) and draw random ``--set`` lines: the loader accepts or raises ``WorldError``,
nothing else, within the same bounds."""

from __future__ import annotations

import copy
import json
import signal
import tracemalloc
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import pytest
import yaml
from yaml_paths import key_paths
from hypothesis import HealthCheck, Phase, given, note, settings
from hypothesis import strategies as st
from world_files import write

from simulator.cli import main
from worlds.errors import MAX_SHOWN, WorldError, format_path
from worlds.loader import LoadedWorld, load_world, shipped_worlds
from worlds.rates import divisors_text
from worlds.yaml_input import MAX_DEPTH, MAX_NODES, MAX_WORLD_BYTES

DEMO = shipped_worlds()["demo"]

SECONDS = 5.0
"""Wall-clock bound of one load: generous for a loaded test machine (the worst 1 MB file takes about 1.5 s)."""

PEAK_MB = 200.0
"""Bound on the memory one load adds at its peak, MB."""

CLEAR_REFS = Path("/proc/self/clear_refs")
"""Linux: writing 5 here resets the process's peak resident size (VmHWM), so a block's peak can be read without
tracemalloc, which slows PyYAML several times over."""


def _status_kb(field: str) -> int:
    for row in Path("/proc/self/status").read_text().splitlines():
        if row.startswith(field + ":"):
            return int(row.split()[1])
    raise KeyError(field)


@contextmanager
def _peak_mb() -> Iterator[list[float]]:
    """Yield a list that holds, after the block, the most memory (MB) the block added at any time: the growth of the
    peak resident size over the resident size at the start (Linux), else tracemalloc's peak."""
    out: list[float] = []
    try:
        CLEAR_REFS.write_text("5")
        rss = _status_kb("VmRSS")
    except OSError:
        tracemalloc.start()
        try:
            yield out
        finally:
            out.append(tracemalloc.get_traced_memory()[1] / 2**20)
            tracemalloc.stop()
        return
    try:
        yield out
    finally:
        out.append((_status_kb("VmHWM") - rss) / 1024)


@contextmanager
def _bounded(seconds: float = SECONDS, peak_mb: float = PEAK_MB) -> Iterator[None]:
    """Fail the block when it runs longer than ``seconds`` (SIGALRM interrupts a runaway loop) or adds more than
    ``peak_mb`` of memory at its peak."""

    def expire(signum: int, frame: object) -> None:
        raise TimeoutError(f"took more than {seconds} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        with _peak_mb() as peak:
            yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    assert peak[0] < peak_mb, f"added {peak[0]:.0f} MB at the peak"


def test_the_memory_bound_sees_an_allocation():
    with pytest.raises(AssertionError, match="added 3.. MB at the peak"):
        with _bounded():
            block = bytearray(300 * 2**20)
            block[::4096] = b"x" * len(block[::4096])  # touch every page
    del block


def _load(source: str | Path, overrides: list[str] | tuple[str, ...] = ()) -> LoadedWorld | WorldError:
    """The loaded world or the WorldError, within the bounds; any other exception fails the test."""
    with _bounded():
        try:
            return load_world(source, list(overrides))
        except WorldError as exc:
            return exc


def _refusal(source: str | Path, overrides: list[str] | tuple[str, ...] = ()) -> WorldError:
    result = _load(source, overrides)
    assert isinstance(result, WorldError), f"accepted: {overrides}"
    return result


def _issue(err: WorldError, path: str):
    found = [i for i in err.issues if i.path == path]
    assert found, f"no issue at {path}: {err}"
    return found[0]


# --- the physics rate -------------------------------------------------------------------------------------------------


def test_divisors_of_a_huge_prime_physics_rate_are_listed_at_once():
    with _bounded(seconds=2.0):
        assert divisors_text(1_000_000_007) == "1000000007, 1"
        assert divisors_text(240) == "240, 120, 80, 60, 48, 40, 30, 24, 20, 16, 15, 12"
        assert divisors_text(2**30, count=3) == f"{2**30}, {2**29}, {2**28}"


def test_a_huge_physics_rate_is_refused_at_its_key_path():
    err = _refusal("demo", ["sim.physics_hz=1000000007"])
    issue = _issue(err, "sim.physics_hz")
    assert issue.value == 1_000_000_007 and issue.expected == "a value less than or equal to 2400"
    assert f"{DEMO}:13: sim.physics_hz = 1000000007: expected a value less than or equal to 2400" in str(err)


# --- files that are not UTF-8 YAML of a sane size ---------------------------------------------------------------------

BOMB = b"".join([b"a: &a [x, x, x, x, x, x, x, x, x]\n"]
                + [b"%c: &%c [%s]\n" % (c, c, b", ".join([b"*%c" % (c - 1)] * 9)) for c in b"bcdefghi"])
"""A "billion laughs": 9 levels of lists of nine aliases of the level below, 9^9 = 387 million strings once
expanded, in 403 bytes."""

FILES = [
    pytest.param(bytes(range(256)) * 4, "<file>", "UTF-8 text (this file holds NUL bytes", 1, id="binary"),
    pytest.param("name: café\n".encode("latin-1"), "<file>",
                 "UTF-8 text (byte 0xe9 on line 1 is not UTF-8: Latin-1", 1, id="latin-1"),
    pytest.param(DEMO.read_text(encoding="utf-8").encode("utf-16"), "<file>",
                 "UTF-8 text (this file starts with a UTF-16 byte-order mark", None, id="utf-16"),
    pytest.param("name: x\n".encode("utf-32"), "<file>",
                 "UTF-8 text (this file starts with a UTF-32 byte-order mark", None, id="utf-32"),
    pytest.param(b"sim: " + b"[" * 5000 + b"]" * 5000 + b"\n", "<yaml>",
                 f"nesting at most {MAX_DEPTH} deep", 1, id="deep-flow"),
    pytest.param("".join("  " * i + f"k{i}:\n" for i in range(100)).encode(), "<yaml>",
                 f"nesting at most {MAX_DEPTH} deep", MAX_DEPTH + 1, id="deep-block"),
    pytest.param(BOMB, "<yaml>", f"at most {MAX_NODES} values (mappings, lists and scalars, aliases expanded)", 5,
                 id="alias-bomb"),
    pytest.param(b"a: &a [1, *a]\n", "<yaml>", "no alias to a node that contains it (a recursive structure)", 1,
                 id="recursive-alias"),
    pytest.param(b"a: &a " + b"[" * 30 + b"]" * 30 + b"\nb: [[[*a]]]\n", "<yaml>",
                 f"nesting at most {MAX_DEPTH} deep with aliases expanded (this alias reaches 34)", 2,
                 id="deep-alias"),
    pytest.param(b"sim: {seed: " + b"9" * 5000 + b"}\n", "<yaml>", "valid YAML values (Exceeds the limit", None,
                 id="5000-digit-int"),
    pytest.param(b"sim: {seed: !!python/object/apply:os.system [true]}\n", "<yaml>",
                 "no YAML tags (this value is tagged 'tag:yaml.org,2002:python/object/apply:os.system')", 1,
                 id="python-tag"),
    pytest.param(b"sim: {seed: !!timestamp x}\n", "<yaml>", "no YAML tags", 1, id="timestamp-tag"),
    pytest.param(b"name: a\x15b\n", "<yaml>",
                 "valid YAML (character #x0015 on line 1 is a control character, which YAML does not allow)", 1,
                 id="control-character"),
    pytest.param(b"a: [" + b"1," * 499_990 + b"]", "<yaml>", f"at most {MAX_NODES} values", 1, id="1MB-of-values"),
    pytest.param(b"\n" * MAX_WORLD_BYTES + b"name: x\n", "<file>",
                 f"a world file of at most {MAX_WORLD_BYTES} bytes (this one is {MAX_WORLD_BYTES + 8} bytes", None,
                 id="too-large"),
]


@pytest.mark.parametrize("data, path, expected, line", FILES)
def test_a_hostile_file_is_a_world_error_naming_it(tmp_path: Path, data: bytes, path: str, expected: str,
                                                   line: int | None):
    file = tmp_path / "hostile.yaml"
    file.write_bytes(data)
    err = _refusal(file)
    assert len(err.issues) == 1, str(err)
    issue = err.issues[0]
    assert issue.path == path and issue.expected.startswith(expected), issue.expected
    assert issue.line == line
    assert str(err).startswith(f"invalid world {file} (1 problem):\n  {file}")


def test_a_50_mb_file_is_refused_without_reading_it(tmp_path: Path):
    file = tmp_path / "huge.yaml"
    with file.open("wb") as f:
        f.write(b"name: x\ndescription: '")
        f.seek(50_000_000)
        f.write(b"'\n")
    err = _refusal(file)
    assert err.issues[0].expected == (f"a world file of at most {MAX_WORLD_BYTES} bytes (this one is 50000002 bytes; "
                                      "maps and towns come from roads.osm or roads.town)")


def test_a_utf8_byte_order_mark_is_fine(tmp_path: Path):
    file = tmp_path / "bom.yaml"
    file.write_bytes(b"\xef\xbb\xbf" + DEMO.read_bytes())
    assert _load(file).name == "demo"


def test_a_world_within_the_limits_loads(tmp_path: Path):
    """Aliases are fine as long as the expanded world stays within the limits (each alias is copied out)."""
    text = DEMO.read_text(encoding="utf-8").replace("params: {q: 2.0}}", "params: &p {q: 2.0}}", 1)
    text = text.replace("params: {q: 2.0}}", "params: *p}")
    loaded = _load(write(tmp_path, text))
    assert [u.autonomy.estimator.params for u in loaded.world.uavs] == [{"q": 2.0}, {"q": 2.0}]


def test_cli_exits_2_naming_the_file(tmp_path: Path, capsys):
    file = tmp_path / "bomb.yaml"
    file.write_bytes(BOMB)
    with _bounded():
        assert main(["run", str(file), "--quiet", "--no-plots", "--out", str(tmp_path / "run")]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"skytrack: invalid world {file} (1 problem):\n  {file}:5: <yaml> = "
                          f"'e: &e [*d, *d, *d, *d, *d, *d, *d, *d, *d]': expected at most {MAX_NODES} values")
    assert not (tmp_path / "run").exists()


# --- --set lines ------------------------------------------------------------------------------------------------------

SET_LINES = [
    pytest.param("sim.seed=[1,", "a YAML value after '=': valid YAML (expected the node content, but found "
                                 "'<stream end>')", id="bad-yaml"),
    pytest.param("sim.seed=!!python/object/apply:os.system ['true']",
                 "a YAML value after '=': no YAML tags (this value is tagged "
                 "'tag:yaml.org,2002:python/object/apply:os.system')", id="python-tag"),
    pytest.param("sim.seed=!!bool x", "a YAML value after '=': no YAML tags", id="bool-tag"),
    pytest.param("sim.seed=" + "[" * 100 + "]" * 100,
                 f"a YAML value after '=': nesting at most {MAX_DEPTH} deep", id="deep-value"),
    pytest.param("sim.seed=[&a [x,x,x,x,x,x,x,x,x,x], &b [*a,*a,*a,*a,*a,*a,*a,*a,*a,*a], "
                 "&c [*b,*b,*b,*b,*b,*b,*b,*b,*b,*b], &d [*c,*c,*c,*c,*c,*c,*c,*c,*c,*c], "
                 "[*d,*d,*d,*d,*d,*d,*d,*d,*d,*d]]",
                 f"a YAML value after '=': at most {MAX_NODES} values", id="alias-bomb"),
    pytest.param("sim.seed=" + "9" * 5000, "a YAML value after '=': valid YAML values (Exceeds the limit",
                 id="5000-digit-int"),
    pytest.param("." .join(["a"] * 100) + "=1", f"a key path of at most {MAX_DEPTH} parts (this one has 100)",
                 id="deep-key-path"),
    pytest.param("sim.seed", "key.path=value naming an existing place (override 'sim.seed' must look like "
                             "key.path=value)", id="no-value"),
    pytest.param("sim..seed=1", "key.path=value naming an existing place (bad key path 'sim..seed')",
                 id="bad-key-path"),
]


@pytest.mark.parametrize("line, expected", SET_LINES)
def test_a_bad_set_line_is_a_world_error_naming_it(line: str, expected: str):
    err = _refusal("demo", [line])
    assert len(err.issues) == 1, str(err)
    issue = err.issues[0]
    assert issue.path == f"--set {line}" and issue.value == line
    assert issue.expected.startswith(expected), issue.expected


def test_set_lines_that_together_nest_too_deep_are_refused():
    path = ".".join(f"k{i}" for i in range(20))
    err = _refusal("demo", [f"uavs[0].{path}=" + "[" * 20 + "]" * 20])
    issue = err.issues[0]
    assert issue.path == "--set" and issue.expected == f"nesting at most {MAX_DEPTH} deep in the world with its " \
                                                       "overrides"


def test_cli_exits_2_on_a_bad_set_line(tmp_path: Path, capsys):
    argv = ["run", "demo", "--quiet", "--no-plots", "--out", str(tmp_path / "run"), "--set", "sim.seed=[1,"]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert f"skytrack: invalid world {DEMO} (1 problem):\n  {DEMO}: --set sim.seed=[1, = 'sim.seed=[1,': " \
           "expected a YAML value after '=': valid YAML" in err


# --- values that used to fail deep inside, without a key path ---------------------------------------------------------

@pytest.mark.parametrize("override, path, expected", [
    ("uavs[0].sensors[0].rate_hz=1e-300", "uavs[0].sensors[0].rate_hz", "a rate in Hz that divides "
                                                                         "sim.physics_hz=240 into whole ticks"),
    ("buildings[0].size=[1e-300,50,25]", "buildings[0].size[0]", "a value greater than or equal to 0.5"),
    ("buildings[0].center=[.inf,0]", "buildings[0].center[0]", "a finite number"),
    ("buildings[0].center=[.nan,0]", "buildings[0].center[0]", "a finite number"),
    ("uavs[0].sensors[0].sigma_range=-.inf", "uavs[0].sensors[0].sigma_range", "a finite number"),
])
def test_a_bad_number_is_refused_at_its_key_path(override, path, expected):
    issue = _issue(_refusal("demo", [override]), path)
    assert issue.expected.startswith(expected), issue.expected


# --- names ------------------------------------------------------------------------------------------------------------

NAME_EXPECTED = ("a plain name: ASCII letters, digits, '_', '-' and '.' (not first), at most 100 characters (it names "
                 "the run directory runs/<name>: no '/', no '..')")


@pytest.mark.parametrize("name", ["../../x", "/abs/path", "..", ".hidden", "a/b", "a\\b", "a b", "", "x" * 101,
                                  "na\nme", "café", "~user", "C:x"])
def test_a_name_that_is_no_plain_directory_name_is_refused(name: str):
    err = _refusal("demo", [f"name={json.dumps(name)}"])  # a JSON string is a YAML double-quoted scalar
    issue = _issue(err, "name")
    assert issue.value == name and issue.expected == NAME_EXPECTED and issue.line == 10


@pytest.mark.parametrize("name", ["demo", "my-world_2.v1", "x" * 100, "2024"])
def test_plain_names_are_fine(name: str):
    assert _load("demo", [f"name={json.dumps(name)}"]).name == name


# --- physics no airframe can fly --------------------------------------------------------------------------------------

@pytest.mark.parametrize("override, path, expected", [
    ("environment.wind.mean_W=[1.0e+4, 0, 0]", "environment.wind.mean_W", "a wind of at most 25 m/s"),
    ("environment.wind.mean_W=[0, 1.0e+6, 0]", "environment.wind.mean_W", "a wind of at most 25 m/s"),
    ("environment.wind.turbulence.sigma=1.0e+10", "environment.wind.turbulence.sigma",
     "a value less than or equal to 5"),
    ("environment.gravity=1.0e+4", "environment.gravity", "a value less than or equal to 20"),
    ("environment.gravity=1.0e+300", "environment.gravity", "a value less than or equal to 20"),
    ("environment.gravity=0", "environment.gravity", "a value greater than or equal to 1"),
    ("uavs[0].initial.position=[0, 0, -5]", "uavs[0].initial.position", "a start above the ground: 0 < z <= 5000 m"),
    ("uavs[0].initial.position=[0, 0, 1.0e+30]", "uavs[0].initial.position[2]",
     "a value less than or equal to 50000"),
    ("terrain.size=[.inf, .inf]", "terrain.size[0]", "a finite number"),
    ("terrain.size=[1.0e+300, 10]", "terrain.size[0]", "a value less than or equal to 100000"),
    ("sim.duration_s=1.0e+300", "sim.duration_s", "a value less than or equal to 86400"),
    ("sim.seed=1180591620717411303424", "sim.seed", "a value less than or equal to 9223372036854775807"),
])
def test_physics_that_must_not_run_is_refused(override, path, expected):
    issue = _issue(_refusal("demo", [override]), path)
    assert issue.expected.startswith(expected), issue.expected


INSIDE = ("a start outside every building, at least 0.5 m from its walls and roof: buildings[1] (center [200.0, "
          "60.0], size [60.0, 40.0, 35.0], yaw_deg 10) holds it")


@pytest.mark.parametrize("position", [[200, 60, 20], [200, 60, 35.4], [229, 65, 1]])
def test_a_uav_starting_inside_a_building_is_refused(position):
    err = _refusal("demo", [f"uavs[1].initial.position={position}"])
    issue = _issue(err, "uavs[1].initial.position")
    assert issue.value == [float(p) for p in position] and issue.expected == INSIDE
    assert f"{DEMO}:58: uavs[1].initial.position = " in str(err)


@pytest.mark.parametrize("position", [[200, 60, 35.6], [231, 40, 20], [0, 0, 1]])
def test_a_uav_starting_above_or_beside_a_building_loads(position):
    """Above the roof, or inside the building's axis-aligned bounding box but outside the building (yaw 10 deg)."""
    loaded = _load("demo", [f"uavs[1].initial.position={position}"])
    assert isinstance(loaded, LoadedWorld), str(loaded)


def test_many_problems_are_counted_beyond_the_first_fifty():
    overrides = [f"buildings[{k}]={{center: [.nan, 0], size: [1, 1, 1]}}" for k in range(5, 65)]
    err = _refusal("demo", overrides)
    assert len(err.issues) == 60
    lines = str(err).splitlines()
    assert len(lines) == 1 + MAX_SHOWN + 1 and lines[-1] == "  ... and 10 more problems"


# --- properties: whatever the input, a WorldError or a world, quickly -------------------------------------------------

WORLD_NAMES = tuple(shipped_worlds())
RAW = {name: yaml.safe_load(path.read_text(encoding="utf-8")) for name, path in shipped_worlds().items()}
TEXT = {name: path.read_bytes() for name, path in shipped_worlds().items()}




PATHS = {name: key_paths(raw) for name, raw in RAW.items()}

HOSTILE = (float("nan"), float("inf"), -float("inf"), 0, -1, 1e-300, 1e300, 2**70, -(2**70), 10**400 - 1, True,
           None, "", "../../x", "/abs", "x" * 10_000, "\x00", [], {}, [[[[[[[[[[]]]]]]]]]], [1e300] * 3,
           {"bogus": 1}, list(range(1000)), b"bytes", 1 + 2j, float("1e-320"))
"""Replacement values: wrong types, non-finite, tiny and huge numbers, long strings, deep and long containers."""


def _values() -> st.SearchStrategy:
    scalars = st.one_of(st.sampled_from(HOSTILE), st.integers(), st.floats(), st.text(max_size=30))
    return st.recursive(scalars, lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8),
                                                                                            inner, max_size=4),
                        max_leaves=12)


# Generation only: an example that fails by running out of time is reported as found, since shrinking inputs that each
# take seconds would take minutes.
PROPERTY = settings(max_examples=60, derandomize=True, deadline=None, database=None, phases=[Phase.generate],
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


@PROPERTY
@given(data=st.data())
def test_a_mutated_shipped_world_loads_or_is_a_world_error(data: st.DataObject, tmp_path: Path):
    name = data.draw(st.sampled_from(WORLD_NAMES))
    raw = copy.deepcopy(RAW[name])
    loc = data.draw(st.sampled_from(PATHS[name]))
    value = copy.deepcopy(data.draw(_values()))
    node = raw
    for key in loc[:-1]:
        node = node[key]
    node[loc[-1]] = value
    note(f"{name}: {format_path(loc)} = {value!r}")
    try:
        text = yaml.dump(raw, allow_unicode=True)  # complex numbers and bytes dump as python tags: refused
    except (yaml.YAMLError, RecursionError):
        return
    _load(write(tmp_path, text))


@st.composite
def _text_mutants(draw: st.DrawFn) -> bytes:
    """A shipped world's bytes with a few bytes replaced, inserted or deleted, or cut short."""
    text = bytearray(TEXT[draw(st.sampled_from(WORLD_NAMES))])
    pieces = st.sampled_from([b"&a ", b"*a", b"!!python/name:os.system ", b"[", b"{", b"]", b": ", b"- ", b"\t",
                              b"\x00", b"\xe9", b"\xff\xfe", b"<<: *a\n", b"? ", b"|\n", b"'", b'"', b"\n  ", b"#",
                              b"1e999", b"9" * 5000, b".nan", b"%YAML 1.1\n---\n", b"---\n"])
    for _ in range(draw(st.integers(1, 4))):
        at = draw(st.integers(0, len(text)))
        action = draw(st.sampled_from(["insert", "replace", "delete", "cut"]))
        if action == "cut":
            del text[at:]
        elif action == "delete":
            del text[at:at + draw(st.integers(1, 40))]
        else:
            piece = draw(pieces | st.binary(min_size=1, max_size=8))
            text[at:at + (len(piece) if action == "replace" else 0)] = piece
    return bytes(text)


@PROPERTY
@given(data=_text_mutants())
def test_a_shipped_world_with_mangled_text_loads_or_is_a_world_error(data: bytes, tmp_path: Path):
    note(repr(data[:200]))
    file = tmp_path / "mangled.yaml"
    file.write_bytes(data)
    result = _load(file)
    if isinstance(result, WorldError):
        assert str(file) in str(result)


@st.composite
def _set_lines(draw: st.DrawFn) -> tuple[str, str]:
    """(world name, ``key=value``): a key path of the world, sometimes mangled, and a value as YAML text."""
    name = draw(st.sampled_from(WORLD_NAMES))
    key = format_path(draw(st.sampled_from(PATHS[name])))
    if draw(st.booleans()):
        key = draw(st.sampled_from([key + ".x", key + "[0]", key + "[99]", key[: len(key) // 2], key + "..",
                                    "[0]" + key, key.replace("[", "]")]))
    value = draw(st.one_of(
        st.text(alphabet=st.sampled_from("[]{}:,-&*!|>'\"#%@`?.\\ \t\n0123456789eEinfaul+"), max_size=40),
        st.text(max_size=20),
        st.sampled_from(["[1,", "{a: ", "!!python/object/apply:os.system ['true']", "!!binary AAAA", "*a", "&a 1",
                         ".inf", "-.inf", ".nan", "1e-300", "1.0e+300", "9" * 5000, "[" * 50 + "]" * 50,
                         "2001-13-45", "~", "''", "!!set {a, b}", "!!timestamp x", "<<: 1"]),
    ))
    return name, f"{key}={value}"


@PROPERTY
@given(line=_set_lines())
def test_a_random_set_line_loads_or_is_a_world_error(line: tuple[str, str]):
    name, text = line
    note(f"{name} --set {text!r}")
    _load(name, [text])
