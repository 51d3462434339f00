"""pins.lattice: the pin field is found without a count on every phenomenon preset, and a count only confirms it."""

import functools
import hashlib

import cv2
import numpy as np
import pytest
from scipy.spatial import Delaunay, cKDTree

from pins import (REJECTION_REASONS, DetectionParams, NoSensorError, PinField, detect_pins, draw_pin_field,
                  find_pin_field, find_sensor_disc)
from tactip.sim import Contact, SyntheticTacTip, preset_names
from tests.pins.conftest import TAP, preset_frame, preset_params, preset_sensor, score

CONTACTS = {"rest": None, "tap5mm": TAP}


@functools.lru_cache(maxsize=None)
def _field(name: str, contact: str, expected: bool = False) -> PinField:
    f = preset_frame(name, CONTACTS[contact])
    count = int(f.visible.sum() + f.partial.sum()) if expected else None
    # The polarity is decided (dark_pins=None), as tactip detect and tactip replay decide it.
    return find_pin_field(f.image, expected_pins=count)


def _gate_px(frame) -> float:
    """Matching gate: 3 px, or 0.4 of the true pitch on dense or small pads."""
    centres = frame.centres[frame.visible]
    distance, _ = cKDTree(centres).query(centres, 2)
    return min(3.0, 0.4 * float(np.median(distance[:, 1])))


@pytest.mark.parametrize("contact", list(CONTACTS))
@pytest.mark.parametrize("name", preset_params(preset_names()))
def test_field_without_a_count_meets_the_bar(name, contact):
    f = preset_frame(name, CONTACTS[contact])
    field = _field(name, contact)
    recall, precision, rmse = score(field.centres, f, gate_px=_gate_px(f))
    assert recall >= 0.99 and precision >= 0.99, (recall, precision, field.summary())
    assert rmse <= 0.1
    assert field.expected_pins is None and field.count_error is None
    assert field.params.dark_pins == preset_sensor(name).dark_pins  # the polarity decided right


@pytest.mark.parametrize("contact", list(CONTACTS))
@pytest.mark.parametrize("name", preset_params(preset_names()))
def test_a_count_confirms_and_does_not_steer(name, contact):
    f = preset_frame(name, CONTACTS[contact])
    without, given = _field(name, contact), _field(name, contact, expected=True)
    np.testing.assert_array_equal(given.centres, without.centres)
    drawn = int(f.visible.sum() + f.partial.sum())
    assert given.expected_pins == drawn
    assert given.count_error == given.count - drawn
    recall, precision, rmse = score(given.centres, f, gate_px=_gate_px(f))
    assert recall >= 0.99 and precision >= 0.99 and rmse <= 0.1
    assert f"expected {drawn}" in given.summary()


@pytest.mark.parametrize("name", ["tactip-331", "rim-ring-331", "brown-127", "radial-120", "small-pad-100"])
def test_later_frames_found_with_the_field_parameters(name):
    """The fast path (`detect_pins` with the field's params and region) finds the pins of a tap frame."""
    field = _field(name, "rest")
    f = preset_frame(name, TAP)
    pins = detect_pins(f.image, params=field.params, disc=field.disc)
    recall, _, rmse = score(pins, f, gate_px=_gate_px(f))
    assert recall >= 0.99 and rmse <= 0.1
    assert isinstance(field.params, DetectionParams) and field.params.dark_pins == preset_sensor(name).dark_pins


@pytest.mark.parametrize("name", ["tactip-127", "tactip-331", "dark-331", "brown-127", "radial-led-120",
                                  "small-pad-100"])
def test_a_sensors_own_lattice_is_not_outnumbered_by_its_gaps(name):
    """The probe of the other polarity at the field's pitch keeps fewer blobs than the sensor's pins
    (the gaps between pins; reflections), so a right polarity is never searched twice for it."""
    from pins.disc import as_grey
    from pins.lattice import _other_keeps_more

    for contact in CONTACTS:
        f = preset_frame(name, CONTACTS[contact])
        assert not _other_keeps_more(as_grey(f.image), _field(name, contact), DetectionParams()), (name, contact)


def test_rim_ring_is_the_field_boundary():
    """The search stops at the black rim ring's inner edge: its glare never becomes a candidate."""
    sensor, f = preset_sensor("rim-ring-331"), preset_frame("rim-ring-331")
    field = _field("rim-ring-331", "rest")
    cx, cy = sensor.disc[:2]
    assert field.disc.radius_px == pytest.approx(sensor.disc[2], abs=1.0)
    everything = np.vstack([field.centres, field.rejected])
    assert np.hypot(*(everything - [cx, cy]).T).max() < sensor.rim_radius_px
    # Later frames look no farther: the field's circle ends at the ring, short of its glare.
    reach = np.hypot(*(field.centres - [cx, cy]).T).max()
    assert reach < field.field_disc.radius_px <= sensor.rim_radius_px
    assert (np.hypot(*(sensor.ring_glare_centres - [cx, cy]).T) > field.field_disc.radius_px + 2.0).all()
    assert score(field.centres, f)[1] == 1.0
    assert score(detect_pins(f.image, params=field.params), f)[1] == 1.0


def test_rim_ring_hides_pins_from_the_count():
    """A rim ring hides 6 of 331 pins and cuts 12 more, some too little of a tip to find."""
    assert 331 - 6 - 12 <= _field("rim-ring-331", "rest").count <= 331 - 6


