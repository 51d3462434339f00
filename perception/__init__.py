"""Perception: likelihood model, sequential Bayes, policies and Monte Carlo validation."""

from .errors import DatasetError, ModelError, PerceptionError

__all__ = ["PerceptionError", "DatasetError", "ModelError"]
