"""ECE of the torch model's width belief after 1, 3 and 5 taps on the small simulated station, per collection seed.

Builds the test suite's small station (four gaps, 0.5 mm depth step, ``--repeats`` taps per depth) for each
collection seed (``[protocol] seed`` and ``[sim] seed``), prepares it with ``likelihood = "torch"`` (train,
fixation, threshold and tap tempering on held-out training taps), then runs ``tactip validate --policy active
--json`` on the test collection and prints the ECE after 1, 3 and 5 taps and the tap tempering written.

With ``--ece-repeats N`` it also collects a third collection, ``datasets/ece.h5`` (``N`` taps per depth and
gap, independent of the training and test taps: its own set name in the collection plan), and validates on
it too. Why: the ECE of few beliefs is biased upwards. After one tap every test tap is one belief, and
a perfectly calibrated model with the same beliefs measures an ECE of about 0.07 on the 96 test taps
of 2 repeats (`perception.calibration_error_floor`, printed as ``floor_1``: mean and 95th
percentile of 1000 draws), more than the bar of 0.05; on 16 repeats (768 taps) about 0.025.
``ece_1_all`` is the ECE after one tap over every tap of the set once (what the Monte Carlo runs
sample with replacement). Slow (minutes per seed; the ECE collection about 0.5 s per tap on two
workers). Usage: ``python bench/bench_station_ece.py --seeds 0 1 2 --out /tmp/ece --ece-repeats 16``.

Measured 2026-11-28 (models prepared by main 2137c4f, 2 repeats, ``--ece-repeats 16``): ECE after one tap over
the 768 ECE taps 0.082 / 0.063 / 0.091 / 0.029 / 0.047 for seeds 0-4 (floor 0.024 / 0.025 / 0.022 / 0.022 /
0.021), on the 96 test taps 0.086 / 0.100 / 0.103 / 0.061 / 0.059 (floor 0.068 / 0.064 / 0.064 / 0.057 /
0.054); after 3 and 5 taps (validate, 1000 runs, on the ECE taps) 0.000 / 0.000, 0.006 / 0.000 and 0.000 /
0.000 on the other three. The models of 4 repeats on the same ECE taps:
0.026 / 0.066 / 0.047 after one tap (floor 0.02), 0.041 / 0.012 / 0.007 after 3, 0.054 / 0.014 / 0.001
after 5 (2000 runs).

With the held-out folds balanced (12 taps each) and the model refitted on every training tap
(`calibration.fit_with_fixation`), on the same ECE taps, ``ece_1_all``: 0.054 / 0.117 / 0.113 / 0.098 for
seeds 0-3 (fold 0's model kept instead: 0.099 / 0.127 / 0.069 / 0.044); the Gaussian 0.025 / 0.042 / 0.071 / 0.042 /
0.062 for seeds 0-4 (main before: 0.032 / 0.061 / 0.021 / 0.043 / 0.035). Measured in one process per
seed on the collections this script wrote, not by rerunning it (the machine was loaded, 13-28 on 2 cores).

With the folds dealt as a Latin square (2026-11-29; before, fold k held out gap k alone), same collections and
way of measuring: the Gaussian 0.031 / 0.022 / 0.080 / 0.019 / 0.016 for seeds 0-4 (mean 0.034; 0.000 after 3
and 5 taps), test accuracy 0.925 / 0.965 / 0.962 / 1.00 / 0.99 in 1.32-1.42 taps (main, rerun alike: 0.032 /
0.061 / 0.021 / 0.043 / 0.035, accuracy 0.99 / 0.961 / 0.938 / 0.952 / 0.962); the torch on seed 0 0.052 (0.067
after one active tap, 0.000 after 3 and 5), accuracy 0.983 in 1.37 taps. Load 7-18 on 2 cores.

With 12 location classes, one per depth (the suite's station since 2026-11-29; before, 11 classes put 5.0
and 5.5 mm in one), Latin-square folds and the Gaussian's cross-validation in 4 folds, same collections
and way of measuring: the Gaussian 0.024 / 0.051 / 0.024 / 0.019 / 0.026 for seeds 0-4 (mean 0.029;
0.000 after 3 and 5 taps), test accuracy 0.945 / 0.943 / 1.00 / 0.965 / 0.966 in 1.27-1.35 taps. In
two folds it had 0.27-0.29 (accuracy 0.70-0.75 in 1.0 taps). The torch 0.068 / 0.126 / 0.102 / 0.074 / 0.131 for seeds
0-4, mean 0.100 (main, 11 classes: 0.082 / 0.063 / 0.091 / 0.029 / 0.047, mean 0.062; 0.000 after 3 and 5
taps), accuracy 0.989 / 1.00 / 0.989 / 1.00 / 1.00 in 1.36-1.45 taps. Load 14-20 on 2 cores.

With every identity of a location held out together, every tap off the extremes held out once and the torch's
tempering one beta fitted on the pooled out-of-fold scores (`calibration.cross_fitted_environment`; 2026-11-29,
same collections, measured in one process per seed from pickled fits, load 15-20): the Gaussian 0.028 / 0.036 /
0.024 / 0.016 / 0.031 for seeds 0-4 (mean 0.027), test accuracy 0.945 / 0.961 / 1.00 / 0.965 / 0.989 in
1.32-1.35 taps; the torch 0.021 / 0.044 / 0.042 / 0.046 for seeds 0-3 (mean 0.038; main 0.082 / 0.063 / 0.091 /
0.029, mean 0.066; seed 4 not measured), test accuracy 0.949 / 0.956 / 0.966 / 0.959 in 1.32 taps (the target 0.95;
the Latin folds' pessimism had given 0.99-1.00 in 1.36-1.45), pooled beta 5.0 / 5.4 / 5.3 / 4.0, g1 0.95 / 0.76 /
0.63 / 0.48; with each fit's own beta 0.023 / 0.081 / 0.049 / 0.046 (fold betas 2.6-15.7 on seed 1).
Seed 4 (2026-11-29, main f84c508, rerun by this script from scratch, load 8-9 on 2 cores): 0.043 over its 768
ECE taps (floor 0.020, 95th percentile 0.032), 0.000 after 3 and 5 taps (validate, 1000 runs), pooled beta 3.19,
g1 0.95, fixation 3.90 mm, threshold 0.385: the torch over seeds 0-4 0.021 / 0.044 / 0.042 / 0.046 / 0.043
after one tap, mean 0.039, every seed under the bar of 0.05.

With the Gaussian's fold models of the refit's components and shrinkage and one pooled beta for all
(`calibration.fit_with_fixation`, 2026-11-29; measured in one process per seed on collections made alike, 8
ECE repeats, 384 taps, for seeds 0-3 and this script's 768 for seed 4, load 9-11): the Gaussian 0.027 / 0.044 /
0.043 / 0.043 / 0.027 after one tap (mean 0.037; before, on the same taps, 0.036 / 0.043 / 0.042 / 0.028 / 0.031,
mean 0.036), test decisions within tolerance 0.945 / 0.965 / 1.000 / 0.954 / 0.966 (before 0.945 / 0.961 / 1.000
/ 0.965 / 0.989; target 0.95).
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from perception import calibration_error_floor, expected_calibration_error, one_tap_beliefs  # noqa: E402
from perception import load_dataset, load_model  # noqa: E402
from tactip.station.config import parse_station_config  # noqa: E402
from tactip.station.procedures import collect_station, prepare_model  # noqa: E402
from tests.tactip.conftest import run_cli, small_station_table, write_station  # noqa: E402


def one_tap_calibration(model, test) -> dict:
    """ECE after one tap over every tap of ``test`` once, and the floor a calibrated model measures on it."""
    belief, right = one_tap_beliefs(model, test)
    floor = calibration_error_floor(belief, draws=1000, seed=0)
    return {"taps": len(belief), "ece_1_all": expected_calibration_error(belief, right),
            "floor_1": [float(floor.mean()), float(np.quantile(floor, 0.95))],
            "mean_belief_1": float(belief.mean()), "accuracy_1": float(right.mean())}


def validate(root: Path, test: Path, runs: int) -> list:
    """ECE after 1, 3 and 5 taps of ``tactip validate --policy active`` on ``test``."""
    out = root / f"validation_{test.stem}.json"
    code, _, err = run_cli(["validate", root / "model.h5", test, "--policy", "active", "--runs", str(runs),
                            "--json", out, "--quiet"])
    if code != 0:
        raise SystemExit(err)
    row = json.loads(out.read_text())[0]
    return [row[f"ece_{t}_taps"] for t in (1, 3, 5)]


def measure(root: Path, seed: int, repeats: int, runs: int, ece_repeats: int, reuse: bool) -> dict:
    """Build, prepare and validate one station; its ECE after 1, 3 and 5 taps and its schedule."""
    table = small_station_table(root, perception={"likelihood": "torch"}, protocol={"seed": seed, "repeats": repeats},
                                sim={"seed": seed})
    toml = write_station(root, table)
    for command in (["calibrate", "--config", toml],
                    ["collect", "--config", toml, "--out", root / "datasets", "--workers", "2", "--quiet"]):
        if not (root / "datasets" / "test.h5").exists() or command[0] == "calibrate" and \
                not (root / "calibration.h5").exists():
            code, _, err = run_cli(command)
            if code != 0:
                raise SystemExit(err)
    lines = []
    if not (reuse and (root / "model.h5").exists()):
        prepare_model(parse_station_config(table, base_dir=root), progress=False, log=lines.append)
    model = load_model(root / "model.h5")
    result = {"seed": seed, "repeats": repeats, "ece": validate(root, root / "datasets" / "test.h5", runs),
              **one_tap_calibration(model, load_dataset(root / "datasets" / "test.h5"))}
    if ece_repeats:
        ece_table = small_station_table(root, perception={"likelihood": "torch"},
                                        protocol={"seed": seed, "repeats": ece_repeats}, sim={"seed": seed})
        ece_set = root / "datasets" / "ece.h5"
        if not ece_set.exists():
            collect_station(parse_station_config(ece_table, base_dir=root), root / "datasets", progress=False,
                            workers=2, log=lambda line: None, sets=("ece",))
        result["ece_set"] = {"repeats": ece_repeats, "ece": validate(root, ece_set, runs),
                             **one_tap_calibration(model, load_dataset(ece_set))}
    return {**result, "tap_tempering": list(model.tap_tempering), "tempering": model.tempering,
            "recommended": model.recommended, "lines": [line for line in lines if "fixation depth" in line]}


def main() -> None:
    """Measure every seed asked for and print one JSON line each."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--ece-repeats", type=int, default=0,
                        help="also collect datasets/ece.h5 with this many taps per depth and gap and validate on it")
    parser.add_argument("--reuse-model", action="store_true", help="validate the model.h5 already prepared, if any")
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    for seed in args.seeds:
        result = measure(args.out / f"seed{seed}_r{args.repeats}", seed, args.repeats, args.runs, args.ece_repeats,
                         args.reuse_model)
        print(json.dumps(result), flush=True)


if __name__ == "__main__":
    main()
