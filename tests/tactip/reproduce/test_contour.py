"""Contour following (paper 004): what the runs report about why a contour stays open, and the diagnostics."""

import numpy as np
import pytest

from tactip.reproduce.contour import follow_contour

OPTIONS = dict(runs=16, decisions=20, max_taps=15, seed=3)


@pytest.fixture(scope="module")
def edge_env():
    from tactip.reproduce.report import environment
    from tactip.reproduce.stimuli import make_stimulus

    return environment(make_stimulus("edge"), seed=0, taps_per_identity=90, n_locations=18)


def test_a_closed_contour_lost_neither_the_edge_nor_the_trace(edge_env):
    for method in (dict(active=False), dict(active=True, adaptive=True)):
        r = follow_contour(edge_env, threshold=0.5, **OPTIONS, **method)
        assert 0.0 <= r.closed_contour <= 1.0 - max(r.edge_lost, r.trace_lost) + 1e-12
        assert 0.0 <= r.trace_error_mm
    default = follow_contour(edge_env, threshold=0.5, active=True, adaptive=True, **OPTIONS)
    explicit = follow_contour(edge_env, threshold=0.5, active=True, adaptive=True, step="tangent", **OPTIONS)
    for field in default.__dataclass_fields__:
        assert np.array_equal(getattr(default, field), getattr(explicit, field), equal_nan=True), field


def test_the_arc_step_keeps_the_sensor_on_the_edge(edge_env):
    """Passive runs never move along the normal: with the arc step the sensor stays where it started (|x| <= 2 mm)."""
    arc = follow_contour(edge_env, threshold=0.2, active=False, step="arc", **OPTIONS)
    assert arc.edge_lost == 0.0
    # the straight step along a wrongly perceived tangent walks off the edge in the same runs
    tangent = follow_contour(edge_env, threshold=0.2, active=False, **OPTIONS)
    assert tangent.edge_lost > 0.5


def test_learning_delta_alongside_active_runs_leaves_them_unchanged(edge_env):
    plain = follow_contour(edge_env, threshold=0.5, active=True, **OPTIONS)
    learning = follow_contour(edge_env, threshold=0.5, active=True, learn_delta=True, **OPTIONS)
    for field in ("angle_error_deg", "position_error_mm", "taps_per_decision", "closed_contour", "trace_error_mm"):
        assert getattr(learning, field) == getattr(plain, field)
    assert np.isnan(plain.delta_right) and np.isnan(plain.delta_error_classes)
    assert 0.0 < learning.delta_right <= 1.0 and np.isfinite(learning.delta_error_classes)
    # the turn is 2 angle classes per decision: the learner finds it by the end (ground truth of the circle)
    assert learning.delta_error_classes < 0.5


def test_bad_diagnostic_options(edge_env):
    with pytest.raises(ValueError, match="step"):
        follow_contour(edge_env, threshold=0.5, active=True, step="chord", runs=2, decisions=2)
