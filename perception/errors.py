"""Errors raised by the perception package."""

__all__ = ["PerceptionError", "DatasetError", "ModelError"]


class PerceptionError(Exception):
    """Base of every error the perception package raises on bad input or state."""


class DatasetError(PerceptionError, ValueError):
    """A dataset file or array breaks the `tactip-dataset/1` contract."""


class ModelError(PerceptionError, ValueError):
    """A model file is unreadable or does not fit the data it is given."""