@pytest.mark.parametrize("name", ["tactip-331", "brown-127", "dark-331"])
def test_without_a_rim_ring_the_search_reaches_the_disc_rim(name):
    """Only a rim ring stops the search: without one, a pin field filling the disc is whole."""
    field = _field(name, "rest")
    cx, cy, radius = preset_sensor(name).disc
    assert field.disc.radius_px == pytest.approx(radius, abs=2.0)
    assert np.hypot(*(field.centres - [cx, cy]).T).max() > radius - 1.5 * field.pitch_px


# Mixes of the phenomena no preset shows (bench/bench_pin_field_sweep.py draws them at random): a
# black rim ring with LED glare, on radial and hexagonal layouts, brown skin and a bright surround.
RIM = dict(rim_polar_deg=77.0, ring_glare=18, glare=False)
BROWN = dict(colour=True, skin_tint="brown", membrane_level=70.0, pin_level=140.0, skin_texture=12.0, pin_shadows=22.0)
BRIGHT = dict(surround_level=240.0, glare_gain=1.6, veil=40.0)
RING_MIXES = {
    "radial+brown": dict(pins=127, image_size=(640, 480), pad_fraction=0.7, layout="radial", **RIM, **BROWN),
    "radial+bright": dict(pins=200, image_size=(640, 480), pad_fraction=0.66, layout="radial", **RIM, **BRIGHT),
    "hex+bright, small pad": dict(pins=100, image_size=(320, 240), pad_fraction=0.45, **RIM, **BRIGHT),
    "hex+brown": dict(pins=127, image_size=(320, 240), pad_fraction=0.79, **RIM, **BROWN),
}


@pytest.mark.parametrize("seed", [1, 2])
@pytest.mark.parametrize("mix", list(RING_MIXES))
def test_rim_ring_mixes_meet_the_bar(mix, seed):
    """Glare on the ring (in a radial layout one pitch beyond the outermost ring of pins) is not
    kept, nor the membrane along the ring's edge."""
    sensor = SyntheticTacTip(**RING_MIXES[mix], seed=seed)
    for contact in (None, TAP):
        f = sensor.render(contact)
        field = find_pin_field(f.image)
        recall, precision, rmse = score(field.centres, f, gate_px=_gate_px(f))
        assert recall >= 0.99 and precision >= 0.99 and rmse <= 0.1, (mix, contact, recall, precision, rmse)


@pytest.mark.parametrize("pins, seed, contact", [(127, 0, None), (100, 1, Contact(indentation_mm=3.0, gap_width_mm=2.0))])
def test_brown_radial_pins_first_judged_among_skin_texture_rejoin(pins, seed, contact):
    """The ends of a radial layout's spokes on a brown textured skin, first judged among skin
    highlights and specks (which make them look unlike their neighbours), rejoin the field once
    those are rejected (recall was 0.976 and 0.950 when a rejection was final)."""
    sensor = SyntheticTacTip(pins=pins, image_size=(320, 240), pad_fraction=0.85, layout="radial", seed=seed, **BROWN)
    f = sensor.render(contact)
    field = find_pin_field(f.image)
    recall, precision, rmse = score(field.centres, f, gate_px=_gate_px(f))
    assert recall >= 0.99 and precision >= 0.99 and rmse <= 0.1, (recall, precision, rmse)


def _voter_grid():
    """A 10 x 10 lattice of pitch `_VOTER_PITCH` px: (100, 2) px."""
    return _VOTER_PITCH * np.stack(np.meshgrid(np.arange(10.0), np.arange(10.0)), axis=-1).reshape(-1, 2)


def _voter(centres, lost):
    """One candidate set for `_consensus`: blobs at `centres`, the first `lost` of them off the lattice."""
    from pins.detect import Blobs
    from pins._judge import _KEPT, _OFF
    from pins._candidates import _Run

    reason = np.full(len(centres), _KEPT)
    reason[:lost] = _OFF
    n = len(centres)
    blobs = Blobs(centres=centres, areas=np.full(n, 20), fills=np.full(n, 0.8), candidates=n,
                  contrasts=np.full(n, 40.0))
    return _Run(DetectionParams(), blobs, reason, _VOTER_PITCH)


_VOTER_PITCH = 10.0


def test_consensus_agrees_on_pins_half_the_voters_keep_and_never_on_one_sets_own():
    """Of four voting candidate sets, the two least complete do not veto the pins only the two most
    complete keep (a most complete one wins); of two voters, a set keeping a few extra blobs does
    not agree with itself (the other wins)."""
    from pins._candidates import _consensus

    pitch, grid, run = _VOTER_PITCH, _voter_grid(), _voter

    membership, _ = _consensus([run(grid, 3), run(grid, 3), run(grid, 0), run(grid, 0)], pitch)
    assert np.isfinite(membership).all() and np.argmax(membership) in (2, 3)
    extras = np.vstack([grid, grid[:3] + pitch / 2])
    membership, _ = _consensus([run(extras, 0), run(grid, 0)], pitch)
    assert np.isfinite(membership).all() and np.argmax(membership) == 1


