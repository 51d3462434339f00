"""Replay's luma-to-grey lookup two pixels at a time (`tactip.replay.luma.look_up`, issue 20, outcome 9: cheaper on
the tracking thread) gives `cv2.LUT`'s pixels, whatever the table, the frame's size and layout."""

import cv2
import numpy as np
import pytest

from pins._kernels import choose
from tactip.replay.luma import look_up, mapped, pair_table
from tactip.sources import Frame


@pytest.mark.parametrize("kernels", ["compiled", "numpy"])
@pytest.mark.parametrize("seed", range(4))
def test_look_up_is_cv2_lut(kernels, seed):
    rng = np.random.default_rng(seed)
    tables = [rng.integers(0, 256, 256, dtype=np.uint8),                      # any table
              np.clip(np.round((np.arange(256) - 16) * 255 / 219), 0, 255).astype(np.uint8),  # mp4v's range
              np.arange(256, dtype=np.uint8)]
    before = choose(kernels)
    try:
        for table in tables:
            pairs = pair_table(table)
            for height, width in [(480, 640), (7, 3), (1, 1), (3, 2), (int(rng.integers(1, 60)), int(rng.integers(1, 60)))]:
                image = rng.integers(0, 256, (height, width), dtype=np.uint8)
                expected = cv2.LUT(image, table)
                assert look_up(image, table, pairs) is image
                assert np.array_equal(image, expected)
            strided = rng.integers(0, 256, (20, 40), dtype=np.uint8)[:, ::2]  # not contiguous: cv2.LUT, in place
            expected = cv2.LUT(strided, table)
            look_up(strided, table, pairs)
            assert np.array_equal(strided, expected)
    finally:
        choose(before)


def test_mapped_frames_are_looked_up_in_place_in_order():
    rng = np.random.default_rng(9)
    table = rng.integers(0, 256, 256, dtype=np.uint8)
    frames = [Frame(k, k / 120.0, rng.integers(0, 256, (48, 64), dtype=np.uint8)) for k in range(5)]
    expected = [cv2.LUT(frame.image, table) for frame in frames]
    got = list(mapped(iter(frames), table))
    assert [frame.index for frame in got] == list(range(5))
    assert all(np.array_equal(frame.image, image) for frame, image in zip(got, expected))
    assert list(mapped(iter(frames), None)) == frames
