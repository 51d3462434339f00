"""Issue 21: is the torch likelihood calibrated on the simulated station? ECE after 1, 3 and 5 taps over seeds.

For each collection seed, the small simulated station of the tests (4 gaps, depths every 0.5 mm,
``--repeats`` taps per depth and gap in each collection) is calibrated and collected, the model is
prepared as the station prepares it (`calibration.fit_with_fixation`: settings and tempering chosen
on training taps held out in folds, target 95 % within 0.25 mm), and the active policy's width belief
on the test collection is traced (`perception.trace_beliefs`). Printed per seed: the expected
calibration error after 1, 3 and 5 taps, the accuracy and mean belief there, and the floor of the
1-tap figure: the mean ECE that a perfectly calibrated model with the same beliefs would show on
the same distinct test taps (each right with the probability it states), i.e. what the test
collection's size alone costs.

    python bench/bench_torch_calibration.py [--seeds 0 1 2] [--repeats 2] [--kind torch] [--runs 1000] [--packaged]

Measured 2026-11-28 (2 busy cores; 2-6 min a seed), ``--kind torch``: repeats 2, seeds 0/1/2:
ECE 0.112/0.179/0.136 after 1 tap (floor 0.045-0.055), 0.000/0.053/0.045 after 3, 0.000/0.076/0.022
after 5; repeats 4, seeds 0/1: 0.048/0.024, 0.000/0.000, 0.000/0.000; ``--packaged``, seeds 0/1:
0.071/0.089, 0.073/0.033, 0.159/0.091 (floor 0.030; without the within-class deviations in training
0.070/0.072, 0.027/0.040, 0.057/0.148).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

#: The packaged simulated station's gaps (samples/station_sim.toml: 0.25-5 mm).
PACKAGED_GAPS = tuple(f"g{k:02d}" for k in range(1, 21))


def one_tap_floor(model, environment, *, draws: int = 500, seed: int = 0) -> float:
    """Mean ECE of a perfectly calibrated model with these 1-tap beliefs over the distinct test taps."""
    from scipy.special import logsumexp

    from perception import calibration_error_floor

    ll = environment.log_likelihood.reshape(-1, model.n_locations, model.n_identities)
    decision = np.exp(logsumexp(ll - logsumexp(ll, axis=(1, 2), keepdims=True), axis=1 if model.n_identities > 1
                                else 2))
    return float(calibration_error_floor(decision.max(axis=1), draws=draws, seed=seed).mean())


def measure(seed: int, repeats: int, kind: str, runs: int, root: Path, *, packaged: bool = False) -> str:
    """One line of figures for one collection seed."""
    from calibration import fit_with_fixation
    from perception import VirtualEnvironment, load_dataset, make_policy, trace_beliefs
    from tactip.station.config import parse_station_config
    from tactip.station.procedures import calibrate_station, collect_station
    from tests.tactip.conftest import small_station_table

    options = dict(gaps=PACKAGED_GAPS, depth_step=0.25) if packaged else {}
    table = small_station_table(root, repeats=repeats, protocol={"seed": seed}, sim={"seed": seed}, **options)
    config = parse_station_config(table, base_dir=root)
    calibrate_station(config, log=lambda line: None)
    paths = collect_station(config, root / "datasets", progress=False, workers=2, log=lambda line: None)
    train, test = load_dataset(paths["train"]), load_dataset(paths["test"])
    model = fit_with_fixation(train, kind=kind, n_locations=config.perception.locations, target_accuracy=0.95,
                              tolerance=min(g.tolerance for g in config.gaps), log=lambda line: None)
    environment = VirtualEnvironment(model, test)
    policy = make_policy("active", fixation_class=model.fixation_class(model.recommended["fixation_location"]))
    trace = trace_beliefs(environment, policy, runs=runs, max_taps=20, seed=0, shift_mode=model.shift_mode)
    taps = (1, 3, 5)
    right = trace.estimate == trace.truth
    return (f"seed {seed}: ECE " + " / ".join(f"{trace.calibration_error(t):.3f}" for t in taps)
            + " | accuracy " + " / ".join(f"{right[:, t - 1].mean():.2f}" for t in taps)
            + " | belief " + " / ".join(f"{trace.belief[:, t - 1].mean():.2f}" for t in taps)
            + f" | 1-tap floor {one_tap_floor(model, environment):.3f} ({len(test)} test taps)"
            + f" | fixation {model.recommended['fixation_location']:g} mm")


def main(argv=None) -> int:
    """Print one line per seed."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--repeats", type=int, default=2, help="taps per depth and gap in each collection")
    parser.add_argument("--kind", default="torch", help="likelihood kind (perception.MODEL_KINDS)")
    parser.add_argument("--runs", type=int, default=1000, help="Monte Carlo runs of the trace")
    parser.add_argument("--packaged", action="store_true",
                        help="the packaged station's 20 gaps and 0.25 mm depth step instead of the tests' small one")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    if args.kind == "torch":
        import torch

        torch.set_num_threads(2)
    station = "packaged" if args.packaged else "small"
    print(f"{args.kind} likelihood, {station} station, {args.repeats} repeats per depth; "
          f"ECE / accuracy / belief after 1 / 3 / 5 taps")
    for seed in args.seeds:
        start = time.perf_counter()
        with tempfile.TemporaryDirectory() as tmp:
            line = measure(seed, args.repeats, args.kind, args.runs, Path(tmp), packaged=args.packaged)
        print(f"{line} ({time.perf_counter() - start:.0f} s)", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
