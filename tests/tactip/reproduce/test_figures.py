"""The reproduced figures: each plotted curve is the reproduction's rows, the paper's numbers beside, valid PNGs."""

import numpy as np
import pytest

from tactip.reproduce import Comparison, Report
from tactip.reproduce.figures import make_figures, save_figures
from tactip.reproduce.figures.p000 import PAPER_TABLES

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def line(fig, label, panel=0):
    """The one line labelled ``label`` on panel ``panel``: (x, y) as float arrays."""
    found = [ln for ln in fig.axes[panel].get_lines() if ln.get_label() == label]
    assert len(found) == 1, (label, [ln.get_label() for ln in fig.axes[panel].get_lines()])
    return np.asarray(found[0].get_xdata(), float), np.asarray(found[0].get_ydata(), float)


def assert_png(path, *, min_px=(400, 300)):
    from PIL import Image

    assert path.read_bytes()[:8] == PNG_SIGNATURE
    with Image.open(path) as image:
        image.verify()
    with Image.open(path) as image:
        width, height = image.size
        assert width >= min_px[0] and height >= min_px[1]
        assert len(image.getcolors(1 << 20) or range(1 << 20)) > 20      # not blank: curves, text, colours


def test_000_tables_from_either_layout_beside_the_paper(tmp_path):
    wide = [{"classes": c, "class_width_mm": 30 / c, "passive_error_mm": 4.0 + k, "active_error_mm": 0.01 * (k + 1),
             "active_taps": 2.0, "acuity_mm": 30 / c} for k, c in enumerate((10, 30, 300))]
    figures = make_figures(Report("000", "t", wide))
    assert list(figures) == ["table2"]                                   # no skin rows: no Table III
    x, y = line(figures["table2"], "active (simulated)")
    np.testing.assert_array_equal(x, [10, 30, 300])
    np.testing.assert_allclose(y, [0.01, 0.02, 0.03])
    x, y = line(figures["table2"], "passive (simulated)")
    np.testing.assert_allclose(y, [4.0, 5.0, 6.0])
    x, y = line(figures["table2"], "active (paper)")
    np.testing.assert_allclose(y, list(PAPER_TABLES["fingertip"]["active"].values()))

    long = [{"sensor": s, "classes": c, "policy": p, "error_mm": e, "mean_taps": 4.0}
            for s, c, p, e in (("skin", 50, "active", 0.2), ("skin", 25, "active", 0.1), ("skin", 25, "passive", 0.5),
                               ("skin", 50, "passive", 0.6), ("fingertip", 300, "active", 0.15))]
    figures = make_figures(Report("000", "t", long))
    assert list(figures) == ["table2", "table3"]
    x, y = line(figures["table3"], "active (simulated)")                 # sorted by class count
    np.testing.assert_array_equal(x, [25, 50])
    np.testing.assert_allclose(y, [0.1, 0.2])
    x, y = line(figures["table3"], "passive (paper)")
    np.testing.assert_allclose(y, 0.4)
    np.testing.assert_allclose(line(figures["table2"], "active (simulated)")[1], [0.15])
    paths = save_figures(figures, tmp_path / "new", paper="000")
    assert [p.name for p in paths] == ["000_table2.png", "000_table3.png"]
    for p in paths:
        assert_png(p)


def _rows_001():
    rng = np.random.default_rng(0)
    return [{"deadline": d, "threshold": t, "shape_error_mm": rng.uniform(1, 3), "position_error_mm": rng.uniform(0, 1),
             "reaction_taps": rng.uniform(1, 20), "null_fraction": 0.0 if d is None else rng.uniform(),
             "forced_fraction": 0.0} for d in (None, 5, 10) for t in (0.9, 0.2, 0.5)]


