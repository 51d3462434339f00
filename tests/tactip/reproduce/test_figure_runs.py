"""The runs only figures need (002 Figs 10-11, 004 Figs 7 sweep and 8), on small worlds."""

import dataclasses
from pathlib import Path

import numpy as np
import pytest

from perception import VirtualEnvironment, fit_model, fixation_sweep, save_dataset
from tactip.reproduce import figure_runs
from tests.perception.synthetic import gap_dataset

GRID = dict(depths=6, widths=4, samples=10, dims=8, legible_from=0.5)


@pytest.fixture(scope="module")
def model():
    return fit_model(gap_dataset(seed=1, taps_per_class=4, **GRID), n_locations=6)


def test_fig10_rows_are_the_sweeps_best_errors_within_each_budget(model):
    from tactip.reproduce.p002 import TAP_BUDGETS, THRESHOLDS, fixation_from_sweep, sweep_rows

    env = VirtualEnvironment(model, gap_dataset(seed=2, taps_per_class=10, **GRID))
    rows = sweep_rows(fixation_from_sweep(env, runs=200, seed=3))
    assert len(rows) == 6 * len(TAP_BUDGETS)

    sweep = fixation_sweep(env, thresholds=THRESHOLDS, runs=200, seed=3, max_taps=20)
    for fixation, result in zip(sweep.fixations, sweep.results):
        for budget in TAP_BUDGETS:
            row, = [r for r in rows if r["fixation_mm"] == fixation and r["tap_budget"] == budget]
            k = result.best_within(budget)
            assert row["width_error_mm"] == result.mean_identity_error[k] and row["mean_taps"] <= max(budget, 1.0)
    # the width is legible only in the deep half (ground truth of the world): deep fixations win
    at_12 = {r["fixation_mm"]: r["width_error_mm"] for r in rows if r["tap_budget"] == 12}
    assert at_12[max(at_12)] < at_12[min(at_12)] / 4
    # a larger budget never does worse (it can only add thresholds)
    for fixation in at_12:
        errors = [r["width_error_mm"] for r in rows if r["fixation_mm"] == fixation]
        assert errors == sorted(errors, reverse=True)


@dataclasses.dataclass(frozen=True)
class _Protocol:
    lateral_jitter_mm: float = 0.0


@dataclasses.dataclass(frozen=True)
class _Station:
    data_dir: Path
    protocol: _Protocol = _Protocol()


def test_lateral_rows_tap_a_noisy_test_set_per_sigma_and_divide_by_the_noise_free_error(tmp_path, monkeypatch):
    import tactip.station.procedures

    grid = dict(GRID, legible_from=0.0, noise=0.2)                      # the width legible at every depth
    model = fit_model(gap_dataset(seed=1, taps_per_class=4, **grid), n_locations=6)

    asked = []

    def collect(config, out_dir, *, progress, log, sets):
        sigma = config.protocol.lateral_jitter_mm
        asked.append((sigma, Path(out_dir), tuple(sets)))
        path = Path(out_dir) / "test.h5"
        path.parent.mkdir(parents=True)
        save_dataset(path, gap_dataset(seed=4, taps_per_class=2, lateral=np.linspace(-sigma, sigma, 5), **grid))
        return {"test": path}

    monkeypatch.setattr(tactip.station.procedures, "collect_station", collect)
    test = gap_dataset(seed=4, taps_per_class=10, **grid)
    rows = figure_runs.lateral_rows(_Station(tmp_path), model, test, sigmas_mm=(0.5, 2.0), runs=300, seed=5)
    assert asked == [(0.5, tmp_path / "lateral-0.5", ("test",)), (2.0, tmp_path / "lateral-2", ("test",))]
    by = {(r["policy"], r["sigma_mm"]): r for r in rows}
    assert {p for p, _ in by} == {"active", "random", "stationary"} and {s for _, s in by} == {0.0, 0.5, 2.0}
    for (policy, sigma), r in by.items():
        assert r["ratio"] == pytest.approx(r["width_error_mm"] / by[policy, 0.0]["width_error_mm"])
    # the world's width signal fades with |lateral|: noise degrades the active policy's width error
    assert by["active", 0.0]["width_error_mm"] < by["active", 0.5]["width_error_mm"] < \
        by["active", 2.0]["width_error_mm"]


