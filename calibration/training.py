"""Training and fixation search: from the collected datasets to a model with recommended settings.

Paper 002: the model is trained on one collection, and the virtual environment built from the
other, independent collection validates it. The fixation depth of active perception is a free
parameter; the sweep over every depth class picks the one with the lowest mean width error within a
tap budget (paper 002 Fig. 10: best after about 12 taps, at the deep end of the range), together
with the decision threshold that reaches it; or, given a target accuracy, the depth and threshold
whose decisions are within a tolerance of the true width in that fraction of runs in the fewest
taps (a calibrated model's belief means what it says, so its threshold is an accuracy). Both are
written into the model's recommended settings, which the station uses unless its configuration
overrides them. With a target accuracy, a calibrated kind gets a tap tempering schedule fitted at the
chosen depth, one factor g_t for each of taps 1 to 5 of active perception (`perception.fit_tap_tempering`):
the taps of one inspection repeat each other's evidence, which a tempering fitted on single taps ignores.

No peeking (`fit_with_fixation`, `prepare_station_model`): the station's fixation depth, threshold and
tempering are chosen on training taps held out in folds (`holdout_folds`), each scored by a model
fitted on the others (`cross_fitted_environment`); the model kept is then fitted on every training
tap and given those settings. The test
collection is used once, at the end, for the figures reported (`final_figures`), so that they are not
flattered by settings picked on the very taps they are measured on.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from calibration.errors import CalibrationError
from perception import (DEFAULT_THRESHOLDS, FixationPolicy, VirtualEnvironment, fit_tap_tempering, monte_carlo, fixation_for_accuracy, fixation_sweep, load_dataset, load_model,
                        make_policy, save_model, trace_beliefs, train_model)

__all__ = ["train_station_model", "recommend_fixation", "choose_fixation", "carve_validation",
           "prepare_station_model", "fit_with_fixation", "final_figures", "holdout_folds",
           "cross_fitted_environment", "HOLDOUT_FOLDS", "FinalFigures"]


def train_station_model(train_path: str | Path, out: str | Path, *, n_locations: int = 11, bins: int = 100,
                        kind: str = "histogram", log: Callable[[str], None] = print):
    """Fit a model of ``kind`` (`perception.MODEL_KINDS`) on ``train_path`` and save it to ``out``; returns it."""
    dataset = load_dataset(train_path)
    model = train_model(dataset, kind=kind, n_locations=n_locations, bins=bins)
    save_model(out, model, inputs=[train_path])
    log(model.summary())
    return model


def recommend_fixation(model_path: str | Path, test_path: str | Path, *, model=None, test=None,
                       log: Callable[[str], None] = print, **options):
    """Sweep the fixation depth on a dataset; write the best one (and its threshold) into the model file.

    `choose_fixation` on the dataset at ``test_path``, then the model (with its recommended settings,
    tempered as chosen) is saved back to ``model_path``. Use a validation set, not the test set whose
    figures you will report: settings chosen on the test taps flatter them (`prepare_station_model`
    does this for the station).

    Parameters
    ----------
    model_path, test_path : str or path
        The model (rewritten with its recommended settings) and the dataset the sweep runs on.
    model, test : optional
        The model and dataset already loaded from those paths.
    log : callable
        Where the line saying what was chosen goes.
    **options
        As `choose_fixation`.

    Returns
    -------
    (perception.LikelihoodModel, sweep)
        As `choose_fixation`.

    Raises
    ------
    CalibrationError
        As `choose_fixation`; nothing is written then.
    """
    model = load_model(model_path) if model is None else model
    test = load_dataset(test_path) if test is None else test
    model, sweep, line = choose_fixation(model, test, **options)
    save_model(model_path, model, inputs=[test_path])
    log(f"{line}; written to {model_path}")
    return model, sweep


def choose_fixation(model, dataset, *, runs: int = 2000, tap_budget: float = 12.0, seed: int = 0,
                    progress: Callable | None = None, target_accuracy: float | None = None, tolerance: float = 0.0,
                    max_taps: int = 20, fall_back: bool = True, report: Callable | None = None,
                    log: Callable[[str], None] = print, environment=None, **options):
    """Sweep the fixation depth of the active policy on ``dataset``; the model with the best one set.

    Without ``target_accuracy``: the lowest mean width error within ``tap_budget`` mean taps (paper 002).
    With it: the fewest mean taps whose decisions are within ``tolerance`` (identity units) of the
    true width in a fraction ``target_accuracy`` of runs, with a calibrated kind's tap tempering schedule
    fitted there for the beliefs after each of taps 1 to 5 (the model returned carries it).

    Parameters
    ----------
    model : perception.LikelihoodModel
    dataset : perception.Dataset or None
        The taps the runs draw from (a validation split, independent of the model's training taps).
    environment : perception.VirtualEnvironment, optional
        The runs' taps and their log likelihoods, given instead of ``dataset`` (e.g. out-of-fold
        likelihoods, `cross_fitted_environment`).
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
        ``report(sweep)`` before anything is decided (the CLI prints its table there).
    progress, log : callable
        A tqdm-like progress factory; where a line saying that the target was missed goes.
    **options
        Passed to the sweeps: ``thresholds``, ``deadline``, ``move_threshold``, ``shift_mode``, and
        ``map_fn`` (the fixations run through it, e.g. on a Dask cluster: `tactip.cluster.cluster_map`).

    Returns
    -------
    (perception.LikelihoodModel, sweep, str)
        The model with its recommended settings (``fixation_location``, ``decision_threshold``,
        ``policy``), the sweep (`perception.FixationSweep` or `perception.reliability.AccuracySweep`,
        for a plot or a table), and one line saying what was chosen.

    Raises
    ------
    CalibrationError
        ``fall_back`` is False and the target is not reached; or no fixation decides within the tap
        budget at any threshold.
    """
    environment = VirtualEnvironment(model, dataset) if environment is None else environment
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
            if sweep.tap_tempering:
                tempering = f", tap tempering {_schedule_text(sweep.tap_tempering)}"
                model = model.with_tap_tempering(sweep.tap_tempering)
            model = model.with_recommended(fixation_location=fixation, decision_threshold=threshold, policy="active")
            return model, sweep, (f"fixation depth {fixation:g} {unit}: {sweep.accuracy[best]:.3f} of decisions within "
                                  f"{tolerance:g} {identity_unit} in {sweep.taps[best]:.1f} taps (decision threshold "
                                  f"{threshold:g}{tempering})")
        if not fall_back:
            raise CalibrationError(f"--target-accuracy {target_accuracy:g} is not reached at any fixation within "
                                   f"{max_taps} taps (best {sweep.accuracy.max():.3f}); lower it, raise --tolerance "
                                   f"or --max-taps; nothing written")
        log(f"no fixation depth reaches {target_accuracy:g} of decisions within {tolerance:g} "
            f"{identity_unit}; choosing the lowest error within {tap_budget:g} taps instead")
    # A recommended threshold is in (0, 1], as a station's key is: threshold 0 (decide after the first
    # tap whatever the belief) is not a candidate here, although the papers' sweeps include it.
    options.setdefault("thresholds", tuple(t for t in DEFAULT_THRESHOLDS if t > 0))
    sweep = fixation_sweep(environment, tap_budget=tap_budget, runs=runs, seed=seed, progress=progress,
                           max_taps=max_taps, **options)
    if not fall_back and sweep.taps[sweep.best] > tap_budget:
        fewest = float(min(r.mean_taps.min() for r in sweep.results))
        raise CalibrationError(f"--tap-budget {tap_budget:g} is too tight: no fixation decides within {tap_budget:g} "
                               f"mean taps at any threshold (fewest: {fewest:.2f}); use --tap-budget in "
                               f"{fewest:.2f}..{max_taps}; nothing written")
    if report is not None:
        report(sweep)
    threshold, error, taps, tempering = sweep.best_threshold, sweep.errors[sweep.best], sweep.taps[sweep.best], ""
    if target_accuracy is not None and model.temperable:
        # The station's first use, its target missed: its beliefs are still calibrated at the fixation
        # (as on the target's path), and the threshold chosen again on the calibrated beliefs.
        policy = FixationPolicy(int(np.argmin(np.abs(model.location_centres - sweep.best_fixation))))
        schedule = fit_tap_tempering(environment, policy, runs=runs, seed=seed)
        result = monte_carlo(environment.with_tap_tempering(schedule), policy, seed=seed, runs=runs, max_taps=max_taps,
                             **{k: v for k, v in options.items() if k != "fixation_classes"})
        k = result.best_within(tap_budget)
        errors = result.mean_location_error if result.identity_error_map.shape[-1] == 1 else result.mean_identity_error
        threshold, error, taps = float(result.thresholds[k]), float(errors[k]), float(result.mean_taps[k])
        tempering = f", tap tempering {_schedule_text(schedule)}"
        model = model.with_tap_tempering(schedule)
    model = model.with_recommended(fixation_location=float(sweep.best_fixation), decision_threshold=float(threshold),
                                   policy="active")
    return model, sweep, (f"fixation depth {sweep.best_fixation:g} {unit}: mean width error "
                          f"{error:.3f} {identity_unit} in {taps:.1f} taps (decision threshold {threshold:g}{tempering})")


def _schedule_text(schedule) -> str:
    """A tap tempering schedule as printed: ``"g1..g5 0.91, 0.52, 0.4, 0.33, 0.3"``."""
    return f"g1..g{len(schedule)} " + ", ".join(f"{g:.3g}" for g in schedule)


#: Folds of the training taps the station's settings are chosen on (`holdout_folds`).
HOLDOUT_FOLDS = 4


def holdout_folds(dataset, n_locations: int = 11, folds: int = HOLDOUT_FOLDS) -> np.ndarray:
    """The fold each training tap is held out in, for choosing settings on taps a model was not fitted on.

    The classes are the model's (`perception.likelihood.fit_class_grid`: ``n_locations`` equal location
    classes x the identities). A tap at the collection's shallowest or deepest location stays in (-1)
    whenever its class has other taps, so that every fold's model spans the same locations and has the
    very classes of the whole set; a class made only of such taps (all at one extreme: the shallowest
    class of a station whose depths fall one per class) holds out one of them and keeps the others. Every
    other tap is held out once (the held-out candidates, in location then collection order within their
    class), so that a class is judged on all its taps, each by a model fitted without it. They are held out
    by location: the r-th candidate of every identity at one location class is held out in one fold, these
    groups (by location class, then candidate rank) dealt to folds 0, 1, ..., ``folds`` - 1 in turn, so a
    class's candidates go to different folds and one of its taps stays in every fold's fit.

    Why every identity of a location together: a held-out tap is then judged against competitors that lost
    the same tap as its own class did, as the test collection's taps meet a model whose classes all have
    every training tap. Held out in different folds (a Latin square: the identities of one depth in
    different folds), a held-out tap's class was the only one at its location short of that tap, and every
    competitor still had a tap right there: on the packaged simulated station (one tap per depth, two
    depths per class) the histogram's out-of-fold one-tap width accuracy was 0.00-0.15 at every depth
    (collection seeds 0-2; on the test collection 0.53-0.87 at 2.75-5.25 mm), so the fixation sweep chose on
    noise. Why every tap: holding out all but one tap of a class (the last in location order), each class
    was judged on its shallow half only, and there the sweep's errors alternated from class to class
    (3.75 and 4.75 mm low, 4.25 and 5.25 mm high on every seed) where the test collection's do not.
    Deterministic, so a rerun chooses the same settings.

    Parameters
    ----------
    dataset : perception.Dataset
    n_locations : int
        Location classes of the model to be fitted.
    folds : int
        Number of folds (>= 2): each fold's model is fitted on the other taps.

    Returns
    -------
    (N,) int ndarray
        The fold of each tap, -1 for a tap never held out.

    Raises
    ------
    CalibrationError
        A class has a single tap (nothing to hold out): the message names it.
    """
    from perception.likelihood import fit_class_grid

    grid = fit_class_grid(dataset, n_locations=n_locations)
    tap_class = grid.tap_class(dataset)
    extreme = (dataset.location == dataset.location.min()) | (dataset.location == dataset.location.max())
    order = np.lexsort((np.arange(len(dataset)), dataset.location, extreme, tap_class))   # by class; extremes last
    cls = tap_class[order]
    starts = np.flatnonzero(np.r_[True, cls[1:] != cls[:-1]])
    counts = np.diff(np.r_[starts, len(order)])
    if (counts < 2).any():
        l, i = divmod(int(cls[starts[np.argmax(counts < 2)]]), grid.n_identities)
        raise CalibrationError(f"the class at location {grid.location_centres[l]:g} {dataset.location_unit}, "
                               f"identity {grid.identities[i]:g} {dataset.identity_unit} has a single training tap: "
                               f"nothing to hold out for choosing the fixation and threshold (collect repeats, or "
                               f"use fewer location classes)")
    rank = np.arange(len(order)) - np.repeat(starts, counts)                 # position within the class
    off_extremes = np.add.reduceat((~extreme[order]).astype(int), starts)   # taps of each class not at an extreme
    # Held-out candidates: the taps off the extremes (sorted first within their class); a class of extreme taps
    # only holds out its first.
    held = rank < np.repeat(np.where(off_extremes > 0, off_extremes, 1), counts)
    # One group per (location class, candidate rank), every identity in it; the groups dealt to the folds in turn.
    group = (cls // grid.n_identities) * len(order) + rank
    fold = np.full(len(order), -1, np.int64)
    fold[held] = np.unique(group[held], return_inverse=True)[1] % folds
    out = np.empty(len(dataset), np.int64)
    out[order] = fold
    return out


def carve_validation(dataset, n_locations: int = 11) -> tuple[np.ndarray, np.ndarray]:
    """Fold 0 of `holdout_folds`: ``(fit, validation)`` tap indices, disjoint, together every tap."""
    fold = holdout_folds(dataset, n_locations)
    return np.flatnonzero(fold != 0), np.flatnonzero(fold == 0)


def cross_fitted_environment(train, *, n_locations: int = 11, folds: int = HOLDOUT_FOLDS,
                             progress: Callable | None = None, pool_tempering: bool | None = None, **fit_options):
    """A model fitted on most training taps, and the out-of-fold environment its settings are chosen in.

    Each fold of `holdout_folds` gets a model fitted on the other taps, which scores the fold's taps;
    together they give every held-out training tap a log likelihood from a model that never saw it
    (out-of-fold), so a Monte Carlo run at the fixation draws from all of a class's held-out taps, not
    from one. The models share their classes (the extreme locations are never held out). With
    ``pool_tempering`` a calibrated kind's tempering beta is then fitted once on the pooled out-of-fold
    scores (`perception.fit_tempering` on them untempered) and given to every fold's model.

    Parameters
    ----------
    train : perception.Dataset
    n_locations, folds, **fit_options
        As `holdout_folds` and `perception.train_model` (``kind``, ``bins``, ...).
    progress : callable, optional
        A tqdm-like wrapper of the iterable of folds (one model fitted per fold).
    pool_tempering : bool, optional
        Default: for the torch kind, whose own beta comes from the network's own split (one tap a class
        on the small station: the four fold models' were 2.6-15.7 on one station); the Gaussian's own,
        from 4 folds, agree within 1.15-1.7x and pooled they were no better (seeds 0-3: one-tap ECE
        0.024 / 0.036 / 0.024 / 0.027 against 0.028 / 0.036 / 0.024 / 0.016).

    Returns
    -------
    (perception.LikelihoodModel, perception.VirtualEnvironment)
        Fold 0's model (fitted on every tap but fold 0's; a calibrated kind with the pooled beta) and the
        environment of the held-out taps, in that model's terms.
    """
    fold = holdout_folds(train, n_locations, folds)
    held = np.flatnonzero(fold >= 0)
    table = np.empty((len(held), 0))
    models = {}
    wrap = progress or (lambda items, **_: items)
    for k in wrap(np.unique(fold[held]).tolist(), desc="fits", unit="fold"):
        models[k] = train_model(train.subset(np.flatnonzero(fold != k)), n_locations=n_locations, **fit_options)
        if table.shape[1] == 0:
            table = np.empty((len(held), models[k].n_classes))
        rows = np.flatnonzero(fold[held] == k)
        table[rows] = models[k].log_likelihood_batch(train.taps[held[rows]]).reshape(len(rows), -1)
    model = models[min(models)]
    environment = VirtualEnvironment(model, train.subset(held), _log_likelihood=table)
    if pool_tempering is None:
        pool_tempering = fit_options.get("kind") == "torch"
    if pool_tempering and model.temperable:   # one beta for all, on the pooled out-of-fold scores
        from perception.tempering import check_tempering, fit_tempering

        betas = np.array([models[k].tempering if k in models else np.nan for k in range(folds)])[fold[held]]
        table = table / betas[:, None]
        beta = fit_tempering(table.reshape(-1, model.n_locations, model.n_identities), environment.decided_class)
        check_tempering(beta)
        model = model.tempered(beta / model.tempering)
        environment = VirtualEnvironment(model, train.subset(held), _log_likelihood=beta * table)
    return model, environment


@dataclass(frozen=True)
class FinalFigures:
    """What the test collection says of a prepared model, at its recommended fixation and threshold.

    Attributes
    ----------
    fixation, threshold : float
        The settings tested (location units; belief).
    mean_taps, mean_error, accuracy : float
        Mean decision taps, mean |decided - true| identity (identity units, wrapped for a circular
        identity) and the fraction of decisions of exactly the right class.
    within_tolerance : float
        Fraction of decisions within ``tolerance`` of the true identity.
    tolerance : float
    runs : int
    """

    fixation: float
    threshold: float
    mean_taps: float
    mean_error: float
    accuracy: float
    within_tolerance: float
    tolerance: float
    runs: int

    def describe(self, model) -> str:
        """One line, in the model's units."""
        return (f"test collection (used once, for these figures): {self.within_tolerance:.3f} of decisions within "
                f"{self.tolerance:g} {model.identity_unit}, mean error {self.mean_error:.3f} {model.identity_unit}, "
                f"accuracy {self.accuracy:.3f} in {self.mean_taps:.2f} taps ({self.runs} runs at fixation "
                f"{self.fixation:g} {model.location_unit}, threshold {self.threshold:g})")