def test_001_curves_per_deadline_and_the_papers_numbers_at_their_threshold():
    rows = _rows_001()
    comparisons = [Comparison("Fig. 4 fixed, theta 0.9: shape error", 2.0, 2.2, "mm"),
                   Comparison("Fig. 4 deadline 5, theta 0.9: position error", 0.2, 0.1, "mm"),
                   Comparison("Fig. 6 null fraction, D=5, theta 0.9", 0.5, None)]
    figures = make_figures(Report("001", "t", rows, comparisons))
    assert list(figures) == ["fig4", "fig5", "fig6", "fig7b"]              # no samples: no Figs 7A and 8
    for deadline, label in ((None, "fixed (no deadline)"), (5, "deadline 5 taps"), (10, "deadline 10 taps")):
        mine = sorted((r for r in rows if r["deadline"] == deadline), key=lambda r: r["threshold"])
        for panel, error in enumerate(("shape_error_mm", "position_error_mm")):
            x, y = line(figures["fig4"], label, panel)
            np.testing.assert_allclose(x, [r["threshold"] for r in mine])
            np.testing.assert_allclose(y, [r[error] for r in mine])
            x, y = line(figures["fig5"], label, panel)
            np.testing.assert_allclose(x, [r["reaction_taps"] for r in mine])
            np.testing.assert_allclose(y, [r[error] for r in mine])
        np.testing.assert_allclose(line(figures["fig6"], label)[1], [r["null_fraction"] for r in mine])
        np.testing.assert_allclose(line(figures["fig7b"], label)[1], [r["reaction_taps"] for r in mine])
    # the paper's numbers sit at the threshold they were compared at, on the right panel
    assert line(figures["fig4"], "paper: Fig. 4 fixed, theta 0.9: shape error = 2.2 mm", 0) == ([0.9], [2.2])
    assert line(figures["fig4"], "paper: Fig. 4 deadline 5, theta 0.9: position error = 0.1 mm", 1) == ([0.9], [0.1])
    assert not [ln for ln in figures["fig4"].axes[1].get_lines() if "shape" in ln.get_label()]
    assert figures["fig4"].axes[0].get_xscale() == "linear"
    # the paper's high thresholds (0.99 ... 0.99999) are spread on a logit axis, the data unchanged
    high = [dict(r, threshold=1 - (1 - r["threshold"]) / 1000) for r in rows]
    figures = make_figures(Report("001", "t", high))
    assert {ax.get_xscale() for name in ("fig4", "fig6", "fig7b") for ax in figures[name].axes} == {"logit"}
    mine = sorted((r for r in high if r["deadline"] == 10), key=lambda r: r["threshold"])
    np.testing.assert_allclose(line(figures["fig6"], "deadline 10 taps")[0], [r["threshold"] for r in mine])