def test_a_lone_voter_is_no_consensus_with_itself():
    """The lowest offset keeps a few noise blobs more than any other set (a noisy webcam): alone over 97 % of
    the most pins kept, it was the only voter and agreed with itself, noise and all (bench_user_chain
    radial-led-120 seed 0: 122 pins, 3 of them noise). The sets keeping the next most pins vote with it: a
    blob one set alone keeps is no agreement, and the set without them wins (the holes it leaves are
    filled from the others, `pins._rescue`). A set keeping over a tenth more than any other still votes
    alone: its extras are pins only it finds."""
    from pins._candidates import _consensus

    pitch, grid, run = _VOTER_PITCH, _voter_grid(), _voter

    noisy = np.vstack([grid, grid[:4] + pitch / 2])               # 104 kept, 4 of them noise
    runs = [run(noisy, 0), run(grid, 5), run(grid, 5), run(grid, 30)]  # 95 < 0.97 x 104
    membership, _ = _consensus(runs, pitch)
    assert np.isfinite(membership[:3]).all() and not np.isfinite(membership[3])
    assert np.argmax(membership) in (1, 2), membership
    # A set keeping a tenth more pins than any other keeps pins only it finds (faint tips): it votes alone.
    membership, _ = _consensus([run(grid, 0), run(grid, 15)], pitch)
    assert np.isfinite(membership[0]) and not np.isfinite(membership[1])


def test_a_lone_voter_stricter_than_the_sets_that_would_join_it_votes_alone():
    """A lone voter's extras are noise only when it thresholds lower than the sets that would join it: a set
    at a higher offset than each of them that keeps more pins keeps faint pins the lower offsets merge with
    the membrane round them (bench_user_chain radial-led-120 seed 28: offset 15 kept 110, offset 5 kept 102;
    both voted, the lower won and a pin was lost). It votes alone and wins; at a lower offset than theirs it
    is still joined and the set without its extras wins."""
    from pins._candidates import _consensus

    pitch, grid = _VOTER_PITCH, _voter_grid()

    def run(centres, lost, offset):
        one = _voter(centres, lost)
        return type(one)(one.params.replace(offset=offset), one.blobs, one.reason, one.pitch)

    more = np.vstack([grid, grid[:4] + pitch / 2])               # 104 kept
    runs = [run(more, 0, 15.0), run(grid, 5, 5.0), run(grid, 5, 9.0), run(grid, 30, 25.0)]  # 95 >= 0.9 x 104
    membership, _ = _consensus(runs, pitch)
    assert np.isfinite(membership[0]) and not np.isfinite(membership[1:]).any(), membership
    # The same extras kept by the lowest offset: noise it lets through; the sets keeping the next most vote.
    runs = [run(more, 0, 5.0), run(grid, 5, 9.0), run(grid, 5, 15.0), run(grid, 30, 25.0)]
    membership, _ = _consensus(runs, pitch)
    assert np.isfinite(membership[:3]).all() and np.argmax(membership) in (1, 2), membership


def test_consensus_matches_every_centre_with_each_voters_nearest_even_among_crowded_blobs():
    """The one-tree consensus equals asking each voter's own tree for each centre's nearest within the
    gate, also where a centre has more blobs inside the gate than its k nearest (split blobs)."""
    from pins.detect import Blobs
    from pins._judge import _KEPT
    from pins._candidates import _MATCH, _VOTER, _Run, _consensus

    rng = np.random.default_rng(3)
    pitch = 10.0
    grid = pitch * np.stack(np.meshgrid(np.arange(8.0), np.arange(8.0)), axis=-1).reshape(-1, 2)
    runs = []
    for r in range(6):
        centres = grid + rng.normal(0, 0.4, grid.shape)
        # Every set splits the first pins into several blobs: crowded inside the gate.
        centres = np.vstack([centres, grid[:4].repeat(3, axis=0) + rng.normal(0, 0.5, (12, 2))])
        n = len(centres)
        blobs = Blobs(centres=centres, areas=np.full(n, 20), fills=np.full(n, 0.8), candidates=n,
                      contrasts=np.full(n, 40.0))
        reason = np.full(n, _KEPT)
        runs.append(_Run(DetectionParams(), blobs, reason, pitch))
    membership, deviation = _consensus(runs, pitch)

    # Reference: pair by pair, as the consensus was first written.
    kept = [run.blobs.centres[run.kept] for run in runs]
    voters = np.array([len(c) for c in kept]) >= _VOTER * max(len(c) for c in kept)
    for r, centres in enumerate(kept):
        matches = np.full((len(runs), len(centres), 2), np.nan)
        for v, other in enumerate(kept):
            distance, index = cKDTree(other).query(centres, distance_upper_bound=_MATCH * pitch)
            found = np.isfinite(distance)
            matches[v, found] = other[index[found]]
        support = np.isfinite(matches[:, :, 0]).sum(axis=0)
        agreed = (2 * support >= voters.sum()) & (support >= 2)
        assert membership[r] == agreed.sum() - (~agreed).sum()
        consensus = np.nanmean(matches[:, agreed], axis=0)
        assert deviation[r] == pytest.approx(np.median(np.hypot(*(centres[agreed] - consensus).T)), abs=1e-12)


