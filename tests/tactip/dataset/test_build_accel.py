"""dataset build with the images' pins detected in batches as tensors (pins.accel_detect, CPU torch): the same datasets."""

import json
import shutil

import cv2
import numpy as np
import pytest

pytest.importorskip("torch")
pytest.importorskip("kornia")

import pins.accel_detect  # noqa: E402
from perception import load_dataset  # noqa: E402
from tactip.dataset import build_dataset  # noqa: E402


def test_images_detected_in_batches_give_the_same_datasets(shape_images, tmp_path, monkeypatch):
    folder = tmp_path / "set"
    shutil.copytree(shape_images.root, folder)
    cv2.imwrite(str(folder / "small.png"), np.zeros((240, 320), np.uint8))  # another camera's size
    lines = (folder / "labels.csv").read_text().splitlines()
    (folder / "labels.csv").write_text("\n".join([*lines, "small.png,deep", "missing.png,deep"]) + "\n")
    batches = []
    batched = pins.accel_detect.detect_pins_batched

    def spy(frames, **options):
        found = batched(frames, **options)
        batches.append((len(found), options["together"], options["device"]))
        return found

    monkeypatch.setattr(pins.accel_detect, "detect_pins_batched", spy)
    outputs = {}
    for device in ("cpu", "torch-cpu"):
        out = tmp_path / device
        build_dataset(folder / "labels.csv", out, rest=folder / "rest.png", sensor="tactip-127", device=device,
                      together=4)
        outputs[device] = out
    # The batch saw every good image (not the bad ones, left to their rows), 4 at a time, on CPU torch.
    good = len(lines) - 1
    assert batches == [(good, 4, "cpu")]
    for name in ("train.h5", "test.h5"):
        expected, got = (load_dataset(outputs[d] / name) for d in ("cpu", "torch-cpu"))
        assert len(expected) > 0
        np.testing.assert_array_equal(got.taps, expected.taps)
        np.testing.assert_array_equal(got.identity, expected.identity)
    summaries = [json.loads((outputs[d] / "summary.json").read_text()) for d in ("cpu", "torch-cpu")]
    assert summaries[0]["left_out"] == summaries[1]["left_out"] and len(summaries[1]["left_out"]) == 2
    assert summaries[0]["rows"] == summaries[1]["rows"]


def test_no_gpu_means_no_torch_and_a_bad_batch_size_is_refused(shape_images, tmp_path, monkeypatch):
    """device auto without a GPU takes the NumPy path (nothing batched); together must be >= 1."""
    import torch

    from tactip.dataset import LabelsError

    monkeypatch.setattr(torch.cuda, "is_available", lambda: False)
    monkeypatch.setattr(pins.accel_detect, "detect_pins_batched", lambda *a, **k: pytest.fail("batched without a GPU"))
    build_dataset(shape_images.labels, tmp_path / "auto", rest=shape_images.rest, sensor="tactip-127", device="auto")
    assert (tmp_path / "auto" / "train.h5").exists()
    with pytest.raises(LabelsError, match="together"):
        build_dataset(shape_images.labels, tmp_path / "bad", rest=shape_images.rest, sensor="tactip-127",
                      device="torch-cpu", together=0)


def test_cli_device_cuda_without_a_gpu_is_one_clear_error(shape_images, tmp_path, capsys):
    import torch

    from tactip.cli import main

    if torch.cuda.is_available():
        pytest.skip("this machine has a GPU")
    code = main(["dataset", "build", str(shape_images.labels), "--out", str(tmp_path / "out"), "--rest",
                 str(shape_images.rest), "--device", "cuda", "--quiet"])
    error = capsys.readouterr().err
    assert code == 1 and error.startswith("tactip dataset: error: --device cuda:") and "no GPU" in error
    assert error.count("\n") == 1 and not (tmp_path / "out").exists()
    # --together is checked by the parser, naming the flag.
    with pytest.raises(SystemExit):
        main(["dataset", "build", str(shape_images.labels), "--out", str(tmp_path / "out"), "--together", "0"])
    assert "--together" in capsys.readouterr().err
