"""The labels CSV, label schemes (numbers, names, angles, classes) and the splits, against known answers."""

import numpy as np
import pytest

from perception import DatasetError
from perception.dataset import check_identity_labels
from tactip.dataset import LabelScheme, LabelsError, alternate_split, column_split, group_split, read_labels


def test_read_labels_resolves_paths_against_the_csv_and_keeps_line_numbers(tmp_path):
    folder = tmp_path / "set"
    folder.mkdir()
    (folder / "labels.csv").write_text("path,depth_mm,rest,split\n"
                                       "a.avi,1.5,,train\n\n"
                                       "sub/b.png, 2.0 ,rest.png,TEST\n"
                                       "c.avi,3.0\n")
    rows, column, problems = read_labels(folder / "labels.csv")
    assert column == "depth_mm"
    assert [r.line for r in rows] == [2, 4]
    assert rows[1].path == folder / "sub" / "b.png" and rows[1].rest == folder / "rest.png"
    assert rows[1].label == "2.0" and rows[1].split == "test" and rows[0].rest is None
    assert problems == [(5, "2 fields, the header has 4")]


def test_the_label_column_must_be_named_when_there_are_several(tmp_path):
    (tmp_path / "l.csv").write_text("path,depth_mm,angle_deg\na,1,2\n")
    with pytest.raises(LabelsError, match="--label .*depth_mm, angle_deg"):
        read_labels(tmp_path / "l.csv")
    assert read_labels(tmp_path / "l.csv", label="angle_deg")[1] == "angle_deg"
    with pytest.raises(LabelsError, match="no label column 'width'"):
        read_labels(tmp_path / "l.csv", label="width")
    (tmp_path / "m.csv").write_text("file,depth\na,1\n")
    with pytest.raises(LabelsError, match="no 'path' column"):
        read_labels(tmp_path / "m.csv")


def test_numbers_binned_into_equal_width_classes_get_the_bin_centre():
    scheme = LabelScheme.from_values(["0", "1", "2.5", "10"], classes=4, column="depth_mm")
    assert scheme.kind == "number" and scheme.unit == "mm"
    # bins of 2.5 mm over 0..10: centres 1.25, 3.75, 6.25, 8.75; the top value in the last bin
    assert [scheme.identity(v) for v in ("0", "1", "2.5", "10", "6")] == [1.25, 1.25, 3.75, 8.75, 6.25]
    plain = LabelScheme.from_values(["0.5", "1.5"], column="width")
    assert plain.identity("1.5") == 1.5 and plain.unit == "none" and plain.warnings


@pytest.mark.parametrize("classes", [None, 8])
def test_angles_wrap_and_their_classes_are_centred_on_zero(classes):
    scheme = LabelScheme.from_values(["0", "45", "350", "-45", "360"], period=360.0, classes=classes)
    assert scheme.kind == "angle" and scheme.unit == "deg"
    assert scheme.identity("-45") == 315.0 and scheme.identity("360") == 0.0 and scheme.identity("405") == 45.0
    if classes:  # 350 deg is 10 deg from 0 and 35 from 315: the class of 0
        assert scheme.identity("350") == 0.0 and scheme.identity("337") == 315.0 and scheme.identity("23") == 45.0
    else:
        assert scheme.identity("350") == 350.0


def test_names_are_sorted_classes_whose_identity_is_the_index():
    scheme = LabelScheme.from_values(["sphere", "cube", "edge", "cube"])
    assert scheme.kind == "name" and scheme.names == ("cube", "edge", "sphere")
    assert [scheme.identity(v) for v in ("cube", "sphere")] == [0.0, 2.0]
    assert scheme.class_name(1.0) == "edge"
    check_identity_labels(None, scheme.names, np.array([0.0, 2.0]))  # what a Dataset accepts
    with pytest.raises(DatasetError):
        check_identity_labels(360.0, scheme.names)
    with pytest.raises(LabelsError, match="needs number labels"):
        LabelScheme.from_values(["cube", "edge"], classes=2)


def test_bad_labels_are_refused_one_by_one():
    scheme = LabelScheme.from_values(["1", "2", "nan"], classes=2)  # 'nan' is a bad number, not a name
    assert scheme.kind == "number"
    for text, message in (("", "empty label"), ("nan", "not a finite number"), ("deep", "not a finite number")):
        with pytest.raises(LabelsError, match=message):
            scheme.identity(text)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_alternate_split_alternates_within_each_class(seed):
    rng = np.random.default_rng(seed)
    identity = np.repeat(rng.permutation(5), rng.integers(1, 9, size=5))
    test = alternate_split(identity)
    for value in np.unique(identity):
        ours = test[identity == value]
        assert ours.tolist() == [k % 2 == 1 for k in range(len(ours))]


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_group_split_keeps_recordings_whole_and_balances_each_class(seed):
    rng = np.random.default_rng(seed)
    recording = np.repeat(np.arange(24), rng.integers(2, 6, size=24))
    identity = (recording % 4).astype(float)  # 6 recordings of each of 4 classes
    test = group_split(identity, recording, test_fraction=0.5, seed=seed)
    for k in range(24):
        assert len(set(test[recording == k])) == 1
    for value in range(4):
        share = test[identity == value].mean()
        assert 0.25 <= share <= 0.75, share
    assert np.array_equal(test, group_split(identity, recording, test_fraction=0.5, seed=seed))  # seeded
    lone = group_split(np.zeros(3), np.zeros(3, int))
    assert not lone.any()  # one recording of a class: it trains


def test_column_split_reads_train_and_test():
    assert column_split(["train", "TEST", " test "]).tolist() == [False, True, True]
    with pytest.raises(ValueError, match="'validate'"):
        column_split(["train", "validate"])