def test_detection_with_the_field_searchs_cache_gives_the_same_blobs():
    """Candidate sets sharing the blurred disc and block means through the cache detect exactly as alone."""
    from pins.detect import _detect
    from pins.disc import find_sensor_disc

    image = preset_frame("rim-ring-331").image
    grey = cv2.cvtColor(image, cv2.COLOR_BGR2GRAY) if image.ndim == 3 else image
    disc = find_sensor_disc(grey)
    cache: dict = {}
    for blur in (1.2, 0.8):
        for block in (19, 31):
            for offset in (5.0, 15.0):
                params = DetectionParams(blur_sigma_px=blur, block_size_px=block, offset=offset)
                shared, alone = _detect(grey, disc, params, cache), _detect(grey, disc, params)
                for name in ("centres", "areas", "fills", "contrasts"):
                    np.testing.assert_array_equal(getattr(shared, name), getattr(alone, name))
    assert len(cache) == 2 + 4  # two blurs, and their block means


@pytest.mark.parametrize("extra", [{}, BROWN, BRIGHT, dict(dark_pins=True), dict(layout="radial", **BRIGHT)])
@pytest.mark.parametrize("size, pad", [((320, 240), 0.3), ((640, 480), 0.85)])
def test_a_rim_ring_is_found_only_where_there_is_one(extra, size, pad):
    """The ring's inner edge within a pixel and a half when there is one, with glare covering much of
    it; no ring on a membrane without one (bright surround, veil, brown skin, dark pins)."""
    from pins.disc import as_grey
    from pins.lattice import _rim_ring_inner_px

    for ring in (False, True):
        if ring and extra.get("dark_pins"):
            continue
        sensor = SyntheticTacTip(pins=100, image_size=size, pad_fraction=pad, seed=3, **(RIM if ring else {}), **extra)
        grey = as_grey(sensor.render().image)
        found = _rim_ring_inner_px(grey, find_sensor_disc(grey, dark_pins=sensor.dark_pins), sensor.dark_pins)
        if ring:
            assert found == pytest.approx(sensor.rim_radius_px, abs=1.5)
        else:
            assert found == np.inf


def test_painted_specks_and_faint_blobs_between_pins_are_rejected(rng):
    """Clutter painted between the pins (specks, faint pin-sized blobs) never joins the lattice."""
    f = preset_frame("tactip-331")
    image = f.image.copy()
    centres = f.centres[f.visible]
    # Interstices: centroids of the lattice's triangles, about 0.58 pitch from three pins.
    triangles = centres[Delaunay(centres).simplices]
    edges = np.linalg.norm(triangles - np.roll(triangles, 1, axis=1), axis=2).max(axis=1)
    spots = triangles[edges < 1.3 * np.median(edges)].mean(axis=1)
    spots = spots[rng.choice(len(spots), 40, replace=False)]
    level = np.median(image[np.rint(centres[:, 1]).astype(int), np.rint(centres[:, 0]).astype(int)])
    membrane = np.median(image[f.image < level / 2])
    for k, (x, y) in enumerate(spots):
        point = (int(round(x * 16)), int(round(y * 16)))
        radius, grey = [(1.0, level), (2.0, level), (3.0, membrane + 40)][k % 3]  # speck, small blob, faint blob
        cv2.circle(image, point, int(radius * 16), int(grey), -1, cv2.LINE_AA, 4)
    # Plain detection keeps some of the clutter; the lattice does not.
    assert score(detect_pins(image), f)[1] < 0.99
    field = find_pin_field(image)
    recall, precision, rmse = score(field.centres, f)
    assert recall >= 0.99 and precision == 1.0 and rmse <= 0.1
    assert set(field.rejected_reason) <= set(REJECTION_REASONS)
    # Every spot plain detection kept was seen by the field search and rejected (how many of the 40
    # plain detection finds depends on the camera noise: 13 here).
    kept = cKDTree(detect_pins(image)).query(spots)[0] < 2.0
    assert kept.sum() >= 10 and (cKDTree(field.rejected).query(spots[kept])[0] < 2.0).all()


def test_no_pins_is_an_empty_field():
    sensor = preset_sensor("tactip-331")
    blank = sensor.render(hidden=np.ones(sensor.n_pins, dtype=bool)).image
    field = find_pin_field(blank, expected_pins=331, dark_pins=False)
    assert field.centres.shape == (0, 2) and field.centres.dtype == np.float64
    assert field.count == 0 and field.count_error == -331 and np.isnan(field.pitch_px)
    assert field.rejected.shape == (len(field.rejected_reason), 2)
    assert "0 pins" in field.summary()


def test_no_disc_raises():
    with pytest.raises(NoSensorError):
        find_pin_field(np.full((480, 640), 25, np.uint8))


@pytest.mark.parametrize("expected", [0, -3, 2.5, True])
def test_expected_pins_validated_by_name(expected):
    with pytest.raises(ValueError, match="expected_pins"):
        find_pin_field(preset_frame("tactip-127").image, expected_pins=expected)


def test_summary_and_counts_agree():
    field = _field("brown-127", "rest", expected=True)
    counts = field.rejected_counts()
    assert list(counts) == list(REJECTION_REASONS)
    assert sum(counts.values()) == len(field.rejected) == len(field.rejected_reason)
    assert field.summary().startswith(f"{field.count} pins, pitch {field.pitch_px:.1f} px; rejected {len(field.rejected)}")


