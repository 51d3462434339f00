"""The `tactip` command line.

Each subcommand lives in its own module of this package and exposes:

- ``HELP``: one line for the command list;
- ``add_arguments(parser)``: fills an ``argparse`` parser (parsing only);
- ``run(args) -> int``: calls the importable function that does the work, returns the exit code.

Every command gets ``-q/--quiet`` and ``-v/--verbose`` (also accepted before the command), and every
command that writes files gets ``--overwrite``: a file the project wrote is never replaced without it
(checked here, before the command runs, for every argument parsed as an output file). With ``--json``
to standard output, every other line goes to standard error.

Heavy imports (OpenCV, h5py, torch) belong inside ``run`` so that ``tactip --help`` stays fast.
Errors from any package become one line on stderr and exit 1 (with -v/--verbose the traceback
too); Ctrl-C prints "Stopped." and exits 130; SIGTERM and SIGHUP (the terminal closed) are handled like Ctrl-C (work in progress is
closed as aborted, reason "terminated (SIGTERM)", temporary files removed) and exit 143 and 129. Output piped into ``head`` stops quietly; any other broken pipe (a
worker pool, a robot socket) is an error like the others.
"""

from __future__ import annotations

import argparse
import contextlib
import errno
import importlib
import os
import signal
import sys

# Subcommand name -> module. Nested groups (``tactip arm status``) are handled by their module.
COMMANDS: dict[str, str] = {
    "detect": "tactip.cli.detect",
    "record": "tactip.cli.record",
    "replay": "tactip.cli.replay",
    "calibrate": "tactip.cli.calibrate",
    "collect": "tactip.cli.collect",
    "dataset": "tactip.cli.dataset",
    "train": "tactip.cli.train",
    "validate": "tactip.cli.validate",
    "inspect": "tactip.cli.inspect",
    "results": "tactip.cli.results",
    "serve": "tactip.cli.serve",
    "arm": "tactip.cli.arm",
    "simulate": "tactip.cli.simulate",
    "reproduce": "tactip.cli.reproduce",
}


# The error families whose message is meant for the user (no traceback): (module, base class).
_ERROR_FAMILIES = (("tactip.errors", "TactipError"), ("pins.errors", "PinsError"),
                   ("perception.errors", "PerceptionError"), ("arm.errors", "ArmError"),
                   ("calibration.errors", "CalibrationError"))


