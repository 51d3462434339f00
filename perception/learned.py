"""A small learned likelihood (kind ``torch``): an ensemble of networks, early-stopped and temperature-scaled.

The tap (samples x dims) is flattened, centred on the training taps' mean and divided by their
spread pooled over every value (one scale, so values that carry only noise stay small), and mapped
by each of M small networks (one hidden layer of ``hidden`` ReLU units, different seeds) to one
score per joint class; the members' log posteriors are averaged (a geometric-mean ensemble):

    s_c(z) = 1/M sum_m log softmax_c(W2_m relu(W1_m (x - mu) / sigma + b1_m) + b2_m),
    log P(z | c) = beta s_c(z) + const

Trained with torch (Adam, cross-entropy over the joint classes, weight decay; all members at once as
one batched network, on every core when it is large, `perception._ensemble_training`) on the training taps of every
fold but one; each member keeps the epoch of its lowest held-out loss (early stopping), beta is
fitted on the held-out taps' decision posteriors of the ensemble (temperature scaling,
`perception.tempering`), and the members are trained again on every training tap for their epochs.
With a balanced training set the scores are log posteriors under a flat prior, i.e. log likelihoods
up to a constant shared by all classes.

Every minibatch tap is moved by a within-class deviation drawn from the training taps
(`within_class_residuals`: a tap's offset from its class mean, drawn afresh at every step), so that
the networks learn the spread of each class, not its one or two taps. Why: on the small simulated
station (96 training taps, 44 classes) the networks trained on the taps alone memorised their noise,
and taps in air, where the four gaps cannot be told apart, were given one gap at a belief of 0.99-1.00
(out-of-fold, a median 54-96 nats between the gaps); with the deviations 0.32-0.55 (0.5-2.2 nats,
measured when the early-stopping fold lent its deviations too; the Gaussian 0.27-0.28). On the test
collection, at the settings chosen out-of-fold, the active policy's
accuracy after 3 / 5 taps went from 0.66 / 0.67, 0.77 / 0.84, 0.73 / 0.66 to 1.00 / 1.00, 0.93 / 0.90,
0.95 / 0.97 (collection seeds 0, 1, 2). Early stopping waits 25 epochs rather than 10: the augmented
held-out loss is noisier, and with 10 seed 1 stopped at 50 epochs (accuracy 0.67 / 0.66); seeds 0
and 2 were the same with either. Label smoothing (0.1, 0.3) did not help: the tempering scaled the
bounded scores up again. On the packaged station (20 gaps, 920 training taps) it is no clear gain:
ECE after 1 / 3 / 5 taps 0.071 / 0.073 / 0.159 and 0.089 / 0.033 / 0.091 (seeds 0, 1) against
0.070 / 0.027 / 0.057 and 0.072 / 0.040 / 0.148 without it (`bench/bench_torch_calibration.py --packaged`).

Pooled deviations assume that every class spreads alike (as the Gaussian's shared covariance does).
Where classes differ in their spread they blur them: on xor-like taps (pins along x = y in one class,
x = -y in the other, `bench/bench_baselines.py`) a tap moved by the other class's deviation is no
longer of its class, and the 1-tap error was 0.026 / 0.029 / 0.036 (seeds 0-2) where kNN's is 0.009 /
0.005 / 0.019. So early stopping is run twice, with pooled deviations and with deviations drawn from
each tap's own class only (`train_ensemble`'s ``residual_class``), and the lower held-out loss (at its
best temperature) chooses; xor then gives 0.000 on those seeds.

The input is chosen the same way: every value, or the imputation Gaussian's leading directions (its
rank, chosen as above; the first layer on them is folded back into one on every value, W1 = Q W1', so
the stored model is the same). On depths whose mean taps lie along one code among 144 noisy values
(the `bench/bench_baselines.py` numeric case, 180 taps) the networks on every value followed the noise,
1-tap error 0.55 / 0.53 / 0.50 mm against ridge's 0.10 / 0.18 / 0.13 (seeds 0-2); on the directions
0.017 / 0.080 / 0.020, like the Gaussian. Where the classes differ in many ways (named shapes) every value
is kept. The directions tried are fitted on the trained taps only (fitted on the held-out taps too they
flattered those taps' loss, and named shapes picked them wrongly).

Why these choices (held-out one-tap accuracy, three seeds each): one pooled scale rather than one
per value, 0.61 against 0.49 on the small simulated station's collection (96 taps, 44 classes; the
Gaussian: 0.61) and 1.00 against 0.99 on slides replayed from a radial TacTip, where a scale per
value raised the noise of pins far from the contact to the level of the informative ones; five
members rather than one, 0.49 against 0.38 on that station (with scales per value) and a lower
held-out log loss on the slides (0.038 against 0.053 nats); every value as input rather than the
imputation Gaussian's 64 leading components, 1.00 against 0.75 (whitened) or 0.94 (not) on those
slides; at least 8 steps per epoch, since a hundred taps in batches of 64 left the networks far from
trained after 100 epochs.

A tap missing values (NaN: the dimensions of a pin unseen during the tap) is scored on its
conditional-mean imputation: the standardised training taps are fitted by a Gaussian (probabilistic
PCA, `perception.marginal.fit_low_rank_gaussian`, ``imputation_*``; its rank, a power of two up to 64,
is the one that best imputes a dim hidden in each held-out tap, `_fit_imputation`), and a missing value is replaced
by its mean given the tap's observed values, E[x_M | x_O], before the network scores it; training
taps missing values are filled the same way. Why this route rather than training with random
dimension dropout and a mask input: the network and its numpy evaluation stay as they are; every
missing pattern is handled, not only those drawn in training; neighbouring pins move together, so
the observed pins predict an unseen one well (the conditional mean is the least-squares guess); and
it costs one eigendecomposition at training. It is a plug-in, not the exact marginal
(integrating the network's posterior over P(x_M | x_O)): the two agree when the scores are close to
linear over the spread of the missing values, which the measured accuracy checks.

A circular or named identity needs nothing special: the networks classify the joint classes, whose
order plays no part.

Torch is needed to train only (``pip install torch==2.13.0``, the optional extra ``learned``): the
weights are stored as arrays and the likelihood is computed with numpy, so a station runs the model
without torch. A model file of one network (written before the ensemble) is read as an ensemble of one.

Example
-------
>>> model = fit_torch(train, n_locations=11)       # doctest: +SKIP
>>> model.log_likelihood(tap).shape                # doctest: +SKIP
(11, 20)
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.special import log_softmax

from .dataset import Dataset
from .errors import DatasetError, ModelError
from .likelihood import LikelihoodModel, fit_class_grid
from .marginal import LowRankGaussian, fit_low_rank_gaussian
from .tempering import check_tempering, cross_validation_folds, fit_tempering

__all__ = ["TorchModel", "fit_torch", "require_torch", "TORCH_PIN"]

_BATCH = 1024
#: The torch the project is tested with (CPU build); an unpinned ``pip install torch`` pulls gigabytes of GPU wheels.
TORCH_PIN = "torch==2.13.0"
#: Directions of the Gaussian that imputes missing values (capped by the training taps).
IMPUTATION_COMPONENTS = 64


@dataclass(frozen=True, repr=False)
class TorchModel(LikelihoodModel):
    """An ensemble of one-hidden-layer networks, scores as tempered log likelihoods (build with `fit_torch`).

    Attributes
    ----------
    mean, scale : (samples * dims,) float64 ndarray
        Centring and scaling of the flattened tap (sensor units; one pooled scale repeated in models
        trained since issue 21, a scale per value in older files).
    hidden_weight : (M, samples * dims, H) float32 ndarray
        First layer of each of the M members (a (samples * dims, H) array is one member).
    hidden_bias : (M, H) float32 ndarray
    output_weight : (M, H, classes) float32 ndarray
    output_bias : (M, classes) float32 ndarray
    tempering : float
        beta > 0 (1 / temperature), fitted on held-out taps.
    epochs : int
        Most training epochs of a member (each chosen by early stopping).
    imputation_basis : (samples * dims, K) float64 ndarray or None
        Directions of the Gaussian over standardised taps that imputes missing values.
    imputation_variances : (K,) float64 ndarray or None
        Variance along each direction.
    imputation_residual : float
        Variance per standardised value outside the directions; NaN (and the arrays None) in a
        model file written before imputation (such a model scores complete taps only).
    choices : dict
        What `fit_torch` chose on its held-out taps, as its keywords take them: ``{"inputs": "values" or
        "directions", "deviations": "pooled", "own class" or None (not augmented)}``; not stored, so empty
        for a model read from a file. Models fitted on parts of the same taps can take them
        (`calibration.fit_with_fixation`).
    location_edges, identities, front_end, samples, dim_names, sensor, location_unit, identity_unit,
    taps_per_class, recommended
        As for `perception.HistogramModel`.
    """

    mean: np.ndarray
    scale: np.ndarray
    hidden_weight: np.ndarray
    hidden_bias: np.ndarray
    output_weight: np.ndarray
    output_bias: np.ndarray
    tempering: float
    epochs: int
    location_edges: np.ndarray
    identities: np.ndarray
    front_end: str
    samples: int
    dim_names: tuple[str, ...]
    sensor: dict
    location_unit: str
    identity_unit: str
    taps_per_class: np.ndarray
    recommended: dict = field(default_factory=dict)
    identity_period: float | None = None   # circular identity (e.g. 360 deg), from the training dataset
    identity_names: tuple[str, ...] = ()   # class names of a named identity, from the training dataset
    tap_tempering: tuple[float, ...] = ()  # g_1..g_K on the t-th tap's log likelihood (`perception.bayes.tap_factor`)
    imputation_basis: np.ndarray | None = None
    imputation_variances: np.ndarray | None = None
    imputation_residual: float = float("nan")
    choices: dict = field(default_factory=dict, compare=False)   # not stored

    KIND = "torch"
    _ARRAYS = ("mean", "scale", "hidden_weight", "hidden_bias", "output_weight", "output_bias", "imputation_basis",
               "imputation_variances")
    _ATTRS = ("tempering", "epochs", "imputation_residual")
    _OPTIONAL = {"imputation_basis": None, "imputation_variances": None, "imputation_residual": float("nan")}

    def __post_init__(self):
        if np.ndim(self.hidden_bias) == 1:   # one network (a file from before the ensemble): an ensemble of one
            for name in ("hidden_weight", "hidden_bias", "output_weight", "output_bias"):
                object.__setattr__(self, name, np.asarray(getattr(self, name))[None])
        values = self.samples * len(self.dim_names)
        members, hidden = self.hidden_bias.shape if self.hidden_bias.ndim == 2 else (-1, -1)
        shapes = {"mean": (values,), "scale": (values,), "hidden_weight": (members, values, hidden),
                  "output_weight": (members, hidden, self.n_classes), "output_bias": (members, self.n_classes)}
        if self.imputation_basis is not None:
            k = self.imputation_basis.shape[-1]
            shapes.update(imputation_basis=(values, k), imputation_variances=(k,))
        for name, shape in shapes.items():
            if getattr(self, name) is None or getattr(self, name).shape != shape:
                raise ModelError(f"{name} must have shape {shape}, got "
                                 f"{None if getattr(self, name) is None else getattr(self, name).shape}")
        if not (np.isfinite(self.tempering) and self.tempering > 0):
            raise ModelError(f"tempering must be a finite number > 0, got {self.tempering!r}")
        self._check_recommended()
        self._check_tap_tempering()

    @property
    def members(self) -> int:
        """Networks M in the ensemble."""
        return self.hidden_bias.shape[0]

    def _kind_summary(self) -> str:
        """One line: front end, class grid, tap shape, members, hidden units, tempering."""
        return (f"{self._grid_summary()}; torch ensemble of {self.members} networks of {self.hidden_bias.shape[1]} "
                f"hidden units, up to {self.epochs} epochs, tempering {self.tempering:.4g}")

    def imputed(self, taps) -> np.ndarray:
        """Standardised flattened taps, (N, samples * dims) float64, each missing value replaced by its
        conditional mean given the tap's observed values.

        Raises
        ------
        ModelError
            A tap misses values and the model has no imputation Gaussian (a file from before it was stored).
        """
        x = (np.asarray(taps, dtype=np.float64).reshape(len(taps), -1) - self.mean) / self.scale
        if not np.isnan(x).any():
            return x
        if self.imputation_basis is None or not np.isfinite(self.imputation_residual):
            raise ModelError("this torch model was trained before missing values could be handled (its file has "
                             "no imputation Gaussian); train it again to score taps with unseen pins")
        gaussian = LowRankGaussian(np.zeros(x.shape[1]), np.asarray(self.imputation_basis, dtype=np.float64),
                                   np.asarray(self.imputation_variances, dtype=np.float64),
                                   float(self.imputation_residual))
        return gaussian.conditional_mean(x)

    def scores(self, taps) -> np.ndarray:
        """Untempered ensemble scores s_c(z), (N, classes) float64, with numpy (missing values imputed): the
        members' log softmax, averaged."""
        x = self.imputed(taps)
        hidden = np.maximum(np.matmul(x, self.hidden_weight) + self.hidden_bias[:, None], 0.0)   # (M, N, H)
        logits = np.matmul(hidden, self.output_weight) + self.output_bias[:, None]
        return log_softmax(logits, axis=2).mean(axis=0)

    def log_likelihood_batch(self, taps) -> np.ndarray:
        """beta x the network's scores of many taps against every class.

        Parameters
        ----------
        taps : (N, samples, dims) array

        Returns
        -------
        (N, n_locations, n_identities) float64 ndarray
        """
        taps = self._check_taps(taps, batch=True)
        out = np.empty((len(taps), self.n_classes))
        for start in range(0, len(taps), _BATCH):
            out[start:start + _BATCH] = self.tempering * self.scores(taps[start:start + _BATCH])
        return out.reshape(len(taps), self.n_locations, self.n_identities)

    def _stored(self) -> tuple[dict, dict]:
        return ({name: getattr(self, name) for name in self._ARRAYS if getattr(self, name) is not None},
                {"tempering": self.tempering, "epochs": self.epochs, "imputation_residual": self.imputation_residual})

    @classmethod
    def _from_stored(cls, common: dict, arrays: dict, attrs: dict):
        try:
            settings = dict(tempering=float(attrs["tempering"]), epochs=int(attrs["epochs"]),
                            imputation_residual=float(attrs["imputation_residual"]))
        except (TypeError, ValueError):
            raise ModelError(f"unreadable torch model settings {dict(attrs)!r}") from None
        return cls(**{k: np.asarray(v) for k, v in arrays.items()}, **common, **settings)


