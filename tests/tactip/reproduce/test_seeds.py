"""tactip.reproduce.seeds: a claim is judged from its margins' interval over seeds, never from one seed."""

import numpy as np
import pytest

from tactip.reproduce.seeds import CLAIMS, claim_margin, judge_claim


def _003_rows(passive, weakly, strongly):
    return [{"move_threshold": m, "texture_error_classes": e} for m, e in ((1.5, passive), (0.999, weakly),
                                                                            (0.05, strongly))]


def test_003_margin_is_the_smaller_of_its_two_conditions():
    assert claim_margin("003", _003_rows(1.4, 1.2, 0.4)) == pytest.approx(min(0.7 - 0.4, 1.4 - 1.2))
    assert claim_margin("003", _003_rows(1.4, 1.5, 0.4)) == pytest.approx(-0.1)     # weakly worse than passive


def test_002_margin_compares_the_policies_at_10_taps():
    rows = [{"policy": p, "mean_taps": t, "width_error_mm": e} for p, (e5, e15) in
            {"active": (0.4, 0.2), "random": (0.6, 0.4), "stationary": (0.9, 0.7)}.items()
            for t, e in ((5.0, e5), (15.0, e15))]
    assert claim_margin("002", rows) == pytest.approx(0.2)                          # 0.3, 0.5, 0.8 at 10 taps
    # the variant (the station's own fixation) is a row of its own: the claim judges the faithful active row,
    # and `VARIANTS` judges the variant beside it
    from tactip.reproduce.p002 import STATION_FIXATION
    from tactip.reproduce.seeds import VARIANTS

    rows += [{"policy": STATION_FIXATION, "mean_taps": t, "width_error_mm": e} for t, e in ((5.0, 0.8), (15.0, 0.6))]
    assert claim_margin("002", rows) == pytest.approx(0.2)
    (name, read), = VARIANTS["002"]
    assert name == STATION_FIXATION
    assert claim_margin("002", read(rows)) == pytest.approx(0.5 - 0.7)               # variant 0.7 at 10 taps


def test_004_an_open_contour_fails_whatever_the_angle():
    rows = [{"method": "active", "threshold": 0.5, "angle_error_deg": 10.0, "closed_contour": 1.0},
            {"method": "adaptive", "threshold": 0.5, "angle_error_deg": 5.0, "closed_contour": 1.0}]
    assert claim_margin("004", rows) == pytest.approx(4.0)
    rows[1]["closed_contour"] = 0.2
    assert claim_margin("004", rows) < 0


def test_verdicts_come_from_the_interval():
    # weakly active far below passive: the strongly active margin decides
    held = judge_claim("003", {s: _003_rows(1.4, 0.5, 0.7 - m) for s, m in enumerate([0.3, 0.35, 0.25, 0.3])})
    assert held.verdict == "holds" and np.allclose(held.margins, [0.3, 0.35, 0.25, 0.3])
    assert held.mean == pytest.approx(0.3) and 0 < held.interval[0] < 0.3 < held.interval[1]
    mixed = judge_claim("003", {s: _003_rows(1.4, 0.5, 0.7 - m) for s, m in enumerate([0.3, -0.05, 0.2])})
    assert mixed.verdict == "partly holds" and mixed.mean > 0 and mixed.interval[0] < 0
    failed = judge_claim("003", {s: _003_rows(1.4, 0.5, 0.7 - m) for s, m in enumerate([-0.1, 0.05, -0.2])})
    assert failed.verdict == "fails"
    one = judge_claim("003", {0: _003_rows(1.4, 1.2, 0.4)})
    assert one.verdict == "partly holds" and one.interval == (one.mean, one.mean)   # one seed is not a claim
    assert "held on 1 of 1 seeds" in one.line() and one.json()["verdict"] == "partly holds"


def _000_rows(passive, active):
    return [{"sensor": "skin", "classes": 25, "policy": "passive", "error_mm": passive},
            {"sensor": "skin", "classes": 25, "policy": "active", "error_mm": active}]


def test_a_tie_holds_a_claim_of_no_larger_than_and_not_a_strict_one():
    # 000 says active <= passive: equal errors on a seed hold it.
    ties = judge_claim("000", {s: _000_rows(0.3, 0.3 - m) for s, m in enumerate([0.0, 0.0, 0.0])})
    assert ties.verdict == "holds" and ties.held().all() and "held on 3 of 3 seeds" in ties.line()
    one_tie = judge_claim("000", {s: _000_rows(0.3, 0.3 - m) for s, m in enumerate([0.0, 0.02, 0.04])})
    assert one_tie.held().all() and one_tie.verdict == "partly holds"      # the interval reaches below 0
    worse = judge_claim("000", {s: _000_rows(0.3, 0.3 - m) for s, m in enumerate([0.0, -0.01, 0.0])})
    assert worse.verdict == "fails" and worse.held().sum() == 2
    # 003's weakly active must be below passive: a tie does not hold it.
    strict = judge_claim("003", {s: _003_rows(1.4, 1.4, 0.4) for s in range(3)})
    assert not strict.held().any() and strict.verdict == "fails"


def test_every_paper_has_a_claim():
    assert set(CLAIMS) == {"000", "001", "002", "003", "004"}
    with pytest.raises(ValueError, match="no claim"):
        claim_margin("005", [])


def test_000_margin_is_the_skin_rows_smallest_gain():
    rows = [{"sensor": s, "classes": n, "policy": p, "error_mm": e} for s, n, p, e in (
        ("skin", 25, "passive", 0.10), ("skin", 25, "active", 0.02), ("skin", 500, "passive", 0.80),
        ("skin", 500, "active", 0.75), ("fingertip", 300, "passive", 4.0), ("fingertip", 300, "active", 4.5))]
    assert claim_margin("000", rows) == pytest.approx(0.05)                         # the fingertip does not count
    rows[3]["error_mm"] = 0.85
    assert claim_margin("000", rows) == pytest.approx(-0.05)


def _001_rows(fixed, five):
    return [{"deadline": d, "threshold": t, "shape_error_mm": s, "position_error_mm": p, "forced_fraction": f}
            for d, errors in ((None, fixed), (5, five)) for t, (s, p, f) in errors.items()]


def test_001_margin_is_the_worst_threshold_at_or_above_0_99():
    fixed = {0.5: (2.3, 0.2, 0.0), 0.99: (2.3, 0.2, 0.0), 0.999: (2.2, 0.2, 0.0)}
    five = {0.5: (9.0, 9.0, 0.0), 0.99: (2.3, 0.1, 0.0), 0.999: (2.2 * 1.02, 0.15, 0.0)}   # 0.5 is not judged
    assert claim_margin("001", _001_rows(fixed, five)) == pytest.approx(0.03)       # 0.05 - 0.02 shape at 0.999
    five[0.99] = (float("nan"), float("nan"), 0.6)                                  # runs that never decide
    assert claim_margin("001", _001_rows(fixed, five)) == pytest.approx(-0.6)
