"""Sensor calibration against the synthetic TacTip's ground truth; its refusals; its file."""

import h5py
import numpy as np
import pytest
from scipy.spatial import cKDTree
from scipy.spatial.distance import pdist

from calibration import SCHEMA, CalibrationError, calibrate_sensor, load_calibration, save_calibration
from perception import Dataset, save_dataset
from pins import select_feature_pins
from tactip.sim import SyntheticTacTip


@pytest.fixture(scope="module")
def sensor():
    """The station's sensor: 331 pins, camera noise 4 grey levels."""
    return SyntheticTacTip(pins=331, noise_sigma=4.0, seed=0)


@pytest.fixture(scope="module")
def rest_frames(sensor):
    return [sensor.render().image for _ in range(5)]


@pytest.fixture(scope="module")
def calibration(rest_frames):
    return calibrate_sensor(rest_frames, expected_pins=331, selected_pins=40, min_separation_mm=4.0,
                            sensor={"source": "synthetic", "serial": "T-07"})


def test_reference_pins_are_the_true_pins(sensor, calibration):
    truth, visible = sensor.pin_centres()
    assert len(calibration.reference_pins) == 331 == visible.sum()
    # one detected pin per true pin, each within a tenth of a pixel (5 averaged noisy frames)
    distance, index = cKDTree(calibration.reference_pins).query(truth[visible])
    assert len(np.unique(index)) == 331
    assert distance.max() < 0.1
    assert calibration.rest_frames == 5 and calibration.frame_size == sensor.image_size
    cx, cy, radius = sensor.disc
    assert (calibration.disc.cx, calibration.disc.cy) == pytest.approx((cx, cy), abs=1.0)
    assert calibration.disc.radius_px == pytest.approx(radius, rel=0.02)
    # the scale is the pin pitch (mm, 331 pins on a 40 mm pad) over the central pin pitch (px): the renderer's
    assert calibration.mm_per_px == pytest.approx(sensor.mm_per_px, rel=0.05)
    assert "pin pitch 2.793 mm" in calibration.scale["source"]
    assert calibration.scale["mm_per_px"] == calibration.mm_per_px


def test_selected_pins_are_far_enough_apart_in_mm(calibration):
    chosen = calibration.selected_pins
    assert calibration.n_selected == 40 == len(np.unique(chosen))
    assert chosen.min() >= 0 and chosen.max() < len(calibration.reference_pins)
    separation_mm = pdist(calibration.reference_pins[chosen]) * calibration.mm_per_px
    assert separation_mm.min() >= 4.0


def test_a_larger_separation_selects_pins_further_apart(rest_frames, calibration):
    wide = calibrate_sensor(rest_frames, expected_pins=331, selected_pins=20, min_separation_mm=6.0)
    assert (pdist(wide.reference_pins[wide.selected_pins]) * wide.mm_per_px).min() >= 6.0
    assert np.array_equal(wide.reference_pins, calibration.reference_pins)


def test_a_measured_scale_overrides_the_pad_estimate(rest_frames):
    measured = calibrate_sensor(rest_frames, expected_pins=331, mm_per_px=0.146, selected_pins=20)
    assert measured.mm_per_px == 0.146
    assert (pdist(measured.reference_pins[measured.selected_pins]) * 0.146).min() >= 4.0


@pytest.mark.parametrize("pins", [127, 532])
def test_other_presets_calibrate_to_their_count(pins):
    sensor = SyntheticTacTip(pins=pins, seed=1)
    calibration = calibrate_sensor([sensor.render().image for _ in range(3)], expected_pins=pins)
    truth, visible = sensor.pin_centres()
    assert len(calibration.reference_pins) == pins
    assert cKDTree(calibration.reference_pins).query(truth[visible])[0].max() < 0.2


