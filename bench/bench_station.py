"""The simulated inspection station: cost per tap, and active vs passive perception (paper 002 Fig. 9).

Prepares the packaged simulated station in a data folder (calibrate, collect, train, fixation
sweep: timed, as a first `tactip inspect --sim` would), then reports:

1. the cost of one simulated tap (render + track + features), one process;
2. Monte Carlo on the test collection, the same test data for every policy: mean absolute
   width error and accuracy over 8-12 mean taps, as in paper 002 Fig. 9;
3. live inspections of the 20 gaps on the simulated station, once per policy, from the same
   random start depths: mean absolute width error and mean taps.

Fig. 9 is a fit, not a prediction: the skin's sag over a gap (`tactip.sim._pad.MEMBRANE_RHO_MM`, 8 -> 1 mm)
was tuned so that the station reproduces it (`tactip reproduce 002` reports the figure with that note).

The station is trained as in the figure, with the papers' histogram likelihood on one tap per depth,
unless --likelihood and --repeats say otherwise (as tests/tactip/station/test_station_bar.py does); the
preset's own default (gaussian, two repeats) decides in a few taps: bench_likelihoods.py measures it.

    python bench/bench_station.py [--data-dir DIR] [--depth-step MM] [--runs N] [--seed S] [--likelihood KIND]
                                  [--repeats N]
"""

from __future__ import annotations

import argparse
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np


def main() -> None:
    """Run the benchmark and print its figures."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data-dir", type=Path, default=None, help="reuse a prepared station folder")
    parser.add_argument("--depth-step", type=float, default=None, help="override [protocol] depth_step, mm")
    parser.add_argument("--runs", type=int, default=5000, help="Monte Carlo runs per threshold")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--likelihood", default="histogram",
                        choices=("histogram", "calibrated-histogram", "gaussian", "torch"),
                        help="[perception] likelihood of the station (default histogram: paper 002's model)")
    parser.add_argument("--repeats", type=int, default=1, help="[protocol] repeats, taps per depth (default 1)")
    args = parser.parse_args()

    import cv2

    from perception import VirtualEnvironment, compare_policies, load_dataset, load_model, make_policy
    from tactip.station.config import SIM_PRESET, parse_station_config
    from tactip.station.inspection import inspect_station
    from tactip.station.procedures import load_station_calibration, prepare_model
    from tactip.station.station import Station

    cv2.setNumThreads(1)
    data_dir = (args.data_dir or Path(tempfile.mkdtemp(prefix="bench_station_"))).resolve()
    data = tomllib.loads(SIM_PRESET.read_text())
    data["station"].update(data_dir=str(data_dir), results=str(data_dir / "results.sqlite"))
    data["perception"]["model"] = str(data_dir / "model.h5")
    data["perception"]["likelihood"] = args.likelihood
    data["protocol"]["repeats"] = args.repeats
    if args.depth_step:
        data["protocol"]["depth_step"] = args.depth_step
    config = parse_station_config(data, base_dir=data_dir)
    print(f"station folder: {data_dir} ({args.likelihood} likelihood, {args.repeats} tap(s) per depth)")

    started = time.monotonic()
    if not config.perception.model.exists():
        prepare_model(config, progress=False, log=lambda line: None)
    print(f"prepare (calibrate, collect, train, sweep fixation): {time.monotonic() - started:.1f} s")

    calibration = load_station_calibration(config)
    with Station(config, calibration=calibration) as station:
        gap = config.gaps[len(config.gaps) // 2]
        station.tap(gap, 4.0)
        times = []
        for depth in np.linspace(0.0, 5.5, 12):
            t0 = time.perf_counter()
            result = station.tap(gap, float(depth))
            times.append((time.perf_counter() - t0, result.frames))
        cost = np.array(times)
    print(f"one simulated tap: {1e3 * cost[:, 0].mean():.0f} ms mean ({cost[:, 1].mean():.1f} frames, "
          f"{1e3 * cost[:, 0].sum() / cost[:, 1].sum():.1f} ms per frame), one process")

    model = load_model(config.perception.model)
    environment = VirtualEnvironment(model, load_dataset(data_dir / "datasets" / "test.h5"))
    fixation = model.fixation_class()
    policies = [make_policy(name, fixation_class=fixation) for name in ("active", "random", "stationary")]
    # The paper's mean log-likelihood keeps width posteriors modest: 8-12 taps lie at thresholds ~0.1-0.3.
    thresholds = np.round(np.linspace(0.05, 0.4, 36), 3)
    results = compare_policies(environment, policies, runs=args.runs, seed=args.seed, thresholds=thresholds)
    print(f"\nMonte Carlo on the test collection ({args.runs} runs per threshold, fixation "
          f"{model.location_centres[fixation]:g} mm); rows with 8-12 mean taps, else the nearest:")
    print(f"{'policy':<11} {'threshold':>9} {'taps':>6} {'width error mm':>15} {'accuracy':>8}")
    for name, result in results.items():
        rows = result.rows()
        window = [r for r in rows if 8 <= r["mean_taps"] <= 12] or [min(rows, key=lambda r: abs(r["mean_taps"] - 10))]
        for r in window:
            print(f"{name:<11} {r['threshold']:>9.3g} {r['mean_taps']:>6.2f} {r['mean_identity_error']:>15.3f} "
                  f"{r['accuracy']:>8.3f}")
        error = np.mean([r["mean_identity_error"] for r in window])
        print(f"{name:<11} {'mean':>9} {np.mean([r['mean_taps'] for r in window]):>6.2f} {error:>15.3f}")

    print("\nlive inspections of every gap on the simulated station, same random start depths:")
    for name in ("active", "random", "stationary"):
        t0 = time.monotonic()
        outcomes = inspect_station(config, policy=name, seed=args.seed, log=lambda line: None)
        errors = [abs(o.estimated_width - o.gap.nominal_width) for o in outcomes]
        print(f"{name:<11} mean width error {np.mean(errors):.3f} mm, mean taps {np.mean([o.taps for o in outcomes]):.1f}, "
              f"{sum(o.passed is True for o in outcomes)}/{len(outcomes)} pass, {time.monotonic() - t0:.0f} s")


if __name__ == "__main__":
    main()
