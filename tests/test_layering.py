"""The wall between truth and autonomy: autonomy/ and worlds/ never import pybullet or simulator (DESIGN.md)."""

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FORBIDDEN = {"autonomy": {"pybullet", "simulator", "vehicles"},
             "worlds": {"pybullet", "simulator", "vehicles", "autonomy"},
             "vehicles": {"simulator", "autonomy"}}


def imported_roots(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    roots = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            roots |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            roots.add(node.module.split(".")[0])
    return roots


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_package_imports_respect_layering(package):
    bad = []
    for path in sorted((ROOT / package).rglob("*.py")):
        crossing = imported_roots(path) & FORBIDDEN[package]
        if crossing:
            bad.append(f"{path.relative_to(ROOT)} imports {sorted(crossing)}")
    assert not bad, "layering violated:\n" + "\n".join(bad)


def test_the_check_itself_sees_imports(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text("import pybullet as p\nfrom simulator.engine import run_world\n")
    assert imported_roots(probe) == {"pybullet", "simulator"}
