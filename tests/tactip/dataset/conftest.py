"""Synthetic labelled recordings with known labels, rendered once per test session (shared by xdist workers).

- `slide_videos`: the radial pad ``radial-led-120`` sliding in 8 directions (0, 45, ..., 315 deg), one MJPG
  video per direction with 4 slides each; labels.csv ``path,direction_deg``.
- `press_videos`: the 331-pin pad pressed at 3 depths (2-5 mm), 2 videos per depth with 3 presses each; the
  labels are written as measured depths (2.0 +- 0.2 mm), so that --classes has to bin them.
- `shape_images`: the 127-pin pad, one image per tap of three named contacts (``shallow``, ``deep``, ``gap``)
  plus a rest image; labels.csv ``path,shape``.

Each sensor keeps its pin layout (one seed) across recordings; each recording has its own noise.
"""

from pathlib import Path
from types import SimpleNamespace

import cv2
import numpy as np
import pytest

from tactip.sim import SyntheticTacTip
from tactip.sim.contact import Contact
from tests.tactip.conftest import built_once

DIRECTIONS = tuple(range(0, 360, 45))
DEPTHS_MM = (2.0, 3.5, 5.0)
SHAPES = {"shallow": Contact(1.5), "deep": Contact(3.5), "gap": Contact(2.5, gap_width_mm=3.0)}


def write_video(path: Path, frames, frame_rate: float) -> Path:
    """Frames (SyntheticFrame or arrays) to an MJPG .avi, grey."""
    frames = [getattr(f, "image", f) for f in frames]
    height, width = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), frame_rate, (width, height), isColor=False)
    assert writer.isOpened()
    for image in frames:
        writer.write(image)
    writer.release()
    return path


def slide_run(sensor: SyntheticTacTip, directions, *, count: int = 4):
    """``count`` short slides in each of ``directions`` (deg), 3 rest frames between them, 120 frames/s."""
    strokes = [a for a in directions for _ in range(count)]
    return sensor.slides(strokes, distance_mm=3 * sensor.pin_spacing_mm, rest_s=3 / 120, press_s=0.04,
                         slide_s=0.06, lift_s=0.04, frame_rate=120.0)


def press_run(sensor: SyntheticTacTip, depth_mm: float, *, count: int = 3):
    """``count`` presses to ``depth_mm``, 3 rest frames between them, 60 frames/s."""
    return sensor.taps(count, indentation_mm=depth_mm, rest_s=3 / 60, press_s=0.1, hold_s=0.05, lift_s=0.1,
                       frame_rate=60.0)


@pytest.fixture(scope="session")
def slide_videos(tmp_path_factory):
    """Folder with slide_DDD.avi and labels.csv (path,direction_deg) of the radial pad."""
    with built_once(tmp_path_factory, "dataset-slides") as (root, build):
        if build:
            sensor = SyntheticTacTip.from_preset("radial-led-120", seed=0)
            rows = ["path,direction_deg"]
            for k, angle in enumerate(DIRECTIONS):
                sensor.reseed_noise(k + 1)
                write_video(root / f"slide_{angle:03d}.avi", slide_run(sensor, [angle]), 120.0)
                rows.append(f"slide_{angle:03d}.avi,{angle}")
            (root / "labels.csv").write_text("\n".join(rows) + "\n")
    return SimpleNamespace(root=root, labels=root / "labels.csv")


@pytest.fixture(scope="session")
def press_videos(tmp_path_factory):
    """Folder with press_D_R.avi and labels.csv (path,depth_mm: the depth measured, +- 0.2 mm) of the 331-pin pad."""
    with built_once(tmp_path_factory, "dataset-presses") as (root, build):
        if build:
            sensor = SyntheticTacTip.from_preset("tactip-331", seed=0)
            rng = np.random.default_rng(0)
            rows = ["path,depth_mm,operator"]
            for depth in DEPTHS_MM:
                for repeat in range(2):
                    sensor.reseed_noise(int(10 * depth) + repeat)
                    name = f"press_{depth:g}_{repeat}.avi"
                    write_video(root / name, press_run(sensor, depth), 60.0)
                    rows.append(f"{name},{depth + rng.uniform(-0.2, 0.2):.3f},op{repeat}")
            (root / "labels.csv").write_text("\n".join(rows) + "\n")
    return SimpleNamespace(root=root, labels=root / "labels.csv")


@pytest.fixture(scope="session")
def shape_images(tmp_path_factory):
    """Folder with rest.png, one PNG per tap and labels.csv (path,shape) of the 127-pin pad."""
    with built_once(tmp_path_factory, "dataset-images") as (root, build):
        if build:
            sensor = SyntheticTacTip.from_preset("tactip-127", seed=0)
            rng = np.random.default_rng(1)
            cv2.imwrite(str(root / "rest.png"), sensor.render().image)
            rows = ["path,shape"]
            for repeat in range(6):
                for name, contact in SHAPES.items():
                    sensor.reseed_noise(100 + 10 * repeat + len(rows))
                    jittered = Contact(contact.indentation_mm + rng.uniform(-0.1, 0.1), contact.gap_width_mm)
                    cv2.imwrite(str(root / f"{name}_{repeat}.png"), sensor.render(jittered).image)
                    rows.append(f"{name}_{repeat}.png,{name}")
            (root / "labels.csv").write_text("\n".join(rows) + "\n")
    return SimpleNamespace(root=root, labels=root / "labels.csv", rest=root / "rest.png")


@pytest.fixture(scope="session")
def slides_model(slide_videos, tmp_path_factory):
    """`slide_videos` after ``tactip dataset build --period 360`` and ``tactip train --model gaussian``: the folder."""
    from tactip.cli import main

    with built_once(tmp_path_factory, "dataset-slides-model") as (out, build):
        if build:
            assert main(["dataset", "build", str(slide_videos.labels), "--out", str(out), "--period", "360",
                         "--sensor", "radial-led-120", "--quiet", "--overwrite"]) == 0
            assert main(["train", str(out / "train.h5"), "--out", str(out / "model.h5"), "--model", "gaussian"]) == 0
    return out