@pytest.mark.parametrize("name", ["rim-ring-331", "brown-127"])
def test_rim_glare_and_skin_texture_stay_out_of_the_reference_pins(name):
    """A rim ring hides some pins and carries glare; brown skin has light patches: the count confirms."""
    sensor = SyntheticTacTip.from_preset(name, seed=0)
    frames = [sensor.render() for _ in range(3)]
    expected = {"rim-ring-331": 331, "brown-127": 127}[name]
    calibration = calibrate_sensor([f.image for f in frames], expected_pins=expected)
    truth = frames[0].centres
    visible, drawn = frames[0].visible, frames[0].visible | frames[0].partial
    distance = cKDTree(truth[drawn]).query(calibration.reference_pins)[0]
    assert distance.max() < 3.0                                   # no glare, no skin kept
    assert cKDTree(calibration.reference_pins).query(truth[visible])[0].max() < 0.3   # every whole pin
    assert "expected" in calibration.describe()


# A noise frame is not here: it shows no sensor disc in either polarity, so the pin field is searched over the
# whole frame in both (a flat gel's search) among thousands of noise blobs, whose lattice judge iterates 20-50
# times (2 on a sensor's frame): 29 CPU-s at 480 x 640, 11 at 240 x 320. find_pin_field refuses exactly that
# frame (240 x 320, seed 0) in both polarities in tests/pins/test_flat_gel.py
# (test_camera_noise_filling_the_frame_is_no_sensor); the refusal's wrapping is the same for these two.
@pytest.mark.parametrize("frame", [
    np.full((480, 640), 128, np.uint8),                                          # uniform grey
    np.zeros((480, 640, 3), np.uint8),                                           # lens covered
], ids=["grey", "black"])
def test_a_frame_without_a_sensor_is_refused(frame):
    with pytest.raises(CalibrationError, match="no sensor in view"):
        calibrate_sensor([frame, frame], expected_pins=331)


def test_a_pin_count_far_from_expected_is_refused(rest_frames):
    with pytest.raises(CalibrationError, match="532 pins") as info:
        calibrate_sensor(rest_frames, expected_pins=532)
    assert "[sensor] pins" in str(info.value)


@pytest.mark.parametrize("frames, message", [
    ([], "no rest frames"),
    ([np.zeros((480, 640), np.uint8), np.zeros((240, 320), np.uint8)], "differ in size"),
])
def test_bad_rest_frames_are_refused(frames, message):
    with pytest.raises(CalibrationError, match=message):
        calibrate_sensor(frames, expected_pins=331)


def test_too_many_pins_for_the_separation_are_spread_as_far_as_the_pad_allows(rest_frames):
    # 300 of 331 pins cannot be 4 mm apart: calibrate takes them as far apart as they can be, by replay's rule.
    crowded = calibrate_sensor(rest_frames, expected_pins=331, selected_pins=300, min_separation_mm=4.0)
    reached = pdist(crowded.reference_pins[crowded.selected_pins]).min() * crowded.mm_per_px
    assert crowded.n_selected == 300 == len(np.unique(crowded.selected_pins))
    assert crowded.separation_mm == pytest.approx(reached) and reached < 4.0
    assert crowded.min_separation_mm == 4.0 and "as far as the pad allows; 4 mm asked" in crowded.describe()
    same = select_feature_pins(crowded.reference_pins, n_pins=300, min_separation_mm=4.0,
                               mm_per_px=crowded.mm_per_px, centre=(crowded.disc.cx, crowded.disc.cy))
    assert np.array_equal(same.indices, crowded.selected_pins)
    # One pin more than the pad has is still refused: a calibration has the feature pins it was asked for.
    with pytest.raises(CalibrationError, match="cannot select the feature pins: only 331 pins"):
        calibrate_sensor(rest_frames, expected_pins=331, selected_pins=332)


def test_a_radial_pad_too_small_for_40_pins_10_mm_apart_is_calibrated_as_replay_does():
    # A radial layout of 120 pins (the home-built sensor): 40 of them cannot be 10 mm apart.
    sensor = SyntheticTacTip.from_preset("radial-120", seed=4)
    image = sensor.render().image
    radial = calibrate_sensor([image], expected_pins=120, description="radial-120", min_separation_mm=10.0)
    assert radial.mm_per_px == pytest.approx(sensor.mm_per_px, rel=0.05) and "radial-120" in radial.scale["source"]
    assert radial.n_selected == 40 and radial.separation_mm < 10.0 and "10 mm asked" in radial.describe()
    reached = pdist(radial.reference_pins[radial.selected_pins]).min() * radial.mm_per_px
    assert radial.separation_mm == pytest.approx(reached)
    replayed = select_feature_pins(radial.reference_pins, n_pins=40, min_separation_mm=10.0, mm_per_px=radial.mm_per_px,
                                   centre=(radial.disc.cx, radial.disc.cy))
    assert np.array_equal(replayed.indices, radial.selected_pins)


