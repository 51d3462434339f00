"""The tip probe's evidence threshold (`pins._tipprobe.threshold`) without scipy.stats: the chi-square's inverse
survival function from scipy.special gives scipy.stats.chi2.isf's values bit for bit, and the pin-field search no
longer imports scipy.stats (~0.25 s of CPU on the main thread of every `tactip replay`)."""

import subprocess
import sys

import numpy as np
from scipy.stats import chi2

from pins._tipprobe import _EXTRA, threshold


def test_threshold_is_chi2_isf_bit_for_bit():
    """Over false-alarm rates 1e-12 to 0.5 and 1 to 1e6 cells (fewer than one counted as one), scalars and
    arrays alike."""
    rng = np.random.default_rng(0)
    false_alarm = 10.0 ** rng.uniform(-12.0, np.log10(0.5), 500)
    cells = np.concatenate([[0.0, 0.5, 1.0], 10.0 ** rng.uniform(0.0, 6.0, 497)])
    expected = chi2.isf(false_alarm / np.maximum(cells, 1.0), _EXTRA)
    assert np.array_equal(threshold(false_alarm, cells), expected)
    for rate in (1e-3, 1e-6, 0.05):
        assert threshold(rate, 1.0) == chi2.isf(rate, _EXTRA)
        assert np.array_equal(threshold(rate, cells), chi2.isf(rate / np.maximum(cells, 1.0), _EXTRA))


def test_a_field_search_does_not_import_scipy_stats():
    """A fresh process finds a pin field whose holes the tip probe looks at (radial-led-120, seed 1: its
    threshold is computed) without scipy.stats in its modules."""
    code = ("import sys\n"
            "import pins._tipprobe as probe\n"
            "import pins\n"
            "from tactip.sim import SyntheticTacTip\n"
            "calls = []\n"
            "real = probe.threshold\n"
            "probe.threshold = lambda *a: calls.append(1) or real(*a)\n"
            "import pins._rescue as rescue\n"
            "rescue.threshold = probe.threshold\n"
            "pins.find_pin_field(SyntheticTacTip.from_preset('radial-led-120', seed=1).render().image)\n"
            "print(len(calls), 'scipy.stats' in sys.modules)\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    assert int(out[0]) >= 1 and out[1] == "False", out
