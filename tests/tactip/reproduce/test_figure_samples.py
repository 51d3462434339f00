"""The figures drawn from samples (001 Figs 7A and 8, 003 Figs 5 sweep, 6A and 7, 004 Fig. 6 traced, 000 Figs 7, 8B,
10 and 11): each drawn line, bar or map is the samples or rows it came from, read back from the figure's artists."""

import numpy as np
import pytest

from perception import StationaryPolicy, VirtualEnvironment, fit_model, monte_carlo
from tactip.reproduce import Comparison, Report, figure_runs, figure_samples, taxel_runs
from tactip.reproduce.figures import make_figures, save_figures
from tests.perception.synthetic import gap_dataset
from tests.tactip.reproduce.test_figures import assert_png, line

GRID = dict(depths=6, widths=4, samples=10, dims=8, legible_from=0.3)


@pytest.fixture(scope="module")
def gap_env():
    model = fit_model(gap_dataset(seed=1, taps_per_class=6, **GRID), n_locations=6)
    return VirtualEnvironment(model, gap_dataset(seed=2, taps_per_class=6, **GRID))


@pytest.fixture(scope="module")
def edge_env():
    from tactip.reproduce.report import environment
    from tactip.reproduce.stimuli import make_stimulus

    return environment(make_stimulus("edge"), seed=0, taps_per_identity=90, n_locations=18)


@pytest.fixture(scope="module")
def fingertip():
    """A small simulated fingertip: 600 taps over its 30 mm per collection."""
    from tactip.taxel import TaxelSimulator, simulate_taxel_dataset, sweep_locations

    simulator = TaxelSimulator("fingertip", seed=3)
    where = sweep_locations(simulator.sensor, 600)
    return (simulate_taxel_dataset(simulator, where, seed=(3, 2), collection="train"),
            simulate_taxel_dataset(simulator, where, seed=(3, 3), collection="test"))


def test_monte_carlo_keeps_each_runs_error_and_taps(gap_env):
    result = monte_carlo(gap_env, StationaryPolicy(), thresholds=(0.3, 0.9), runs=300, seed=4, max_taps=12)
    assert result.identity_error_runs.shape == result.taps_runs.shape == (2, 300)
    np.testing.assert_allclose(result.identity_error_runs.mean(axis=1), result.mean_identity_error)
    np.testing.assert_allclose(result.taps_runs.mean(axis=1), result.mean_taps)
    assert (result.taps_runs[1] >= result.taps_runs[0]).all()            # common runs: a higher bar takes longer


def test_001_fig7a_is_each_runs_reaction_time_and_fig8_the_per_class_maps(gap_env):
    result = monte_carlo(gap_env, StationaryPolicy(), thresholds=(0.5, 0.9, 0.99), runs=400, seed=5, max_taps=30,
                         decision_rule="joint")
    samples = figure_samples.p001_samples(result, gap_env.model)
    assert samples["fig7a"]["thresholds"] == [0.9, 0.99]                 # 0.999 not run: the nearest, 0.99
    assert samples["fig8"]["threshold"] == 0.9
    figures = make_figures(Report("001", "t", [{"deadline": None, "threshold": 0.9, "shape_error_mm": 1.0,
                                                "position_error_mm": 1.0, "reaction_taps": 3.0, "null_fraction": 0.0}],
                                  samples=samples))
    assert {"fig7a", "fig8"} <= set(figures)
    for k, t in ((1, 0.9), (2, 0.99)):
        x, y = line(figures["fig7a"], f"threshold {t:g} (mean {result.mean_taps[k]:.1f} taps, 400 runs)")
        np.testing.assert_array_equal(y, np.bincount(result.taps_runs[k]))
        assert y.sum() == 400 and (x * y).sum() / 400 == pytest.approx(result.mean_taps[k])
    for panel, name in enumerate(("identity_error_map", "location_error_map", "taps_map")):
        drawn = np.asarray(figures["fig8"].axes[panel].images[0].get_array(), float)
        np.testing.assert_allclose(drawn, getattr(result, name)[1].T)    # rods as rows, positions as columns


