"""The package layout rules of DEVELOPERS.md, checked on the source itself."""

import ast
import pathlib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PACKAGES = ("tactip", "pins", "arm", "perception", "calibration", "_shared")
# pins, perception and arm import none of each other; none of them imports the composers;
# _shared, the file-safety helpers every package may import, imports none of them.
FORBIDDEN = {
    "_shared": {"tactip", "pins", "arm", "perception", "calibration"},
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


def _module_name(path: pathlib.Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def import_graph(packages=PACKAGES) -> dict[str, set[str]]:
    """Module -> the modules of ``packages`` it imports, at any depth of the file (inside functions too).

    ``from a.b import c`` is an edge to ``a.b.c`` when that is a module, else to ``a.b``; an import
    of a name the tree does not define as a module goes to the nearest module above it.
    """
    paths = {_module_name(p): p for package in packages if (ROOT / package).is_dir()
             for p in (ROOT / package).rglob("*.py")}

    def nearest(name: str) -> str | None:
        while name and name not in paths:
            name = name.rpartition(".")[0]
        return name or None

    graph = {}
    for module, path in paths.items():
        base = module.split(".") if path.name == "__init__.py" else module.split(".")[:-1]
        edges = set()
        for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
            if isinstance(node, ast.Import):
                edges.update(nearest(alias.name) for alias in node.names)
            elif isinstance(node, ast.ImportFrom):
                source = node.module or ""
                if node.level:
                    source = ".".join(base[: len(base) - node.level + 1] + ([source] if source else []))
                edges.update(nearest(f"{source}.{a.name}") if f"{source}.{a.name}" in paths else nearest(source)
                             for a in node.names)
        graph[module] = edges - {None, module}
    return graph


def import_circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected groups of more than one module: each is an import circle."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    names = sorted(graph)
    index = {name: k for k, name in enumerate(names)}
    pairs = [(index[a], index[b]) for a, targets in graph.items() for b in targets]
    rows, cols = zip(*pairs) if pairs else ((), ())
    matrix = coo_matrix(([1] * len(pairs), (rows, cols)), shape=(len(names), len(names)))
    _, label = connected_components(matrix, directed=True, connection="strong")
    groups: dict[int, list[str]] = {}
    for name, group in zip(names, label):
        groups.setdefault(group, []).append(name)
    return [members for members in groups.values() if len(members) > 1]


def test_the_circle_finder_finds_a_circle():
    assert import_circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert import_circles({"a": {"b"}, "b": set()}) == []


def test_no_import_circle_anywhere():
    circles = import_circles(import_graph())
    assert not circles, "import circles (each group imports itself through the others):\n" + "\n".join(
        " <-> ".join(group) for group in circles)


# A module is at most this many lines: small enough to read in one sitting, split by what its parts are.
MAX_MODULE_LINES = 500
# Packages whose every module is held to it; tactip/cli (one module per subcommand) is exempt.
SHORT_PACKAGES = ("pins", "perception", "arm", "calibration", "tactip")
EXEMPT = (("tactip", "cli"),)


def long_modules(package: str) -> dict[str, int]:
    """Modules of ``package`` (outside the exempt folders) over `MAX_MODULE_LINES` lines: path -> lines."""
    long = {}
    for path in sorted((ROOT / package).rglob("*.py")):
        parts = path.relative_to(ROOT).parts
        if any(parts[:len(folder)] == folder for folder in EXEMPT):
            continue
        if (lines := len(path.read_text().splitlines())) > MAX_MODULE_LINES:
            long[str(path.relative_to(ROOT))] = lines
    return long


@pytest.mark.parametrize("package", SHORT_PACKAGES)
def test_modules_are_short(package):
    long = long_modules(package)
    assert not long, f"{package} modules over {MAX_MODULE_LINES} lines (split them by what they are): {long}"


def test_the_length_check_sees_long_modules_and_skips_only_the_cli(tmp_path, monkeypatch):
    # The check itself: a long module is reported wherever it lies, but for tactip/cli.
    for relative in ("pkg/deep/long.py", "tactip/cli/long.py", "tactip/long.py", "pkg/short.py"):
        path = tmp_path / relative
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text("x = 1\n" * (MAX_MODULE_LINES + (relative != "pkg/short.py")))
    monkeypatch.setitem(globals(), "ROOT", tmp_path)
    assert long_modules("pkg") == {"pkg/deep/long.py": MAX_MODULE_LINES + 1}
    assert long_modules("tactip") == {"tactip/long.py": MAX_MODULE_LINES + 1}
