"""Training and fixation search: from the collected datasets to a model with recommended settings.

Paper 002: the model is trained on one collection, and the virtual environment built from the
other, independent collection validates it. The fixation depth of active perception is a free
parameter; the sweep over every depth class picks the one with the lowest mean width error within a
tap budget (paper 002 Fig. 10: best after about 12 taps, at the deep end of the range), together
with the decision threshold that reaches it; or, given a target accuracy, the depth and threshold
whose decisions are within a tolerance of the true width in that fraction of runs in the fewest
taps (a calibrated model's belief means what it says, so its threshold is an accuracy). Both are
written into the model's recommended settings, which the station uses unless its configuration
overrides them. With a target accuracy, a calibrated kind's tempering is refitted at the chosen depth
for the beliefs after 1 to 5 taps of active perception (`perception.fit_policy_tempering`): the taps
of one inspection repeat each other's evidence, which a tempering fitted on single taps ignores.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

from perception import (VirtualEnvironment, fixation_for_accuracy, fixation_sweep, load_dataset, load_model,
                        save_model, train_model)

__all__ = ["train_station_model", "recommend_fixation"]


def train_station_model(train_path: str | Path, out: str | Path, *, n_locations: int = 11, bins: int = 100,
                        kind: str = "histogram", log: Callable[[str], None] = print):
    """Fit a model of ``kind`` (`perception.MODEL_KINDS`) on ``train_path`` and save it to ``out``; returns it."""
    dataset = load_dataset(train_path)
    model = train_model(dataset, kind=kind, n_locations=n_locations, bins=bins)
    save_model(out, model, inputs=[train_path])
    log(model.summary())
    return model


def recommend_fixation(model_path: str | Path, test_path: str | Path, *, runs: int = 2000, tap_budget: float = 12.0,
                       seed: int = 0, progress: Callable | None = None, log: Callable[[str], None] = print,
                       target_accuracy: float | None = None, tolerance: float = 0.0, max_taps: int = 20):
    """Sweep the fixation depth on the test set; write the best one (and its threshold) into the model.

    Without ``target_accuracy``: the lowest mean width error within ``tap_budget`` mean taps (paper 002).
    With it: the fewest mean taps whose decisions are within ``tolerance`` (identity units) of the
    true width in a fraction ``target_accuracy`` of runs (falling back to the tap budget when no
    fixation reaches it within ``max_taps``), with the tempering of a calibrated kind refitted there
    for the beliefs after 1 to 5 taps (the model written is tempered accordingly).

    Returns
    -------
    (perception.LikelihoodModel, perception.FixationSweep or perception.reliability.AccuracySweep)
        The model with its recommended settings, and the sweep (for a plot or a table).
    """
    model = load_model(model_path)
    if target_accuracy is not None:
        sweep = fixation_for_accuracy(VirtualEnvironment(model, load_dataset(test_path)), target=target_accuracy,
                                      tolerance=tolerance, runs=runs, max_taps=max_taps, seed=seed,
                                      progress=progress, temper=model.temperable)
        if sweep.best is not None:
            best = sweep.best
            tempering = ""
            if model.temperable:
                tempering = f", tempering {model.tempering:.4g} x {sweep.tempering:.3g} for 1-5 taps"
                model = model.tempered(sweep.tempering)
            model = model.with_recommended(fixation_location=float(sweep.fixations[best]),
                                           decision_threshold=float(sweep.thresholds[best]), policy="active")
            save_model(model_path, model, inputs=[test_path])
            log(f"fixation depth {sweep.fixations[best]:g} {model.location_unit}: {sweep.accuracy[best]:.3f} of "
                f"decisions within {tolerance:g} {model.identity_unit} in {sweep.taps[best]:.1f} taps (decision "
                f"threshold {sweep.thresholds[best]:g}{tempering}); written to {model_path}")
            return model, sweep
        log(f"no fixation depth reaches {target_accuracy:g} of decisions within {tolerance:g} "
            f"{model.identity_unit}; choosing the lowest error within {tap_budget:g} taps instead")
    sweep = fixation_sweep(VirtualEnvironment(model, load_dataset(test_path)), tap_budget=tap_budget, runs=runs,
                           seed=seed, progress=progress)
    model = model.with_recommended(fixation_location=float(sweep.best_fixation),
                                   decision_threshold=float(sweep.best_threshold), policy="active")
    save_model(model_path, model, inputs=[test_path])
    log(f"fixation depth {sweep.best_fixation:g} {model.location_unit}: mean width error "
        f"{sweep.errors[sweep.best]:.3f} {model.identity_unit} in {sweep.taps[sweep.best]:.1f} taps "
        f"(decision threshold {sweep.best_threshold:g}); written to {model_path}")
    return model, sweep
