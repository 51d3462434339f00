"""The opaque-tip test (`pins._tipprobe`) and the probe of lattice holes that uses it (`pins._rescue`).

Ground truth from the renders: the synthetic TacTip knows every pin; noise-free renders give each
pin's ideal matched-filter SNR.
"""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from pins._noise import noise_sigma
from pins._rescue import probe_lattice_holes
from pins._tipprobe import threshold, tip_evidence
from tactip.sim import SyntheticTacTip
from tests.pins.conftest import preset_frame, preset_sensor


def _membrane(size=400, sigma=5.0, seed=0):
    """A curved membrane (a veil's slope and curvature, 100-200 grey) with Gaussian noise, float32."""
    rng = np.random.default_rng(seed)
    yy, xx = np.mgrid[0:size, 0:size] / size
    clean = 100.0 + 60.0 * xx + 30.0 * yy ** 2 + 10.0 * xx * yy
    return clean, (clean + rng.normal(0.0, sigma, clean.shape)).astype(np.float32)


def test_bare_membrane_passes_the_bar_at_the_false_alarm_rate():
    """On a quadratic membrane with noise sigma 5, the evidence at a fixed point is chi-square with 2
    degrees of freedom: the share above the bar for a rate of 1 % is 1 % (2500 points, 25 +- 10 expected)."""
    _, image = _membrane()
    grid = np.array([(x, y) for y in range(20, 380, 7) for x in range(20, 380, 7)], float)[:2500]
    evidence, _, _ = tip_evidence(image, grid, np.repeat(4.0 * np.eye(2)[None], len(grid), 0), np.zeros((0, 2)), 5.0)
    assert 10 <= int(np.sum(evidence >= threshold(0.01, 1.0))) <= 45
    assert float(threshold(1e-3, 1.0)) == pytest.approx(-2.0 * np.log(1e-3))  # chi-square 2: exp(-t / 2)


def test_an_opaque_tip_at_the_membrane_level_is_found_by_the_slope_it_hides():
    """A domed tip whose mean level equals the membrane's round it (its core mean stands ~0 above a fit) on
    a slope of 8 grey per px is strong evidence, and its contrast is near 0; the same without the tip is not."""
    yy, xx = np.mgrid[0:100, 0:100].astype(float)
    clean = 100.0 + 8.0 * (xx - 50.0)
    centre = np.array([50.3, 49.8])
    q = ((xx - centre[0]) / 2.8) ** 2 + ((yy - centre[1]) / 1.8) ** 2
    coverage = np.clip(0.5 + (1.0 - np.sqrt(q)) * 2.2, 0.0, 1.0)
    level = 100.0 + 8.0 * (centre[0] - 50.0) + 6.0 * (1.0 - 2.0 * np.minimum(q, 1.0))  # dome, mean ~ membrane
    with_tip = (1.0 - coverage) * clean + coverage * level
    rng = np.random.default_rng(3)
    shape = np.diag([2.8 ** 2, 1.8 ** 2])[None]
    found = [tip_evidence((with_tip + rng.normal(0, 5.0, clean.shape)).astype(np.float32), centre[None], shape,
                          np.zeros((0, 2)), 5.0) for _ in range(20)]
    bare = [tip_evidence((clean + rng.normal(0, 5.0, clean.shape)).astype(np.float32), centre[None], shape,
                         np.zeros((0, 2)), 5.0)[0][0] for _ in range(20)]
    bar = threshold(1e-3, 4.0)
    assert min(f[0][0] for f in found) > bar and max(bare) < bar
    # The tip's core is on average no brighter than the membrane there (a core-above-ring test misses it); its
    # fitted contrast is its centre's, +6 grey on the dome.
    assert abs(float(np.mean((with_tip - clean)[coverage > 0.5]))) < 1.5
    assert np.median([f[2][0] for f in found]) == pytest.approx(6.0, abs=3.0)


