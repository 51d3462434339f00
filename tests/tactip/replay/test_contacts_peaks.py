"""tactip.replay.contacts.local_maxima finds the peaks scipy.signal.find_peaks finds (split_at_dips' peaks
without importing scipy.signal): plateaus, edges and NaN included."""

import numpy as np
import pytest
from scipy.signal import find_peaks

from tactip.replay.contacts import local_maxima


@pytest.mark.parametrize("seed", range(20))
def test_same_peaks_as_find_peaks(seed):
    rng = np.random.default_rng(seed)
    for length in (0, 1, 2, 3, 4, 7, 50, 400):
        values = rng.integers(0, 4 + seed % 5, length).astype(float)    # few levels: many plateaus
        if seed % 3 == 0 and length:
            values[rng.random(length) < 0.1] = np.nan
        np.testing.assert_array_equal(local_maxima(values), find_peaks(values)[0])


def test_smooth_signal_and_plateau_middle():
    t = np.linspace(0, 6 * np.pi, 300)
    values = np.round(np.sin(t) * 20)                                   # rounded: plateaus at each top
    np.testing.assert_array_equal(local_maxima(values), find_peaks(values)[0])
    assert local_maxima(np.array([0.0, 1, 1, 1, 1, 0])).tolist() == [2]