def test_003_quick_samples_are_the_runs_behind_its_rows_and_the_json_is_unchanged(tmp_path):
    from tactip.reproduce import reproduce

    report = reproduce("003", quick=True, seed=2)
    assert {tuple(sorted(r)) for r in report.json_rows()} == {
        ("forced_fraction", "mean_taps", "move_threshold", "seed", "texture_error_classes")}
    assert "samples" not in str(report.json_rows())
    counts = report.samples["fig7_hist"]
    for row in report.rows:                                              # the histogram's mean is the row's error
        n = counts[row["move_threshold"]]
        assert n.sum() == 600
        assert (np.arange(len(n)) * n).sum() / n.sum() == pytest.approx(row["texture_error_classes"], abs=1e-12)
    figures = make_figures(report)
    for panel, move in enumerate((1.5, 0.999, 0.05)):
        bars = [p.get_height() for p in figures["fig7_hist"].axes[panel].containers[0]]
        np.testing.assert_allclose(bars, counts[move] / counts[move].sum())
    (fig6a,) = report.samples["fig6a"]
    assert fig6a["seed"] == 2 and fig6a["texture_error_classes"].shape == (15, 10)
    np.testing.assert_allclose(np.asarray(figures["fig6a"].axes[0].images[0].get_array(), float),
                               fig6a["texture_error_classes"].T)
    paths = save_figures(figures, tmp_path, paper="003")
    assert [p.name for p in paths] == ["003_fig5.png", "003_fig6a.png", "003_fig6b.png", "003_fig7.png",
                                       "003_fig7_hist.png"]
    for p in paths:
        assert_png(p)


def test_003_fig6a_is_the_mean_of_the_seeds_maps():
    rng = np.random.default_rng(0)
    maps = [{"seed": s, "depths_mm": np.arange(15) * 0.2 + 0.1, "textures": np.arange(10.0),
             "texture_error_classes": rng.uniform(0, 4, (15, 10))} for s in (0, 1, 2)]
    maps[1]["texture_error_classes"][3, 4] = np.nan                      # no run started there on seed 1
    figures = make_figures(Report("003", "t", [], samples={"fig6a": maps}))
    drawn = np.asarray(figures["fig6a"].axes[0].images[0].get_array(), float)
    expected = np.nanmean([m["texture_error_classes"] for m in maps], axis=0).T
    np.testing.assert_allclose(drawn, expected)
    assert drawn[4, 3] == pytest.approx((maps[0]["texture_error_classes"][3, 4] +
                                         maps[2]["texture_error_classes"][3, 4]) / 2)


def test_003_fig5_sweep_rows_are_one_depth_runs_at_each_offset():
    from tactip.reproduce.p003 import _single_depth
    from tactip.reproduce.report import collections
    from tactip.reproduce.stimuli import make_stimulus

    train, test = collections(make_stimulus("textures"), seed=1, taps_per_identity=150)
    rows = figure_runs.fig5_sweep_rows(train, test, offsets_mm=(-0.4, 0.0, 0.4), runs=300, seed=6)
    assert [r["offset_mm"] for r in rows] == [-0.4, 0.0, 0.4]
    for r in rows:
        again = _single_depth(train, test, r["offset_mm"], 300, 6)
        assert r["texture_error_classes"] == again.mean_identity_error[0] and r["mean_taps"] == again.mean_taps[0]
    assert rows[1]["texture_error_classes"] < min(rows[0]["texture_error_classes"], rows[2]["texture_error_classes"])
    comparisons = [Comparison("Fig. 5 one depth class, test offset 0 mm: texture error", 0.5, 0.4, "classes"),
                   Comparison("Fig. 5 one depth class, test offset 0.2 mm: texture error", 1.1, 1.0, "classes")]
    figures = make_figures(Report("003", "t", [], comparisons), {"fig5_sweep": rows[::-1]})
    x, y = line(figures["fig5_sweep"], "passive (simulated)")
    np.testing.assert_array_equal(x, [-0.4, 0.0, 0.4])
    np.testing.assert_array_equal(y, [r["texture_error_classes"] for r in rows])
    np.testing.assert_array_equal(line(figures["fig5_sweep"], "paper (text)")[1], [0.4, 1.0])


