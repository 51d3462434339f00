"""Shared helpers for the pins tests: renders from the synthetic TacTip and ground-truth matching."""

import functools

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist

from tactip.synthetic import Contact, SyntheticTacTip

TAP = Contact(indentation_mm=5.0, gap_width_mm=2.0)


@functools.lru_cache(maxsize=None)
def sensor(pins: int = 331, *, dark_pins: bool = False, seed: int = 0) -> SyntheticTacTip:
    """A synthetic TacTip with gradient, glare and noise sigma 4 (the bars' conditions)."""
    return SyntheticTacTip(pins=pins, noise_sigma=4.0, glare=True, gradient=True, dark_pins=dark_pins, seed=seed)


@functools.lru_cache(maxsize=None)
def frame(pins: int = 331, contact: Contact | None = None, *, dark_pins: bool = False, seed: int = 0):
    """One rendered frame (cached: tests must not modify it)."""
    return sensor(pins, dark_pins=dark_pins, seed=seed).render(contact)


def match(detected: np.ndarray, truth: np.ndarray, gate_px: float = 3.0):
    """Recall, precision and centroid RMSE (px) of detections against true centres.

    One-to-one by the Hungarian method, pairs farther than `gate_px` do not count.
    """
    if len(detected) == 0:
        return 0.0, 0.0, np.inf
    distance = cdist(truth, detected)
    cost = np.where(distance <= gate_px, distance, 1e6)
    rows, cols = linear_sum_assignment(cost)
    ok = cost[rows, cols] <= gate_px
    errors = detected[cols[ok]] - truth[rows[ok]]
    rmse = float(np.sqrt(np.mean(np.sum(errors**2, axis=1)))) if ok.any() else np.inf
    return ok.sum() / len(truth), ok.sum() / len(detected), rmse


@pytest.fixture
def rng():
    return np.random.default_rng(12345)