def final_figures(model, test, *, tolerance: float = 0.0, runs: int = 2000, max_taps: int = 20,
                 seed: int = 0) -> FinalFigures:
    """Monte Carlo figures of the active policy on the test collection at the model's recommended settings.

    Parameters
    ----------
    model : perception.LikelihoodModel
        With ``fixation_location`` and ``decision_threshold`` recommended.
    test : perception.Dataset
        The test collection, independent of everything the model and its settings were chosen on.
    tolerance : float
        Identity units: a decision this close to the truth counts as within tolerance.
    runs, max_taps, seed : int

    Returns
    -------
    FinalFigures
    """
    fixation = float(model.recommended["fixation_location"])
    threshold = float(model.recommended["decision_threshold"])
    policy = make_policy("active", fixation_class=model.fixation_class(fixation))
    trace = trace_beliefs(VirtualEnvironment(model, test), policy, runs=runs, max_taps=max_taps, seed=seed,
                          shift_mode=model.shift_mode)
    decisions = trace.decisions(threshold)
    right = decisions.identity == trace.truth[np.arange(trace.runs), decisions.taps - 1]
    return FinalFigures(fixation, threshold, float(decisions.taps.mean()), float(decisions.error.mean()),
                       float(right.mean()), float((decisions.error <= tolerance + 1e-9).mean()), float(tolerance),
                       int(runs))


