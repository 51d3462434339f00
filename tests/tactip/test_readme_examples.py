"""Every README example that calls ``tactip`` runs as written (issue 22).

Each example (a line of a ```sh block whose command is ``tactip``; a line ending in ``\\`` goes on on the
next) runs in a fresh folder of its own, with this tree's CLI (below: in this process or in bash). The folder
holds what the example reads, standing in for the user's files: ``station.toml`` is the session's small
simulated station (`sim_station`, its gap g02 renamed door-left; without its calibration for
``calibrate``, a new station), ``data/`` its taps, calibration and model, ``models/`` its histogram model
and a Gaussian one trained once, the ``samples/`` folder of the repository, the labelled recordings of the
dataset tests (``slides.csv``, ``presses.csv``, ``shapes.csv``), ``frame.png`` a sample frame and
``taps.mp4``/``new.avi`` sample videos. A file the example writes is never put there first. Output folders
are not created: the commands create them. ``--sim`` runs on a shared simulated data folder
(``TACTIP_SIM_DIR``: the small station's calibration and that Gaussian model with its settings), so that
the first run does not train the packaged station for minutes.

An example passes when it exits 0 (3 where it asks ``--fail-on``: a gap failed, as it may) with no
traceback. `SKIPPED` lists the examples that cannot run here or that another test runs as written, each with the
reason.

Most examples run in this process: ``tactip.cli.main`` with the example's words, in its folder and with its
environment, stdout and stderr captured; an exception escaping ``main`` is the traceback a user would see. A
fresh interpreter per example would import the package again (~1.7 s of CPU each) and prove nothing more about
the example. Two kinds still run in a subprocess through bash, as a user types them, with ``tactip`` on the
PATH: an example that needs the shell (a redirection, a parameter expansion; `_needs_shell`), where ``tactip``
is ``python -m tactip.cli``, and those of `ENTRY_POINT`, where it is the installed console script itself.
"""

from __future__ import annotations

import contextlib
import io
import os
import re
import shlex
import shutil
import stat
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from tests.tactip.conftest import LOCATIONS, built_once, run_cli, small_station_table, write_station
from tests.tactip.dataset import conftest as _recordings

# The labelled recordings of the dataset tests, built once per session (fixtures of that folder's conftest).
slide_videos, press_videos = _recordings.slide_videos, _recordings.press_videos
shape_images, slides_model = _recordings.shape_images, _recordings.slides_model

ROOT = Path(__file__).resolve().parents[2]
README = ROOT / "README.md"

_GEL = ("needs flat-gel recordings (tests/tactip/dataset/test_flat_gel_dataset.py runs detect, replay, dataset "
        "build, train and validate with --sensor gelsight-mini on synthetic GelSight-Mini videos)")

#: Examples that need what a test machine does not have: a substring of the example -> why.
SKIPPED = {
    "postgresql://": "needs the line's PostgreSQL server (tests/tactip/line/test_results_postgres.py runs a "
                     "throwaway one of its own)",
    "tactip serve": "starts the dashboard, a web server that runs until stopped (tests/tactip/line/"
                    "test_dashboard.py drives it in a browser)",
    "tactip record 0 ": "records camera 0, a real camera (tests/tactip/replay/test_record.py records fake and "
                        "synthetic cameras)",
    "gel_frame.png": _GEL, "gel_video.avi": _GEL, "gel/labels.csv": _GEL, "data/gel/": _GEL,
    "tactip reproduce 00": "tests/tactip/reproduce/test_reproduce.py runs 'tactip reproduce PAPER' for every paper "
                           "with --quick and checks its figures (full sizes: bench/bench_reproduce.py)",
    "tactip collect --config station.toml --out data/line3/datasets": "the session's small station is collected by "
        "this very command on this station (tests/tactip/conftest.py, sim_station; tests/tactip/cli/test_cli_station.py "
        "checks what it wrote): run once, not twice",
    "--scheduler tcp://HEAD": "needs a Dask cluster on other machines (tests/tactip/replay/test_batch.py starts a "
                              "dask scheduler and a dask worker of its own)",
}