@pytest.fixture(scope="module")
def edge_env():
    from tactip.reproduce.report import environment
    from tactip.reproduce.stimuli import make_stimulus

    return environment(make_stimulus("edge"), seed=0, taps_per_identity=90, n_locations=18)


def test_beta_sweep_rows_are_the_contour_runs_and_fig8_their_learning_curves(edge_env):
    from tactip.reproduce.contour import follow_contour

    options = dict(runs=4, decisions=6, max_taps=6)
    sweep, learning = figure_runs.beta_sweep_rows(edge_env, thresholds=(0.3, 0.5), seed=7, **options)
    assert [(r["method"], r["threshold"]) for r in sweep] == [(m, t) for t in (0.3, 0.5)
                                                             for m in figure_runs.SWEEP_METHODS]
    again = follow_contour(edge_env, threshold=0.5, active=True, adaptive=True, seed=8, **options)
    row, = [r for r in sweep if r["method"] == "adaptive" and r["threshold"] == 0.5]
    assert row["angle_error_deg"] == again.angle_error_deg and row["taps_per_decision"] == again.taps_per_decision
    # Fig. 8 only at its thresholds (0.5 here), only for the adaptive methods, one row per decision
    assert {(r["method"], r["threshold"]) for r in learning} == {("adaptive", 0.5), ("adaptive_angle_only", 0.5)}
    curve = [r["delta_error_classes"] for r in learning if r["method"] == "adaptive"]
    assert [r["decision"] for r in learning if r["method"] == "adaptive"] == list(range(6))
    assert curve[0] is None                                              # no prediction before the first decision
    np.testing.assert_allclose(curve[1:], again.delta_error_by_decision[1:])


def test_002_figure_runs_share_the_station_the_reproduction_prepared(monkeypatch):
    """`run_with_figure_runs("002")` prepares the simulated station once: the reproduction's Monte Carlo and
    the figure runs read the same collections and model (preparing is most of the work). Fig. 10 is the
    reproduction's own sweep (it chose Fig. 9's fixation), not swept again; Fig. 11 fixates where Fig. 9's
    active rows do. A small model and test set stand in for the station's; the figure runs (tested above)
    only record what they were given."""
    import tactip.station.procedures
    from perception import save_model

    prepared, given = [], {}
    test = gap_dataset(seed=2, taps_per_class=10, **GRID)
    model = fit_model(gap_dataset(seed=1, taps_per_class=4, **GRID), n_locations=6).with_recommended(
        fixation_location=0.2)                       # the station's own fixation: shallow, where the width is illegible

    def prepare(config, *, progress, log):
        prepared.append(config.data_dir)
        (config.data_dir / "datasets").mkdir(parents=True)
        save_dataset(config.data_dir / "datasets" / "test.h5", test)
        save_model(config.perception.model, model)

    swept = []

    def fixation_from_sweep(environment, **options):                   # counted: Fig. 10 is swept once
        swept.append(options)
        return sweep_once(environment, **options)

    def lateral_rows(config, model, test, **options):
        given["fig11"] = config.data_dir, test, options["fixation"]
        return [{"sigma_mm": 0.0}]

    monkeypatch.setattr(tactip.station.procedures, "prepare_model", prepare)
    import tactip.reproduce.p002 as p002

    sweep_once = p002.fixation_from_sweep
    monkeypatch.setattr(p002, "fixation_from_sweep", fixation_from_sweep)
    monkeypatch.setattr(figure_runs, "lateral_rows", lateral_rows)
    report, extra = figure_runs.run_with_figure_runs("002", quick=True, seed=0)
    assert len(prepared) == 1 and len(swept) == 1        # the station prepared and Fig. 10 swept, once each
    from tactip.reproduce.p002 import STATION_FIXATION

    assert report.paper == "002"
    assert {r["policy"] for r in report.rows} == {"active", "random", "stationary", STATION_FIXATION}
    assert any(c.fit for c in report.comparisons)                          # marked as `reproduce` marks it
    assert extra["fig10"] == report.samples["fig10"] and extra["fig11"] == [{"sigma_mm": 0.0}]
    assert given["fig11"][0] == prepared[0]                                # the folder the reproduction prepared
    np.testing.assert_array_equal(given["fig11"][1].taps, test.taps)
    active_mm, = {r["fixation_mm"] for r in report.rows if r["policy"] == "active"}
    assert given["fig11"][2] == model.location_class(active_mm) != model.fixation_class()