def within_class_residuals(x, tap_class) -> np.ndarray:
    """Deviations of taps from their class mean, (K, values): the taps of classes with two or more taps,
    each scaled by sqrt(n / (n - 1)) so that their spread is the class's unbiased one."""
    tap_class = np.asarray(tap_class, dtype=np.intp)
    counts = np.bincount(tap_class)
    sums = np.zeros((len(counts), x.shape[1]))
    np.add.at(sums, tap_class, x)
    n = counts[tap_class]
    keep = n > 1
    means = sums[tap_class[keep]] / n[keep, None]
    return (x[keep] - means) * np.sqrt(n[keep] / (n[keep] - 1.0))[:, None]


def _fit_imputation(x, train, held, samples: int) -> LowRankGaussian:
    """The Gaussian (mean 0, over standardised taps) that imputes missing values, its rank chosen on held-out taps.

    Candidate ranks (powers of two up to `IMPUTATION_COMPONENTS`) are fitted on the ``train`` rows; in
    each ``held`` row one dim, over all its samples, is hidden and imputed, and the rank with the lowest
    squared error is refitted on every row. Why: a fixed 64 directions fitted on 150 taps of 144 values
    follow the noise, and the imputed values were worse than the mean (`bench/bench_baselines.py`).
    """
    ranks = [k for k in 2 ** np.arange(7) if k <= IMPUTATION_COMPONENTS]
    cap = max(min(len(x) - 1, x.shape[1] - 1), 1)
    rows = np.flatnonzero(held)
    rng = np.random.default_rng(0)
    hidden_dim = rng.integers(x.shape[1] // samples, size=len(rows))
    columns = np.arange(x.shape[1]).reshape(samples, -1)[:, hidden_dim].T          # (rows, samples)
    truth = x[rows[:, None], columns]
    probe = x[rows].copy()
    probe[np.arange(len(rows))[:, None], columns] = np.nan
    scored = ~np.isnan(truth) & ~np.isnan(probe).all(axis=1)[:, None]
    errors = {}
    if scored.any() and train.sum() > 2:
        full = fit_low_rank_gaussian(x[train], min(max(ranks), max(int(train.sum()) - 1, 1)))
        total = float(full.variances.sum() + full.residual_variance * (x.shape[1] - len(full.variances)))
        for k in ranks:
            if k > len(full.variances):
                break
            left = max((total - float(full.variances[:k].sum())) / (x.shape[1] - k), 1e-12)
            g = LowRankGaussian(full.mean, full.basis[:, :k], np.maximum(full.variances[:k], left * (1 + 1e-9)), left)
            guess = g.conditional_mean(probe)[np.arange(len(rows))[:, None], columns]
            errors[k] = float(np.mean((guess - truth)[scored] ** 2))
    k = min(errors, key=errors.get) if errors else IMPUTATION_COMPONENTS
    imputation = fit_low_rank_gaussian(x, min(k, cap))
    return LowRankGaussian(np.zeros(x.shape[1]), imputation.basis, imputation.variances, imputation.residual_variance)


def require_torch() -> None:
    """Raise ImportError, in one line saying how to install it, when torch is not installed.

    Checked without importing torch (a second or more), so a command can refuse early.
    """
    import importlib.util

    if importlib.util.find_spec("torch") is None:
        raise ImportError(f"the torch model needs torch: pip install {TORCH_PIN} (the CPU build; an unpinned "
                          f"torch pulls gigabytes of GPU wheels), or install tactip[learned]")


#: `fit_torch`'s ``inputs`` and ``deviations``, each chosen on held-out taps unless given.
INPUTS = ("values", "directions")
DEVIATIONS = ("pooled", "own class")


def fit_torch(dataset: Dataset, *, n_locations: int = 11, min_taps_per_class: int = 1, members: int = 5,
              hidden: int = 64, max_epochs: int = 100, patience: int = 25, weight_decay: float = 1e-3,
              folds: int = 2, seed: int = 0, augment: bool = True, inputs: str | None = None,
              deviations: str | None = None) -> TorchModel:
    """Train the ensemble likelihood: early stopping and temperature on held-out taps, then all taps.

    Parameters
    ----------
    dataset : Dataset
    n_locations : int
        Equal location classes over the training locations.
    min_taps_per_class : int
    members : int
        Networks in the ensemble (each with its own initialisation and batch order).
    hidden : int
        Hidden ReLU units per network.
    max_epochs : int
        Most epochs tried by early stopping.
    patience : int
        Epochs without a lower held-out loss (of any member) after which early stopping gives up.
    weight_decay : float
        L2 penalty of Adam.
    folds : int
        Cross-validation folds; fold 0 is held out for early stopping and the temperature.
    seed : int
        Seed of the initialisations and batch orders.
    augment : bool
        Train on taps moved by within-class deviations (`within_class_residuals`, drawn afresh at every
        step) rather than on the taps alone; see the module docstring.
    inputs, deviations : str, optional
        The networks' input, ``"values"`` (every value) or ``"directions"`` (the imputation Gaussian's
        leading directions), and the augmentation's deviations, ``"pooled"`` (from every class) or
        ``"own class"``; by default each is chosen by the lower held-out loss (every pair tried, one early
        stopping each). Given, only that one is trained: e.g. the choices (`TorchModel.choices`) of a model
        fitted on every tap, for models fitted on parts of them (`calibration.fit_with_fixation`).

    Returns
    -------
    TorchModel

    Raises
    ------
    ImportError
        torch is not installed (``pip install torch==2.13.0``).
    DatasetError
        No class has training taps in two folds, or the held-out taps are told apart no better than chance.
    ValueError
        ``members``, ``hidden``, ``max_epochs`` or ``patience`` is below 1; ``inputs`` or ``deviations``
        is not one of `INPUTS` or `DEVIATIONS`.
    """
    for name, value in (("members", members), ("hidden", hidden), ("max_epochs", max_epochs), ("patience", patience)):
        if int(value) != value or value < 1:
            raise ValueError(f"{name} must be an integer >= 1, got {value!r}")
    for name, value, allowed in (("inputs", inputs, INPUTS), ("deviations", deviations, DEVIATIONS)):
        if value is not None and value not in allowed:
            raise ValueError(f"{name} must be one of {', '.join(map(repr, allowed))} or None, got {value!r}")
    require_torch()
    import torch

    from ._ensemble_training import _tempered_losses, all_cores, train_ensemble

    grid = fit_class_grid(dataset, n_locations=n_locations, min_taps_per_class=min_taps_per_class)
    x = dataset.taps.reshape(len(dataset), -1).astype(np.float64)
    never = np.isnan(x).all(axis=0)            # values left out of the model: their input weights are zeroed
    x[:, never] = 0.0
    mean = np.nanmean(x, axis=0)   # over the observed values
    # One scale for every value (their spread about their means, pooled), not one per value: a value
    # that only carries noise (a pin far from the contact) stays small instead of being raised to
    # the level of the informative ones.
    spread = float(np.sqrt(np.nanmean((x - mean) ** 2)))
    scale = np.full(x.shape[1], spread if spread > 0 else 1.0)
    x = (x - mean) / scale
    cls = grid.tap_class(dataset)
    fold = cross_validation_folds(cls, folds, order=dataset.location)
    train, held = fold != 0, fold == 0
    imputation = _fit_imputation(x, train, held, grid.samples)
    x = imputation.conditional_mean(x)   # training taps missing values: filled as the model fills test taps
    seen = np.bincount(cls[train], minlength=grid.n_classes) > 0
    held &= seen[cls]
    if not held.any():
        raise DatasetError("no class has training taps in two folds: collect at least two taps per class")
    knobs = dict(members=int(members), hidden=int(hidden), weight_decay=weight_decay, seed=seed)

    def augmentation(xi, rows, own_class):
        """Augmentation: a tap moved by another's deviation from its class mean (of the taps trained on),
        drawn from every class (pooled) or from the tap's own class only."""
        if not augment:
            return dict(residuals=None)
        rows = np.arange(len(xi))[rows]
        kept = np.bincount(cls[rows])[cls[rows]] > 1   # the taps within_class_residuals keeps
        return dict(residuals=within_class_residuals(xi[rows], cls[rows]),
                    residual_class=cls[rows][kept] if own_class else None)

    def early_stopping(projection, own_class):
        """(held-out loss at the best temperature, epochs, held-out scores) of one choice of input and deviations."""
        xi = x if projection is None else x @ projection
        _, epochs, held_scores = train_ensemble(torch, xi[train], cls[train], grid.n_classes, epochs=max_epochs,
                                                held=(xi[held], cls[held]), patience=patience,
                                                **augmentation(xi, train, own_class), **knobs)
        loss = _tempered_losses(torch, torch.as_tensor(held_scores.mean(axis=0)[None]), torch.as_tensor(cls[held]))
        return float(loss[0]), projection, own_class, epochs, held_scores

    with all_cores(torch, work=members * x.shape[1] * hidden):
        # The input: every value, or the imputation Gaussian's leading directions (the taps' structure, fitted
        # without labels). Where the classes lie along few directions among many noisy values (depths along one
        # code), the networks trained on every value followed the noise (1-tap error 2.9-5.5x ridge's) and on
        # the directions matched the Gaussian; where they differ in many ways (shapes) every value is better.
        # The augmentation: pooled deviations assume every class spreads alike (they made the small station's
        # beliefs honest); where classes spread differently (xor) they blur them, and only own-class
        # deviations keep the classes apart. The held-out loss chooses both, the input first.
        # (The directions tried are fitted on the taps trained on only: fitted on the held-out taps too, they
        # would hold part of those taps' noise and flatter their loss.)
        # The given choice, else every one that applies (the directions only where they are few).
        few = imputation.basis.shape[1] <= x.shape[1] // 2
        projections = [None if name == "values" else fit_low_rank_gaussian(x[train], imputation.basis.shape[1]).basis
                       for name in ([inputs] if inputs else INPUTS[:1 + few])]
        own_classes = [name == "own class" for name in ([deviations] if deviations else DEVIATIONS)] if augment \
            else [False]
        tried = [early_stopping(projection, own_class) for projection in projections for own_class in own_classes]
        _, projection, own_class, epochs, held_scores = min(tried, key=lambda t: t[0])
        if projection is not None:
            projection = imputation.basis
        truth = grid.identity_class(dataset.identity[held]) if grid.n_identities > 1 \
            else grid.location_class(dataset.location[held])
        # The ensemble's held-out scores, each member at its best epoch: beta calibrates what the station uses.
        beta = fit_tempering(held_scores.mean(axis=0).reshape(-1, grid.n_locations, grid.n_identities), truth)
        check_tempering(beta)
        xi = x if projection is None else x @ projection
        (w1, b1, w2, b2), _, _ = train_ensemble(torch, xi, cls, grid.n_classes, epochs=epochs,
                                               **augmentation(xi, slice(None), own_class), **knobs)
    if projection is not None:   # a first layer on the directions is one on every value: W1 = Q W1'
        w1 = np.einsum("dk,mkh->mdh", projection, w1).astype(np.float32)
    w1[:, never] = 0.0   # a value never observed in training has no say, whatever a tap holds there
    return TorchModel(mean, scale, w1, b1, w2, b2, float(beta), int(epochs.max()), grid.location_edges,
                      grid.identities, grid.front_end, grid.samples, grid.dim_names, grid.sensor, grid.location_unit,
                      grid.identity_unit, grid.taps_per_class, imputation_basis=imputation.basis,
                      imputation_variances=imputation.variances, imputation_residual=imputation.residual_variance,
                      identity_period=grid.identity_period, identity_names=grid.identity_names,
                      choices={"inputs": INPUTS[projection is not None],
                               "deviations": DEVIATIONS[own_class] if augment else None})
