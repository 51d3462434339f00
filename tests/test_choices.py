"""Each list of named choices is written once, in perception/choices.py; everything else imports it."""

import ast
import pathlib

from perception import choices

ROOT = pathlib.Path(__file__).resolve().parents[1]
PACKAGES = ("tactip", "pins", "arm", "perception", "calibration")
HOME = ROOT / "perception" / "choices.py"
LISTS = {name: frozenset(getattr(choices, name)) for name in choices.__all__}


def copies_in(path: pathlib.Path, root: pathlib.Path = ROOT) -> list[str]:
    """``file:line NAME`` for every tuple, list or set literal of strings equal (as a set) to a choice list."""
    found = []
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if not isinstance(node, (ast.Tuple, ast.List, ast.Set)) or not node.elts:
            continue
        if not all(isinstance(e, ast.Constant) and isinstance(e.value, str) for e in node.elts):
            continue
        strings = frozenset(e.value for e in node.elts)
        for name, values in LISTS.items():
            if strings == values:
                found.append(f"{path.relative_to(root)}:{node.lineno} {name}")
    return found


def test_no_copy_of_a_choice_list():
    found = [hit for package in PACKAGES for path in sorted((ROOT / package).rglob("*.py")) if path != HOME
             for hit in copies_in(path)]
    assert not found, "copies of perception.choices lists (import them instead):\n" + "\n".join(found)


def test_a_copy_is_found(tmp_path):
    """The scan sees a literal tuple, a reordered list and a ``choices=`` argument, and nothing else."""
    source = tmp_path / "probe.py"
    source.write_text('POLICIES = ("active", "stationary", "random")\n'
                      'kinds = ["gaussian", "torch", "histogram", "calibrated-histogram"]\n'
                      'parser.add_argument("--shift", choices=("uniform", "edge"))\n'
                      'other = ("edge", "rod")\n')
    assert copies_in(source, tmp_path) == ["probe.py:1 POLICIES", "probe.py:2 MODEL_KINDS", "probe.py:3 SHIFT_MODES"]