def test_drawing_shows_kept_and_rejected_without_touching_the_frame():
    f = preset_frame("brown-127")
    before = f.image.copy()
    field = _field("brown-127", "rest")
    picture = draw_pin_field(f.image, field)
    assert picture.shape == f.image.shape[:2] + (3,) and picture.dtype == np.uint8
    np.testing.assert_array_equal(f.image, before)
    # Green rings round the kept pins, magenta crosses on the glare round the rim.
    green = (picture[:, :, 1] > 150) & (picture[:, :, 0] < 60) & (picture[:, :, 2] < 60)
    magenta = (picture[:, :, 0] > 200) & (picture[:, :, 2] > 200) & (picture[:, :, 1] < 120)
    assert green.sum() > 10 * field.count and magenta.sum() > 0
    x, y = np.rint(field.rejected[field.rejected_reason == "outside field"][0]).astype(int)
    assert magenta[y - 3:y + 4, x - 3:x + 4].any()


def test_small_frames_are_drawn_enlarged():
    f = preset_frame("small-pad-100")
    field = _field("small-pad-100", "rest")
    picture = draw_pin_field(f.image, field)
    assert picture.shape == (480, 640, 3)
    # Each kept pin is ringed in green at twice its coordinates.
    green = (picture[:, :, 1] > 150) & (picture[:, :, 0] < 60) & (picture[:, :, 2] < 60)
    x, y = np.rint(2 * field.centres[0] + 0.5).astype(int)
    assert green[y - 4:y + 5, x - 4:x + 5].any()


@pytest.mark.parametrize("name", ["tactip-331", "dark-331"])
def test_deciding_the_polarity_refuses_a_pad_without_a_lattice_saying_why_for_both(name):
    """A pad without pins, or with a dozen blobs (glare), shows no sensor when the polarity is decided:
    neither polarity forms a lattice of MIN_SENSOR_PINS pins, and the message says what each found."""
    from pins import MIN_SENSOR_PINS

    sensor = preset_sensor(name)
    hidden = np.ones(sensor.n_pins, dtype=bool)
    hidden[::30] = False  # a dozen pins: a field of the polarity asked, no sensor when deciding
    image = sensor.render(hidden=hidden).image
    assert find_pin_field(image, dark_pins=sensor.dark_pins).count < MIN_SENSOR_PINS
    with pytest.raises(NoSensorError, match=f"no pin lattice of at least {MIN_SENSOR_PINS} pins") as caught:
        find_pin_field(image)
    message = str(caught.value)
    assert "bright pins on a dark membrane" in message and "dark markers on a light membrane" in message
    assert "pins form a lattice" in message and "no sensor disc" in message  # one polarity's disc, not the other's


def test_a_forced_polarity_is_kept():
    """dark_pins=True or False (or params with a polarity) is searched as asked, never decided."""
    f = preset_frame("tactip-127")
    assert find_pin_field(f.image, dark_pins=False).params.dark_pins is False
    assert find_pin_field(f.image, params=DetectionParams(), dark_pins=None).params.dark_pins is False
    with pytest.raises(NoSensorError, match="no sensor disc"):
        find_pin_field(f.image, dark_pins=True)


def test_the_polarity_asked_for_on_white_pins_in_a_dark_casing():
    """White pins on a dark membrane in a dark casing frame no bright-pin disc of their own: asked for
    bright pins (dark_pins=False), the field is the one decided without asking (as bench_pins asks with
    the renderer's polarity), not a refusal; the wrong polarity on a bright-pin pad is still refused."""
    f = preset_frame("white-dark-331")
    field = find_pin_field(f.image, dark_pins=False)
    assert field.params.dark_pins is False
    assert np.array_equal(field.centres, find_pin_field(f.image).centres)
    assert field.count == int(f.visible.sum())
    with pytest.raises(NoSensorError, match="no sensor disc"):
        find_pin_field(preset_frame("tactip-331").image, dark_pins=True)


@pytest.mark.parametrize("sides", ["left", "left+bottom"])
@pytest.mark.parametrize("name", ["tactip-331", "dark-331", "brown-127", "radial-120", "rim-ring-331"])
def test_pin_field_of_a_pad_cut_by_the_frame_edge_meets_the_bar(name, sides):
    """The membrane cut by the frame edge: the disc is found through its visible rim, the polarity is
    decided, and the pins the frame shows whole are found (those it cuts may be or not); the black
    beyond the frame is no rim ring."""
    from tests.pins.test_disc import _cut

    for seed in (0, 1):
        f, _, sensor = _cut(name, seed, sides)
        field = find_pin_field(f.image)
        recall, precision, rmse = score(field.centres, f, gate_px=_gate_px(f))
        # This case failed in full-suite runs only (recall 0.79 and 0.88): the rim-ring search read
        # recycled memory beyond the frame (test_disc's ..._whatever_memory_the_polar_samples_reuse).
        # The message says what the search saw (the frame's digest, disc, field, parameters).
        seen = (hashlib.md5(f.image.tobytes()).hexdigest()[:10], field.disc, field.summary(), field.params)
        assert recall >= 0.99 and precision >= 0.99 and rmse <= 0.1, (seed, recall, precision, rmse, seen)
        assert field.params.dark_pins == sensor.dark_pins


