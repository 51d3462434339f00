"""The replay summary says how many feature pins each contact saw (issue 20, outcome 4: "the summary says
how many were"), not only the poorest contact's count."""

import pathlib

import numpy as np

from pins import DetectionParams, SensorDisc
from tactip.replay.result import ReplayResult


def _result(pins_seen):
    frames = 30
    return ReplayResult(out_path=pathlib.Path("out.h5"), annotate_path=None, video="v.avi", frames=frames, pins=50,
                        frame_rate=120.0, lost_per_frame=np.zeros(frames, int), retired_per_frame=np.zeros(frames, int),
                        blank_frames=[], rest_frame=0, tap_bounds=[(2, 8), (10, 16), (20, 26)][:len(pins_seen)],
                        invalid_taps=[], selected_pins=np.arange(40), selection=None, mm_per_px=0.2, scale=None,
                        disc=SensorDisc(100.0, 100.0, 80.0), detection=DetectionParams(), pins_detected=50,
                        pins_seen=list(pins_seen))


def test_the_summary_lists_the_pins_seen_in_each_contact_that_missed_some():
    text = _result([40, 36, 39]).summary()
    assert "pins seen 36/40 in the poorest tap (per tap: 40 36 39)" in text


def test_the_summary_stays_short_when_every_contact_saw_the_same_pins():
    text = _result([40, 40, 40]).summary()
    assert "pins seen 40/40 in the poorest tap" in text and "per tap" not in text
