"""`tactip reproduce 004 --quick` end to end: the bars of issue 10 and 25 on contour following (paper 004), a file of
its own so that pytest-xdist runs it beside the other papers' reproductions."""

import json

import pytest

from tactip.cli import main


@pytest.fixture(scope="module")
def rows_004(tmp_path_factory):
    out = tmp_path_factory.mktemp("004") / "004.json"
    assert main(["reproduce", "004", "--quick", "--quiet", "--json", str(out)]) == 0
    return json.loads(out.read_text())


def test_004_contour_following_and_the_adaptive_prior(rows_004):
    rows = rows_004
    keys = {"method", "threshold", "angle_error_deg", "position_error_mm", "taps_per_decision", "closed_contour",
            "delta_error_classes"}
    assert all(set(r) == keys for r in rows)
    assert {r["method"] for r in rows} == {"passive", "active", "adaptive", "adaptive_angle_only", "adaptive_shift0"}
    r = {(row["method"], row["threshold"]): row for row in rows}
    low, high = sorted({row["threshold"] for row in rows})
    # Fig. 6: only active perception at a high threshold traces the circle
    assert r["active", high]["closed_contour"] >= 0.9
    assert all(r[m, t]["closed_contour"] <= 0.1 for m, t in (("passive", low), ("passive", high), ("active", low)))
    # Fig. 7C: the adaptive prior decides in fewer taps, eq. 7 as printed and the angle-only variant alike
    for method in ("adaptive", "adaptive_angle_only"):
        assert r[method, high]["taps_per_decision"] < r["active", high]["taps_per_decision"]
    # Eq. 7 as printed carries the last decision's position belief into the next, stale after the straight step
    # along the tangent (0.45 mm further out per decision on the 30 mm circle): the traced points leave the 2 mm
    # band, though the pad never loses the edge (bench/bench_004_mechanism.py; seeds 0-2: 17-21 % of runs close
    # the contour, against 67-96 % with the angle-only prediction)
    assert r["adaptive", high]["closed_contour"] < r["adaptive_angle_only", high]["closed_contour"]
    # Fig. 8: the learned shift converges on the true turn (2 classes per decision)
    assert r["adaptive_angle_only", high]["delta_error_classes"] < 0.5
    # without the shift the prior is a handicap, not a gain
    assert r["adaptive_shift0", high]["angle_error_deg"] > r["active", high]["angle_error_deg"]
    assert r["active", high]["delta_error_classes"] is None


@pytest.mark.xfail(strict=False, reason="issue 25, the paper's claim fails in this world with eq. 7 as printed: at "
                                        "threshold 0.5 the adaptive angle error is 5.0-5.4 deg against active's "
                                        "3.0-3.6 (quick, seeds 0-2) and the contour closes in 17-21 % of runs; the "
                                        "angle-only variant is within -7..+10 % of active, not 0.9x. Causes "
                                        "(bench/bench_004_mechanism.py): the straight tangent step drifts 0.45 mm "
                                        "outward per decision, which the joint prior cannot predict, so traced "
                                        "points leave the 2 mm band (the edge is never lost); the learned Delta, "
                                        "fed ~5 taps per decision, is right in about half the decisions. Without "
                                        "the drift and with Delta = 2 the claim holds (seeds 0-2: 1.75-1.91 against "
                                        "2.93-3.36 deg; seeds 0-9: margin +1.09 deg [0.91, 1.27], 10 of 10). At full size "
                                        "the claim fails too (2026-11-28/29, seeds 0-9, ~470-630 s of CPU each): margin "
                                        "-2.32 deg [-2.51, -2.13], 0 of 10; adaptive 4.7-6.2 deg against active's "
                                        "2.97-3.77, closed in 3-13 % of runs (active 66-98 %)")
def test_004_the_adaptive_prior_lowers_the_angle_error_by_a_tenth_with_the_contour_closed(rows_004):
    from tactip.reproduce.seeds import claim_margin

    assert claim_margin("004", rows_004) > 0
