"""The package layout rules of DEVELOPERS.md, checked on the source itself."""

import ast
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PACKAGES = ("tactip", "pins", "arm", "perception", "calibration", "_files")
# pins, perception and arm import none of each other; none of them imports the composers;
# _files, the file-safety helpers every package may import, imports none of them.
FORBIDDEN = {
    "_files": {"tactip", "pins", "arm", "perception", "calibration"},
    "pins": {"arm", "perception", "tactip", "calibration"},
    "perception": {"arm", "pins", "tactip", "calibration"},
    "arm": {"pins", "perception", "tactip", "calibration"},
    "calibration": {"tactip"},
}


def imported_top_levels(path: pathlib.Path) -> set[str]:
    """Top-level package names a module imports (absolute imports only)."""
    tree = ast.parse(path.read_text(), filename=str(path))
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


@pytest.mark.parametrize("package", sorted(FORBIDDEN))
def test_dependencies_flow_one_way(package):
    offenders = {}
    for path in (ROOT / package).rglob("*.py"):
        bad = imported_top_levels(path) & FORBIDDEN[package]
        if bad:
            offenders[str(path.relative_to(ROOT))] = sorted(bad)
    assert not offenders, f"{package} must not import {sorted(FORBIDDEN[package])}: {offenders}"


@pytest.mark.parametrize("package", PACKAGES)
def test_init_declares_public_names(package):
    init = ROOT / package / "__init__.py"
    tree = ast.parse(init.read_text())
    wildcard = [n for n in ast.walk(tree) if isinstance(n, ast.ImportFrom) and any(a.name == "*" for a in n.names)]
    assert not wildcard, f"{init} uses a wildcard import"
    assigned = {t.id for n in tree.body if isinstance(n, ast.Assign) for t in n.targets if isinstance(t, ast.Name)}
    assert "__all__" in assigned


def test_public_functions_have_docstrings():
    missing = []
    for package in PACKAGES:
        for path in (ROOT / package).rglob("*.py"):
            tree = ast.parse(path.read_text())
            for node in tree.body:
                nodes = [node]
                if isinstance(node, ast.ClassDef) and not node.name.startswith("_"):
                    nodes += [n for n in node.body if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef))]
                for n in nodes:
                    if isinstance(n, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
                        if not n.name.startswith("_") and ast.get_docstring(n) is None:
                            missing.append(f"{path.relative_to(ROOT)}:{n.lineno} {n.name}")
    assert not missing, "public names without a docstring:\n" + "\n".join(missing)
