"""The pin field's outermost ring is placed without a radial bias (issue 20's return bar, outcome 7).

Just outside a pad's outer ring lies its brightest light: the surround, its veil and the glare gradient
(``radial-led-120``, ``radial-120``), or a dark casing (``white-dark-331``). A centre measured by an
intensity-weighted centroid, or by a fit without a membrane slope, leans towards the bright side: out of
the pad where the surround is bright. `find_pin_field` fits each tip as an opaque ellipse over a curved
membrane (`pins._tipfit`); against the renderer's ground truth its outer ring's mean radial error is
+0.002 to +0.019 px on seeds 0-35 (rest and a 5 mm tap; 48-59 held out: +0.003 to +0.019), near its
inner rings' (+-0.01). The blobs' centroids alone lean outward on ``radial-led-120`` (seeds 0-2: mean
+0.11 px, median +0.08; the fit: +0.04, +0.015), checked below so that the bar can fail.

The few outer tips placed 0.5-1.9 px off (7 of 612 outer-ring pin-frames at rest, seeds 0-35, 6 of them
outward) are faint tips under the veil that the lattice-hole probe (`pins._rescue.probe_lattice_holes`)
started 1-1.6 px out: on their noisy renders the fit has a second minimum there whose squared residual is
within 3 noise variances of the one by the truth, lower on seed 17 (on noise-free renders of those seeds
the fit ends within 0.02 px of the truth): noise on a faint tip, not a bias of the model. They weigh on the mean (seed 1: +0.04 of the +0.04), not on the median.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linear_sum_assignment

from pins import find_pin_field
from pins import lattice
from tactip.sim import SyntheticTacTip

SEEDS = (0, 1, 2)
OUTER = 0.93  # the outer ring: true radius beyond this fraction of the outermost visible pin's


def _outer_radial_errors(preset: str) -> tuple[np.ndarray, np.ndarray]:
    """Radial errors (outward positive) and error lengths, px, of the outer ring's pins over `SEEDS`."""
    radial, length = [], []
    for seed in SEEDS:
        sensor = SyntheticTacTip.from_preset(preset, seed=seed)
        frame = sensor.render()
        field = find_pin_field(frame.image, dark_pins=None if preset == "white-dark-331" else sensor.dark_pins)
        truth = frame.centres[frame.visible]
        distance = np.hypot(*(truth[:, None, :] - field.centres[None, :, :]).transpose(2, 0, 1))
        rows, cols = linear_sum_assignment(np.where(distance <= 3.0, distance, 1e6))
        kept = distance[rows, cols] <= 3.0
        rows, cols = rows[kept], cols[kept]
        offset = truth - np.asarray(sensor.disc[:2])
        radius = np.hypot(*offset.T)
        outer = radius[rows] > OUTER * radius.max()
        rows, cols = rows[outer], cols[outer]
        error = field.centres[cols] - truth[rows]
        radial.append(np.sum(error * offset[rows], axis=1) / radius[rows])
        length.append(np.hypot(*error.T))
    return np.concatenate(radial), np.concatenate(length)


@pytest.mark.parametrize("preset", ["radial-led-120", "radial-120", "white-dark-331", "small-pad-100"])
def test_the_outer_ring_has_no_radial_bias(preset):
    radial, length = _outer_radial_errors(preset)
    assert len(radial) >= 3 * 15
    assert abs(radial.mean()) <= 0.1  # the bar
    assert abs(np.median(radial)) <= 0.03
    assert np.median(length) <= (0.15 if preset == "radial-led-120" else 0.06)


def test_centroids_alone_lean_out_of_a_bright_surround(monkeypatch):
    """Without the tip fit (the blobs' centroids) the outer ring of ``radial-led-120`` leans outward, beyond
    both bars above: they can fail."""
    monkeypatch.setattr(lattice, "fit_tip_centres", lambda grey, centres, radius_px, dark_pins=False: centres)
    radial, _ = _outer_radial_errors("radial-led-120")
    assert radial.mean() > 0.08 and np.median(radial) > 0.05
