"""Issue 9, input validation: every command refuses bad input before it starts, naming the argument or key
and the accepted range, with no traceback, its inputs byte-identical and no temporary file left.

Three layers, cheapest last:

- `test_bad_input_is_refused_by_the_real_cli`: one row per case of the issue (and a few more found by a
  sweep of every flag), each run as ``python -m tactip.cli`` in a subprocess through `faultkit.run_tactip`;
- `test_an_unreadable_video_says_permission_denied`: the same for a file the user may not read (as root,
  with the capability that overrides file permissions dropped);
- `test_every_numeric_flag_refuses_non_numbers` and `test_every_station_key_refuses_wrong_types`: the
  whole sweep of flags and TOML keys in-process (argparse and the configuration loader), which is
  where those refusals happen.

The station files are a small copy of the packaged simulated station (`conftest.small_station_table`);
the model and test taps are a tiny synthetic dataset trained in-process, so the suite needs no collection.
"""

from __future__ import annotations

import argparse
import math
import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pytest

from tactip.cli import build_parser
from tactip.station.config import parse_station_config
from tactip.errors import ConfigError
from tests.tactip.conftest import small_station_table, write_station
from tests.tactip.faultkit import assert_refused, digest, leftover_temporaries, run_tactip, run_tactip_in_process

SAMPLES = Path(__file__).resolve().parents[2] / "samples"
VIDEO = SAMPLES / "synthetic_tap.mp4"
IMAGE = SAMPLES / "synthetic_frame.png"
ARM = SAMPLES / "arm_sim.toml"


# -- the files every case starts from -----------------------------------------------------------------------