def test_002_fig9_is_marked_a_fit_and_figs_10_11_need_their_runs(tmp_path):
    from tactip.reproduce.p002 import STATION_FIXATION

    rows = [{"seed": 0, "policy": p, "fixation_mm": f, "threshold": t, "width_error_mm": e, "mean_taps": n,
             "accuracy": 0.5}
            for p, base, f in (("active", 0.3, 5.25), ("random", 0.5, None), ("stationary", 0.7, None),
                               (STATION_FIXATION, 0.4, 4.75))
            for t, e, n in ((0.5, base + 0.2, 3.0), (0.9, base, 11.0), (0.2, base + 0.4, 1.0))]
    report = Report("002", "t", rows)
    figures = make_figures(report)
    assert list(figures) == ["fig9"]
    assert "FIT" in figures["fig9"]._suptitle.get_text() and "MEMBRANE_RHO_MM" in figures["fig9"]._suptitle.get_text()
    x, y = line(figures["fig9"], "random (simulated)")
    np.testing.assert_allclose(x, [1.0, 3.0, 11.0])                         # ordered by mean taps
    np.testing.assert_allclose(y, [0.9, 0.7, 0.5])
    x, y = line(figures["fig9"], "active (paper, 8-12 taps)")
    np.testing.assert_allclose(x, [8, 12])
    np.testing.assert_allclose(y, [0.35, 0.35])
    x, y = line(figures["fig9"], f"variant: {STATION_FIXATION} (simulated)")   # beside active, named a variant
    np.testing.assert_allclose(x, [1.0, 3.0, 11.0])
    np.testing.assert_allclose(y, [0.8, 0.6, 0.4])

    fig10 = [{"fixation_mm": f, "tap_budget": b, "width_error_mm": 1 / (f + b), "mean_taps": b}
             for b in (4.0, 12.0) for f in (4.75, 0.25, 2.5)]
    fig11 = [{"policy": p, "sigma_mm": s, "width_error_mm": 0.1 * (1 + s), "ratio": 1 + s}
             for p in ("active", "stationary") for s in (0.0, 2.0, 0.5)]
    figures = make_figures(report, {"fig10": fig10, "fig11": fig11})
    assert list(figures) == ["fig9", "fig10", "fig11"]
    x, y = line(figures["fig10"], "within 12 mean taps (simulated)")
    np.testing.assert_allclose(x, [0.25, 2.5, 4.75])
    np.testing.assert_allclose(y, [1 / 12.25, 1 / 14.5, 1 / 16.75])
    x, _ = line(figures["fig10"], "simulated best within 12 mean taps, Fig. 9's fixation: 5.25 mm")
    np.testing.assert_allclose(x, [5.25, 5.25])
    x, _ = line(figures["fig10"], "variant: the station's, from training taps: 4.75 mm")
    np.testing.assert_allclose(x, [4.75, 4.75])
    x, y = line(figures["fig11"], "stationary (simulated)", 0)
    np.testing.assert_allclose(x, [0.0, 0.5, 2.0])
    np.testing.assert_allclose(y, [1.0, 1.5, 3.0])
    x, y = line(figures["fig11"], "stationary (simulated)", 1)            # B: the errors themselves
    np.testing.assert_allclose(y, [0.1, 0.15, 0.3])
    for path in save_figures(figures, tmp_path, paper="002"):
        assert_png(path)
    # A policy whose noise-free error is 0 mm has no ratio: panel A names it and says why, B draws its errors.
    for r in fig11:
        if r["policy"] == "active":
            r["width_error_mm"], r["ratio"] = (0.0, None) if r["sigma_mm"] == 0 else (r["width_error_mm"], None)
    figures = make_figures(report, {"fig11": fig11})
    _, y = line(figures["fig11"], "active: no ratio, its noise-free error is 0 mm (B)", 0)
    assert np.isnan(y).all()
    _, y = line(figures["fig11"], "active (simulated)", 1)
    np.testing.assert_allclose(y, [0.0, 0.15, 0.3])


def test_003_fig7_bars_are_the_mean_over_seeds_each_seed_a_dot():
    rows = [{"seed": s, "move_threshold": m, "texture_error_classes": e, "mean_taps": 3.0, "forced_fraction": 0.0}
            for s, errors in ((0, (1.2, 1.0, 0.5)), (1, (1.6, 1.2, 0.3)))
            for m, e in zip((1.5, 0.999, 0.05), errors)]
    comparisons = [Comparison("Fig. 7 passive: texture error (mean of 2 seeds)", 1.4, 1.4, "classes"),
                   Comparison("Fig. 7 strongly active: texture error (mean of 2 seeds)", 0.4, 0.4, "classes"),
                   Comparison("Fig. 5 one depth class, test offset 0.2 mm: texture error", 1.1, 1.0, "classes"),
                   Comparison("Fig. 5 one depth class, test offset 0 mm: texture error", 0.3, 0.4, "classes")]
    figures = make_figures(Report("003", "t", rows, comparisons))
    ax = figures["fig7"].axes[0]
    simulated, paper = (c for c in ax.containers)
    np.testing.assert_allclose([b.get_height() for b in simulated], [1.4, 1.1, 0.4])
    heights = [b.get_height() for b in paper]
    np.testing.assert_allclose(heights[0::2], [1.4, 0.4]) and np.isnan(heights[1])
    dots = sorted(float(v) for ln in ax.get_lines() for v in ln.get_ydata())
    np.testing.assert_allclose(dots, sorted(r["texture_error_classes"] for r in rows))
    x, y = line(figures["fig5"], "passive (simulated)")
    np.testing.assert_allclose(x, [0.0, 0.2])
    np.testing.assert_allclose(y, [0.3, 1.1])


