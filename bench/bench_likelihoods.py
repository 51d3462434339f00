"""Issue 11 bars on the simulated station: likelihood models compared on the same Monte Carlo runs, and live.

Prepares the packaged simulated station in a data folder as a first `tactip inspect --sim` would
(calibrate, collect, train the station's default model, choose its fixation and threshold), then:

1. trains every kind of likelihood model on the same training collection and, on the same test
   collection, runs the active policy at the station model's fixation depth (same seed: the same
   true widths and start depths), reporting per model, and for the station's own model (whose
   tempering its preparation refitted on the test taps for the beliefs after 1-5 taps), the expected
   calibration error (ECE) of the width belief after 1, 3 and 5 taps and the lowest mean width error within 3 and within 6 mean
   taps over decision thresholds (bars: <= 0.35 mm within 3, <= 0.2 mm within 6, ECE <= 0.05);
2. inspects every gap live on the simulated station with the station's model and settings
   (bars: mean taps <= 4, mean |estimate - nominal| <= 0.2 mm, fraction of decided gaps within
   tolerance >= mean decision belief - 0.05);
3. with --density, the trade-off of the collection protocol (depth step, repeats): collection
   size against the mean taps to reach the target accuracy, one fresh station folder per setting.

    python bench/bench_likelihoods.py [--data-dir DIR] [--runs N] [--seed S] [--density]
"""

from __future__ import annotations

import argparse
import tempfile
import time
import tomllib
from pathlib import Path

import numpy as np

KINDS = ("histogram", "calibrated-histogram", "gaussian")


def kinds() -> tuple[str, ...]:
    """The kinds compared: torch's too when it is installed (the optional extra 'learned')."""
    import importlib.util

    return KINDS + (("torch",) if importlib.util.find_spec("torch") else ())


def station_config(data_dir: Path, **protocol):
    """The packaged simulated station in ``data_dir``, with some ``[protocol]`` keys replaced."""
    from tactip.station.config import SIM_PRESET, parse_station_config

    data = tomllib.loads(SIM_PRESET.read_text())
    data["station"].update(data_dir=str(data_dir), results=str(data_dir / "results.sqlite"))
    data["perception"]["model"] = str(data_dir / "model.h5")
    data["protocol"].update(protocol)
    return parse_station_config(data, base_dir=data_dir)


def best_error_within(trace, taps: float):
    """(error mm, mean taps, threshold) of the threshold with the lowest mean error within ``taps`` mean taps."""
    best = None
    for threshold in np.concatenate([np.linspace(0.0, 0.99, 100), [0.995, 0.999, 0.9999]]):
        decisions = trace.decisions(float(threshold))
        mean_taps = decisions.taps.mean()
        if mean_taps <= taps and (best is None or decisions.error.mean() < best[0]):
            best = (float(decisions.error.mean()), float(mean_taps), float(threshold))
    return best


def compare_models(config, runs: int, seed: int) -> None:
    """Part 1: every kind on the same runs."""
    from perception import VirtualEnvironment, load_dataset, load_model, make_policy, trace_beliefs, train_model

    datasets = config.data_dir / "datasets"
    train, test = load_dataset(datasets / "train.h5"), load_dataset(datasets / "test.h5")
    station_model = load_model(config.perception.model)
    fixation = station_model.fixation_class()
    print(f"\nMonte Carlo on the test collection ({len(test)} taps), active policy at "
          f"{station_model.location_centres[fixation]:g} mm, {runs} runs, seed {seed}:")
    print(f"{'model':<22} {'fit s':>6} {'ECE 1':>6} {'ECE 3':>6} {'ECE 5':>6}   {'error <= 3 taps':>22}   "
          f"{'error <= 6 taps':>22}")
    for kind in (*kinds(), "station"):
        started = time.monotonic()
        if kind == "station":  # the station's own model: its tap tempering g1..g5 fitted when it was prepared
            model, kind = station_model, f"station ({station_model.KIND})"
        else:
            model = train_model(train, kind=kind, n_locations=config.perception.locations, bins=config.perception.bins)
        fit_s = time.monotonic() - started
        trace = trace_beliefs(VirtualEnvironment(model, test), make_policy("active", fixation_class=fixation),
                              runs=runs, seed=seed, max_taps=config.perception.max_taps)
        ece = [trace.calibration_error(t) for t in (1, 3, 5)]
        cells = []
        for taps in (3, 6):
            best = best_error_within(trace, taps)
            cells.append("-" if best is None else f"{best[0]:.3f} mm in {best[1]:.2f} (t {best[2]:.3g})")
        print(f"{kind:<22} {fit_s:>6.1f} {ece[0]:>6.3f} {ece[1]:>6.3f} {ece[2]:>6.3f}   {cells[0]:>22}   {cells[1]:>22}")