@pytest.mark.parametrize("name", ["tactip-331", "dark-331", "brown-127", "radial-120"])
def test_no_pin_the_frame_edge_cuts_is_kept_on_a_pad_cut_by_it(name):
    """A pad cut by the frame edge (its disc found through the visible rim, not the whole frame): a pin
    whose tip the frame cuts leans inwards and the tracker loses it on every still frame (12 of 320
    lost and retired on tactip-331 with the pad 0.45 radius low, `bench/bench_conditions.py`). None is
    kept whose true centre lies more than 1.5 px nearer the frame's edge than the tip radius (before:
    2-12 per frame, 168 over five presets); the pins shown whole are all found."""
    from tests.pins.test_disc import _cut

    for seed in (0, 1):
        f, _, sensor = _cut(name, seed, "left+bottom")
        field = find_pin_field(f.image)
        height, width = f.image.shape[:2]
        distance, index = cKDTree(f.centres).query(field.centres)
        true = f.centres[index]
        room = np.minimum(np.minimum(true[:, 0] + 0.5, width - 0.5 - true[:, 0]),
                          np.minimum(true[:, 1] + 0.5, height - 0.5 - true[:, 1]))
        cut = room < sensor.pin_radius_px - 1.5
        assert not cut.any(), (seed, field.centres[cut], room[cut])
        recall, precision, _ = score(field.centres, f, gate_px=_gate_px(f))
        assert recall >= 0.99 and precision >= 0.99, (seed, recall, precision)


def test_a_noisy_camera_gives_the_pins_not_a_lattice_of_noise():
    """radial-led-120 filmed by a noisier camera (sigma 12 against the preset's 5): the candidate offsets
    (5-25 grey) were set on sigma 2-5; at offset 5 the blurred noise passed the threshold one pixel in
    six, a lattice of noise blobs near the pins' pitch was kept by more candidate sets than the pins
    and won the vote (126-169 pins found of 120, precision 0.30-0.59, held-out seeds 40-44). Each
    offset is now at least two standard deviations of the blurred noise: recall 0.97-0.99, precision
    0.99-1.00 on those seeds; here seeds 0-2."""
    for seed in (0, 1, 2):
        f = SyntheticTacTip.from_preset("radial-led-120", seed=seed, noise_sigma=12.0).render()
        field = find_pin_field(f.image)
        recall, precision, _ = score(field.centres, f, gate_px=_gate_px(f))
        assert recall >= 0.95 and precision >= 0.98, (seed, recall, precision, field.summary())


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_white_pins_filmed_large_outnumber_the_gaps_between_them(seed):
    """white-dark-331 filmed at 1920x1080 (tips of 13 px, pitch 43 px; `bench/bench_conditions.py`, seeds
    42-43): the dark polarity's disc is the pad and its search keeps 177 gaps between the pins at a
    pitch of 21.7 px; the white pins were probed at that pitch, whose blur and block are too small for
    them, kept 77-103 and lost: detect found 177 dark 'pins', none true. Probed also at sqrt(3) of it
    (the gaps of a hexagonal lattice lie 1/sqrt(3) pitch apart) they keep 331. Here that state: the
    gaps round the centre as the dark field, at the pitch the search measured (0.505 of the pins')."""
    from pins import SensorDisc
    from pins.lattice import _other_keeps_more
    from pins.scale import central_spacing_px

    sensor = SyntheticTacTip.from_preset("white-dark-331", seed=seed, noise_sigma=0.0)
    f = sensor.render()
    zoom, (cx, cy, radius) = 2.25, sensor.disc
    matrix = np.array([[zoom, 0, 719.5 - zoom * cx], [0, zoom, 539.5 - zoom * cy]])
    image = cv2.warpAffine(f.image.astype(np.float32), matrix, (1440, 1080), flags=cv2.INTER_LINEAR)
    image = np.clip(np.rint(image + np.random.default_rng(seed).normal(0, 4.0, image.shape)), 0, 255).astype(np.uint8)
    pins = f.centres * zoom + matrix[:, 2]
    gaps = pins[Delaunay(pins).simplices].mean(axis=1)
    gaps = gaps[np.argsort(np.hypot(gaps[:, 0] - 719.5, gaps[:, 1] - 539.5))[:170]]
    disc = SensorDisc(719.5, 539.5, zoom * radius)
    dark = PinField(centres=gaps, params=DetectionParams(dark_pins=True, rim_margin_px=0.34 * disc.radius_px),
                    disc=disc, pitch_px=0.505 * central_spacing_px(pins), rejected=np.zeros((0, 2)),
                    rejected_reason=np.zeros(0, str))
    assert _other_keeps_more(image, dark, DetectionParams())


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_radial_layout_with_led_reflections_keeps_the_pins_on_them(seed):
    """radial-led-120: pins on the four LED reflections inside the pad (background ~50 grey brighter,
    contrast ~35 against ~50) are kept and the reflections are not; the count is within 3 % of the pins
    drawn whole (the outermost ring under the veil and the rim glare is the faintest: a few of its pins
    stand 10-15 grey above noise of 5 and may be lost). Before the lattice holes were filled, 108-114
    of 120 were found and 8 of 119 pins on reflections (6 seeds) were lost; before they were probed and
    reflections' flat tops rejected, 35 of 2880 pins were missed and 2 reflections kept (seeds 0-11)."""
    sensor = preset_sensor("radial-led-120", seed)
    on_reflection = found_on_reflection = 0
    for contact in (None, TAP):
        f = preset_frame("radial-led-120", contact, seed=seed)
        field = find_pin_field(f.image)
        recall, precision, rmse = score(field.centres, f, gate_px=_gate_px(f))
        assert precision == 1.0 and recall >= 0.97, (contact, recall, precision, field.summary())
        # Tips fitted as opaque ellipses over the reflections' and the veil's curved flanks: 0.09-0.11 px
        # (blob centroids leaning up those flanks: 0.12-0.19; the bar of 0.1 is not met everywhere). The
        # faint outer-ring tips the probe finds (SNR 6-9) are placed to 0.37 px RMSE (30 of them, seeds
        # 0-11): with them 0.09-0.14.
        assert rmse <= 0.14, (contact, rmse)
        assert abs(field.count - int(f.visible.sum())) <= 0.03 * f.visible.sum()
        truth = f.centres[f.visible]
        reach = np.min(np.hypot(*(truth[:, None] - sensor.reflection_centres[None]).transpose(2, 0, 1))
                       / sensor.reflection_radii_px, axis=1)
        on = reach < 1.0
        on_reflection += int(on.sum())
        found_on_reflection += int((on & (cKDTree(field.centres).query(truth)[0] < _gate_px(f))).sum())
    assert on_reflection >= 10 and found_on_reflection >= on_reflection - 1, (found_on_reflection, on_reflection)


