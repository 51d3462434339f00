"""The collection plan and the resumable collection, with a cheap deterministic tap function."""

import dataclasses

from pathlib import Path

import numpy as np
import pytest

from calibration import SETS, CalibrationError, collect_datasets, collection_plan, tap_seed
from perception import DatasetError, load_dataset
from tactip.station.config import GapConfig

GAPS = (GapConfig("a", 0.0, 0.0, 0.5, 0.25), GapConfig("b", 30.0, 0.0, 1.5, 0.25), GapConfig("c", 60.0, 0.0, 2.5, 0.25))
DEPTHS = [0.0, 1.0, 2.0, 3.0]
SAMPLES, DIMS = 6, 4
SENSOR = {"kind": "tactip", "pins": 331, "selected_pins": 2}


def fake_tap(planned):
    """Features that depend only on the planned tap (its seed), like the simulated station's."""
    return np.random.default_rng(planned.seed).normal(planned.depth_mm, 1.0, (SAMPLES, DIMS)).astype(np.float32)


def collect(plan, out_dir, **kwargs):
    options = dict(samples=SAMPLES, dims=DIMS, sensor=SENSOR, progress=False)
    return collect_datasets(kwargs.pop("tap", fake_tap), plan, out_dir, **{**options, **kwargs})


def test_plan_order_and_counts():
    plan = collection_plan(GAPS, DEPTHS, repeats=2, seed=3)
    assert list(plan) == list(SETS) == ["train", "test"]
    for set_name, taps in plan.items():
        assert len(taps) == len(GAPS) * len(DEPTHS) * 2
        assert [t.index for t in taps] == list(range(len(taps)))
        assert all(t.set == set_name for t in taps)
        # gap-major, then depth, then repeat
        assert [(t.gap.name, t.depth_mm, t.repeat) for t in taps] == [
            (g.name, d, r) for g in GAPS for d in DEPTHS for r in range(2)]
        assert [t.width_mm for t in taps] == [g.nominal_width for g in GAPS for _ in DEPTHS for _ in range(2)]
    assert len({t.seed for taps in plan.values() for t in taps}) == 2 * len(plan["train"])   # every tap its own


def test_seeds_depend_only_on_seed_set_gap_depth_and_repeat():
    plan = collection_plan(GAPS, DEPTHS, repeats=2, lateral_jitter_mm=0.5, seed=3)
    assert plan == collection_plan(GAPS, DEPTHS, repeats=2, lateral_jitter_mm=0.5, seed=3)
    for taps in plan.values():
        for t in taps:
            assert t.seed == tap_seed(3, t.set, GAPS.index(t.gap), DEPTHS.index(t.depth_mm), t.repeat)
    # a plan of one set, or with an extra gap and depth at the end, keeps every tap it shares
    alone = collection_plan(GAPS, DEPTHS, repeats=2, lateral_jitter_mm=0.5, seed=3, sets=("test",))
    assert alone["test"] == plan["test"]
    more = collection_plan(GAPS + (GapConfig("d", 90.0, 0.0, 3.5, 0.25),), DEPTHS + [4.0], repeats=2,
                           lateral_jitter_mm=0.5, seed=3)
    shared = {(t.gap.name, t.depth_mm, t.repeat): (t.seed, t.lateral_mm) for t in more["train"]}
    assert all(shared[t.gap.name, t.depth_mm, t.repeat] == (t.seed, t.lateral_mm) for t in plan["train"])


def test_another_seed_changes_the_seeds_and_the_jitter():
    a = collection_plan(GAPS, DEPTHS, lateral_jitter_mm=0.5, seed=3)["train"]
    b = collection_plan(GAPS, DEPTHS, lateral_jitter_mm=0.5, seed=4)["train"]
    assert not {t.seed for t in a} & {t.seed for t in b}
    assert all(x.lateral_mm != y.lateral_mm for x, y in zip(a, b))
    assert [(t.gap, t.depth_mm) for t in a] == [(t.gap, t.depth_mm) for t in b]


def test_lateral_jitter_is_uniform_within_the_half_width():
    plan = collection_plan(GAPS, np.linspace(0, 5, 200), lateral_jitter_mm=0.8, seed=0)
    lateral = np.array([t.lateral_mm for taps in plan.values() for t in taps])
    assert np.abs(lateral).max() <= 0.8
    assert lateral.min() < -0.7 and lateral.max() > 0.7 and abs(lateral.mean()) < 0.05   # 1200 draws
    assert not any(t.lateral_mm for t in collection_plan(GAPS, DEPTHS, seed=0)["train"])


@pytest.mark.parametrize("gaps, depths, repeats, message", [
    ((), DEPTHS, 1, "no gaps"), (GAPS, [], 1, "no depths"), (GAPS, DEPTHS, 0, "repeats")])
def test_an_empty_plan_is_refused(gaps, depths, repeats, message):
    with pytest.raises(CalibrationError, match=message):
        collection_plan(gaps, depths, repeats=repeats)