def inspect_live(config, seed: int) -> None:
    """Part 2: every gap inspected on the simulated station with the station's model."""
    from perception import load_model
    from tactip.station.inspection import inspect_station

    model = load_model(config.perception.model)
    print(f"\nlive inspections, {model.KIND} model, threshold {model.recommended.get('decision_threshold')}, "
          f"fixation {model.recommended.get('fixation_location')} mm:")
    overall = []
    for run_seed in range(seed, seed + 5):
        outcomes = inspect_station(config, seed=run_seed, log=lambda line: None)
        errors = np.array([abs(o.estimated_width - o.gap.nominal_width) for o in outcomes])
        decided = [o for o in outcomes if o.decided]
        within = np.mean([abs(o.estimated_width - o.gap.nominal_width) <= o.gap.tolerance + 1e-9 for o in decided]) \
            if decided else float("nan")
        belief = np.mean([o.belief for o in decided]) if decided else float("nan")
        print(f"  seed {run_seed}: mean taps {np.mean([o.taps for o in outcomes]):.2f}, mean |estimate - nominal| "
              f"{errors.mean():.3f} mm, decided {len(decided)}/{len(outcomes)}, within tolerance {within:.3f} vs "
              f"mean belief {belief:.3f} (bar: >= belief - 0.05: {'met' if within >= belief - 0.05 else 'not met'})")
        overall.append((np.mean([o.taps for o in outcomes]), errors.mean()))
    taps, error = np.mean(overall, axis=0)
    print(f"  over the {len(overall)} seeds ({len(overall) * len(outcomes)} inspections): mean taps {taps:.2f} "
          f"(bar <= 4), mean |estimate - nominal| {error:.3f} mm (bar <= 0.2); worst seed {max(e for _, e in overall):.3f} mm")


def density(runs: int, seed: int, root: Path, main_config) -> None:
    """Part 3: collection size against taps per decision."""
    from perception import VirtualEnvironment, load_dataset, load_model
    from perception.reliability import fixation_for_accuracy
    from tactip.station.procedures import prepare_model

    print("\ndata density: collection protocol against mean taps to 95 % of decisions within 0.25 mm "
          "(gaussian model, best fixation):")
    print(f"{'step mm':>8} {'repeats':>7} {'taps/collection':>15} {'prepare s':>9} {'mean taps':>9} {'accuracy':>8}")
    for step, repeats in ((0.5, 2), (0.25, 2), (0.25, 3)):
        if (step, repeats) == (main_config.protocol.depth_step, main_config.protocol.repeats):
            folder, config = root, main_config  # the station prepared above
        else:
            folder = root / f"density_{step:g}_{repeats}"
            folder.mkdir(parents=True, exist_ok=True)
            config = station_config(folder, depth_step=step, repeats=repeats)
        started = time.monotonic()
        if not config.perception.model.exists():
            prepare_model(config, progress=False, log=lambda line: None)
        elapsed = time.monotonic() - started
        model = load_model(config.perception.model)
        test = load_dataset(folder / "datasets" / "test.h5")
        sweep = fixation_for_accuracy(VirtualEnvironment(model, test), target=0.95, tolerance=0.25, runs=runs,
                                      seed=seed)
        taps = "-" if sweep.best is None else f"{sweep.taps[sweep.best]:.2f}"
        accuracy = sweep.accuracy[sweep.best] if sweep.best is not None else np.nanmax(sweep.accuracy)
        print(f"{step:>8g} {repeats:>7} {len(test):>15} {elapsed:>9.0f} {taps:>9} {accuracy:>8.3f}")


def main() -> None:
    """Run the benchmark and print its figures."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--data-dir", type=Path, default=None, help="reuse a prepared station folder")
    parser.add_argument("--runs", type=int, default=5000, help="Monte Carlo runs")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--density", action="store_true", help="also the collection-protocol trade-off (slow)")
    args = parser.parse_args()

    import cv2

    from tactip.station.procedures import prepare_model

    cv2.setNumThreads(1)
    data_dir = (args.data_dir or Path(tempfile.mkdtemp(prefix="bench_likelihoods_"))).resolve()
    config = station_config(data_dir)
    print(f"station folder: {data_dir}")
    started = time.monotonic()
    if not config.perception.model.exists():
        prepare_model(config, progress=False, log=lambda line: None)
    print(f"prepare (calibrate, collect, train {config.perception.likelihood}, choose fixation and threshold): "
          f"{time.monotonic() - started:.1f} s")
    compare_models(config, args.runs, args.seed)
    inspect_live(config, args.seed)
    if args.density:
        density(min(args.runs, 2000), args.seed, data_dir, config)


if __name__ == "__main__":
    main()
