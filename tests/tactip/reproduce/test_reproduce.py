"""`tactip reproduce PAPER --quick` end to end: JSON rows and the bars of issue 10.

The quick runs are the session's (`quick_reproduction`, tests/tactip/conftest.py): the CLI run once per paper.
"""

import numpy as np
import pytest

from tactip.cli import main


@pytest.fixture(scope="module")
def run_001(quick_reproduction):
    rows, text, _ = quick_reproduction("001")       # the session's run, which test_cluster.py compares with Dask's
    return rows, text


def test_001_deadline_and_relocation(run_001):
    rows, text = run_001
    keys = {"deadline", "threshold", "shape_error_mm", "position_error_mm", "reaction_taps", "null_fraction",
            "forced_fraction"}
    assert all(set(r) == keys for r in rows)
    by = {d: sorted((r for r in rows if r["deadline"] == d), key=lambda r: r["threshold"]) for d in (None, 5, 10)}
    assert by[None][-1]["threshold"] >= 0.99                                   # the paper's thresholds
    assert all(r["position_error_mm"] < 1.0 for r in rows if r["position_error_mm"] is not None)   # hyperacuity
    assert all(r["forced_fraction"] < 0.05 for r in by[None])                  # no cap: fixed runs decide
    assert all(r["null_fraction"] == 0 for r in by[None])
    for d in (5, 10):
        # a deadline run either decides (every mean defined) or its rod never decides (means undefined)
        for r in by[d]:
            assert (r["forced_fraction"] == 0) == (r["shape_error_mm"] is not None) == (r["reaction_taps"] is not None)
        nulls = [r["null_fraction"] for r in by[d]]                            # Fig. 6: rises with theta ...
        assert np.all(np.diff(nulls) >= 0) and nulls[-1] > nulls[0]
    for short, long in zip(by[5], by[10]):                                     # ... and with shorter deadlines
        assert short["null_fraction"] >= long["null_fraction"]
    # Fig. 5: at a matched mean reaction time, deadline 5 lowers both errors
    fixed_taps = [r["reaction_taps"] for r in by[None]]
    matched = [r for r in by[5] if r["reaction_taps"] is not None and r["null_fraction"] > 0.1
               and fixed_taps[0] <= r["reaction_taps"] <= fixed_taps[-1]]
    assert matched
    for r in matched:
        for error in ("shape_error_mm", "position_error_mm"):
            assert r[error] < np.interp(r["reaction_taps"], fixed_taps, [f[error] for f in by[None]])
    assert "never decide" in text


@pytest.mark.xfail(strict=False, reason="issue 25, the simulated rods give ~0.15 nats per tap (fixed perception needs "
                                        "~44 taps to reach 0.99): at theta >= 0.99 most rods never decide within a "
                                        "5-tap attempt (seed 0: 3 of 5 in 2000 attempts each), so deadline-5 runs "
                                        "on them never end and the paper's comparison has no value")
def test_001_deadline_5_lowers_the_position_error_at_the_paper_thresholds(run_001):
    from tactip.reproduce.seeds import claim_margin

    assert claim_margin("001", run_001[0]) > 0


@pytest.fixture(scope="module")
def rows_000(quick_reproduction):
    rows, text, _ = quick_reproduction("000")
    assert "Table III" in text
    return rows


def test_000_tables_ii_and_iii_rows(rows_000):
    from tactip.reproduce.acuity import TABLE3_CLASSES

    keys = {"sensor", "classes", "class_width_mm", "policy", "error_mm", "mean_taps", "threshold", "fixation_mm"}
    assert all(set(r) == keys for r in rows_000)
    by = {(r["sensor"], r["classes"], r["policy"]): r for r in rows_000}
    assert len(by) == len(rows_000)
    skin = sorted({n for s, n, _ in by if s == "skin"})
    assert skin == sorted(TABLE3_CLASSES)                                      # every count of Table III
    for sensor, fixation, budget in (("fingertip", 15.0, 2.0), ("skin", 37.0, 4.0)):   # the paper's protocol
        counts = {n for s, n, _ in by if s == sensor}
        for n in counts:
            passive, active = by[sensor, n, "passive"], by[sensor, n, "active"]
            assert passive["fixation_mm"] is None and active["fixation_mm"] == fixation
            assert passive["mean_taps"] <= budget and active["mean_taps"] <= budget
            assert active["class_width_mm"] == pytest.approx((30.0 if sensor == "fingertip" else 50.0) / n, rel=1e-3)
    # Table II: active perception is hyperacute on the fingertip, passive is not (paper: 0.12 against 4.5 mm)
    assert by["fingertip", 300, "active"]["error_mm"] <= 0.2
    assert by["fingertip", 300, "passive"]["error_mm"] >= 10 * by["fingertip", 300, "active"]["error_mm"]
    # Table III: the skin is hyperacute too (sub-mm against a 4 mm taxel spacing), active or passive
    assert all(by["skin", n, p]["error_mm"] < 1.0 for n in skin for p in ("passive", "active"))


@pytest.mark.xfail(strict=False, reason="issue 25, the simulated skin has no sweet spot (its passive acuity is about "
                                        "the same everywhere), so fixating at the paper's 37 mm gains 0-10 %, within "
                                        "Monte Carlo noise at fine class counts: seed 0 quick, 250 classes, active "
                                        "0.354 against passive 0.343 mm (5000 runs: 0.346 against 0.365). The quick "
                                        "margin moves by up to 0.02 mm between Monte Carlo seeds of one sensor; at "
                                        "5000 runs, sensor seeds 0-9: -0.033 mm [-0.094, 0.028], held on 6 of 10 "
                                        "(bench/bench_000_skin_fixation.py)")
def test_000_skin_active_no_worse_than_passive_at_every_class_count(rows_000):
    from tactip.reproduce.seeds import claim_margin

    assert claim_margin("000", rows_000) >= 0


def test_003_active_touch_beats_passive(quick_reproduction):
    rows, text, _ = quick_reproduction("003")
    assert "paper 003:" in text and "paper " in text.splitlines()[1]
    error = {r["move_threshold"]: r["texture_error_classes"] for r in rows}
    assert set(error) == {1.5, 0.999, 0.05} and all("mean_taps" in r for r in rows)
    assert error[0.05] <= 0.5 * error[1.5]                                     # paper: 0.4 against 1.4
    assert error[0.05] < error[0.999] <= error[1.5]
    assert "Fig. 5" in text and "Fig. 6B" in text


def test_unknown_papers(capsys):
    with pytest.raises(SystemExit):
        main(["reproduce", "005"])
