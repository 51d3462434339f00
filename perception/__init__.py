"""Perception: likelihood model, sequential Bayes, policies and Monte Carlo validation."""

from .dataset import SCHEMA, Dataset, DatasetWriter, load_dataset, save_dataset
from .errors import DatasetError, ModelError, PerceptionError

__all__ = [
    "PerceptionError", "DatasetError", "ModelError",
    "SCHEMA", "Dataset", "DatasetWriter", "load_dataset", "save_dataset",
]