def _known_errors() -> tuple[type[BaseException], ...]:
    """The error families whose message is meant for the user (no traceback), and `OSError`.

    Only the families already imported: an error of a package never imported cannot have been raised,
    and importing one (``arm``, ``calibration``) for its error class cost a second per failed command.
    """
    loaded = (sys.modules.get(module) for module, _ in _ERROR_FAMILIES)
    return (*(getattr(m, name) for m, (_, name) in zip(loaded, _ERROR_FAMILIES) if m is not None), OSError)


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The argument parser, one subparser per entry of `COMMANDS`.

    With ``only`` (a command name, or ``""`` for none), only that command's arguments are added (the
    others keep their one-line help): `main` parses one command, and some commands' arguments import
    heavy packages (``replay``'s sensor list needs `pins`), which ``tactip --help`` or a refusal of
    another command should not wait for.
    """
    from tactip import __version__

    parser = argparse.ArgumentParser(
        prog="tactip",
        description="TacTip optical tactile sensing: pin tracking, active Bayesian gap inspection, arm control.",
        epilog="Try it with no hardware: tactip inspect --sim. A new station: tactip arm status, calibrate, "
               "collect, train, validate --sweep-fixation, then inspect. 'tactip COMMAND --help' for each.",
    )
    parser.add_argument("--version", action="version", version=f"tactip {__version__}")
    parser.add_argument("-q", "--quiet", dest="_quiet", action="store_true", help=_QUIET_HELP)
    parser.add_argument("-v", "--verbose", dest="_verbose", action="store_true", help=_VERBOSE_HELP)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name, module_name in COMMANDS.items():
        module = importlib.import_module(module_name)
        doc = (module.__doc__ or "").strip()
        cmd = sub.add_parser(name, help=module.HELP, description=doc or module.HELP,
                             formatter_class=argparse.RawDescriptionHelpFormatter)
        if only is None or name == only:
            module.add_arguments(cmd)
            for leaf in _leaf_parsers(cmd):
                _add_common_arguments(leaf)
        cmd.set_defaults(_run=module.run)
    return parser


_QUIET_HELP = "no progress bars; only results, verdicts and warnings"
_VERBOSE_HELP = "on an error, also print its traceback (for a bug report)"
_EXIT_CODES = ("exit status: 0 done; 1 an error (one line on standard error); 2 a bad command line; "
               "130 stopped by Ctrl-C (143 SIGTERM, 129 the terminal closed)")


def _leaf_parsers(parser: argparse.ArgumentParser) -> list[argparse.ArgumentParser]:
    """The parsers that take a command's options: ``parser`` itself, or those of its subcommands
    (``tactip results list``), so that every command has the same common flags."""
    groups = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    if not groups:
        return [parser]
    return [leaf for group in groups for child in dict.fromkeys(group.choices.values()) for leaf in _leaf_parsers(child)]


def _add_common_arguments(parser: argparse.ArgumentParser) -> None:
    """``-q``/``--quiet`` and ``-v``/``--verbose`` on every command, and ``--overwrite`` on every command
    that writes a file (`tactip.cli._types.OutputPath`; a command writing a folder of outputs adds its own)."""
    from tactip.cli._types import creatable_file, image_file, json_target, output_file

    taken = set(parser._option_string_actions)
    parser.add_argument("-q", "--quiet", action="store_true", help=_QUIET_HELP)
    parser.add_argument("-v", "--verbose", action="store_true", help=_VERBOSE_HELP)
    writes = any(a.type in (creatable_file, image_file, json_target, output_file) for a in parser._actions)
    if writes and "--overwrite" not in taken:
        parser.add_argument("--overwrite", action="store_true",
                            help="replace a file tactip wrote (a model, calibration, collected taps, replay, "
                                 "results database or station TOML); without it such a file is never replaced")
    if parser.epilog is None:
        parser.epilog = _EXIT_CODES


def main(argv: list[str] | None = None) -> int:
    """Entry point of the `tactip` console script; returns the process exit code."""
    from tactip._signals import Terminated, terminate_like_ctrl_c

    words = sys.argv[1:] if argv is None else argv
    command = next((str(w) for w in words if not str(w).startswith("-")), None)
    parser = build_parser(only=command if command in COMMANDS else "")
    args = parser.parse_args(argv)
    args.quiet = bool(getattr(args, "quiet", False) or args._quiet)
    args.verbose = bool(getattr(args, "verbose", False) or args._verbose)
    try:
        with terminate_like_ctrl_c():
            _refuse_replacing_outputs(args)
            with _json_on_stdout(args):
                return int(args._run(args) or 0)
    except Terminated as exc:
        with contextlib.suppress(OSError):  # after a hang-up the terminal may be gone
            print("Stopped (terminated)." if exc.signum == signal.SIGTERM else
                  f"Stopped ({exc.signal_name}: the terminal closed).", file=sys.stderr)
        return 128 + exc.signum
    except KeyboardInterrupt:  # 128 + SIGINT, as a shell reports a process Ctrl-C stopped
        print("Stopped.", file=sys.stderr)
        return 130
    except BrokenPipeError as exc:
        if _stdout_broken():  # output piped into `head` and the like: stop quietly
            _silence_stdout()
            return 1
        print(f"tactip {args.command}: error: broken pipe ({_one_line(exc)}): a connection or a worker "
              f"process closed", file=sys.stderr)
        return 1
    except _known_errors() as exc:
        if args.verbose:
            import traceback

            traceback.print_exc(file=sys.stderr)
        print(f"tactip {args.command}: error: {_one_line(exc)}", file=sys.stderr)
        return 1


def _refuse_replacing_outputs(args: argparse.Namespace) -> None:
    """Before the command runs: no file the project wrote is among its outputs, unless --overwrite."""
    from tactip._output import refuse_replacing_project_files
    from tactip.cli._types import OutputPath

    outputs = [value for value in vars(args).values() if isinstance(value, OutputPath)]
    refuse_replacing_project_files(outputs, overwrite=bool(getattr(args, "overwrite", False)))


@contextlib.contextmanager
def _json_on_stdout(args: argparse.Namespace):
    """With ``--json`` to standard output, every other line goes to standard error (the JSON is written by
    `tactip._output.write_json` to the real standard output), so a script can parse standard output."""
    if str(getattr(args, "json", None)) != "-":
        yield
        return
    from tactip import _output

    _output.JSON_STDOUT = sys.stdout
    try:
        with contextlib.redirect_stdout(sys.stderr):
            yield
    finally:
        _output.JSON_STDOUT = None


def _stdout_broken() -> bool:
    """Whether standard output is a pipe whose reader has gone (``tactip ... | head``)."""
    try:
        fd = sys.stdout.fileno()
    except (AttributeError, ValueError, OSError):  # replaced by a StringIO, or closed
        return getattr(sys.stdout, "closed", False)
    try:
        import select

        poller = select.poll()
        poller.register(fd, select.POLLOUT)
        return any(event & (select.POLLERR | select.POLLHUP) for _, event in poller.poll(0))
    except (OSError, ValueError):
        return False


def _silence_stdout() -> None:
    # Python flushes stdout at exit: point it at /dev/null so that flush cannot fail again.
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    except (OSError, ValueError, AttributeError):
        pass


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.strerror and exc.errno is not None and str(exc).startswith("[Errno"):
        text = exc.strerror  # our own OSErrors carry the whole message in strerror
        if exc.errno in (errno.ENOENT, errno.EACCES, errno.EPERM, errno.EISDIR) and exc.filename and \
                str(exc.filename) not in text:
            text = f"{text}: {exc.filename}"
    else:
        text = str(exc) or type(exc).__name__
    if isinstance(exc, OSError) and exc.filename and str(exc.filename) not in text:
        text = f"{text}: {exc.filename}"
    return " ".join(text.split())


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
