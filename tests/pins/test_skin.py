"""`pins.skin_rest`'s rest of a pin unseen at a rest frame (``fill``) and its rest frames (``return_frames``)."""

import numpy as np

from pins import neighbour_median, segment_taps, skin_rest, tap_signal


def test_a_pin_found_again_after_a_lift_rests_where_its_neighbours_do():
    """A tracker loses a third of the pins through a slide and finds them again a few frames after the lift
    (tactip-127's tours: 45-53 of 127 lost, found again 1-30 frames later). Their last rest was before the slide;
    what the slide left in the skin is then read as a contact starting where they reappear, unless their rest
    is their neighbourhood's at the lift's rest frame."""
    rng = np.random.default_rng(3)
    grid = np.stack(np.meshgrid(np.arange(12), np.arange(12)), -1).reshape(-1, 2) * 20.0
    frames = 60
    field = np.zeros((frames, len(grid), 2))
    field[5:15, :, 0] = np.linspace(2.0, 40.0, 10)[:, None]                 # a slide along x
    field[15:20, :, 0] = np.linspace(30.0, 6.0, 5)[:, None]                # its lift: 6 px left in the skin
    field[20:, :, 0] = 6.0
    field += rng.normal(0.0, 0.05, field.shape)
    lost = rng.random(len(grid)) < 0.35
    field[8:26, lost] = np.nan                                             # lost through the slide, found at 26
    local = neighbour_median(field, grid)
    filled = skin_rest(field, low_px=0.5, high_px=1.5, fill=local)
    stale = skin_rest(field, low_px=0.5, high_px=1.5)
    assert segment_taps(tap_signal(field - filled), high_px=1.5, low_px=0.5, pad_frames=0) == [(5, 20)]
    assert np.abs(filled[40, lost, 0] - 6.0).max() < 0.3                   # the neighbours' rest, not the first
    # without it the pins found again, still before the next contact, rest where they are found (until session 23
    # at the first frame's rest: a "contact" from frame 26 to the end)
    assert segment_taps(tap_signal(field - stale), high_px=1.5, low_px=0.5, pad_frames=0) == [(5, 20)]
    assert np.abs(stale[40, lost, 0] - 6.0).max() < 0.3


def test_pins_found_again_in_a_rest_rest_where_they_are_until_the_next_contact():
    """A tracker that retired pins through a slide finds them again only once the skin is back at rest, after the
    lift's rest frame, and its neighbourhood medians there come from whichever neighbours are back (radial-led-120's
    creeping tours: 30-60 % of pins found again 1-40 frames after the rest frame, the signal held at twice the high
    threshold by their older rests until the next slide ended). Found again in a rest, a pin rests where it is
    frame by frame until the next contact; found again during it, it keeps its older rest."""
    rng = np.random.default_rng(5)
    pins, frames = 150, 90
    field = np.zeros((frames, pins, 2))
    field[5:15, :, 0] = np.linspace(2.0, 40.0, 10)[:, None]                 # a slide along x
    field[15:20, :, 0] = np.linspace(30.0, 6.0, 5)[:, None]                # its lift: 6 px left in the skin
    field[20:, :, 0] = 6.0
    field[60:70, :, 1] = np.linspace(1.0, 10.0, 10)[:, None]               # a press across it, from frame 60
    field[70:, :, 1] = 0.0
    field += rng.normal(0.0, 0.05, field.shape)
    lost = rng.random(pins) < 0.4
    back = 22 + rng.integers(3, 30, pins)                                   # found again 25-51 frames in, at rest
    late = lost & (rng.random(pins) < 0.25)
    back[late] = 64                                                         # ... or during the press
    for pin in np.flatnonzero(lost):
        field[8:back[pin], pin] = np.nan
        if not late[pin]:                                                   # its first frames back 1 px off or so
            field[back[pin]:back[pin] + 4, pin] += rng.normal(0.0, 1.0, (4, 2))
    rest, frames_at = skin_rest(field, low_px=0.5, high_px=1.5, return_frames=True)
    assert 20 in frames_at or 19 in frames_at or 21 in frames_at                   # the lift's rest frame
    found = segment_taps(tap_signal(field - rest), high_px=1.5, low_px=0.5, pad_frames=0)
    assert len(found) == 2 and found[0] == (5, 20) and found[1][0] == 60 and found[1][1] - 70 in (0, 1), found
    settled = lost & ~late
    assert np.abs(rest[58, settled, 0] - field[58, settled, 0]).max() < 0.3    # where they were just before it
    assert np.abs(rest[65, late, 0]).max() < 1.0                          # found in the press: their older rest


def test_rest_frames_are_where_the_rest_is_taken():
    field = np.zeros((12, 20, 2))
    field[2:5, :, 0] = [[2.0], [8.0], [3.0]]
    field[5:, :, 0] = 3.0
    field[8:10, :, 1] = 2.0
    rest, frames = skin_rest(field, low_px=0.5, high_px=1.5, return_frames=True)
    assert np.array_equal(rest, skin_rest(field, low_px=0.5, high_px=1.5))
    assert frames[0] == 0 and all(np.array_equal(rest[t], field[frames[frames <= t][-1]]) for t in range(12))
    empty, none = skin_rest(np.full((4, 3, 2), np.nan), low_px=0.5, high_px=1.5, return_frames=True)
    assert none.size == 0 and not empty.any()


def test_the_rest_is_the_same_whatever_the_frames_measured_at_once(monkeypatch):
    """`skin_rest` measures the signal from a rest a run of frames at a time (8 after a rest frame, doubling up to
    128): the same rests as one frame at a time, on creeping fields with lifts, lost pins and a blank start."""
    import pins.skin as skin

    rng = np.random.default_rng(7)
    fields = []
    for _ in range(25):
        frames, pins = int(rng.integers(20, 200)), int(rng.integers(1, 60))
        field = np.cumsum(rng.normal(0.0, 0.15, (frames, pins, 2)), axis=0)        # drift and creep
        for start in rng.integers(0, frames, 3):                                      # contacts, lifted
            field[start:start + 10] += rng.normal(0.0, 4.0, (1, pins, 2))
        field[rng.random((frames, pins)) < 0.1] = np.nan
        field[: int(rng.integers(0, 3))] = np.nan
        fields.append(field)
    default = [skin_rest(f, low_px=0.5, high_px=1.5, return_frames=True) for f in fields]
    monkeypatch.setattr(skin, "_FIRST", 1)
    monkeypatch.setattr(skin, "_AHEAD", 1)
    for field, (rest, frames) in zip(fields, default):
        one, at = skin_rest(field, low_px=0.5, high_px=1.5, return_frames=True)
        assert np.array_equal(rest, one, equal_nan=True) and np.array_equal(frames, at)
    assert sum(len(frames) for _, frames in default) > 2 * len(fields)              # rests do move