def _tiny_taps(rng, locations, identities, repeats=4, samples=5, dims=4):
    """Taps whose values follow location and identity, with noise: enough for a model that decides in a few taps."""
    loc, ident = np.meshgrid(locations, identities, indexing="ij")
    loc, ident = np.repeat(loc.ravel(), repeats), np.repeat(ident.ravel(), repeats)
    signal = np.stack([loc, ident, loc * ident, loc - ident], axis=-1)[:, None, :dims]
    taps = signal + rng.normal(0, 0.6, (len(loc), samples, dims))
    return taps, loc, ident


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A station TOML (small simulated station), a trained model and its test taps, a video and variants."""
    from perception import Dataset, fit_model, save_dataset, save_model

    root = tmp_path_factory.mktemp("faults_input")
    table = small_station_table(root)
    toml = write_station(root, table)
    rng = np.random.default_rng(0)
    locations, identities = np.linspace(0.0, 5.5, 6), np.array([0.5, 1.5])
    train = Dataset(*_tiny_taps(rng, locations, identities), None, "tactip")
    test = Dataset(*_tiny_taps(rng, locations, identities), None, "tactip")
    save_dataset(root / "train.h5", train)
    save_dataset(root / "test.h5", test)
    save_model(root / "model.h5", fit_model(train, n_locations=6, bins=10))
    shutil.copy(VIDEO, root / "video.mp4")
    (root / "not_a_video.mp4").write_text("hello, I am text\n")
    (root / "corrupt.mp4").write_bytes(VIDEO.read_bytes()[:20000])
    (root / "empty.mp4").write_bytes(b"")
    (root / "binary.toml").write_bytes(bytes(range(256)))
    (root / "latin1.toml").write_bytes(toml.read_text().replace('"sim-line-1"', '"ligne-é"').encode("latin-1"))
    (root / "folder").mkdir()
    (root / "text.txt").write_text("a file\n")
    import cv2

    cv2.imwrite(str(root / "tiny.png"), np.zeros((1, 1), np.uint8))
    model_bytes = (root / "model.h5").read_bytes()
    (root / "model_cut.h5").write_bytes(model_bytes[:len(model_bytes) // 2])   # a copy that did not finish

    def variant(name, section, **values):
        changed = tomllib.loads(toml.read_text())
        node = changed
        for part in section.split("."):
            node = node.setdefault(part, {})
        node.update(values)
        return write_station(root, changed, name)

    variant("data_dir_5.toml", "station", data_dir=5)
    variant("data_dir_file.toml", "station", data_dir=str(root / "text.txt"))
    variant("results_under_file.toml", "station", results=str(root / "text.txt" / "results.sqlite"))
    variant("results_5.toml", "station", results=5)
    variant("sim_seed.toml", "sim", seed=-1)
    variant("protocol_seed.toml", "protocol", seed=-3)
    variant("pins_5.toml", "sensor", pins=5, selected_pins=5)
    variant("pins_huge.toml", "sensor", pins=100000)
    variant("dwell.toml", "arm.tap", dwell=100000)
    variant("depth_step.toml", "protocol", depth_step=1e-7)
    variant("repeats.toml", "protocol", depth_step=0.01, repeats=100)
    variant("samples.toml", "protocol", samples=10**6)
    variant("bins.toml", "perception", bins=10**7)
    (root / "nan.toml").write_text(toml.read_text().replace("noise_sigma = 4.0", "noise_sigma = nan"))
    far = tomllib.loads(toml.read_text())
    far["gaps"][0]["x"] = 1e30
    write_station(root, far, "gap_far.toml")
    return root


# -- the issue's cases and the sweep's, through the real CLI --------------------------------------------------

# (case id, command line with {root} for the files' folder, words the message must contain)
CASES = [
    # tracebacks
    ("record --seconds inf", ["record", "synthetic", "--out", "r.mp4", "--seconds", "inf", "--quiet"],
     ["--seconds", "finite"]),
    ("simulate huge --locations", ["simulate", "taxel", "--out", "tx", "--locations", "10000000000"],
     ["--locations", "2..100000"]),
    ("simulate locations x taps", ["simulate", "taxel", "--out", "tx", "--locations", "60000",
                                   "--taps-per-location", "2"], ["--locations", "--taps-per-location", "100000"]),
    ("validate huge --runs", ["validate", "{root}/model.h5", "{root}/test.h5", "--runs", "100000000000"],
     ["--runs", "1..10000000"]),
    ("train huge --bins", ["train", "{root}/train.h5", "--out", "m.h5", "--bins", "100000000"], ["--bins"]),
    ("train huge --locations", ["train", "{root}/train.h5", "--out", "m.h5", "--locations", "100000000"],
     ["--locations"]),
    ("validate negative --seed", ["validate", "{root}/model.h5", "{root}/test.h5", "--seed", "-1"],
     ["--seed", "0..4294967295"]),
    ("simulate negative --seed", ["simulate", "taxel", "--out", "tx", "--seed", "-1"], ["--seed", "0.."]),
    ("validate negative --sweep-lateral", ["validate", "{root}/model.h5", "{root}/test.h5", "--sweep-lateral", "-1"],
     ["--sweep-lateral", ">= 0"]),
    ("validate --plot x.xyz", ["validate", "{root}/model.h5", "{root}/test.h5", "--plot", "x.xyz"],
     ["--plot", "xyz", "png", "pdf", "svg"]),
    ("validate --json a folder", ["validate", "{root}/model.h5", "{root}/test.h5", "--json", "{root}/folder"],
     ["--json", "folder"]),
    ("binary TOML", ["calibrate", "--config", "{root}/binary.toml"], ["binary.toml", "binary", "UTF-8"]),
    ("Latin-1 TOML", ["calibrate", "--config", "{root}/latin1.toml"], ["latin1.toml", "UTF-8", "Latin-1", "0xe9"]),
    ("TOML is a folder", ["collect", "--config", "{root}/folder", "--out", "d"], ["folder", "not a TOML file"]),
    ("data_dir = 5", ["calibrate", "--config", "{root}/data_dir_5.toml"], ["station.data_dir", "path", "5"]),
    ("results = 5", ["inspect", "--config", "{root}/results_5.toml"], ["station.results", "path", "5"]),
    ("negative [sim] seed", ["calibrate", "--config", "{root}/sim_seed.toml"], ["sim.seed", "0..4294967295", "-1"]),
    ("negative [protocol] seed", ["collect", "--config", "{root}/protocol_seed.toml", "--out", "d"],
     ["protocol.seed", "-3"]),
    ("calibrate pins = 5", ["calibrate", "--config", "{root}/pins_5.toml"], ["sensor.pins", "7..2000", "5"]),
    ("calibrate pins = 100000", ["calibrate", "--config", "{root}/pins_huge.toml"], ["sensor.pins", "7..2000"]),
    ("noise_sigma = nan", ["calibrate", "--config", "{root}/nan.toml"], ["sim.noise_sigma", "number", "nan"]),
    ("gap outside the workspace", ["inspect", "--config", "{root}/gap_far.toml"], ["gaps[0].x", "workspace"]),
    # silent nonsense
    ("validate --fixation 100", ["validate", "{root}/model.h5", "{root}/test.h5", "--fixation", "100"],
     ["--fixation", "100", "0..5.5"]),
    ("validate --fixation nan", ["validate", "{root}/model.h5", "{root}/test.h5", "--fixation", "nan"],
     ["--fixation", "finite"]),
    ("replay --mm-per-px inf", ["replay", "{root}/video.mp4", "--out", "r.h5", "--mm-per-px", "inf"],
     ["--mm-per-px", "finite"]),
    ("record --frame-rate huge", ["record", "synthetic", "--out", "r.mp4", "--frame-rate", "1e9"],
     ["--frame-rate", "[0.01, 1000]"]),
    ("record --frame-rate too small for the encoder", ["record", "synthetic", "--out", "r.mp4", "--frame-rate",
                                                       "0.001"], ["--frame-rate", "[0.01, 1000]", "0.001"]),
    ("replay --mm-per-px huge", ["replay", "{root}/video.mp4", "--out", "r.h5", "--mm-per-px", "1e300"],
     ["--mm-per-px", "(0, 10] mm/px"]),
    ("replay --samples huge", ["replay", "{root}/video.mp4", "--out", "r.h5", "--samples", "1000000000000"],
     ["--samples", "1..1000"]),
    ("replay --expected-pins 1..5", ["replay", "{root}/video.mp4", "--out", "r.h5", "--expected-pins", "3"],
     ["--expected-pins", "7..2000", "got 3"]),
    ("replay --pins-on-pad huge", ["replay", "{root}/video.mp4", "--out", "r.h5", "--pins-on-pad", "1000000"],
     ["--pins-on-pad", "7..2000"]),
    ("record --exposure of a synthetic source", ["record", "synthetic", "--out", "r.mp4", "--exposure", "5"],
     ["exposure", "camera only"]),
    ("results plot --out x.xyz", ["results", "plot", "--db", "{root}/missing.sqlite", "--out", "x.xyz"],
     ["--out", "xyz", "png"]),
    ("arm tap --depth nan", ["arm", "tap", "--config", str(ARM), "--depth", "nan"], ["--depth", "finite"]),
    ("tap budget 0", ["validate", "{root}/model.h5", "{root}/test.h5", "--sweep-fixation", "--tap-budget", "0"],
     ["--tap-budget", "[1, 1000]"]),
    ("tap budget nan", ["validate", "{root}/model.h5", "{root}/test.h5", "--sweep-fixation", "--tap-budget", "nan"],
     ["--tap-budget", "finite"]),
    ("tap budget above --max-taps", ["validate", "{root}/model.h5", "{root}/test.h5", "--sweep-fixation",
                                     "--tap-budget", "30"], ["--tap-budget", "1..--max-taps (20)"]),
    ("tap budget too tight", ["validate", "{root}/model.h5", "{root}/test.h5", "--sweep-fixation", "--runs", "200",
                              "--thresholds", "0.9", "0.99", "--tap-budget", "1", "--quiet"],
     ["--tap-budget", "too tight", "nothing written"]),
    ("sweep thresholds that decide after one tap", ["validate", "{root}/model.h5", "{root}/test.h5", "--sweep-fixation",
                                                    "--thresholds", "0", "0.2", "--quiet"],
     ["--thresholds", "1/2", "first tap"]),
    # hangs
    ("dwell = 100000", ["collect", "--config", "{root}/dwell.toml", "--out", "d"], ["dwell", "[0, 10] s", "100000"]),
    ("depth_step = 1e-7", ["collect", "--config", "{root}/depth_step.toml", "--out", "d"],
     ["protocol.depth_step", "55000001 depths", "10000"]),
    ("repeats x depths x gaps", ["collect", "--config", "{root}/repeats.toml", "--out", "d"],
     ["taps per collection", "220400", "551 depths", "repeats 100", "200000"]),
    ("samples = 10**6", ["collect", "--config", "{root}/samples.toml", "--out", "d"], ["protocol.samples", "2..1000"]),
    ("bins = 10**7", ["inspect", "--config", "{root}/bins.toml"], ["perception.bins", "2..10000"]),
    ("collect --workers 500", ["collect", "--config", "{root}/station.toml", "--out", "d", "--workers", "500"],
     ["--workers", "500", "CPUs"]),
    ("calibrate --rest-frames huge", ["calibrate", "--config", "{root}/station.toml", "--rest-frames", "10000000"],
     ["--rest-frames", "1..1000"]),
    ("validate --max-taps huge", ["validate", "{root}/model.h5", "{root}/test.h5", "--max-taps", "1000000000"],
     ["--max-taps", "1..1000"]),
    # misleading messages
    ("video: not a video", ["replay", "{root}/not_a_video.mp4", "--out", "r.h5"], ["not_a_video.mp4", "not a video"]),
    ("video: corrupt", ["replay", "{root}/corrupt.mp4", "--out", "r.h5"], ["corrupt.mp4", "corrupt", "MP4"]),
    ("video: empty", ["replay", "{root}/empty.mp4", "--out", "r.h5"], ["empty.mp4", "empty file"]),
    ("record: out is a folder", ["record", "synthetic", "--out", "{root}/folder", "--frames", "2"],
     ["--out", "folder"]),
    ("collect: out is a file", ["collect", "--config", "{root}/station.toml", "--out", "{root}/text.txt"],
     ["--out", "not a folder"]),
    ("simulate: out under a file", ["simulate", "taxel", "--out", "{root}/text.txt/sub"], ["--out", "not a folder"]),
    # a careful user's further tries (beyond the issue's list)
    ("detect a text file", ["detect", "{root}/text.txt"], ["text.txt", "not an image"]),
    ("detect a video", ["detect", "{root}/video.mp4"], ["video.mp4", "a video", "tactip replay"]),
    ("detect a 1x1 image", ["detect", "{root}/tiny.png"], ["1x1 px", "too small"]),
    ("validate a model cut short", ["validate", "{root}/model_cut.h5", "{root}/test.h5"],
     ["model_cut.h5", "cut short", "did not finish"]),
    ("simulate over a TacTip collection", ["simulate", "taxel", "--out", "{root}", "--locations", "10", "--quiet"],
     ["train.h5", "collected taps", "--overwrite"]),
    ("simulate --overwrite over a TacTip collection", ["simulate", "taxel", "--out", "{root}", "--locations", "10",
                                                       "--quiet", "--overwrite"],
     ["train.h5", "'tactip' dataset", "another --out"]),
    ("replay --decision-threshold 0", ["replay", "{root}/video.mp4", "--out", "r.h5", "--decision-threshold", "0"],
     ["--decision-threshold", "(0, 1]"]),
    ("inspect --start-depth outside the protocol", ["inspect", "--config", "{root}/station.toml", "--start-depth",
                                                    "100"], ["--start-depth", "100 mm", "0..5.5 mm"]),
    ("an output name too long", ["train", "{root}/train.h5", "--out", "b" * 260 + ".h5"],
     ["--out", "too long for the file system", "at most 255"]),
    ("data_dir is a file", ["calibrate", "--config", "{root}/data_dir_file.toml"],
     ["station.data_dir", "text.txt", "is a file, not a folder"]),
    ("results under a file", ["inspect", "--config", "{root}/results_under_file.toml"],
     ["station.results", "text.txt' is a file, not a folder"]),
    ("replay --annotate not .mp4", ["replay", "{root}/video.mp4", "--out", "r.h5", "--annotate", "a.txt"],
     ["a.txt", "MPEG-4", ".mp4"]),
    ("replay --rest-frame beyond the end", ["replay", "{root}/video.mp4", "--out", "r.h5", "--rest-frame", "86",
                                            "--quiet"], ["86 frames", "no rest frame 86"]),
]

# Every file of the fixture folder is an input of every case: none may change.
_INPUTS = ("station.toml", "model.h5", "train.h5", "test.h5", "video.mp4", "not_a_video.mp4", "corrupt.mp4",
           "binary.toml", "latin1.toml", "dwell.toml", "depth_step.toml", "pins_5.toml")


# The cases issue 9 lists run as real subprocesses; the others found by the sweep run in-process (the same
# `tactip.cli.main`, the same checks), because a subprocess start costs about a second.
ISSUE_CASES = {
    "record --seconds inf", "simulate huge --locations", "validate huge --runs", "train huge --bins",
    "train huge --locations", "validate negative --seed", "validate negative --sweep-lateral", "validate --plot x.xyz",
    "binary TOML", "Latin-1 TOML", "data_dir = 5", "results = 5", "negative [sim] seed", "calibrate pins = 5",
    "validate --fixation 100", "validate --fixation nan", "replay --mm-per-px inf", "tap budget 0", "tap budget nan",
    "tap budget too tight", "dwell = 100000", "depth_step = 1e-7", "collect --workers 500", "video: not a video",
    "video: corrupt",
}
SUBPROCESS = [c for c in CASES if c[0] in ISSUE_CASES]
IN_PROCESS = [c for c in CASES if c[0] not in ISSUE_CASES]


def _check_refusal(result, tmp_path, words):
    assert_refused(result, *words)
    # One line naming the problem (after argparse's usage lines), and nothing written in the working folder.
    assert result.stderr.strip().splitlines()[-1].startswith("tactip "), result.stderr
    assert not list(tmp_path.iterdir()), [p.name for p in tmp_path.iterdir()]


@pytest.mark.parametrize("case, argv, words", SUBPROCESS, ids=[c[0] for c in SUBPROCESS])
def test_bad_input_is_refused_by_the_real_cli(files, tmp_path, case, argv, words):
    args = [a.replace("{root}", str(files)) for a in argv]
    result = run_tactip(*args, cwd=tmp_path, inputs=[files / name for name in _INPUTS], timeout=60)
    _check_refusal(result, tmp_path, words)


@pytest.mark.parametrize("case, argv, words", IN_PROCESS, ids=[c[0] for c in IN_PROCESS])
def test_bad_input_is_refused_in_process(files, tmp_path, monkeypatch, capsys, case, argv, words):
    from tactip.cli import main

    inputs = [files / name for name in _INPUTS]
    before = {p: digest(p) for p in inputs}
    monkeypatch.chdir(tmp_path)
    try:
        code = main([a.replace("{root}", str(files)) for a in argv])  # an exception here is a traceback: fails
    except SystemExit as exit_:
        code = exit_.code
    captured = capsys.readouterr()
    result = subprocess.CompletedProcess(argv, code, captured.out, captured.err)
    _check_refusal(result, tmp_path, words)
    assert {p: digest(p) for p in inputs} == before
    assert not leftover_temporaries(files, tmp_path)


def test_the_sweep_recommends_within_a_workable_budget(files, tmp_path):
    """The refusals above are not blanket ones: a budget the model can meet is written into the model."""
    from perception import load_model

    model = tmp_path / "model.h5"
    shutil.copy(files / "model.h5", model)
    result = run_tactip_in_process("validate", model, files / "test.h5", "--sweep-fixation", "--runs", "200",
                                   "--thresholds", "0.2", "0.9", "0.99", "--tap-budget", "6", "--quiet", cwd=tmp_path,
                                   inputs=[files / "test.h5"])
    assert result.returncode == 0, result.stderr
    recommended = load_model(model).recommended
    assert recommended["decision_threshold"] in (0.9, 0.99)  # 0.2 < 1/2 decides after the first tap: never chosen
    assert 0.0 <= recommended["fixation_location"] <= 5.5


def _without_file_permission_override():
    """A command prefix under which root obeys file permissions (None when not needed or not possible)."""
    if os.geteuid() != 0:
        return []
    setpriv = shutil.which("setpriv")
    if setpriv is None:
        return None
    drop = "-dac_override,-dac_read_search"
    return [setpriv, f"--inh-caps={drop}", f"--bounding-set={drop}"]


def test_an_unreadable_video_says_permission_denied(files, tmp_path):
    prefix = _without_file_permission_override()
    if prefix is None:
        pytest.skip("running as root without setpriv: permissions cannot be enforced")
    video = tmp_path / "locked.mp4"
    shutil.copy(VIDEO, video)
    video.chmod(0)
    before = digest(video) if os.geteuid() == 0 else None
    try:
        result = subprocess.run([*prefix, sys.executable, "-m", "tactip.cli", "replay", str(video), "--out",
                                 str(tmp_path / "r.h5")], cwd=tmp_path, capture_output=True, text=True, timeout=60,
                                stdin=subprocess.DEVNULL)
    finally:
        video.chmod(0o644)
    assert "Traceback" not in result.stderr, result.stderr
    assert_refused(result, "locked.mp4", "permission denied")
    assert "corrupt" not in result.stderr
    assert before is None or digest(video) == before
    assert not leftover_temporaries(tmp_path) and not (tmp_path / "r.h5").exists()


# -- the sweep of every flag and key, in-process ----------------------------------------------------------------

def _numeric_flags():
    """(subcommand path, flag, needs) for every option parsed by a numeric type of `tactip.cli._types` or float/int."""
    from tactip.cli import _types

    numeric = {_types.finite_float, _types.positive_float, _types.non_negative_float, _types.fraction,
               _types.fractions, _types.positive_int, _types.non_negative_int, _types.seed, _types.worker_count,
               float, int}
    found = []

    def walk(parser, path):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                for name, sub in action.choices.items():
                    walk(sub, path + [name])
            elif action.option_strings and action.type is not None:
                typ = action.type
                closure_numeric = getattr(typ, "__qualname__", "").startswith(("int_at_least", "float_in_range",
                                                                               "_finite", "_pin_count"))
                if typ in numeric or closure_numeric:
                    found.append((tuple(path), action.option_strings[-1], action.nargs))

    walk(build_parser(), [])
    return found


NUMERIC_FLAGS = _numeric_flags()
NOT_A_NUMBER = ("nan", "inf", "-inf", "", "abc")


def test_the_sweep_finds_the_flags():
    flags = {(" ".join(path), flag) for path, flag, _ in NUMERIC_FLAGS}
    assert {("validate", "--fixation"), ("validate", "--tap-budget"), ("record", "--seconds"),
            ("replay", "--mm-per-px"), ("collect", "--workers"), ("simulate taxel", "--seed"),
            ("arm tap", "--depth"), ("train", "--epsilon")} <= flags
    assert len(flags) >= 35


@pytest.mark.parametrize("path, flag, nargs", NUMERIC_FLAGS, ids=[f"{' '.join(p)} {f}" for p, f, _ in NUMERIC_FLAGS])
def test_every_numeric_flag_refuses_non_numbers(path, flag, nargs, capsys):
    """Every numeric flag of every command refuses nan, inf, -inf, '' and words while parsing, naming the flag."""
    parser = build_parser()
    for value in NOT_A_NUMBER:
        values = [value, "0"] if nargs == 2 else [value]
        with pytest.raises(SystemExit) as exit_:
            parser.parse_args([*path, f"{flag}={values[0]}", *values[1:]] if nargs != 2 else [*path, flag, *values])
        err = capsys.readouterr().err
        assert exit_.value.code == 2 and f"argument {flag}" in err, (value, err)


def _station_keys(table, prefix=()):
    for key, value in table.items():
        if isinstance(value, dict):
            yield from _station_keys(value, prefix + (key,))
        elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
            yield from _station_keys(value[0], prefix + (key, 0))
        else:
            yield prefix + (key,), value


def _sample_keys():
    rows = []
    for sample in ("station_sim.toml", "station_ur.toml"):
        table = tomllib.loads((SAMPLES / sample).read_text())
        rows += [(sample, path, value) for path, value in _station_keys(table)]
    return rows


SAMPLE_KEYS = _sample_keys()


def _with(sample: str, path, value) -> dict:
    table = tomllib.loads((SAMPLES / sample).read_text())
    node = table
    for part in path[:-1]:
        node = node[part]
    node[path[-1]] = value
    return table


def _named(message: str, path) -> bool:
    names = [str(p) for p in path if not isinstance(p, int)]
    return names[-1] in message


def wrong_values(path, value) -> list:
    """Values of another type for the key ``path`` whose sample value is ``value`` (numbers: also nan, inf, 1e30)."""
    wrong = [{"a": 1}, [1, 2]] if not isinstance(value, list) else [{"a": 1}, "x"]
    if isinstance(value, bool):
        wrong += [1, "yes"]
    elif isinstance(value, (int, float)):
        wrong += ["1", True, math.nan, math.inf, -math.inf, 1e30]
    elif isinstance(value, str):
        wrong += [True, 3.5] if path[-1] != "source" else [True, 3.5, -1, 10**6]
    return wrong


@pytest.mark.parametrize("sample, path, value", SAMPLE_KEYS,
                         ids=[f"{s.split('.')[0]}:{'.'.join(map(str, p))}" for s, p, _ in SAMPLE_KEYS])
def test_every_station_key_refuses_wrong_types(sample, path, value):
    """Each key of the sample stations, set to a value of another type (and a number to nan, inf, 1e30),
    is refused with a `ConfigError` naming it; the sample itself loads."""
    for bad in wrong_values(path, value):
        with pytest.raises(ConfigError) as err:
            parse_station_config(_with(sample, path, bad), base_dir=SAMPLES)
        assert _named(str(err.value), path), (bad, str(err.value))
    parse_station_config(_with(sample, path, value), base_dir=SAMPLES)


def test_the_key_sweep_counts():
    """Both samples have every table swept (a guard against the sweep silently finding nothing)."""
    sections = {(s, p[0]) for s, p, _ in SAMPLE_KEYS}
    assert {"station", "sensor", "arm", "protocol", "perception", "gaps"} <= {p for _, p in sections}
    assert len(SAMPLE_KEYS) >= 80


def test_the_simulate_limit_matches_the_library():
    from tactip.cli.simulate import MAX_TAPS as CLI_MAX
    from tactip.taxel.collect import MAX_TAPS

    assert CLI_MAX == MAX_TAPS


def test_taxel_library_refuses_too_many_taps(tmp_path):
    from tactip.taxel import simulate_taxel_datasets

    with pytest.raises(ValueError, match="locations x taps_per_location"):
        simulate_taxel_datasets(tmp_path / "tx", locations=10**6)
    assert not (tmp_path / "tx").exists()


def test_a_job_larger_than_memory_is_refused_with_the_estimate(monkeypatch):
    from tactip.cli import _types
    from tactip.errors import TactipError

    monkeypatch.setattr(_types, "available_memory_bytes", lambda: 10 * 2**30)
    _types.check_memory(7 * 2**30, what="runs", hint="use fewer --runs")  # within 80 %: accepted
    with pytest.raises(TactipError) as err:
        _types.check_memory(9 * 2**30, what="5000000 Monte Carlo runs", hint="use fewer --runs")
    assert str(err.value) == ("5000000 Monte Carlo runs need about 9.0 GiB of memory, more than the 8.0 GiB usable "
                              "(80% of the 10.0 GiB available): use fewer --runs")
    monkeypatch.setattr(_types, "available_memory_bytes", lambda: None)
    _types.check_memory(2**60, what="runs", hint="")  # unknown memory: no guess, no refusal


def test_validate_estimates_the_memory_of_its_runs(files, monkeypatch, capsys):
    from tactip.cli import _types, main

    monkeypatch.setattr(_types, "available_memory_bytes", lambda: 2**20)  # 1 MiB: 5000 runs do not fit
    assert main(["validate", str(files / "model.h5"), str(files / "test.h5"), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "5000 Monte Carlo runs of 12 classes need about" in err and "use fewer --runs" in err


def test_a_small_max_taps_is_not_refused_for_the_default_tap_budget(files, capsys):
    """--max-taps 10 alone is valid: the default --tap-budget (12) follows it instead of being blamed."""
    from tactip.cli import main

    assert main(["validate", str(files / "model.h5"), str(files / "test.h5"), "--max-taps", "10", "--runs", "10",
                 "--quiet"]) == 0
    assert "--tap-budget" not in capsys.readouterr().err


def test_an_output_name_near_the_length_limit_is_written(files, tmp_path, monkeypatch, capsys):
    """A 250-byte name is valid: its temporary (``.NAME.PID.part.h5``) is shortened, not refused by the system."""
    from tactip.cli import main

    monkeypatch.chdir(tmp_path)
    name = "a" * 247 + ".h5"
    assert main(["train", str(files / "train.h5"), "--out", name, "--locations", "6", "--bins", "10"]) == 0, \
        capsys.readouterr().err
    assert [p.name for p in tmp_path.iterdir()] == [name]


def test_warned_cases_of_the_issue_run_to_the_end_through_the_real_cli(files, tmp_path):
    """Issue 9's cases that are not refusals: a count far off (--expected-pins 1..5 was a traceback), one black
    frame in a video (every pin lost at once was a ValueError), and a rest frame taken during a tap (silent)."""
    import cv2

    detected = run_tactip("detect", IMAGE, "--expected-pins", "1", cwd=tmp_path, inputs=[IMAGE])
    assert detected.returncode == 0 and "331 pins found, 1 expected" in detected.stderr, detected.stderr
    # The sample video with frame 30 (mid-tap) black, as when the LEDs flicker off.
    capture = cv2.VideoCapture(str(VIDEO))
    frames = []
    while (read := capture.read())[0]:
        frames.append(read[1])
    capture.release()
    black = tmp_path / "black.mp4"
    writer = cv2.VideoWriter(str(black), cv2.VideoWriter_fourcc(*"mp4v"), 20.0, frames[0].shape[1::-1], True)
    for k, frame in enumerate(frames):
        writer.write(frame * 0 if k == 30 else frame)
    writer.release()
    replayed = run_tactip("replay", black, "--out", "b.h5", cwd=tmp_path, inputs=[black])
    assert replayed.returncode == 0 and "1 blank frame(s)" in replayed.stdout, replayed.stdout + replayed.stderr
    during = run_tactip("replay", files / "video.mp4", "--out", "r.h5", "--rest-frame", "40", cwd=tmp_path,
                        inputs=[files / "video.mp4"])
    assert during.returncode == 0 and "rest frame 40 looks taken during a tap" in during.stdout, during.stdout
    assert (tmp_path / "b.h5").exists() and (tmp_path / "r.h5").exists()
    # The black frame taken as the rest frame: refused, naming the frame and the way out (in-process: a variant).
    refused = run_tactip_in_process("replay", black, "--out", "c.h5", "--rest-frame", "30", cwd=tmp_path,
                                    inputs=[black])
    assert_refused(refused, "rest frame 30", "no sensor disc", "--rest-frame")
    assert not (tmp_path / "c.h5").exists()
