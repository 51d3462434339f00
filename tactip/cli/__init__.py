"""The `tactip` command line.

Each subcommand lives in its own module of this package and exposes:

- ``HELP``: one line for the command list;
- ``add_arguments(parser)``: fills an ``argparse`` parser (parsing only);
- ``run(args) -> int``: calls the importable function that does the work, returns the exit code.

Heavy imports (OpenCV, h5py, torch) belong inside ``run`` so that ``tactip --help`` stays fast.
Errors from any package become one line on stderr and a non-zero exit; Ctrl-C prints "Stopped."
and exits 1; SIGTERM and SIGHUP (the terminal closed) are handled like Ctrl-C (work in progress is
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
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name, module_name in COMMANDS.items():
        module = importlib.import_module(module_name)
        doc = (module.__doc__ or "").strip()
        cmd = sub.add_parser(name, help=module.HELP, description=doc or module.HELP,
                             formatter_class=argparse.RawDescriptionHelpFormatter)
        if only is None or name == only:
            module.add_arguments(cmd)
        cmd.set_defaults(_run=module.run)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Entry point of the `tactip` console script; returns the process exit code."""
    from tactip._signals import Terminated, terminate_like_ctrl_c

    words = sys.argv[1:] if argv is None else argv
    command = next((str(w) for w in words if not str(w).startswith("-")), None)
    parser = build_parser(only=command if command in COMMANDS else "")
    args = parser.parse_args(argv)
    try:
        with terminate_like_ctrl_c():
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
        print(f"tactip {args.command}: error: {_one_line(exc)}", file=sys.stderr)
        return 1


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
