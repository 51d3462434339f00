"""Paper 000 on the simulated fingertip: localisation acuity against class count (Table II).

Two collections of 3000 taps over 30 mm (`tactip.taxel.simulate_taxel_dataset`), passive
(stationary) and active (fixation at the centre) perception compared at a mean decision time of
2 taps, beliefs shifted with the uniform fill of eq. 8 (`tactip.reproduce.acuity.acuity_table`). The
simulator's read noise was calibrated against this table (`tactip.taxel.sim`).
"""

from __future__ import annotations

from tactip.reproduce.report import Comparison, Report

__all__ = ["PAPER_TABLE2", "run"]

#: Paper 000 Table II, active perception: mean error (mm) at each class count (300 classes: 0.12 mm).
PAPER_TABLE2 = {300: 0.12}


def run(*, quick: bool = False, seed: int = 0, progress=None, map_fn=None) -> Report:
    """Table II rows: ``classes, class_width_mm, passive_error_mm, active_error_mm, active_taps, acuity_mm``."""
    from tactip.taxel import TaxelSimulator, simulate_taxel_dataset, sweep_locations
    from tactip.reproduce.acuity import TABLE2_CLASSES, acuity_table

    simulator = TaxelSimulator("fingertip", seed=seed)
    where = sweep_locations(simulator.sensor, 3000)
    train = simulate_taxel_dataset(simulator, where, seed=(seed, 2), collection="train")
    test = simulate_taxel_dataset(simulator, where, seed=(seed, 3), collection="test")
    counts = (30, 300) if quick else TABLE2_CLASSES
    table = acuity_table(train, test, class_counts=counts, fixation_mm=15.0, tap_budget=2.0,
                         runs=1000 if quick else 5000, seed=seed + 1, progress=progress, map_fn=map_fn)
    rows = [{"classes": r.classes, "class_width_mm": r.class_width_mm, "passive_error_mm": r.passive_error_mm,
             "active_error_mm": r.active_error_mm, "active_taps": r.active_taps, "acuity_mm": r.acuity_mm}
            for r in table]
    last = table[-1]
    comparisons = [Comparison(f"Table II {last.classes} classes: active error", last.active_error_mm,
                              PAPER_TABLE2.get(last.classes), "mm"),
                   Comparison(f"Table II {last.classes} classes: passive error", last.passive_error_mm, None, "mm")]
    return Report("000", "tactile hyperacuity: localisation error against class count (Table II)", rows, comparisons,
                  ["tuned: the simulator's read noise against this table (the paper's only figure used)."])