def _hexagon_with_a_hole(pitch: float):
    """A hexagonal lattice (``pitch`` px, radius 4.6 pitches about the origin), the index of its site at (2, 0)
    pitches, and the lattice without it: (lattice, hole, kept)."""
    rows = [(x + 0.5 * (y % 2), y * np.sqrt(3) / 2) for y in range(-5, 6) for x in range(-5, 6)
            if np.hypot(x + 0.5 * (y % 2), y * np.sqrt(3) / 2) <= 4.6]
    lattice = pitch * np.array(rows)
    hole = int(np.argmin(np.hypot(*(lattice - [2.0 * pitch, 0.0]).T)))
    return lattice, hole, np.delete(lattice, hole, axis=0)


def test_lattice_holes_are_filled_only_at_lattice_sites_inside_the_field():
    """fill_lattice_holes takes back a pin-like blob at a hole of the lattice (inside, and at the outer
    end of a lone row), and nothing else: not a blob off the sites, one too large (a reflection with its
    pins), one beyond the field (glare on the rim), one at the next row of a hexagonal edge (skin), nor
    one at the inner end of a radial spoke (the empty zone round the centre pin)."""
    from pins._rescue import fill_lattice_holes

    pitch = 10.0
    lattice, hole, kept = _hexagon_with_a_hole(pitch)
    edge = lattice[np.argmax(lattice[:, 1])]  # a pin of the top edge: the next row is beyond the field

    def blobs(points, area=12.0):
        points = np.asarray(points, float).reshape(-1, 2)
        return points, np.full(len(points), area), np.full(len(points), 0.8), np.full(len(points), 40.0)

    areas, contrasts = np.full(len(kept), 12.0), np.full(len(kept), 40.0)
    cases = {"hole": (blobs(lattice[hole] + 0.4), True),
             "off the sites": (blobs([25.0, 4.0]), False),
             "too large": (blobs(lattice[hole] + 0.4, area=80.0), False),
             "beyond the field": (blobs([0.0, 62.0]), False),
             "next hexagonal row": (blobs(edge + [0.0, pitch * np.sqrt(3) / 2]), False)}
    for name, ((c, a, fl, ct), expected) in cases.items():
        taken = fill_lattice_holes(kept, areas, contrasts, [(c, a, fl, ct, 15.0)], (0.0, 0.0))
        assert (taken == [(0, 0)]) == expected, name

    # A radial spoke: pins 1 pitch apart from 2.7 pitches out, its outermost pin missing; its inner
    # end points into the empty zone round the centre pin.
    angles = np.linspace(0, 2 * np.pi, 17, endpoint=False)
    radii = pitch * (2.7 + np.arange(7))
    spokes = np.array([[r * np.cos(a), r * np.sin(a)] for a in angles for r in radii])
    radial = np.vstack([[0.0, 0.0], spokes[:-1]])  # the last spoke's outermost pin missing
    areas, contrasts = np.full(len(radial), 12.0), np.full(len(radial), 40.0)
    outer = blobs(spokes[-1] + 0.3)
    inner = blobs([pitch * 1.7 * np.cos(angles[0]), pitch * 1.7 * np.sin(angles[0])])
    assert fill_lattice_holes(radial, areas, contrasts, [(*outer, 15.0)], (0.0, 0.0)) == [(0, 0)]
    assert fill_lattice_holes(radial, areas, contrasts, [(*inner, 15.0)], (0.0, 0.0)) == []


def test_a_holes_blob_of_a_few_pixels_is_not_judged_by_its_fill():
    """A blob of a few pixels fills its box by the grid's cut, not by its shape (the judge asks the fill only of
    blobs of `_FILL_AREA` px or more): a 1-2 px tip's blob at a hole fills 0.44-0.56 and was refused
    (bench_user_chain radial-led-120 seed 18: area 7-10 px beside pins of 9.5 px, lost though six candidate
    sets found it). Such a blob is taken back; a blob as poorly filled beside large pins (a crescent of a
    reflection's edge) is not."""
    from pins._rescue import fill_lattice_holes

    pitch = 10.0
    lattice, hole, kept = _hexagon_with_a_hole(pitch)
    contrasts = np.full(len(kept), 40.0)
    site = (lattice[hole] + 0.3).reshape(1, 2)
    for area, expected in ((9.0, True), (30.0, False)):
        blob = (site, np.array([area]), np.array([0.5]), np.array([38.0]), 15.0)
        taken = fill_lattice_holes(kept, np.full(len(kept), area), contrasts, [blob], (0.0, 0.0))
        assert (taken == [(0, 0)]) == expected, area