def test_004_traced_contours_are_the_edge_points_each_decision_perceives(edge_env):
    from tactip.reproduce.contour import follow_contour

    options = dict(threshold=0.5, active=True, runs=6, decisions=12, max_taps=8, seed=3)
    plain = follow_contour(edge_env, **options)
    traced = follow_contour(edge_env, traces=4, **options)
    assert plain.traced_mm.shape == (0, 12, 2) and traced.traced_mm.shape == (4, 12, 2)
    assert (plain.angle_error_deg, plain.closed_contour) == (traced.angle_error_deg, traced.closed_contour)
    radius = np.hypot(*traced.traced_mm.transpose(2, 0, 1))
    assert np.median(np.abs(radius - 30.0)) < 2.0                        # the points lie on the plate's edge
    rows = figure_samples.traced_contour_samples(edge_env, conditions=(("active", 0.5), ("passive", 0.5)), traces=4,
                                                 runs=6, decisions=12, max_taps=8, seed=2)
    mine = [r for r in rows if r["method"] == "active"]
    assert len(mine) == 4 * 12 and {r["closed_contour"] for r in mine} == {traced.closed_contour}
    np.testing.assert_array_equal([[r["x_mm"], r["y_mm"]] for r in mine], traced.traced_mm.reshape(-1, 2))
    row = {"method": "active", "threshold": 0.5, "angle_error_deg": 3.0, "position_error_mm": 1.0,
           "taps_per_decision": 4.0, "closed_contour": 0.5}
    figures = make_figures(Report("004", "t", [row]), {"fig6_traced": rows})
    assert list(figures) == ["fig6", "fig6_traced", "fig7"]
    for run in range(4):
        x, y = line(figures["fig6_traced"], f"_run{run}", panel=0)
        np.testing.assert_array_equal(np.stack([x, y], 1), traced.traced_mm[run])


def test_000_taxel_rows_are_the_monte_carlo_runs_and_the_figures_draw_them(fingertip, tmp_path):
    train, test = fingertip
    env = taxel_runs._environment(train, test, 30)
    fig7 = taxel_runs.trajectory_rows(env, runs=20, seed=4)
    fig8b = taxel_runs.decision_time_rows(env, thresholds=(0.5, 0.99), runs=300, seed=4)
    fig10 = taxel_runs.location_rows(env, thresholds=(0.5, 0.99), runs=300, seed=4)
    fig11 = taxel_runs.threshold_rows(train, test, class_counts=(10, 30), thresholds=(0.5, 0.99), runs=300, seed=4)
    for policy, fixed in (("passive", True), ("active", False)):
        full = taxel_runs._monte_carlo(env, taxel_runs._policies(env)[policy], [0.95], 20, 4)
        for run in range(20):
            trace = sorted((r for r in fig7 if r["policy"] == policy and r["run"] == run), key=lambda r: r["tap"])
            assert [r["tap"] for r in trace] == list(range(1, full.taps_runs[0, run] + 1))
            assert trace[-1]["decided"] and not any(r["decided"] for r in trace[:-1])
            assert trace[-1]["location_mm"] == env.model.location_centres[full.final_location[0, run]]
            if fixed:                                                    # passive perception never moves
                assert len({r["location_mm"] for r in trace}) == 1
    passive = taxel_runs._monte_carlo(env, taxel_runs._policies(env)["passive"], (0.5, 0.99), 300, 4)
    for k, t in enumerate((0.5, 0.99)):
        counts = [r["runs"] for r in fig8b if r["threshold"] == t]
        np.testing.assert_array_equal(counts, np.bincount(passive.taps_runs[k], minlength=51)[1:])
        errors = [r["error_mm"] for r in fig10 if r["threshold"] == t]
        np.testing.assert_array_equal(errors, passive.location_error_map[k, :, 0])
    row = next(r for r in fig11 if (r["policy"], r["classes"], r["threshold"]) == ("passive", 30, 0.99))
    assert row["error_mm"] == passive.mean_location_error[1] and row["mean_taps"] == passive.mean_taps[1]
    extra = {"fig7": fig7, "fig8b": fig8b, "fig10": fig10, "fig11": fig11}
    figures = make_figures(Report("000", "t", []), extra)
    assert list(figures) == ["fig7", "fig8b", "fig10", "fig11"]
    x, y = line(figures["fig8b"], "threshold 0.99")
    np.testing.assert_array_equal(y, np.bincount(passive.taps_runs[1], minlength=51)[1:])
    x, y = line(figures["fig10"], "threshold 0.5", panel=1)
    np.testing.assert_array_equal(x, env.model.location_centres)
    np.testing.assert_array_equal(y, passive.taps_map[0, :, 0])
    mine = [r for r in fig11 if r["policy"] == "active" and r["classes"] == 10]
    x, y = line(figures["fig11"], "active, 10 classes", panel=2)
    np.testing.assert_array_equal(x, [r["mean_taps"] for r in mine])
    np.testing.assert_array_equal(y, [r["error_mm"] for r in mine])
    for p in save_figures(figures, tmp_path, paper="000"):
        assert_png(p)