def test_the_file_round_trips(tmp_path, calibration):
    path = tmp_path / "cal" / "calibration.h5"
    save_calibration(path, calibration)
    assert sorted(p.name for p in path.parent.iterdir()) == ["calibration.h5"]   # no temporary left behind
    loaded = load_calibration(path)
    assert np.array_equal(loaded.reference_pins, calibration.reference_pins)
    assert np.array_equal(loaded.selected_pins, calibration.selected_pins)
    assert loaded.detection == calibration.detection
    assert loaded.disc == calibration.disc
    for name in ("mm_per_px", "expected_pins", "frame_size", "min_separation_mm", "rest_frames", "sensor", "scale",
                 "separation_mm"):
        assert getattr(loaded, name) == getattr(calibration, name), name
    with h5py.File(path, "r") as f:
        assert f.attrs["schema"] == SCHEMA


def test_a_file_of_another_schema_is_refused(tmp_path):
    path = tmp_path / "train.h5"
    save_dataset(path, Dataset(np.zeros((1, 4, 2)), [0.0], [1.0], None, "tactip"))
    with pytest.raises(CalibrationError, match="not a TacTip calibration file"):
        load_calibration(path)


def test_a_damaged_or_foreign_file_is_refused(tmp_path, calibration):
    text = tmp_path / "notes.h5"
    text.write_text("not HDF5")
    with pytest.raises(CalibrationError, match="cannot be read"):
        load_calibration(text)
    damaged = tmp_path / "damaged.h5"
    save_calibration(damaged, calibration)
    with h5py.File(damaged, "r+") as f:
        del f.attrs["mm_per_px"]
    with pytest.raises(CalibrationError, match="mm_per_px"):
        load_calibration(damaged)
    with pytest.raises(CalibrationError, match="run 'tactip calibrate' first"):
        load_calibration(tmp_path / "missing.h5")


@pytest.mark.parametrize("name, value, words", [
    ("detection", "{not json", "unreadable settings"),
    ("mm_per_px", float("nan"), "mm_per_px must be in (0, 10]"),
    ("mm_per_px", 0.0, "mm_per_px must be in (0, 10]"),
    ("disc", np.array([320.0, 240.0, -5.0]), "radius > 0"),
    ("frame_size", np.array([0, 0]), "frame_size"),
])
def test_a_calibration_with_impossible_settings_is_refused_on_load(tmp_path, calibration, name, value, words):
    """Issue 9: the stored numbers are checked on load like a station file's keys, not used as they are."""
    path = tmp_path / "calibration.h5"
    save_calibration(path, calibration)
    with h5py.File(path, "r+") as f:
        f.attrs[name] = value
    with pytest.raises(CalibrationError) as info:
        load_calibration(path)
    assert words in str(info.value) and "run 'tactip calibrate' again" in str(info.value)


def test_a_calibration_with_selected_pins_out_of_range_is_refused(tmp_path, calibration):
    path = tmp_path / "calibration.h5"
    save_calibration(path, calibration)
    with h5py.File(path, "r+") as f:
        f["selected_pins"][0] = len(calibration.reference_pins)
    with pytest.raises(CalibrationError, match="selected_pins must index"):
        load_calibration(path)


def test_a_calibration_cut_short_says_so(tmp_path, calibration):
    path = tmp_path / "calibration.h5"
    save_calibration(path, calibration)
    size = path.stat().st_size
    with open(path, "r+b") as f:
        f.truncate(size // 3)
    with pytest.raises(CalibrationError, match=rf"cut short \({size // 3} of its {size} bytes"):
        load_calibration(path)