#: Flags whose value is a file or folder the example writes (never provided beforehand).
_OUTPUT_FLAGS = ("--out", "--json", "--plot", "--annotate")

#: Examples run through the console script ``tactip`` that ``pip install`` put beside this Python (the
#: ``[project.scripts]`` entry point), in a subprocess: the installed command works, not only ``python -m``.
ENTRY_POINT = ("tactip detect frame.png --expected-pins 331 --json",)

#: Words of an example that only a shell understands: it runs through bash.
_SHELL_WORDS = {">", ">>", "<", "|", "||", "&&", ";", "&", "2>", "2>&1"}


def readme_examples(text: str | None = None) -> list[str]:
    """The README's ``tactip`` command lines, continuation lines joined, each once, in order."""
    text = README.read_text() if text is None else text
    examples, seen = [], set()
    for block in re.findall(r"^```sh\n(.*?)^```", text, flags=re.S | re.M):
        for line in block.replace("\\\n", " ").splitlines():
            words = shlex.split(line, comments=True)
            while words and re.fullmatch(r"[A-Z_]+=\S*", words[0]):       # VAR=value tactip ...
                words = words[1:]
            if words and words[0] == "tactip" and tuple(words) not in seen:
                seen.add(tuple(words))
                examples.append(line.strip())
    return examples


def test_the_readme_has_examples_of_every_command():
    """The parser finds the README's examples (a broken parser would pass every example by finding none)."""
    from tactip.cli import COMMANDS

    examples = readme_examples()
    assert len(examples) >= 30
    used = {next(w for w in shlex.split(e, comments=True) if not w.startswith("-") and "=" not in w and w != "tactip")
            for e in examples}
    assert used == set(COMMANDS), set(COMMANDS) ^ used
    joined = readme_examples("```sh\ntactip train a.h5 \\\n    --out b.h5   # note\nls\n```\n")
    assert joined == ["tactip train a.h5      --out b.h5   # note"]


def test_the_subprocess_examples_are_there():
    """The examples that prove the installed console script and ``python -m`` in a shell are README examples,
    not skipped: a README edit cannot silently leave every example to the in-process path."""
    runnable = [e for e in readme_examples() if not any(key in e for key in SKIPPED)]
    for entry in ENTRY_POINT:
        assert sum(e.startswith(entry) for e in runnable) == 1, entry
    shell = [e for e in runnable if _needs_shell(e)]
    assert any(">" in shlex.split(e, comments=True) for e in shell) and any("$" in e for e in shell), shell
    assert not _needs_shell("tactip train a.h5 --out 'b > c.h5'   # a > in quotes is a word")


@pytest.fixture(scope="session")
def readme_inputs(sim_station, slide_videos, press_videos, shape_images, slides_model, tmp_path_factory):
    """The files the examples read, built once: {path in the example's folder: source}."""
    with built_once(tmp_path_factory, "readme-inputs") as (root, build):
        if build:
            _build_inputs(root, sim_station)
    inputs = {
        "data/train.h5": sim_station.train, "data/test.h5": sim_station.test,
        "data/calibration.h5": sim_station.root / "calibration.h5", "data/model.h5": sim_station.model,
        "data/line3/datasets/train.h5": sim_station.train, "data/line3/datasets/test.h5": sim_station.test,
        "data/line3/model.h5": root / "gaussian.h5",
        "models/gaps.h5": sim_station.model, "models/histogram.h5": sim_station.model,
        "models/gaussian.h5": root / "gaussian.h5",
        "frame.png": ROOT / "samples" / "synthetic_frame.png", "taps.mp4": ROOT / "samples" / "synthetic_tap.mp4",
        "new.avi": slide_videos.root / "slide_000.avi",
        "slides.csv": slide_videos.labels, "presses.csv": press_videos.labels, "shapes.csv": shape_images.labels,
        "shapes/rest.png": shape_images.rest,
        **{f"data/slides/{name}": slides_model / name for name in ("train.h5", "test.h5", "model.h5",
                                                                   "calibration.h5")},
        **{f"data/fingertip/{name}": root / "fingertip" / name for name in ("train.h5", "test.h5", "model.h5")},
    }
    # The recordings the label files name, beside them (paths in a labels file are relative to it).
    recordings = {name: folder / name for folder in (slide_videos.root, press_videos.root, shape_images.root)
                  for name in os.listdir(folder) if name.endswith((".avi", ".png")) and name != "rest.png"}
    return root, inputs, recordings