def test_004_curves_per_method_and_the_learning_curve():
    rows = [{"method": m, "threshold": t, "angle_error_deg": k + t, "position_error_mm": 1 + k * t,
             "taps_per_decision": 5 * t + k, "closed_contour": 0.5, "delta_error_classes": None}
            for k, m in enumerate(("passive", "active", "adaptive", "adaptive_angle_only", "adaptive_shift0"))
            for t in (0.5, 0.05)]
    comparisons = [Comparison("Fig. 7A adaptive, theta 0.5: angle error", 3.0, 2.8, "deg")]
    learning = [{"method": "adaptive", "threshold": 0.5, "decision": d, "delta_error_classes": e}
                for d, e in enumerate((None, 3.0, 1.0, 0.5))]
    figures = make_figures(Report("004", "t", rows, comparisons), {"fig8": learning})
    assert list(figures) == ["fig6", "fig7", "fig8"]
    for panel, key in enumerate(("angle_error_deg", "position_error_mm", "taps_per_decision")):
        x, y = line(figures["fig7"], "adaptive (eq. 7 as printed)", panel)
        np.testing.assert_allclose(x, [0.05, 0.5])
        np.testing.assert_allclose(y, [r[key] for r in sorted((r for r in rows if r["method"] == "adaptive"),
                                                                key=lambda r: r["threshold"])])
    line(figures["fig7"], "adaptive, angle-only (a variant)", 0)
    assert line(figures["fig7"], "paper: Fig. 7A adaptive, theta 0.5: angle error = 2.8 deg", 0) == ([0.5], [2.8])
    x, y = line(figures["fig8"], "adaptive (eq. 7 as printed), threshold 0.5")
    np.testing.assert_allclose(x, [0, 1, 2, 3])
    np.testing.assert_allclose(y, [np.nan, 3.0, 1.0, 0.5])
    heights = [b.get_height() for c in figures["fig6"].axes[0].containers for b in c]
    assert heights == [0.5] * 10


def test_unknown_rows_keys_fail_loudly():
    with pytest.raises(KeyError):
        make_figures(Report("001", "t", [{"deadline": None, "threshold": 0.5}]))


# -- tactip reproduce: where the figures go ---------------------------------------------------------------


@pytest.fixture
def fake_001(monkeypatch):
    """`reproduce` returns a small 001 report at once (the CLI's figure handling is what is tested here), and
    the figures the CLI draws are kept to compare with its JSON rows."""
    import tactip.reproduce
    import tactip.reproduce.figures

    report = Report("001", "t", _rows_001(), [Comparison("Fig. 4 fixed, theta 0.9: shape error", 2.0, 2.2, "mm")])
    monkeypatch.setattr(tactip.reproduce, "reproduce", lambda paper, **options: report)
    drawn = {}

    def spy(*args, **options):
        drawn.update(make(*args, **options))
        return drawn

    make = tactip.reproduce.figures.make_figures
    monkeypatch.setattr(tactip.reproduce.figures, "make_figures", spy)
    return drawn


def test_cli_figures_go_beside_the_json_and_plot_its_rows(tmp_path, capsys, fake_001):
    import json

    from tactip.cli import main

    out = tmp_path / "results" / "001.json"                              # a folder the writers create
    assert main(["reproduce", "001", "--quick", "--quiet", "--json", str(out)]) == 0
    assert f"wrote 4 figures to {out.parent}" in capsys.readouterr().out
    assert sorted(p.name for p in out.parent.glob("*.png")) == ["001_fig4.png", "001_fig5.png", "001_fig6.png",
                                                               "001_fig7b.png"]
    for path in out.parent.glob("*.png"):
        assert_png(path)
    rows = [r for r in json.loads(out.read_text()) if r["deadline"] == 5]
    rows.sort(key=lambda r: r["threshold"])
    x, y = line(fake_001["fig5"], "deadline 5 taps", 1)
    np.testing.assert_allclose(x, [r["reaction_taps"] for r in rows])
    np.testing.assert_allclose(y, [r["position_error_mm"] for r in rows])


