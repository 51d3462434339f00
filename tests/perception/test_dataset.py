"""The tactip-dataset/1 contract: round trip, every error, and the resumable writer."""

import json
import shutil

import h5py
import numpy as np
import pytest

from perception import SCHEMA, Dataset, DatasetError, DatasetWriter, load_dataset, save_dataset


def make_dataset(n=6, samples=5, dims=3, *, lateral=True, seed=0):
    rng = np.random.default_rng(seed)
    return Dataset(rng.normal(size=(n, samples, dims)), np.linspace(0, 5, n), rng.choice([0.25, 0.5], n),
                   rng.uniform(-1, 1, n) if lateral else None, "tactip", dim_names=[f"p{k}" for k in range(dims)],
                   sensor={"kind": "synthetic", "pins": dims // 2})


def test_round_trip_keeps_every_field(tmp_path):
    ds = make_dataset()
    save_dataset(tmp_path / "d.h5", ds)
    back = load_dataset(tmp_path / "d.h5")
    np.testing.assert_array_equal(back.taps, ds.taps)
    np.testing.assert_array_equal(back.location, ds.location)
    np.testing.assert_array_equal(back.identity, ds.identity)
    np.testing.assert_array_equal(back.lateral, ds.lateral)
    assert back.taps.dtype == np.float32 and back.location.dtype == np.float64
    assert (back.front_end, back.dim_names, back.sensor) == ("tactip", ("p0", "p1", "p2"), ds.sensor)
    with h5py.File(tmp_path / "d.h5") as f:
        assert f.attrs["schema"] == SCHEMA
        assert json.loads(f.attrs["sensor"]) == {"kind": "synthetic", "pins": 1}


def test_round_trip_without_lateral_and_one_location(tmp_path):
    ds = Dataset(np.ones((3, 2, 1)), np.zeros(3), [1.0, 2.0, 3.0], None, "taxel", identity_unit="none")
    save_dataset(tmp_path / "d.h5", ds)
    back = load_dataset(tmp_path / "d.h5")
    assert back.lateral is None and back.identity_unit == "none" and back.dim_names == ("dim00",)


def test_save_is_atomic_and_leaves_no_temporary(tmp_path):
    save_dataset(tmp_path / "d.h5", make_dataset())
    save_dataset(tmp_path / "d.h5", make_dataset(n=2))
    assert [p.name for p in tmp_path.iterdir()] == ["d.h5"]
    assert len(load_dataset(tmp_path / "d.h5")) == 2


@pytest.mark.parametrize("change, field", [
    ({"taps": np.zeros((4, 5))}, "taps"),
    ({"location": np.zeros(5)}, "location"),
    ({"identity": np.zeros((6, 1))}, "identity"),
    ({"lateral": np.zeros(2)}, "lateral"),
    ({"front_end": "camera"}, "front_end"),
    ({"dim_names": ("a",)}, "dim_names"),
    ({"sensor": {"when": object()}}, "sensor"),
])
def test_dataset_refuses_bad_fields_naming_them(change, field):
    ds = make_dataset()
    kwargs = {name: getattr(ds, name) for name in ("taps", "location", "identity", "lateral", "front_end",
                                                   "dim_names", "sensor")}
    kwargs.update(change)
    with pytest.raises(DatasetError, match=field):
        Dataset(**kwargs)


@pytest.mark.parametrize("field", ["location", "identity", "lateral"])
def test_dataset_refuses_nan_labels(field):
    ds = make_dataset()
    arrays = {name: getattr(ds, name).copy() for name in ("taps", "location", "identity", "lateral")}
    arrays[field].reshape(-1)[3] = np.nan
    with pytest.raises(DatasetError, match=f"{field} holds NaN"):
        Dataset(arrays["taps"], arrays["location"], arrays["identity"], arrays["lateral"], "tactip")


def test_dataset_holds_missing_values_but_refuses_infinite_ones_and_empty_taps(tmp_path):
    ds = make_dataset()
    taps = ds.taps.copy()
    taps[1, :, 2] = np.nan                                   # a dimension missing from one tap
    missing = Dataset(taps, ds.location, ds.identity, ds.lateral, "tactip")
    assert not missing.complete and ds.complete and missing.observed.sum() == taps.size - taps.shape[1]
    assert "(1 with missing dims)" in missing.describe()
    save_dataset(tmp_path / "m.h5", missing)
    np.testing.assert_array_equal(load_dataset(tmp_path / "m.h5").taps, taps)
    taps[2, 0, 0] = np.inf
    with pytest.raises(DatasetError, match=r"taps holds infinite values \(first in tap 2\)"):
        Dataset(taps, ds.location, ds.identity, ds.lateral, "tactip")
    taps[2, 0, 0], taps[4] = 0.0, np.nan
    with pytest.raises(DatasetError, match=r"1 tap\(s\) with no observed value \(all NaN; first: tap 4\)"):
        Dataset(taps, ds.location, ds.identity, ds.lateral, "tactip")


def test_load_refuses_another_schema(tmp_path):
    with h5py.File(tmp_path / "m.h5", "w") as f:
        f.attrs["schema"] = "tactip-model/1"
    with pytest.raises(DatasetError, match="not a tactip-dataset/1 file.*tactip-model/1"):
        load_dataset(tmp_path / "m.h5")


def test_load_refuses_missing_fields(tmp_path):
    save_dataset(tmp_path / "d.h5", make_dataset())
    with h5py.File(tmp_path / "d.h5", "r+") as f:
        del f["identity"]
        del f.attrs["front_end"]
    with pytest.raises(DatasetError, match="misses identity, front_end"):
        load_dataset(tmp_path / "d.h5")


def test_load_refuses_mismatched_lengths(tmp_path):
    save_dataset(tmp_path / "d.h5", make_dataset())
    with h5py.File(tmp_path / "d.h5", "r+") as f:
        f["location"].resize(4, axis=0)
    with pytest.raises(DatasetError, match="mismatched lengths: taps 6, location 4"):
        load_dataset(tmp_path / "d.h5")


def test_load_refuses_infinite_values_in_file_naming_the_file(tmp_path):
    save_dataset(tmp_path / "d.h5", make_dataset())
    with h5py.File(tmp_path / "d.h5", "r+") as f:
        f["taps"][2, 0, 0] = -np.inf
        f["location"][3] = np.nan
    with pytest.raises(DatasetError, match=r"d\.h5: taps holds infinite values \(first in tap 2\)"):
        load_dataset(tmp_path / "d.h5")


def test_load_refuses_non_hdf5_and_missing_file(tmp_path):
    (tmp_path / "x.h5").write_text("not hdf5")
    with pytest.raises(DatasetError, match="not an HDF5 file"):
        load_dataset(tmp_path / "x.h5")
    with pytest.raises(FileNotFoundError):
        load_dataset(tmp_path / "missing.h5")


def test_writer_appends_and_resumes(tmp_path):
    ds = make_dataset(n=5)
    path = tmp_path / "w.h5"
    kwargs = dict(samples=5, dims=3, front_end="tactip", dim_names=ds.dim_names, sensor=ds.sensor)
    with DatasetWriter(path, **kwargs) as writer:
        for k in range(3):
            writer.append(ds.taps[k], ds.location[k], ds.identity[k], lateral=ds.lateral[k])
        assert writer.count == 3
    with DatasetWriter(path, **kwargs) as writer:
        assert writer.count == 3
        for k in range(3, 5):
            writer.append(ds.taps[k], ds.location[k], ds.identity[k], lateral=ds.lateral[k])
    back = load_dataset(path)
    np.testing.assert_array_equal(back.taps, ds.taps)
    np.testing.assert_array_equal(back.lateral, ds.lateral)
    assert back.sensor == ds.sensor


def test_writer_flushes_each_tap_so_a_crash_keeps_it(tmp_path):
    path = tmp_path / "w.h5"
    writer = DatasetWriter(path, samples=2, dims=1, front_end="taxel")
    writer.append(np.ones((2, 1)), 1.0, 0.0)
    writer.append(np.full((2, 1), 2.0), 3.0, 0.0)
    shutil.copy(path, tmp_path / "crash.h5")  # the bytes on disk while the writer is still open
    back = load_dataset(tmp_path / "crash.h5")
    np.testing.assert_array_equal(back.location, [1.0, 3.0])
    np.testing.assert_array_equal(back.taps[1], np.full((2, 1), 2.0))
    writer.close()


def test_writer_resume_drops_a_half_written_tap(tmp_path):
    path = tmp_path / "w.h5"
    with DatasetWriter(path, samples=2, dims=1, front_end="taxel") as writer:
        writer.append(np.ones((2, 1)), 1.0, 0.0)
        writer.append(np.ones((2, 1)), 2.0, 0.0)
    with h5py.File(path, "r+") as f:  # a crash after growing taps, before the labels
        f["taps"].resize(3, axis=0)
    with DatasetWriter(path, samples=2, dims=1, front_end="taxel") as writer:
        assert writer.count == 2
    assert len(load_dataset(path)) == 2


@pytest.mark.parametrize("change, field", [
    ({"samples": 4}, r"\(samples, dims\)"),
    ({"front_end": "tactip"}, "front_end"),
    ({"sensor": {"kind": "other"}}, "sensor"),
    ({"location_unit": "deg"}, "location_unit"),
])
def test_writer_refuses_to_resume_a_different_file(tmp_path, change, field):
    kwargs = dict(samples=2, dims=1, front_end="taxel", sensor={"kind": "fingertip"})
    with DatasetWriter(tmp_path / "w.h5", **kwargs) as writer:
        writer.append(np.ones((2, 1)), 1.0, 0.0)
    with pytest.raises(DatasetError, match=field):
        DatasetWriter(tmp_path / "w.h5", **{**kwargs, **change})


def test_writer_refuses_bad_taps(tmp_path):
    with DatasetWriter(tmp_path / "w.h5", samples=2, dims=1, front_end="taxel") as writer:
        with pytest.raises(DatasetError, match="infinite"):
            writer.append(np.array([[1.0], [np.inf]]), 1.0, 0.0)
        with pytest.raises(DatasetError, match="no observed value"):
            writer.append(np.array([[np.nan], [np.nan]]), 1.0, 0.0)
        with pytest.raises(DatasetError, match="shape"):
            writer.append(np.ones((3, 1)), 1.0, 0.0)
        with pytest.raises(DatasetError, match="location must be finite"):
            writer.append(np.ones((2, 1)), np.nan, 0.0)
        writer.append(np.ones((2, 1)), 1.0, 0.0)
        with pytest.raises(DatasetError, match="lateral given for tap 1"):
            writer.append(np.ones((2, 1)), 1.0, 0.0, lateral=0.5)
        writer.append(np.array([[np.nan], [2.0]]), 1.0, 0.0)     # a missing value is stored
        assert writer.count == 2
    assert np.isnan(load_dataset(tmp_path / "w.h5").taps[1, 0, 0])


def test_subset_keeps_metadata():
    ds = make_dataset()
    part = ds.subset(ds.location > 2)
    assert len(part) == 3 and part.sensor == ds.sensor and part.dim_names == ds.dim_names
    np.testing.assert_array_equal(part.lateral, ds.lateral[3:])


# -- issue 9: counted taps, protocol on resume, numbers only -------------------------------------------

def test_only_counted_taps_are_read_or_resumed(tmp_path):
    path = tmp_path / "d.h5"
    with DatasetWriter(path, samples=5, dims=3, front_end="tactip") as writer:
        for k in range(4):
            writer.append(np.full((5, 3), k + 1.0), location=float(k), identity=1.0)
    with h5py.File(path, "r+") as f:                   # the arrays grew, the data never landed (full disk)
        assert f.attrs["complete_taps"] == 4
        for name in ("taps", "location", "identity"):
            f[name].resize(6, axis=0)
    assert len(load_dataset(path)) == 4 and load_dataset(path).taps.min() == 1.0
    with DatasetWriter(path, samples=5, dims=3, front_end="tactip") as writer:
        assert writer.count == 4
        writer.append(np.full((5, 3), 9.0), location=4.0, identity=1.0)
    assert load_dataset(path).taps[:, 0, 0].tolist() == [1.0, 2.0, 3.0, 4.0, 9.0]


def test_a_resume_with_another_protocol_names_the_setting(tmp_path):
    path = tmp_path / "d.h5"
    with DatasetWriter(path, samples=5, dims=3, front_end="tactip", protocol={"seed": 1, "repeats": 2}) as writer:
        writer.append(np.ones((5, 3)), location=0.0, identity=1.0)
    with pytest.raises(DatasetError, match="protocol seed = 1, not 2"):
        DatasetWriter(path, samples=5, dims=3, front_end="tactip", protocol={"seed": 2, "repeats": 2})
    with DatasetWriter(path, samples=5, dims=3, front_end="tactip", protocol={"seed": 1, "repeats": 2}) as writer:
        assert writer.count == 1


def test_taps_that_are_not_numbers_are_refused_naming_the_dataset(tmp_path):
    save_dataset(tmp_path / "d.h5", make_dataset())
    with h5py.File(tmp_path / "d.h5", "r+") as f:
        del f["taps"]
        f.create_dataset("taps", data=np.array([b"tap"] * 6))
    with pytest.raises(DatasetError, match="dataset 'taps' holds .* not numbers"):
        load_dataset(tmp_path / "d.h5")


def test_save_dataset_refuses_to_overwrite_an_input(tmp_path):
    save_dataset(tmp_path / "d.h5", make_dataset())
    before = (tmp_path / "d.h5").read_bytes()
    with pytest.raises(FileExistsError, match="is the input"):
        save_dataset(tmp_path / "d.h5", make_dataset(n=2), inputs=[tmp_path / "d.h5"])
    assert (tmp_path / "d.h5").read_bytes() == before