def _build_inputs(root: Path, sim_station) -> None:
    """The station with a door-left gap and its results, a Gaussian model with its settings, the simulated
    data folder of ``--sim``, and the fingertip collections."""
    station = root / "station"
    station.mkdir()
    for name in ("calibration.h5", "model.h5"):
        shutil.copy(sim_station.root / name, station / name)
    code, _, err = run_cli(["inspect", "--config", _station_toml(station), "--gap", "door-left", "--seed", "0", "-q"])
    assert code == 0, err
    code, _, err = run_cli(["train", sim_station.train, "--out", root / "gaussian.h5", "--model", "gaussian",
                            "--locations", LOCATIONS, "--choose-fixation", "--target-accuracy", "0.95",
                            "--tolerance", "0.25", "-q"])
    assert code == 0, err
    (root / "sim").mkdir()
    shutil.copy(sim_station.root / "calibration.h5", root / "sim" / "calibration.h5")
    shutil.copy(root / "gaussian.h5", root / "sim" / "model.h5")
    code, _, err = run_cli(["inspect", "--sim", "--data-dir", root / "sim", "--gap", "g01", "--seed", "0", "-q"])
    assert code == 0, err                                                  # results for `results list --db`
    code, _, err = run_cli(["simulate", "taxel", "--sensor", "fingertip", "--out", root / "fingertip", "--seed", "1",
                            "-q"])
    assert code == 0, err
    code, _, err = run_cli(["train", root / "fingertip" / "train.h5", "--out", root / "fingertip" / "model.h5",
                            "--locations", "300", "-q"])
    assert code == 0, err


def _station_toml(folder: Path) -> Path:
    """The small simulated station keeping its files in ``folder``, its gap g02 named door-left."""
    table = small_station_table(folder)
    for gap in table["gaps"]:
        gap["name"] = "door-left" if gap["name"] == "g02" else gap["name"]
    return write_station(folder, table)


def _outputs(words: list[str]) -> set[str]:
    return {value for flag, value in zip(words, words[1:]) if flag in _OUTPUT_FLAGS}