@pytest.mark.parametrize("seed", [0, 5])
def test_noise_free_evidence_is_the_ideal_snr_squared(seed):
    """On a noise-free radial-led-120 render, the evidence (sigma 5) of each outermost-ring tip under the veil at its
    true centre and shape is at least 0.8 of its ideal matched-filter SNR^2 (the tip's signal, the render less the
    render without it, projected off a quadratic membrane over the same disc, over sigma 5): the model is what the
    renderer draws (without the tip's dome, 0.45 of it)."""
    sensor = SyntheticTacTip.from_preset("radial-led-120", seed=seed, noise_sigma=0.0)
    sensor.reseed_noise(seed)
    frame = sensor.render()
    _, shapes = sensor.pin_ellipses()
    drawn = frame.visible | frame.partial
    outer = np.flatnonzero(frame.visible & (np.hypot(*(frame.centres - sensor.disc[:2]).T) > 0.85 * sensor.disc[2]))
    image = frame.image.astype(np.float32)
    for i in outer[:6]:
        others = frame.centres[drawn & (np.arange(len(drawn)) != i)]
        evidence = tip_evidence(image, frame.centres[i][None], shapes[i][None], others, 5.0)[0][0]
        hidden = np.zeros(sensor.n_pins, bool)
        hidden[i] = True
        sensor.reseed_noise(seed)
        signal = image - sensor.render(hidden=hidden).image.astype(np.float32)
        x0, y0 = np.rint(frame.centres[i]).astype(int)
        reach = 1.5 * np.sqrt(np.linalg.eigvalsh(shapes[i])[1]) + 2.0
        h = int(np.ceil(reach))
        yy, xx = np.mgrid[-h:h + 1, -h:h + 1]
        inside = np.hypot(xx, yy) <= reach
        s = signal[y0 - h:y0 + h + 1, x0 - h:x0 + h + 1][inside]
        u, v = xx[inside] / reach, yy[inside] / reach
        basis = np.stack([np.ones_like(u), u, v, u * u, u * v, v * v], axis=1)
        off = s - basis @ np.linalg.lstsq(basis, s, rcond=None)[0]
        assert evidence >= 0.8 * np.sum(off ** 2) / 25.0, i


def test_probing_finds_the_radial_layouts_missing_centre_pin_inner_ring_and_spoke_pins():
    """radial-led-120 with the true centres of the pins drawn whole, less the centre pin, a pin of the innermost ring
    and the two outermost pins of one spoke: the probe finds those four back (within 0.5 px) and nothing else."""
    sensor = preset_sensor("radial-led-120", 3)
    frame = preset_frame("radial-led-120", None, seed=3)
    truth = frame.centres[frame.visible]
    centre = np.array(sensor.disc[:2])
    radius = np.hypot(*(truth - centre).T)
    hub = int(np.argmin(radius))
    ring = int(np.argmin(np.where(radius > 5.0, radius, np.inf)))
    outer = int(np.argmax(radius))
    spoke = truth[outer] - centre
    along = (truth - centre) @ spoke / np.linalg.norm(spoke)
    unit = spoke / np.linalg.norm(spoke)
    across = np.abs((truth - centre) @ np.array([-unit[1], unit[0]]))
    on_spoke = np.flatnonzero(across < 2.0)
    second = on_spoke[np.argsort(-along[on_spoke])[1]]
    removed = [hub, ring, outer, second]
    kept = np.delete(truth, removed, axis=0)
    found = probe_lattice_holes(frame.image, kept, tuple(centre), sensor.pin_radius_px, disc_radius_px=sensor.disc[2])
    distance, index = cKDTree(truth[removed]).query(found)
    assert len(found) == 4 and sorted(index.tolist()) == [0, 1, 2, 3] and np.all(distance < 0.5), (found, truth[removed])


def test_noise_sigma_of_the_radial_preset_is_its_renderers():
    """The probe's bar rests on the camera noise `noise_sigma` measures: radial-led-120's 5 within 10 %."""
    assert noise_sigma(preset_frame("radial-led-120", None, seed=0).image) == pytest.approx(5.0, rel=0.1)