def test_cli_figure_runs_write_every_figure_and_the_rows(tmp_path, capsys, monkeypatch):
    import json

    import tactip.reproduce.figure_runs
    from tactip.cli import main

    maps = [{"seed": 0, "depths_mm": np.arange(3) + 0.5, "textures": np.arange(2.0),
             "texture_error_classes": np.ones((3, 2))}]
    report = Report("003", "t", [{"seed": 0, "move_threshold": m, "texture_error_classes": 1.0, "mean_taps": 3.0,
                                  "forced_fraction": 0.0} for m in (1.5, 0.999, 0.05)],
                    samples={"fig6a": maps, "fig7_hist": {m: np.array([5, 3, 2]) for m in (1.5, 0.999, 0.05)}})
    extra = {"fig5_sweep": [{"offset_mm": o, "texture_error_classes": 1.0 + abs(o), "mean_taps": 4.0}
                            for o in (-0.2, 0.0, 0.2)]}
    monkeypatch.setattr(tactip.reproduce.figure_runs, "run_with_figure_runs", lambda paper, **options: (report, extra))
    out = tmp_path / "003.json"
    assert main(["reproduce", "003", "--quiet", "--figure-runs", "--json", str(out)]) == 0
    assert "wrote 6 figures" in capsys.readouterr().out
    assert sorted(p.name for p in tmp_path.glob("*.png")) == sorted(
        f"003_{n}.png" for n in ("fig5", "fig5_sweep", "fig6a", "fig6b", "fig7", "fig7_hist"))
    assert json.loads(out.read_text()) == report.json_rows()            # the samples are not in the JSON
    assert json.loads((tmp_path / "003_figure_runs.json").read_text()) == extra


def test_003_figure_runs_sweep_holds_the_reproductions_own_two_offsets():
    report, extra = figure_runs.run_with_figure_runs("003", quick=True, seed=1)
    assert list(extra) == ["fig5_sweep"]
    sweep = {r["offset_mm"]: r["texture_error_classes"] for r in extra["fig5_sweep"]}
    assert list(sweep) == list(figure_runs.QUICK_FIG5_OFFSETS_MM)
    for offset in (0.0, 0.2):                                            # the same sessions, runs and seed
        compared, = [c for c in report.comparisons if c.figure.startswith(f"Fig. 5 one depth class, test offset "
                                                                          f"{offset:g} mm")]
        assert sweep[offset] == pytest.approx(compared.measured, abs=1e-12)