def test_cli_figures_folder_default_and_none(tmp_path, capsys, monkeypatch, fake_001):
    from tactip.cli import main

    monkeypatch.chdir(tmp_path)
    assert main(["reproduce", "001", "--quick", "--quiet", "--json", "-"]) == 0     # JSON on stdout
    assert (tmp_path / "out" / "reproduce" / "001" / "001_fig4.png").is_file()
    (tmp_path / "out" / "reproduce" / "001" / "001_fig4.png").unlink()
    assert main(["reproduce", "001", "--quick", "--quiet", "--json", "/dev/null"]) == 0   # never beside a device
    assert (tmp_path / "out" / "reproduce" / "001" / "001_fig4.png").is_file()
    assert main(["reproduce", "001", "--quick", "--quiet", "--figures", "figs"]) == 0
    assert (tmp_path / "figs" / "001_fig7b.png").is_file()
    capsys.readouterr()
    with pytest.raises(SystemExit) as exit_:
        main(["reproduce", "001", "--no-figures", "--figures", "x"])
    assert exit_.value.code == 2 and "not allowed with" in capsys.readouterr().err
    empty = tmp_path / "none"
    empty.mkdir()
    assert main(["reproduce", "001", "--quick", "--quiet", "--no-figures", "--json", str(empty / "a.json")]) == 0
    assert not list(empty.glob("*.png")) and "figures to" not in capsys.readouterr().out


def test_cli_refuses_a_figures_folder_that_is_a_file_before_the_work(tmp_path, capsys, monkeypatch):
    import tactip.reproduce
    from tactip.cli import main

    monkeypatch.setattr(tactip.reproduce, "reproduce", lambda *a, **k: pytest.fail("ran the work"))
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(SystemExit) as exit_:
        main(["reproduce", "001", "--figures", str(blocker)])
    assert exit_.value.code == 2 and "is a file, not a folder" in capsys.readouterr().err
    assert main(["reproduce", "001", "--figures", str(blocker / "sub")]) == 1
    assert "is a file" in capsys.readouterr().err



def test_a_figure_the_world_was_tuned_on_says_fit_in_its_title():
    from types import SimpleNamespace

    from tactip.reproduce.figures import figure_label

    assert [figure_label(n) for n in ("fig7b", "fig10", "table3", "fig7_sweep")] == \
        ["Fig. 7B", "Fig. 10", "Table III", "Fig. 7"]
    wide = [{"classes": 30, "class_width_mm": 1.0, "passive_error_mm": 4.0, "active_error_mm": 0.01,
             "active_taps": 2.0, "acuity_mm": 1.0}]
    tuned = SimpleNamespace(figure="Table II 300 classes: active error", measured=0.1, paper=0.12, unit="mm", fit=True)
    free = SimpleNamespace(figure="Table III 500 classes: active error", measured=0.2, paper=0.24, unit="mm",
                           fit=False)
    skin = [{"sensor": "skin", "classes": 50, "policy": "active", "error_mm": 0.1, "mean_taps": 4.0}]
    figures = make_figures(Report("000", "t", wide + skin, [tuned, free]))
    assert "FIT" in figures["table2"]._suptitle.get_text()
    assert "FIT" not in figures["table3"]._suptitle.get_text()
    rows = _rows_001()
    fig4 = SimpleNamespace(figure="Fig. 4 fixed, theta 0.9: shape error", measured=2.0, paper=2.2, unit="mm", fit=True)
    figures = make_figures(Report("001", "t", rows, [fig4]))
    assert ["FIT" in f._suptitle.get_text() for f in figures.values()] == [True, False, False, False]
