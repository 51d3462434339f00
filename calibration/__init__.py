"""Calibration: sensor calibration, data collection protocol, training and fixation search.

Knows the protocols but no hardware: the station (``tactip``) hands it frames and a tap function.
"""

from .collect import SETS, PlannedTap, collect_datasets, collection_plan, tap_seed
from .errors import CalibrationError
from .sensor import (SCHEMA, SensorCalibration, calibrate_sensor, check_model_fits, load_calibration,
                     place_reference_pins, save_calibration)
from .training import (HOLDOUT_FOLDS, FinalFigures, carve_validation, cross_fitted_environment, holdout_folds, choose_fixation, final_figures, fit_with_fixation,
                       prepare_station_model,
                       recommend_fixation, train_station_model)

__all__ = [
    "CalibrationError",
    "SensorCalibration", "calibrate_sensor", "save_calibration", "load_calibration", "SCHEMA",
    "place_reference_pins", "check_model_fits",
    "PlannedTap", "collection_plan", "collect_datasets", "tap_seed", "SETS",
    "train_station_model", "recommend_fixation", "choose_fixation", "carve_validation", "prepare_station_model",
    "fit_with_fixation", "final_figures", "FinalFigures", "holdout_folds", "cross_fitted_environment", "HOLDOUT_FOLDS",
]
