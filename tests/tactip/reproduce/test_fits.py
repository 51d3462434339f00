"""tactip.reproduce.fits: every tuned parameter is listed beside its figure, and that figure is marked a fit."""

from tactip.reproduce import PAPERS, Comparison, Report
from tactip.reproduce.fits import FITS, mark_fits


def test_every_paper_lists_its_fits():
    assert set(FITS) == set(PAPERS)
    assert all(fits and all(f.parameter and f.value and f.figure and f.marks for f in fits) for fits in FITS.values())


def test_fitted_figures_are_marked_and_predictions_are_not():
    report = Report("003", "t", [], [Comparison("Fig. 5 one depth class: texture error", 0.4, 0.4, "classes"),
                                      Comparison("Fig. 6B passive: texture error", 0.5, 0.5, "classes"),
                                      Comparison("Fig. 7 strongly active: texture error", 0.2, 0.4, "classes")],
                    ["a note"])
    marked = mark_fits(report)
    assert [c.fit for c in marked.comparisons] == [True, True, False]
    text = marked.text()
    assert text.count("(fit)") == 2 and "a note" in text
    assert "fit: tactip.reproduce.stimuli.Textures" in text and "tuned on Figs 5 and 6B" in text
    assert not any(c.fit for c in report.comparisons)                         # the report itself is unchanged


def test_the_skins_table_iii_is_a_prediction_though_its_name_starts_like_table_ii():
    report = Report("000", "t", [], [Comparison("Table II fingertip 300 classes: active error", 0.2, 0.2, "mm"),
                                      Comparison("Table III skin 100 classes: active error", 0.6, 0.6, "mm")], [])
    assert [c.fit for c in mark_fits(report).comparisons] == [True, False]