def test_probing_the_holes_finds_a_faint_pin_and_nothing_else():
    """probe_lattice_holes takes a faint pin (20 grey, its neighbours 45, noise 3) at a lattice hole, and nothing at a hole
    under a smooth bright hump (an LED reflection without its pin), nor past the outermost ring."""
    from pins._rescue import probe_lattice_holes

    rng = np.random.default_rng(7)
    pitch, radius = 10.0, 2.0
    grid = pitch * np.array([(x, y) for y in range(-4, 5) for x in range(-4, 5) if np.hypot(x, y) <= 4.05], float) + 60.0
    yy, xx = np.mgrid[0:120, 0:120]

    def render(pins, faint=(), hump=None):
        image = np.full((120, 120), 100.0)
        for x, y in pins:
            image += 45.0 * (np.hypot(xx - x, yy - y) <= radius)
        for x, y in faint:
            image += 20.0 * (np.hypot(xx - x, yy - y) <= radius)
        if hump is not None:
            image += 60.0 * 2.0 ** -(np.hypot(xx - hump[0], yy - hump[1]) / 8.0) ** 4
        return np.clip(image + rng.normal(0.0, 3.0, image.shape), 0, 255).astype(np.uint8)

    hole = int(np.argmin(np.hypot(*(grid - 60.0).T)))  # the centre site, (60, 60)
    kept = np.delete(grid, hole, axis=0)
    found = probe_lattice_holes(render(kept, faint=[grid[hole]]), kept, (60.0, 60.0), radius)
    assert len(found) == 1 and np.hypot(*(found[0] - grid[hole])) < 0.5
    assert len(probe_lattice_holes(render(kept, hump=grid[hole]), kept, (60.0, 60.0), radius)) == 0
    # Nothing past the field (a spot a pitch beyond the outermost pins), nor at an empty hole.
    assert len(probe_lattice_holes(render(kept, faint=[[60.0, 110.0]]), kept, (60.0, 60.0), radius)) == 0
    assert len(probe_lattice_holes(render(kept), kept, (60.0, 60.0), radius)) == 0


@pytest.mark.parametrize("name", ["radial-led-120", "radial-120", "small-pad-100", "tactip-331"])
def test_probing_adds_no_pin_off_the_pad(name):
    """Over several seeds, rest and tap, every pin the probe takes is a pin drawn there."""
    import pins.lattice as lattice
    from pins._tipfit import _REACH_PX, _REFIT_ROUNDS

    taken = []
    probe = lattice.probe_lattice_holes

    def spy(*args, **kwargs):
        found = probe(*args, **kwargs)
        taken.append(found[0] if isinstance(found, tuple) else found)  # (with the tips' lattice prior)
        return found

    for seed in range(3):
        for contact in (None, TAP):
            f = preset_frame(name, contact, seed=seed)
            taken.clear()
            with pytest.MonkeyPatch.context() as patch:
                patch.setattr(lattice, "probe_lattice_holes", spy)
                field = lattice.find_pin_field(f.image, dark_pins=False)
            found = np.vstack(taken) if taken else np.zeros((0, 2))
            drawn = f.centres[f.visible | f.partial]
            assert np.all(cKDTree(drawn).query(found)[0] < _gate_px(f)), (seed, contact, found)
            # Each kept, moved only by its tip fit (`pins._tipfit`: `_REACH_PX` a round).
            reach = (1 + _REFIT_ROUNDS) * _REACH_PX
            assert np.all(cKDTree(field.centres).query(found)[0] < reach) if len(found) else True


def test_radial_layout_with_led_reflections_count_over_many_seeds():
    """Issue 20, outcome 7's bar, over seeds 0-11 at rest and under a 5 mm tap: the count within 1 % on every
    frame, no reflection (nor anything else) kept, at most 2 of the 2880 pins missed (none when this was
    written). Before the holes were probed with the opaque-tip test (`pins._tipprobe`) 23 were missed and
    the bar met on 17 of 24 frames. (Seeds 0-11 are those the probe was developed on; on seeds 24-35, never
    looked at while developing, the bar was met on 24 of 24 frames, 1 pin missed and 1 false; on 12-23, on 21:
    see `NOT_YET_MET`.)"""
    within_bar = missed = drawn = 0
    for seed in range(12):
        for contact in (None, TAP):
            f = preset_frame("radial-led-120", contact, seed=seed)
            field = find_pin_field(f.image)
            recall, precision, _ = score(field.centres, f, gate_px=_gate_px(f))
            visible = int(f.visible.sum())
            assert precision == 1.0 and abs(field.count - visible) <= 0.03 * visible, (seed, contact, field.summary())
            within_bar += abs(field.count - visible) <= 0.01 * visible
            missed += round((1.0 - recall) * visible)
            drawn += visible
    assert missed <= 2 and within_bar == 24, (missed, within_bar)
