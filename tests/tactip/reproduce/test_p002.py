"""tactip.reproduce.p002 on a small synthetic station: Fig. 9's fixation is read off the Fig. 10 sweep on the
test collection (paper 002 Sec. IV-C), the station's own choice (from training taps) is a named variant beside
it, and the claim judges the faithful row. A model and a test set of `gap_dataset` stand in for the prepared
station (the end-to-end run on the simulated station is `test_reproduce_002.py`)."""

import numpy as np
import pytest

from perception import FixationPolicy, VirtualEnvironment, fit_model, monte_carlo, save_dataset, save_model
from tactip.reproduce import p002
from tactip.reproduce.seeds import claim_margin
from tests.perception.synthetic import gap_dataset

# 6 depths (0-5 mm), 4 widths; the width is legible only in the deep half (depth > 2.5 mm): ground truth
GRID = dict(depths=6, widths=4, samples=10, dims=8, legible_from=0.5)
#: The station's own fixation here: the shallowest class, where the width cannot be read.
STATION_FIXATION_MM = 0.2


@pytest.fixture(scope="module")
def station(tmp_path_factory):
    import tactip.station.procedures

    test = gap_dataset(seed=2, taps_per_class=10, **GRID)
    model = fit_model(gap_dataset(seed=1, taps_per_class=4, **GRID), n_locations=6)
    model = model.with_recommended(fixation_location=STATION_FIXATION_MM)

    def prepare(config, *, progress, log):
        (config.data_dir / "datasets").mkdir(parents=True)
        save_dataset(config.data_dir / "datasets" / "test.h5", test)
        save_model(config.perception.model, model)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(tactip.station.procedures, "prepare_model", prepare)
        report = p002.run(quick=True, seed=0, data_dir=tmp_path_factory.mktemp("station"))
    return report, model, test


def _curve(report, policy):
    mine = sorted((r for r in report.rows if r["policy"] == policy), key=lambda r: r["threshold"])
    return np.array([r["width_error_mm"] for r in mine]), np.array([r["mean_taps"] for r in mine])


def test_fig9_fixation_is_the_sweeps_lowest_error_within_12_taps(station):
    report, model, _ = station
    at_12 = [r for r in report.samples["fig10"] if r["tap_budget"] == p002.FIXATION_BUDGET_TAPS]
    assert sorted(r["fixation_mm"] for r in at_12) == pytest.approx(model.location_centres)     # every class swept
    assert all(r["mean_taps"] <= 12 for r in at_12)
    best = min(at_12, key=lambda r: (r["width_error_mm"], r["mean_taps"], r["fixation_mm"]))     # ties: fewer taps
    fixations = {r["policy"]: r["fixation_mm"] for r in report.rows}
    assert fixations["active"] == best["fixation_mm"]
    assert fixations["random"] is None and fixations["stationary"] is None
    # ground truth of the world: the width is legible only deeper than 2.5 mm, so the sweep fixates there
    assert best["fixation_mm"] > 2.5 and best["width_error_mm"] < 0.5 * max(r["width_error_mm"] for r in at_12)
    comparison, = [c for c in report.comparisons if c.figure.startswith("Fig. 10 best fixation")]
    assert comparison.measured == best["fixation_mm"] and comparison.paper == 4.75


def test_the_variant_fixates_where_the_station_chose_on_its_training_taps(station):
    report, model, test = station
    station_class = model.fixation_class()
    assert model.location_centres[station_class] < 1.0                              # the shallowest class
    variant = [r for r in report.rows if r["policy"] == p002.STATION_FIXATION]
    assert {r["fixation_mm"] for r in variant} == {float(model.location_centres[station_class])}
    # its runs are active perception at that class, with Fig. 9's Monte Carlo (seed + 1, the same runs)
    again = monte_carlo(VirtualEnvironment(model, test), FixationPolicy(station_class), runs=p002.RUNS[True], seed=1,
                        thresholds=p002.THRESHOLDS, max_taps=20)
    errors, taps = _curve(report, p002.STATION_FIXATION)
    np.testing.assert_allclose(errors, again.mean_identity_error)
    np.testing.assert_allclose(taps, again.mean_taps)
    # where the width cannot be read, the variant errs far more than the faithful fixation (ground truth)
    assert _curve(report, p002.STATION_FIXATION)[0].min() > 3 * _curve(report, "active")[0].min()
    assert any(p002.STATION_FIXATION in note and "held-out training taps" in note for note in report.notes)
    assert any("reads the test taps, as the paper did" in note for note in report.notes)


def test_the_claim_judges_the_faithful_active_row(station):
    report, _, _ = station
    at_10 = {c.figure.split(":")[0]: c.measured for c in report.comparisons if "width error at 10" in c.figure}
    faithful = min(at_10["Fig. 9 random"] - at_10["Fig. 9 active"], at_10["Fig. 9 stationary"] - at_10["Fig. 9 random"])
    assert claim_margin("002", report.rows) == pytest.approx(faithful)
    # the variant row read as active would give another margin (it fixates where the width is illegible)
    swapped = [dict(r, policy={"active": "x", p002.STATION_FIXATION: "active"}.get(r["policy"], r["policy"]))
               for r in report.rows]
    assert claim_margin("002", swapped) < faithful - 0.1


def test_a_map_fn_runs_the_sweep_and_the_policies_with_the_same_report(station, tmp_path, monkeypatch):
    # `tactip reproduce 002 --scheduler`: the fixations of the sweep and Fig. 9's rows go through map_fn, same numbers
    import tactip.station.procedures

    report, model, test = station

    def prepare(config, *, progress, log):
        (config.data_dir / "datasets").mkdir(parents=True)
        save_dataset(config.data_dir / "datasets" / "test.h5", test)
        save_model(config.perception.model, model)

    mapped = []

    def map_fn(function, items):
        mapped.append(list(items))
        return [function(item) for item in items]

    monkeypatch.setattr(tactip.station.procedures, "prepare_model", prepare)
    again = p002.run(quick=True, seed=0, data_dir=tmp_path, map_fn=map_fn)
    assert mapped[0] == list(range(model.n_locations))                              # the sweep's fixations
    assert [name for name, _ in mapped[1]] == ["active", "random", "stationary", p002.STATION_FIXATION]
    assert again.rows == report.rows and again.samples["fig10"] == report.samples["fig10"]