def fit_with_fixation(train, *, kind: str = "histogram", n_locations: int = 11, bins: int = 100,
                      target_accuracy: float | None = None, tolerance: float = 0.0, max_taps: int = 20,
                      runs: int = 2000, seed: int = 0, fall_back: bool = True, folds: int = HOLDOUT_FOLDS,
                      refit: bool = True, log: Callable[[str], None] = print, progress: Callable | None = None,
                      **fit_options):
    """A model fitted on every training tap, with its fixation, threshold and tempering chosen on held-out taps.

    `cross_fitted_environment`: the training taps fall in ``folds`` folds (`holdout_folds`); each fold's
    taps are scored by a model fitted on the others, and the fixation location, threshold and
    (calibrated kinds) tap tempering g1..g5 for taps 1-5 are chosen on those out-of-fold scores
    (`choose_fixation`). Then the model kept is fitted on every training tap and given those settings
    (``refit``): no tap a user collected is left out of it. No test tap is read.

    What that does to calibration: the settings were chosen for models that each miss one fold, so the
    model kept must be of their making. Its tempering beta is one for all (the torch's and, refitted,
    the Gaussian's; `cross_fitted_environment`): fitted on the pooled out-of-fold scores, given to every
    fold's model and to the refit; and the fold models take the refit's own cross-validated settings
    (the Gaussian's components and shrinkage; the torch's input and deviations, which spares each fold
    model three of its four early stoppings: on the small station, seeds 0-4, the same model in 0.3x the
    CPU, each fold's own search having chosen as the refit did). Each with its own (synthetic `gap_dataset`, 4 taps a
    class, Gaussian, target 0.9, seeds 1-10), the refit's components, shrinkage and beta (0.03-0.66
    against its folds' 0.07-0.43) differed from the models its threshold was chosen for: its decisions
    came in 1.06-1.39 taps against their 1.22-1.47, test accuracy 0.71-0.95 (mean 0.82; the fold model
    kept, 0.80-0.99, mean 0.94); pooled 0.69-0.99 (mean 0.88); pooled, of the refit's settings 0.82-0.99
    (mean 0.88). On the small simulated station (12 classes, 2 taps per depth and gap, one-tap ECE over 768
    further taps, bench/bench_station_ece.py has the history): with every identity of a location held out
    together, the torch with one pooled beta 0.021 / 0.044 / 0.042 / 0.046 / 0.043 on seeds 0-4.

    Parameters
    ----------
    train : perception.Dataset
        The training taps.
    kind, n_locations, bins, **fit_options
        As `perception.train_model`; ``pool_tempering`` among them goes to `cross_fitted_environment`
        (default: the torch kind, and the Gaussian refitted), and the refit then takes the pooled beta.
    target_accuracy, tolerance, max_taps, runs, seed, fall_back
        As `choose_fixation`.
    folds : int
        Folds of the cross-fitting (models fitted: one per fold, and one on every tap with ``refit``).
    refit : bool
        Keep a model fitted on every training tap (True) or fold 0's model, fitted on every tap but
        fold 0's (False), with the settings chosen.
    log : callable
        Where the lines saying what was chosen go.
    progress : callable, optional
        A tqdm-like progress factory, wrapping the folds fitted and the fixations swept.

    Returns
    -------
    perception.LikelihoodModel
    """
    log(f"choosing the fixation and threshold on the training taps held out in {folds} folds, each scored by a "
        f"model fitted on the others ({folds} fits)")
    pooled = fit_options.pop("pool_tempering", None)
    pooled = (kind == "torch" or refit and kind == "gaussian") if pooled is None else bool(pooled)
    every, same = None, {}
    if refit:   # the model kept first: the fold models take its settings (the Gaussian's components, shrinkage)
        every = train_model(train, kind=kind, n_locations=n_locations, bins=bins, **fit_options)
        if kind == "gaussian":
            same = dict(components=every.n_components, shrinkages=every.shrinkage)
        elif kind == "torch":   # its input and deviations: one early stopping per fold model instead of four
            same = dict(every.choices)
    model, environment = cross_fitted_environment(train, n_locations=n_locations, folds=folds, kind=kind, bins=bins,
                                                  progress=progress, pool_tempering=pooled, **fit_options, **same)
    fold = holdout_folds(train, n_locations, folds)
    sizes = np.bincount(fold[fold >= 0], minlength=folds)
    log(f"{len(environment.test)} of the {len(train)} training taps held out "
        f"({'/'.join(map(str, sizes))} in the folds)")
    chosen, _, line = choose_fixation(model, None, environment=environment, target_accuracy=target_accuracy,
                                      tolerance=tolerance, max_taps=max_taps, runs=runs, seed=seed, log=log,
                                      fall_back=fall_back, progress=progress)
    log(line)
    if not refit:
        return chosen
    model = every
    if pooled and model.temperable:   # the beta chosen out of fold (`cross_fitted_environment`), as the g_t
        model = model.tempered(chosen.tempering / model.tempering)
    if chosen.tap_tempering:
        model = model.with_tap_tempering(chosen.tap_tempering)
    log(f"the model kept is fitted on all {len(train)} training taps and given these settings")
    return model.with_recommended(**chosen.recommended)


def prepare_station_model(train_path: str | Path, out: str | Path, *, log: Callable[[str], None] = print, **options):
    """Train the station's model and choose its settings without peeking at the test set; write it to ``out``.

    `fit_with_fixation` on the training collection at ``train_path`` (its options: ``kind``,
    ``n_locations``, ``bins``, ``target_accuracy``, ``tolerance``, ``max_taps``, ``runs``, ``seed``).

    Returns
    -------
    perception.LikelihoodModel
        The model written, with its recommended settings.
    """
    model = fit_with_fixation(load_dataset(train_path), log=log, **options)
    save_model(out, model, inputs=[train_path])
    log(model.summary())
    return model
