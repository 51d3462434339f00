"""The CLI dispatcher: help lists every command; user errors are one line, not a traceback."""

import subprocess
import sys

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