def test_collection_stores_the_plan_with_its_labels(tmp_path):
    plan = collection_plan(GAPS, DEPTHS, lateral_jitter_mm=0.3, seed=1)
    paths = collect(plan, tmp_path / "out", dim_names=["a", "b", "c", "d"])
    assert paths == {"train": tmp_path / "out" / "train.h5", "test": tmp_path / "out" / "test.h5"}
    for set_name, taps in plan.items():
        data = load_dataset(paths[set_name])
        assert np.array_equal(data.taps, np.stack([fake_tap(t) for t in taps]))
        assert np.array_equal(data.location, [t.depth_mm for t in taps])
        assert np.array_equal(data.identity, [t.width_mm for t in taps])
        assert np.array_equal(data.lateral, [t.lateral_mm for t in taps])
        assert data.sensor == SENSOR and data.dim_names == ("a", "b", "c", "d") and data.front_end == "tactip"


def test_an_interrupted_collection_resumes_to_the_same_files(tmp_path):
    plan = collection_plan(GAPS, DEPTHS, lateral_jitter_mm=0.3, seed=1)
    whole = collect(plan, tmp_path / "whole")
    calls = []

    def interrupted(planned):
        if len(calls) == 17:              # in the test set: train is complete, test has 5 taps
            raise KeyboardInterrupt
        calls.append(planned)
        return fake_tap(planned)

    with pytest.raises(KeyboardInterrupt):
        collect(plan, tmp_path / "resumed", tap=interrupted)
    assert len(load_dataset(tmp_path / "resumed" / "test.h5")) == 5
    resumed_calls = []
    collect(plan, tmp_path / "resumed", tap=lambda t: resumed_calls.append(t) or fake_tap(t))
    assert resumed_calls == plan["test"][5:]               # only what was missing was tapped
    for set_name in plan:
        a, b = load_dataset(whole[set_name]), load_dataset(tmp_path / "resumed" / f"{set_name}.h5")
        for name in ("taps", "location", "identity", "lateral"):
            assert np.array_equal(getattr(a, name), getattr(b, name)), (set_name, name)


def test_tap_many_is_used_in_plan_order(tmp_path):
    plan = collection_plan(GAPS, DEPTHS, seed=1)
    seen = []

    def tap_many(planned):
        planned = list(planned)
        seen.append(planned)
        return (fake_tap(t) for t in planned)

    paths = collect(plan, tmp_path, tap=None, tap_many=tap_many)
    assert seen == [plan["train"], plan["test"]]
    assert np.array_equal(load_dataset(paths["test"]).taps, np.stack([fake_tap(t) for t in plan["test"]]))


def test_a_dataset_of_another_protocol_is_refused(tmp_path):
    big = collection_plan(GAPS, DEPTHS, repeats=2, seed=1)
    collect(big, tmp_path)
    small = collection_plan(GAPS, DEPTHS, repeats=1, seed=1)
    with pytest.raises(CalibrationError, match="another protocol"):
        collect(small, tmp_path)
    assert len(load_dataset(tmp_path / "train.h5")) == len(big["train"])    # untouched


@pytest.mark.parametrize("change, field", [
    (dict(sensor={**SENSOR, "pins": 127}), "sensor"),
    (dict(dims=DIMS + 2), "dims"),
    (dict(front_end="taxel"), "front_end"),
])
def test_a_dataset_of_another_sensor_is_refused(tmp_path, change, field):
    plan = collection_plan(GAPS, DEPTHS, seed=1)
    collect({k: v[:2] for k, v in plan.items()}, tmp_path)
    with pytest.raises(DatasetError, match=field if field != "dims" else "samples, dims"):
        collect(plan, tmp_path, **change)


def test_planned_taps_are_frozen():
    tap = collection_plan(GAPS, DEPTHS)["train"][0]
    with pytest.raises(dataclasses.FrozenInstanceError):
        tap.seed = 0


def test_a_crash_while_creating_the_files_does_not_block_the_rerun(tmp_path, monkeypatch):
    # A kill before the first tap used to leave an empty train.h5 that the rerun refused as
    # "not a tactip-dataset/1 file (schema None)".
    import perception._dataset_writer as writer_module  # DatasetWriter writes the attributes

    plan = collection_plan(GAPS, DEPTHS, seed=1)
    write_attributes = writer_module._write_attributes

    def crash(f, *args):
        write_attributes(f, *args)
        if Path(f.filename).name.startswith((".test.", "test.")):
            raise KeyboardInterrupt                        # train.h5 made, test.h5 half made

    monkeypatch.setattr(writer_module, "_write_attributes", crash)
    with pytest.raises(KeyboardInterrupt):
        collect(plan, tmp_path)
    monkeypatch.setattr(writer_module, "_write_attributes", write_attributes)
    paths = collect(plan, tmp_path)
    assert np.array_equal(load_dataset(paths["test"]).taps, np.stack([fake_tap(t) for t in plan["test"]]))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["test.h5", "train.h5"]
