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
    """``tactip --help`` and a refusal while parsing load neither OpenCV, SciPy nor h5py (each start of the
    command line paid about a second for them): the `tactip` package imports its front ends on first use
    and `main` fills only the arguments of the command it runs."""
    script = ("import sys\nfrom tactip.cli import main\n"
              "for argv in (['--help'], ['validate', 'm.h5', 't.h5', '--seed', '-1'], ['train', '--help']):\n"
              "    try:\n        main(argv)\n    except SystemExit:\n        pass\n"
              "print(sorted(m for m in ('cv2', 'scipy', 'h5py', 'pins', 'perception') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert done.stdout.strip().splitlines()[-1] == "[]", done.stdout + done.stderr
    assert "argument --seed: must be in 0..4294967295, got -1" in done.stderr


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
