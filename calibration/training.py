"""Training and fixation search: from the collected datasets to a model with recommended settings.

Paper 002: the histogram model is trained on one collection, and the virtual environment built from
the other, independent collection validates it. The fixation depth of active perception is a free
parameter; the sweep over every depth class picks the one with the lowest mean width error within a
tap budget (paper 002 Fig. 10: best after about 12 taps, at the deep end of the range), together
with the decision threshold that reaches it. Both are written into the model's recommended
settings, which the station uses unless its configuration overrides them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from perception import (VirtualEnvironment, fit_model, fixation_sweep, load_dataset, load_model, save_model)

__all__ = ["train_station_model", "recommend_fixation"]


def train_station_model(train_path: str | Path, out: str | Path, *, n_locations: int = 11, bins: int = 100,
                        log: Callable[[str], None] = print):
    """Fit the histogram model on ``train_path`` and save it to ``out``; returns the model."""
    dataset = load_dataset(train_path)
    model = fit_model(dataset, n_locations=n_locations, bins=bins)
    save_model(out, model, inputs=[train_path])
    log(model.summary())
    return model


def recommend_fixation(model_path: str | Path, test_path: str | Path, *, runs: int = 2000, tap_budget: float = 12.0,
                       seed: int = 0, progress: Callable | None = None, log: Callable[[str], None] = print):
    """Sweep the fixation depth on the test set; write the best one (and its threshold) into the model.

    Returns
    -------
    (perception.HistogramModel, perception.FixationSweep)
        The model with its recommended settings, and the sweep (for a plot or a table).
    """
    model = load_model(model_path)
    sweep = fixation_sweep(VirtualEnvironment(model, load_dataset(test_path)), tap_budget=tap_budget, runs=runs,
                           seed=seed, progress=progress)
    model = model.with_recommended(fixation_location=float(sweep.best_fixation),
                                   decision_threshold=float(sweep.best_threshold), policy="active")
    save_model(model_path, model, inputs=[test_path])
    log(f"fixation depth {sweep.best_fixation:g} {model.location_unit}: mean width error "
        f"{sweep.errors[sweep.best]:.3f} {model.identity_unit} in {sweep.taps[sweep.best]:.1f} taps "
        f"(decision threshold {sweep.best_threshold:g}); written to {model_path}")
    return model, sweep