def _prepare(folder: Path, example: str, readme_inputs) -> dict:
    """Put in ``folder`` what ``example`` reads; returns the environment to run it in."""
    root, inputs, recordings = readme_inputs
    words = shlex.split(example, comments=True)
    outputs = _outputs(words)
    shutil.copytree(ROOT / "samples", folder / "samples")
    for name, source in inputs.items():
        if name in example and name not in outputs and not any(name.startswith(o.rstrip("/") + "/") for o in outputs):
            (folder / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(source, folder / name)
    if any(name.endswith(".csv") and name in example for name in inputs):
        for name, source in recordings.items():
            shutil.copy(source, folder / name)
    if "archive/" in example and "--out-dir" in words:            # an archive of recordings, one in a subfolder
        for name in ("archive/tap_a.mp4", "archive/tap_b.mp4", "more/day1/tap_c.mp4"):
            (folder / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(ROOT / "samples" / "synthetic_tap.mp4", folder / name)
    if "station.toml" in example:
        _station_toml(folder)
        new_station = "calibrate" in words                        # a new station: not calibrated yet
        for name in ("model.h5", "results.sqlite") + (() if new_station else ("calibration.h5",)):
            shutil.copy(root / "station" / name, folder / name)
    sim = folder / ".sim"
    shutil.copytree(root / "sim", sim)
    bin_dir = folder / ".bin"
    bin_dir.mkdir()
    wrapper = bin_dir / "tactip"
    command = f"{shlex.quote(sys.executable)} -m tactip.cli"
    if any(example.startswith(e) for e in ENTRY_POINT):
        script = Path(sys.executable).with_name("tactip")
        assert script.is_file(), f"no console script {script}: install the package (make .venv/.installed)"
        command = shlex.quote(str(script))
    wrapper.write_text(f'#!/bin/sh\nexec {command} "$@"\n')
    wrapper.chmod(wrapper.stat().st_mode | stat.S_IXUSR)
    (folder / ".home").mkdir()
    return {**os.environ, "PATH": f"{bin_dir}{os.pathsep}{os.environ['PATH']}", "PYTHONPATH": str(ROOT),
            "TACTIP_SIM_DIR": str(sim), "HOME": str(folder / ".home"), "MPLBACKEND": "Agg"}


def _needs_shell(example: str) -> bool:
    """Whether ``example`` uses the shell's own syntax (a redirection, a pipe, a parameter expansion)."""
    words = shlex.split(example, comments=True)
    return any(w in _SHELL_WORDS or "$" in w or "`" in w for w in words)


def _run_here(example: str, folder: Path, env: dict, monkeypatch) -> tuple[int, str, str]:
    """``example`` run by ``tactip.cli.main`` in this process, in ``folder`` with ``env``: (exit code, out, err).

    The example's words are the shell's (`shlex`: quotes and comments as bash reads them); a leading
    ``VAR=value`` sets that variable for the command, as in bash. Argument errors (argparse's `SystemExit`)
    give their exit code; any other exception escapes, as the traceback it would print.
    """
    from tactip.cli import main

    words = shlex.split(example, comments=True)
    while re.fullmatch(r"[A-Z_]+=\S*", words[0]):
        name, value = words.pop(0).split("=", 1)
        env = {**env, name: value}
    assert words[0] == "tactip", example
    for name, value in env.items():
        if os.environ.get(name) != value:
            monkeypatch.setenv(name, value)
    monkeypatch.chdir(folder)
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main(words[1:])
        except SystemExit as exc:   # what the interpreter would make of it
            code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    return code, out.getvalue(), err.getvalue()


def _example_id(example: str) -> str:
    """The example's command without its comment, for the test's id."""
    return " ".join(shlex.join(shlex.split(example, comments=True)).split())[:100]


@pytest.mark.slow
@pytest.mark.parametrize("example", readme_examples(), ids=_example_id)
def test_a_readme_example_runs_as_written(example, readme_inputs, tmp_path, monkeypatch):
    reason = next((why for key, why in SKIPPED.items() if key in example), None)
    if reason:
        pytest.skip(reason)
    env = _prepare(tmp_path, example, readme_inputs)
    if _needs_shell(example) or any(example.startswith(e) for e in ENTRY_POINT):
        done = subprocess.run(["bash", "-c", f"set -o pipefail\n{example}"], cwd=tmp_path, env=env,
                              capture_output=True, text=True, timeout=900)
        code, out, err = done.returncode, done.stdout, done.stderr
    else:
        code, out, err = _run_here(example, tmp_path, env, monkeypatch)
    allowed = {0, 3} if "--fail-on" in example else {0}
    assert code in allowed and "Traceback" not in err, (
        f"{example}\nexit {code}\nstdout: {out[-3000:]}\nstderr: {err[-3000:]}")
    for output in _outputs(shlex.split(example, comments=True)):
        if output != "-" and not output.startswith("-"):
            assert (tmp_path / output).exists(), f"{example}: {output} not written"


def test_the_simulated_station_s_data_folder_is_the_one_the_examples_share(readme_inputs):
    """``--sim`` finds a prepared model in TACTIP_SIM_DIR (so no example retrains the packaged station)."""
    from tactip.station.procedures import model_is_prepared

    root, _, _ = readme_inputs
    assert model_is_prepared(root / "sim" / "model.h5")
    assert tomllib.loads((ROOT / "tactip" / "station" / "presets" / "station_sim.toml").read_text())[
        "perception"]["likelihood"] == "gaussian"
