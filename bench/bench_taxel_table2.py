"""Paper 000 Tables II and III on the simulated taxel sensors: acuity against class count, and timings.

Simulates the two collections of the paper (fingertip: 3000 taps over 30 mm; skin: 5000 taps over
50 mm), trains on one, validates on the other by Monte Carlo and prints, for each class count, the
passive and active mean location errors at a mean of 2 decision taps (Table II, fingertip) or 4
(Table III, skin, with --skin), at the paper's fixation points (15 mm, 37 mm). The paper ran 10000
Monte Carlo runs; the default here is 5000. `tactip reproduce 000` runs the same tables.

    .venv/bin/python bench/bench_taxel_table2.py [--seed S] [--runs N] [--skin]
"""

from __future__ import annotations

import argparse
import time

from tactip.reproduce.acuity import TABLE2_CLASSES, TABLE3_CLASSES, acuity_table
from tactip.reproduce.p000 import SENSORS
from tactip.taxel import TaxelSimulator, simulate_taxel_dataset, sweep_locations
from tactip.taxel.collect import DEFAULT_TAPS


def table(sensor: str, classes, *, seed: int, runs: int, tap_budget: float) -> None:
    """Simulate, validate and print one table."""
    began = time.perf_counter()
    simulator = TaxelSimulator(sensor, seed=seed)
    where = sweep_locations(simulator.sensor, DEFAULT_TAPS[sensor])
    train = simulate_taxel_dataset(simulator, where, seed=(seed, 2))
    test = simulate_taxel_dataset(simulator, where, seed=(seed, 3))
    simulated = time.perf_counter() - began
    fixation = SENSORS[sensor]["fixation_mm"]          # the paper's: fingertip 15 mm, skin 37 mm
    rows = acuity_table(train, test, class_counts=classes, runs=runs, seed=1, tap_budget=tap_budget,
                        fixation_mm=fixation)
    validated = time.perf_counter() - began - simulated
    print(f"\n{sensor}: {len(train)} + {len(test)} taps x 50 samples x {simulator.sensor.n_taxels} taxels "
          f"(simulated in {simulated:.1f} s, {2 * len(train) / simulated:.0f} taps/s); {runs} Monte Carlo runs, "
          f"fixation {fixation:g} mm, errors at <= {tap_budget:g} mean taps ({validated:.1f} s)")
    print(f"{'classes':>8} {'width mm':>9} {'passive mm':>11} {'taps':>5} {'active mm':>10} {'taps':>5} "
          f"{'acuity mm':>10} {'passive best mm':>16}")
    for r in rows:
        print(f"{r.classes:>8d} {r.class_width_mm:>9.2f} {r.passive_error_mm:>11.2f} {r.passive_taps:>5.2f} "
              f"{r.active_error_mm:>10.3f} {r.active_taps:>5.2f} {r.acuity_mm:>10.2f} {r.passive_best_error_mm:>16.2f}")


def main() -> None:
    """Print both tables."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--runs", type=int, default=5000)
    parser.add_argument("--skin", action="store_true", help="also Table III with the skin (about 30 s more)")
    args = parser.parse_args()
    print("paper 000 Table II (fingertip, 2 taps): passive 4.5 mm; active 0, 0, 0.01, 0.04, 0.07, 0.08, 0.12 mm")
    table("fingertip", TABLE2_CLASSES, seed=args.seed, runs=args.runs, tap_budget=2.0)
    if args.skin:
        print("\npaper 000 Table III (skin, 4 taps): passive 0.4 mm; active 0.01, 0.05, 0.11, 0.20, 0.18, 0.24 mm")
        table("skin", TABLE3_CLASSES, seed=args.seed, runs=args.runs, tap_budget=4.0)


if __name__ == "__main__":
    main()
