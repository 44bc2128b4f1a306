"""The import walls (DESIGN.md, docs): autonomy/ and worlds/ never import pybullet or simulator; interfaces/ is the
lowest layer (numpy and the standard library only); vehicles/ sees only interfaces/ and worlds/ of the project;
estimation and fusion never import guidance."""

import ast
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FORBIDDEN = {"autonomy": {"pybullet", "simulator", "vehicles"},
             "worlds": {"pybullet", "simulator", "vehicles", "autonomy"},
             "vehicles": {"simulator", "autonomy"}}
PROJECT = {"autonomy", "interfaces", "simulator", "vehicles", "worlds"}
PROJECT_ALLOWED = {"interfaces": {"interfaces"}, "vehicles": {"interfaces", "vehicles", "worlds"}}
"""The only top-level packages of the project each of these packages may import."""
INTERFACES_ALLOWED = {"numpy", "interfaces"} | set(sys.stdlib_module_names)
NO_GUIDANCE = ("autonomy/estimation", "autonomy/fusion")
"""Folders whose modules must import nothing from ``autonomy.guidance`` (guidance sits above them)."""


def imported_roots(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    roots = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            roots |= {a.name.split(".")[0] for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            roots.add(node.module.split(".")[0])
    return roots


def imported_modules(path: Path, root: Path = ROOT) -> set[str]:
    """Dotted names a module imports, relative imports resolved against its package; ``from a import b`` gives
    both ``a`` and ``a.b`` (``b`` may be a submodule)."""
    package = list(path.relative_to(root).parent.parts)
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.Import):
            names |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom):
            base = package[:len(package) - node.level + 1] if node.level else []
            module = ".".join(base + ([node.module] if node.module else []))
            names.add(module)
            names |= {f"{module}.{a.name}" for a in node.names}
    return names


def imports_under(path: Path, prefix: str, root: Path = ROOT) -> set[str]:
    """The modules ``path`` imports that are ``prefix`` or inside it."""
    return {m for m in imported_modules(path, root) if m == prefix or m.startswith(prefix + ".")}


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_package_imports_respect_layering(package):
    bad = []
    for path in sorted((ROOT / package).rglob("*.py")):
        crossing = imported_roots(path) & FORBIDDEN[package]
        if crossing:
            bad.append(f"{path.relative_to(ROOT)} imports {sorted(crossing)}")
    assert not bad, "layering violated:\n" + "\n".join(bad)


@pytest.mark.parametrize("package", sorted(PROJECT_ALLOWED))
def test_package_imports_only_the_project_layers_below_it(package):
    bad = []
    for path in sorted((ROOT / package).rglob("*.py")):
        crossing = (imported_roots(path) & PROJECT) - PROJECT_ALLOWED[package]
        if crossing:
            bad.append(f"{path.relative_to(ROOT)} imports {sorted(crossing)}")
    assert not bad, "layering violated:\n" + "\n".join(bad)


def test_interfaces_import_numpy_and_the_standard_library_only():
    paths = sorted((ROOT / "interfaces").rglob("*.py"))
    assert paths, "interfaces/ has no modules"
    bad = [f"{p.relative_to(ROOT)} imports {sorted(imported_roots(p) - INTERFACES_ALLOWED)}" for p in paths
           if imported_roots(p) - INTERFACES_ALLOWED]
    assert not bad, "interfaces/ must stay the lowest layer:\n" + "\n".join(bad)


@pytest.mark.parametrize("folder", NO_GUIDANCE)
def test_estimation_and_fusion_import_nothing_from_guidance(folder):
    paths = sorted((ROOT / folder).rglob("*.py"))
    assert paths, f"{folder} has no modules"
    bad = [f"{p.relative_to(ROOT)} imports {sorted(imports_under(p, 'autonomy.guidance'))}" for p in paths
           if imports_under(p, "autonomy.guidance")]
    assert not bad, "an upward import inside autonomy/:\n" + "\n".join(bad)


def test_the_check_itself_sees_imports(tmp_path):
    probe = tmp_path / "probe.py"
    probe.write_text("import pybullet as p\nfrom simulator.engine import run_world\n")
    assert imported_roots(probe) == {"pybullet", "simulator"}


def test_the_check_itself_sees_imports_of_guidance_and_outside_interfaces(tmp_path):
    folder = tmp_path / "autonomy" / "estimation"
    folder.mkdir(parents=True)
    probe = folder / "probe.py"
    probe.write_text("import math\nimport numpy as np\nimport scipy.linalg\nfrom autonomy.guidance.types import X\n"
                     "from autonomy import guidance\nfrom ..guidance.base import Guidance\nfrom . import polygons\n"
                     "from autonomy.guidance_notes import Y\n")
    assert imports_under(probe, "autonomy.guidance", tmp_path) == {
        "autonomy.guidance", "autonomy.guidance.types", "autonomy.guidance.types.X", "autonomy.guidance.base",
        "autonomy.guidance.base.Guidance"}
    assert "autonomy.estimation.polygons" in imported_modules(probe, tmp_path)
    assert imported_roots(probe) - INTERFACES_ALLOWED == {"scipy", "autonomy"}
    assert (imported_roots(probe) & PROJECT) - PROJECT_ALLOWED["vehicles"] == {"autonomy"}
