"""pins._tipfit.fit_tip_centres: a tip started beyond one fit's reach (a blob's centroid pulled up a reflection's
flank, 1-1.8 px off on radial-led-120) is fitted again where its fit ended, and placed where it is."""

import numpy as np

from pins._tipfit import _REACH_PX, _REFIT_ROUNDS, fit_tip_centres
from tests.pins.test_tipfit import _grid, _scene


def test_a_tip_started_beyond_the_reach_is_fitted_again_where_its_fit_ended():
    """Small tips (radius 2.1 px) on a flat membrane and under reflections, noise-free, every start 1.1-1.6 px off
    in a random direction (beyond `_REACH_PX`, within the rounds' reach): RMSE under 0.08 px and every tip within
    0.2 px of the truth (its ellipse, the median of its neighbours' fitted in windows as far off, a little off too).
    One fit alone stops within `_REACH_PX` of its start, 0.3 px or more off."""
    rng = np.random.default_rng(7)
    truth = _grid(rng, pitch=14.0)
    shape = np.broadcast_to(np.diag([2.1 ** 2, 2.1 ** 2]), (len(truth), 2, 2)).copy()
    angle = rng.uniform(0, 2 * np.pi, len(truth))
    off = rng.uniform(1.1, 1.6, len(truth))
    assert off.max() < (1 + _REFIT_ROUNDS) * _REACH_PX and off.min() > _REACH_PX + 0.3
    start = truth + off[:, None] * np.column_stack([np.cos(angle), np.sin(angle)])
    for glare in (0.0, 70.0):
        fitted = fit_tip_centres(_scene(truth, shape, glare=glare), start, 2.1)
        error = np.hypot(*(fitted - truth).T)
        assert np.sqrt(np.mean(error ** 2)) < 0.08 and error.max() < 0.2, (glare, error.max())


def test_a_tip_fitted_where_it_started_is_not_fitted_again(monkeypatch):
    """Starts within a few hundredths of the truth: one fit places them, and no tip is fitted a second time."""
    import pins._tipfit as tipfit

    rng = np.random.default_rng(8)
    truth = _grid(rng, pitch=14.0)
    shape = np.broadcast_to(np.diag([2.1 ** 2, 2.1 ** 2]), (len(truth), 2, 2)).copy()
    image = _scene(truth, shape, glare=70.0)
    calls = []
    original = tipfit._windows
    monkeypatch.setattr(tipfit, "_windows", lambda *a: calls.append(len(a[3])) or original(*a))
    fitted = fit_tip_centres(image, truth + rng.uniform(-0.03, 0.03, truth.shape), 2.1)
    assert calls == [len(truth)]  # the first fit's windows only
    assert np.hypot(*(fitted - truth).T).max() < 0.05
