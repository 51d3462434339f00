"""Perception: likelihood model, sequential Bayes, policies and Monte Carlo validation.

The dataset (`Dataset`, `DatasetWriter`, schema ``tactip-dataset/1``) is the contract with the
front ends; `fit_model` trains the papers' histogram likelihood and `train_model` any kind of
likelihood model (`LikelihoodModel`: histogram, calibrated histogram, Gaussian, torch); `Perceiver` classifies tap by tap;
`monte_carlo` and the experiments validate a model on an independent test set, and `compare_baselines`
holds it against simple scikit-learn learners on the same taps.
"""

import importlib

# Public name -> the module of this package that defines it, imported when the name is first used (PEP 562):
# ``import perception.choices`` (the command line's --help, the station configuration) then loads no NumPy,
# SciPy or h5py.
_LAZY = {
    "ShiftLearner": ".adaptive",
    **dict.fromkeys(("BaselineReport", "BaselineResult", "compare_baselines", "keep_verdict"), ".baselines"),
    **dict.fromkeys(("DECISION_RULES", "adaptive_prior", "decide", "flat_prior", "marginals", "normalize", "shift",
                     "shift_identity", "update", "tap_update", "tap_factor", "check_tap_tempering"), ".bayes"),
    **dict.fromkeys(("SCHEMA", "Dataset", "DatasetWriter", "load_dataset", "save_dataset"), ".dataset"),
    **dict.fromkeys(("DatasetError", "ModelError", "PerceptionError"), ".errors"),
    **dict.fromkeys(("FixationSweep", "LateralSweep", "compare_policies", "fixation_sweep", "lateral_sweep"),
                    ".experiments"),
    **dict.fromkeys(("CalibratedHistogramModel", "fit_calibrated_histogram"), ".calibrated"),
    **dict.fromkeys(("GaussianModel", "fit_gaussian"), ".gaussian"),
    "LikelihoodModel": ".likelihood",
    **dict.fromkeys(("HistogramModel", "fit_model"), ".histogram"),
    **dict.fromkeys(("MODEL_KINDS", "MODEL_SCHEMA", "load_model", "save_model", "train_model"), ".model"),
    **dict.fromkeys(("DEFAULT_THRESHOLDS", "MonteCarloResult", "VirtualEnvironment", "monte_carlo"), ".montecarlo"),
    **dict.fromkeys(("Perceiver", "Step"), ".perceiver"),
    **dict.fromkeys(("POLICIES", "FixationPolicy", "Policy", "RandomPolicy", "StationaryPolicy", "make_policy"),
                    ".policies"),
    **dict.fromkeys(("reliability_bins", "expected_calibration_error", "calibration_error_floor", "one_tap_beliefs"),
                    ".calibration_error"),
    **dict.fromkeys(("CALIBRATION_TAPS", "BeliefTrace", "fit_tap_tempering",
                     "fixation_for_accuracy", "threshold_for_accuracy", "trace_beliefs"),
                    ".reliability"),
}

__all__ = [
    "PerceptionError", "DatasetError", "ModelError",
    "SCHEMA", "Dataset", "DatasetWriter", "load_dataset", "save_dataset",
    "MODEL_SCHEMA", "MODEL_KINDS", "LikelihoodModel", "HistogramModel", "fit_model", "load_model", "save_model",
    "train_model", "CalibratedHistogramModel", "fit_calibrated_histogram", "GaussianModel", "fit_gaussian",
    "normalize", "update", "tap_update", "tap_factor", "check_tap_tempering", "shift", "shift_identity", "marginals",
    "decide", "DECISION_RULES", "flat_prior",
    "adaptive_prior", "ShiftLearner",
    "Perceiver", "Step",
    "POLICIES", "Policy", "FixationPolicy", "StationaryPolicy", "RandomPolicy", "make_policy",
    "DEFAULT_THRESHOLDS", "VirtualEnvironment", "MonteCarloResult", "monte_carlo",
    "compare_policies", "FixationSweep", "fixation_sweep", "LateralSweep", "lateral_sweep",
    "CALIBRATION_TAPS", "BeliefTrace", "trace_beliefs", "expected_calibration_error", "reliability_bins",
    "calibration_error_floor", "one_tap_beliefs",
    "threshold_for_accuracy", "fixation_for_accuracy", "fit_tap_tempering",
    "BaselineResult", "BaselineReport", "compare_baselines", "keep_verdict",
]


def __getattr__(name: str):
    """The public name ``name``, its module imported on first use."""
    if name not in _LAZY:
        raise AttributeError(f"module 'perception' has no attribute {name!r}")
    value = getattr(importlib.import_module(_LAZY[name], __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    """The module's names, the public ones not yet imported included."""
    return sorted({*globals(), *__all__})
