"""A small harness for fault-injection tests of the real `tactip` CLI (issue 9).

Helpers shared by ``test_faults_data.py`` and ``test_faults_input.py``:

- `run_tactip` runs ``python -m tactip.cli ARGS`` in a subprocess and checks what every case must
  satisfy whatever its outcome: no Python traceback on stderr, every path in ``inputs`` byte-identical
  afterwards, and no temporary file (``.*.part*``, ``*.tmp``, ``*~``) left beside the inputs or in ``cwd``.
- `run_tactip_in_process` does the same through `tactip.cli.main` in this process (an exception that
  escapes it fails the test, as a traceback would), for variants of a case whose subprocess start is
  not the point (a start costs about a second);
- `assert_refused` checks that a command was refused: non-zero exit and a message naming the problem.

Example
-------
>>> result = run_tactip("train", "train.h5", "--out", "train.h5", cwd=tmp_path, inputs=["train.h5"])
>>> assert_refused(result, "train.h5", "input")
"""

from __future__ import annotations

import contextlib
import hashlib
import io
import os
import subprocess
import sys
from pathlib import Path

__all__ = ["run_tactip", "run_tactip_in_process", "assert_refused", "leftover_temporaries", "digest"]

# Names of the temporary files writers use before renaming them into place.
_TEMPORARY_PATTERNS = (".*.part*", "*.part", "*.tmp", ".*.tmp*", "*~")


def digest(path: Path) -> str | None:
    """SHA-256 of the file at ``path`` (``None`` if it does not exist; a directory hashes its files)."""
    path = Path(path)
    if path.is_dir():
        h = hashlib.sha256()
        for child in sorted(p for p in path.rglob("*") if p.is_file()):
            h.update(str(child.relative_to(path)).encode())
            h.update(child.read_bytes())
        return h.hexdigest()
    if not path.exists():
        return None
    return hashlib.sha256(path.read_bytes()).hexdigest()


def leftover_temporaries(*folders: Path) -> list[Path]:
    """Temporary files (``.NAME.PID.part*``, ``*.tmp``, ``*~``) directly inside ``folders``."""
    found = set()
    for folder in folders:
        folder = Path(folder)
        if not folder.is_dir():
            continue
        for pattern in _TEMPORARY_PATTERNS:
            found.update(p for p in folder.glob(pattern) if p.is_file())
    return sorted(found)


def run_tactip(*args, cwd, inputs=(), timeout: float = 120, env: dict | None = None,
               stdin: str | None = None, **popen) -> subprocess.CompletedProcess:
    """Run ``tactip ARGS`` as a subprocess in ``cwd`` and check the invariants of every fault case.

    Parameters
    ----------
    *args : str or Path
        The command line after ``tactip``.
    cwd : Path
        Working folder of the process (checked for leftover temporary files).
    inputs : sequence of Path
        Files (or folders) the command must not change: hashed before and compared after.
        Relative paths are taken relative to ``cwd``. Their folders are checked for temporaries.
    timeout : float
        Seconds before the process is killed (the test then fails with `subprocess.TimeoutExpired`).
    env : dict, optional
        Extra environment variables (added to a copy of ``os.environ``).
    stdin : str, optional
        Text fed to the process's standard input.
    **popen
        Passed to `subprocess.run` (e.g. ``preexec_fn`` to set a resource limit, ``user`` to drop root).

    Returns
    -------
    subprocess.CompletedProcess
        With text ``stdout`` and ``stderr``; the exit code is not checked here (see `assert_refused`).
    """
    cwd = Path(cwd)
    paths = [p if Path(p).is_absolute() else cwd / p for p in map(Path, inputs)]
    before = {p: digest(p) for p in paths}
    full_env = dict(os.environ)
    full_env.setdefault("PYTHONUNBUFFERED", "1")
    if env:
        full_env.update({k: str(v) for k, v in env.items()})
    argv = [sys.executable, "-m", "tactip.cli", *map(str, args)]
    result = subprocess.run(argv, cwd=cwd, capture_output=True, text=True, timeout=timeout, env=full_env,
                            input=stdin, stdin=None if stdin is not None else subprocess.DEVNULL, **popen)
    _check_after(args, result, paths, before, cwd)
    return result


def _check_after(args, result, paths, before, cwd) -> None:
    """The invariants of every case, after the command: no traceback, inputs unchanged, no temporaries."""
    where = f"`tactip {' '.join(map(str, args))}` (exit {result.returncode})"
    assert "Traceback" not in result.stderr, f"{where} printed a traceback:\n{result.stderr}"
    changed = [str(p) for p in paths if digest(p) != before[p]]
    assert not changed, f"{where} changed its inputs {changed}\nstderr: {result.stderr}"
    left = leftover_temporaries(cwd, *{p.parent for p in paths}, *[p for p in paths if p.is_dir()])
    assert not left, f"{where} left temporary files {[str(p) for p in left]}\nstderr: {result.stderr}"


def run_tactip_in_process(*args, cwd, inputs=()) -> subprocess.CompletedProcess:
    """`run_tactip` through `tactip.cli.main` in this process: the same checks, no process start.

    An exception escaping `main` (a traceback in the real command) propagates and fails the test.
    """
    from tactip.cli import main

    cwd = Path(cwd)
    paths = [p if Path(p).is_absolute() else cwd / p for p in map(Path, inputs)]
    before = {p: digest(p) for p in paths}
    out, err = io.StringIO(), io.StringIO()
    with contextlib.chdir(cwd), contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([str(a) for a in args])
        except SystemExit as exit_:                    # argparse's refusals
            code = exit_.code
    result = subprocess.CompletedProcess(["tactip", *map(str, args)], code, out.getvalue(), err.getvalue())
    _check_after(args, result, paths, before, cwd)
    return result


def assert_refused(result: subprocess.CompletedProcess, *words: str) -> None:
    """Assert that ``result`` exited non-zero and its stderr names each of ``words`` (case-insensitive)."""
    assert result.returncode != 0, f"exit 0 where a refusal was expected\nstdout: {result.stdout}\nstderr: {result.stderr}"
    text = result.stderr.lower()
    missing = [w for w in words if w.lower() not in text]
    assert not missing, f"the message does not name {missing}:\n{result.stderr}"
