"""Perception: likelihood model, sequential Bayes, policies and Monte Carlo validation.

The dataset (`Dataset`, `DatasetWriter`, schema ``tactip-dataset/1``) is the contract with the
front ends; `fit_model` trains the papers' histogram likelihood and `train_model` any kind of
likelihood model (`LikelihoodModel`: histogram, calibrated histogram, Gaussian, torch); `Perceiver` classifies tap by tap;
`monte_carlo` and the experiments validate a model on an independent test set.
"""

from .adaptive import ShiftLearner
from .bayes import DECISION_RULES, adaptive_prior, decide, flat_prior, marginals, normalize, shift, shift_identity, update
from .dataset import SCHEMA, Dataset, DatasetWriter, load_dataset, save_dataset
from .errors import DatasetError, ModelError, PerceptionError
from .experiments import FixationSweep, LateralSweep, compare_policies, fixation_sweep, lateral_sweep
from .calibrated import CalibratedHistogramModel, fit_calibrated_histogram
from .gaussian import GaussianModel, fit_gaussian
from .likelihood import LikelihoodModel
from .histogram import HistogramModel, fit_model
from .model import MODEL_KINDS, MODEL_SCHEMA, load_model, save_model, train_model
from .montecarlo import DEFAULT_THRESHOLDS, MonteCarloResult, VirtualEnvironment, monte_carlo
from .perceiver import Perceiver, Step
from .policies import POLICIES, FixationPolicy, Policy, RandomPolicy, StationaryPolicy, make_policy
from .reliability import (CALIBRATION_TAPS, BeliefTrace, expected_calibration_error, fit_policy_tempering,
                          fixation_for_accuracy, reliability_bins, threshold_for_accuracy, trace_beliefs)

__all__ = [
    "PerceptionError", "DatasetError", "ModelError",
    "SCHEMA", "Dataset", "DatasetWriter", "load_dataset", "save_dataset",
    "MODEL_SCHEMA", "MODEL_KINDS", "LikelihoodModel", "HistogramModel", "fit_model", "load_model", "save_model",
    "train_model", "CalibratedHistogramModel", "fit_calibrated_histogram", "GaussianModel", "fit_gaussian",
    "normalize", "update", "shift", "shift_identity", "marginals", "decide", "DECISION_RULES", "flat_prior",
    "adaptive_prior", "ShiftLearner",
    "Perceiver", "Step",
    "POLICIES", "Policy", "FixationPolicy", "StationaryPolicy", "RandomPolicy", "make_policy",
    "DEFAULT_THRESHOLDS", "VirtualEnvironment", "MonteCarloResult", "monte_carlo",
    "compare_policies", "FixationSweep", "fixation_sweep", "LateralSweep", "lateral_sweep",
    "CALIBRATION_TAPS", "BeliefTrace", "trace_beliefs", "expected_calibration_error", "reliability_bins",
    "threshold_for_accuracy", "fixation_for_accuracy", "fit_policy_tempering",
]
