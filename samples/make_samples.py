"""Write the sample files of samples/ from the synthetic TacTip (seeded: the same files every run).

- ``synthetic_tap.mp4``: 640x480 grey (stored as MPEG-4 part 2, decoded as BGR), 20 fps, noise sigma 3: 0.5 s of rest,
  then three taps over a 2 mm gap at 2, 3.5 and 5 mm indentation, each rising, holding and releasing
  over 0.25 s, with 0.5 s of rest after each (86 frames, 4.25 s). This is what ``make demo`` replays.
- ``synthetic_tap_truth.npz``: its ground truth: ``centres`` (frames, 331, 2) float32 px,
  ``visible`` (frames, 331) bool, ``timestamps_s`` and ``indentation_mm`` (frames,),
  ``gap_width_mm`` and ``gap_offset_mm`` (frames,).
- ``synthetic_frame.png``: one rest frame of the same 331-pin sensor (for ``tactip detect``); its
  true pin centres are ``centres[0]`` of the npz.

Usage: ``python samples/make_samples.py [--out DIR]``
"""

from __future__ import annotations

import argparse
import pathlib

import cv2
import numpy as np

from tactip.sources import DEFAULT_TAPS, SyntheticSource
from tactip.sim.synthetic import SyntheticTacTip

SEED = 0
PINS = 331
FRAME_RATE = 20.0
NOISE_SIGMA = 3.0  # grey levels: the low end of a real sensor's 3-5, so that MPEG-4 keeps the file < 2 MB


def make_samples(out: pathlib.Path) -> list[pathlib.Path]:
    """Write the sample video, its ground truth and the rest frame into ``out``; returns the paths."""
    out.mkdir(parents=True, exist_ok=True)
    video_path, truth_path, frame_path = (out / "synthetic_tap.mp4", out / "synthetic_tap_truth.npz",
                                          out / "synthetic_frame.png")
    sensor = SyntheticTacTip(pins=PINS, noise_sigma=NOISE_SIGMA, seed=SEED)
    source = SyntheticSource(sensor, taps=DEFAULT_TAPS, frame_rate=FRAME_RATE, rest_s=0.5)
    writer = cv2.VideoWriter(str(video_path), cv2.VideoWriter_fourcc(*"mp4v"), FRAME_RATE, source.frame_size,
                             isColor=False)
    if not writer.isOpened():
        raise OSError(f"cannot write {video_path} with the mp4v codec")
    truth = []
    try:
        for frame in source:
            writer.write(frame.image)
            truth.append(source.truth)
    finally:
        writer.release()
    np.savez_compressed(
        truth_path,
        centres=np.array([t.centres for t in truth], dtype=np.float32),
        visible=np.array([t.visible for t in truth]),
        timestamps_s=np.array([t.timestamp_s for t in truth]),
        indentation_mm=np.array([t.contact.indentation_mm for t in truth]),
        gap_width_mm=np.array([t.contact.gap_width_mm for t in truth]),
        gap_offset_mm=np.array([t.contact.gap_offset_mm for t in truth]),
    )
    cv2.imwrite(str(frame_path), SyntheticTacTip(pins=PINS, noise_sigma=NOISE_SIGMA, seed=SEED).render().image)
    return [video_path, truth_path, frame_path]


def main() -> None:
    """Command line: write the samples (default: next to this script)."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path(__file__).resolve().parent)
    for path in make_samples(parser.parse_args().out):
        print(f"{path}: {path.stat().st_size / 1e3:.0f} kB")


if __name__ == "__main__":
    main()
