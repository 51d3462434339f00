"""The histogram model with its tempering fitted on held-out taps (kind ``calibrated-histogram``).

The same counts as the papers' model (`perception.histogram.fit_model`), but the mean log probability
over samples and dimensions (the geometric-mean likelihood, a fixed tempering of the naive-Bayes
product by 1 / (samples x dims)) is multiplied by a tempering factor beta fitted by cross-validation
over the training collection:

    log P_beta(z | c) = beta sum_k sum_j log P_k(b_k(j) | c) / (N_samples N_dims)

Each fold's histograms are counted without its held-out taps, on the full model's bins and classes;
beta maximises the one-tap posterior of the held-out taps' true identity (`perception.tempering`),
so a one-tap belief of 0.9 is right about 90 % of the time on taps like the training ones.
beta = 1 is the papers' model; beta = samples x dims a naive Bayes over every sample.

Example
-------
>>> model = fit_calibrated_histogram(train, n_locations=11)     # doctest: +SKIP
>>> model.tempering                                             # doctest: +SKIP
41.7
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from .dataset import Dataset
from .errors import ModelError
from .histogram import DEFAULT_EPSILON, HistogramModel, fit_model, histogram_log_probability
from .tempering import check_tempering, cross_validation_folds, fit_tempering

__all__ = ["CalibratedHistogramModel", "fit_calibrated_histogram", "held_out_log_likelihood"]


@dataclass(frozen=True, repr=False)
class CalibratedHistogramModel(HistogramModel):
    """A histogram model whose mean log likelihood is tempered by ``tempering`` (beta).

    Attributes
    ----------
    tempering : float
        beta > 0, fitted on held-out taps (1: the papers' model).
    folds : int
        Cross-validation folds beta was fitted with.
    """

    tempering: float = 1.0
    folds: int = 0

    KIND = "calibrated-histogram"
    _ATTRS = ("epsilon", "tempering", "folds")

    def __post_init__(self):
        super().__post_init__()
        if not (np.isfinite(self.tempering) and self.tempering > 0):
            raise ModelError(f"tempering must be a finite number > 0, got {self.tempering!r}")

    def _kind_summary(self) -> str:
        """One line: front end, class grid, tap shape, bins, tempering."""
        return f"{super()._kind_summary()}; calibrated histogram, tempering {self.tempering:.4g}"

    def log_likelihood(self, tap) -> np.ndarray:
        """beta x the histogram model's mean log likelihood of one tap.

        Parameters
        ----------
        tap : (samples, dims) array

        Returns
        -------
        (n_locations, n_identities) float64 ndarray
        """
        return self.tempering * super().log_likelihood(tap)

    def log_likelihood_batch(self, taps) -> np.ndarray:
        """`log_likelihood` of many taps at once.

        Parameters
        ----------
        taps : (N, samples, dims) array

        Returns
        -------
        (N, n_locations, n_identities) float64 ndarray
        """
        return self.tempering * super().log_likelihood_batch(taps)

    def _stored(self) -> tuple[dict, dict]:
        arrays, attrs = super()._stored()
        return arrays, {**attrs, "tempering": self.tempering, "folds": self.folds}

    @classmethod
    def _from_stored(cls, common: dict, arrays: dict, attrs: dict):
        try:
            settings = dict(epsilon=float(attrs["epsilon"]), tempering=float(attrs["tempering"]),
                            folds=int(attrs["folds"]))
        except (TypeError, ValueError):
            raise ModelError(f"unreadable tempering settings {dict(attrs)!r}") from None
        return cls(**arrays, **common, **settings)


def held_out_log_likelihood(model: HistogramModel, dataset: Dataset, *, folds: int = 2):
    """Each training tap's mean log likelihood under histograms counted without its fold.

    Parameters
    ----------
    model : HistogramModel
        Trained on ``dataset`` (gives the bins and classes).
    dataset : Dataset
    folds : int
        Cross-validation folds, >= 2; the taps of each class are dealt to the folds in location order.

    Returns
    -------
    log_likelihood : (M, L, I) float64 ndarray
        Of the M taps whose class keeps training taps outside their fold.
    kept : (N,) bool ndarray
        Which taps these are.
    """
    cls = model.tap_class(dataset)
    fold = cross_validation_folds(cls, folds, order=dataset.location)
    out = np.zeros((len(dataset), model.n_locations, model.n_identities))
    kept = np.zeros(len(dataset), bool)
    for k in range(folds):
        held, train = fold == k, fold != k
        log_p = histogram_log_probability(model, dataset.taps[train], cls[train])
        part = dataclasses.replace(model, log_probability=log_p)
        seen = np.bincount(cls[train], minlength=model.n_classes) > 0
        use = held & seen[cls]
        if use.any():
            out[use] = HistogramModel.log_likelihood_batch(part, dataset.taps[use])
        kept |= use
    return out[kept], kept


def fit_calibrated_histogram(dataset: Dataset, *, n_locations: int = 11, bins: int = 100,
                             epsilon: float = DEFAULT_EPSILON, min_taps_per_class: int = 1,
                             folds: int = 2) -> CalibratedHistogramModel:
    """Train the histogram model and fit its tempering by cross-validation over the training taps.

    Parameters
    ----------
    dataset : Dataset
    n_locations, bins, epsilon, min_taps_per_class
        As for `perception.fit_model`.
    folds : int
        Cross-validation folds, >= 2 (default 2: the protocol collects about two taps per class).

    Returns
    -------
    CalibratedHistogramModel

    Raises
    ------
    DatasetError
        As `perception.fit_model`, or no class has taps in two folds.
    """
    from .errors import DatasetError

    base = fit_model(dataset, n_locations=n_locations, bins=bins, epsilon=epsilon,
                     min_taps_per_class=min_taps_per_class)
    log_likelihood, kept = held_out_log_likelihood(base, dataset, folds=folds)
    if not kept.any():
        raise DatasetError("no class has training taps in two folds: collect at least two taps per class to "
                           "calibrate the model")
    truth = base.identity_class(dataset.identity[kept]) if base.n_identities > 1 \
        else base.location_class(dataset.location[kept])
    beta = fit_tempering(log_likelihood, truth)
    check_tempering(beta)
    fields = {f.name: getattr(base, f.name) for f in dataclasses.fields(base)}
    return CalibratedHistogramModel(**fields, tempering=beta, folds=int(folds))
