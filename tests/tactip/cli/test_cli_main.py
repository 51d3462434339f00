"""The CLI dispatcher: help lists every command; user errors are one line, not a traceback."""

import subprocess
import sys

import pytest

from tactip.cli import COMMANDS, build_parser, main


def test_help_lists_every_command():
    text = build_parser().format_help()
    for name in COMMANDS:
        assert name in text


def test_every_command_has_help(capsys):
    for name in COMMANDS:
        try:
            main([name, "--help"])
        except SystemExit as exc:
            assert exc.code == 0
        out = capsys.readouterr().out
        assert "usage: tactip" in out and name in out


def test_console_script_version():
    out = subprocess.run([sys.executable, "-m", "tactip.cli", "--version"], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.startswith("tactip ")


def test_parsing_and_refusing_import_no_heavy_package():
    """``tactip --help`` and a refusal while parsing load neither OpenCV, SciPy, h5py nor NumPy (each start of
    the command line paid about a second for them): the `tactip` package imports its front ends on first use,
    `main` fills only the arguments of the command it runs, and of perception only the standard-library table
    of choices is read (the `perception` package imports its own names on first use)."""
    script = ("import sys\nfrom tactip.cli import main\n"
              "for argv in (['--help'], ['validate', 'm.h5', 't.h5', '--seed', '-1'], ['train', '--help']):\n"
              "    try:\n        main(argv)\n    except SystemExit:\n        pass\n"
              "heavy = ('cv2', 'scipy', 'h5py', 'numpy', 'pins', 'perception')\n"
              "print(sorted(m for m in sys.modules if m.split('.')[0] in heavy\n"
              "             and m not in ('perception', 'perception.choices')))")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert done.stdout.strip().splitlines()[-1] == "[]", done.stdout + done.stderr
    assert "argument --seed: must be in 0..4294967295, got -1" in done.stderr


def test_a_failure_is_reported_without_importing_other_packages_for_their_errors(tmp_path):
    """A command failing before it needs OpenCV or SciPy (a binary station file) is reported in one line
    without importing every package to catch its error family (that cost about a second)."""
    (tmp_path / "b.toml").write_bytes(bytes(range(256)))
    script = ("import sys\nfrom tactip.cli import main\nprint(main(['calibrate', '--config', 'b.toml']))\n"
              "print(sorted(m for m in ('cv2', 'scipy', 'h5py', 'arm', 'calibration', 'pins') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60, cwd=tmp_path)
    assert done.stdout.split() == ["1", "[]"], done.stdout + done.stderr
    assert done.stderr == "tactip calibrate: error: b.toml: a binary file: byte 0x80 at offset 128; a TOML file " \
                          "must be UTF-8 text\n"


def test_errors_of_every_family_are_one_line(capsys, monkeypatch, tmp_path):
    """Each package's error family (imported by the command that raises it) is a one-line error, exit 1."""
    import importlib

    import tactip.cli.train
    from tactip.cli import _ERROR_FAMILIES

    monkeypatch.chdir(tmp_path)
    for module, name in _ERROR_FAMILIES:
        error = getattr(importlib.import_module(module), name)

        def fail(args, error=error):
            raise error(f"a {error.__name__} for the user")

        monkeypatch.setattr(tactip.cli.train, "run", fail)
        assert main(["train", "d.h5", "--out", "m.h5"]) == 1
        assert capsys.readouterr().err == f"tactip train: error: a {name} for the user\n"


def test_a_partial_parser_parses_its_command_as_the_full_one():
    argv = ["validate", "m.h5", "t.h5", "--runs", "10", "--sweep-fixation"]
    full, only = build_parser().parse_args(argv), build_parser(only="validate").parse_args(argv)
    assert vars(full) == vars(only)


def test_a_lazy_front_end_name_is_the_module_s_own():
    import tactip
    from tactip.sources import VideoSource

    assert tactip.VideoSource is VideoSource and "VideoSource" in dir(tactip)
    with pytest.raises(AttributeError, match="no attribute 'nothing'"):
        tactip.nothing
