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

from calibration.errors import CalibrationError
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
                       target_accuracy: float | None = None, tolerance: float = 0.0, max_taps: int = 20,
                       fall_back: bool = True, report: Callable | None = None, model=None, test=None, **options):
    """Sweep the fixation depth on the test set; write the best one (and its threshold) into the model.

    Without ``target_accuracy``: the lowest mean width error within ``tap_budget`` mean taps (paper 002).
    With it: the fewest mean taps whose decisions are within ``tolerance`` (identity units) of the
    true width in a fraction ``target_accuracy`` of runs, with the tempering of a calibrated kind
    refitted there for the beliefs after 1 to 5 taps (the model written is tempered accordingly).

    Parameters
    ----------
    model_path, test_path : str or path
        The model (rewritten with its recommended settings) and the test collection.
    runs, seed, max_taps : int
        Monte Carlo runs per fixation, their seed, most taps per run.
    tap_budget : float
        Mean taps within which the lowest error is taken.
    target_accuracy, tolerance : float
        See above; ``tolerance`` in the model's identity unit (mm).
    fall_back : bool
        When no fixation reaches ``target_accuracy`` within ``max_taps``: take the lowest error within
        the tap budget instead (the station's first use), or refuse (`tactip validate`).
    report : callable, optional
        ``report(sweep)`` before anything is decided or written (the CLI prints its table there).
    model, test : optional
        The model and dataset already loaded from those paths.
    progress, log : callable
        A tqdm-like progress factory; where the lines saying what was chosen go.
    **options
        Passed to the sweeps: ``thresholds``, ``deadline``, ``move_threshold``, ``shift_mode``.

    Returns
    -------
    (perception.LikelihoodModel, perception.FixationSweep or perception.reliability.AccuracySweep)
        The model with its recommended settings, and the sweep (for a plot or a table).

    Raises
    ------
    CalibrationError
        ``fall_back`` is False and the target is not reached; or no fixation decides within the tap
        budget at any threshold. Nothing is written then.
    """
    model = load_model(model_path) if model is None else model
    environment = VirtualEnvironment(model, load_dataset(test_path) if test is None else test)
    unit, identity_unit = model.location_unit, model.identity_unit
    if target_accuracy is not None:
        accuracy_options = {k: v for k, v in options.items() if k != "thresholds" and k != "deadline"}
        sweep = fixation_for_accuracy(environment, target=target_accuracy, tolerance=tolerance, runs=runs,
                                      max_taps=max_taps, seed=seed, progress=progress, temper=model.temperable,
                                      **accuracy_options)
        if report is not None:
            report(sweep)
        if sweep.best is not None:
            best = sweep.best
            fixation, threshold = float(sweep.fixations[best]), float(sweep.thresholds[best])
            tempering = ""
            if model.temperable:
                tempering = f", tempering {model.tempering:.4g} x {sweep.tempering:.3g} for 1-5 taps"
                model = model.tempered(sweep.tempering)
            model = model.with_recommended(fixation_location=fixation, decision_threshold=threshold, policy="active")
            save_model(model_path, model, inputs=[test_path])
            log(f"fixation depth {fixation:g} {unit}: {sweep.accuracy[best]:.3f} of decisions within {tolerance:g} "
                f"{identity_unit} in {sweep.taps[best]:.1f} taps (decision threshold {threshold:g}{tempering}); "
                f"written to {model_path}")
            return model, sweep
        if not fall_back:
            raise CalibrationError(f"--target-accuracy {target_accuracy:g} is not reached at any fixation within "
                                   f"{max_taps} taps (best {sweep.accuracy.max():.3f}); lower it, raise --tolerance "
                                   f"or --max-taps; nothing written")
        log(f"no fixation depth reaches {target_accuracy:g} of decisions within {tolerance:g} "
            f"{identity_unit}; choosing the lowest error within {tap_budget:g} taps instead")
    sweep = fixation_sweep(environment, tap_budget=tap_budget, runs=runs, seed=seed, progress=progress,
                           max_taps=max_taps, **options)
    if not fall_back and sweep.taps[sweep.best] > tap_budget:
        fewest = float(min(r.mean_taps.min() for r in sweep.results))
        raise CalibrationError(f"--tap-budget {tap_budget:g} is too tight: no fixation decides within {tap_budget:g} "
                               f"mean taps at any threshold (fewest: {fewest:.2f}); use --tap-budget in "
                               f"{fewest:.2f}..{max_taps}; nothing written")
    if report is not None:
        report(sweep)
    model = model.with_recommended(fixation_location=float(sweep.best_fixation),
                                   decision_threshold=float(sweep.best_threshold), policy="active")
    save_model(model_path, model, inputs=[test_path])
    log(f"fixation depth {sweep.best_fixation:g} {unit}: mean width error {sweep.errors[sweep.best]:.3f} "
        f"{identity_unit} in {sweep.taps[sweep.best]:.1f} taps (decision threshold {sweep.best_threshold:g}); "
        f"written to {model_path}")
    return model, sweep
