"""Simulated taxel sensors: geometry, receptive fields, temporal response, noise, determinism, datasets."""

import numpy as np
import pytest

from perception import load_dataset
from tactip.cli import main
from tactip.taxel import (FULL_SCALE_COUNTS, TaxelSensor, TaxelSimulator, contact_profile, receptive_field_response,
                          segment_taps, simulate_taxel_datasets, sweep_locations, taxel_pressure, taxel_sensor)


def test_presets_have_the_papers_taxel_counts_and_ranges():
    fingertip, skin = taxel_sensor("fingertip"), taxel_sensor("skin")
    assert fingertip.n_taxels == 12 and fingertip.location_range_mm == (0.0, 30.0)
    assert skin.n_taxels == 48 and skin.location_range_mm == (0.0, 50.0)
    assert len(set(fingertip.dim_names)) == 12 and fingertip.dim_names[0] == "taxel00"
    with pytest.raises(ValueError, match="unknown taxel sensor 'palm'; choose from fingertip, skin"):
        taxel_sensor("palm")


def test_fingertip_taxels_are_not_on_a_line_and_rows_are_4mm_apart():
    u, v = taxel_sensor("fingertip").taxel_positions_mm.T
    assert len(np.unique(v)) >= 3                            # spread across the width
    # twelve plates: four rows of three; the row positions (flank plates) step by about 4 mm
    rows = np.unique(u[v != 0])
    assert len(rows) == 4 and np.all(np.abs(np.diff(rows) - 4.0) <= 1.0)


def test_skin_taxels_are_distinct_and_span_four_triangles():
    positions = taxel_sensor("skin").taxel_positions_mm
    distances = np.linalg.norm(positions[:, None] - positions[None], axis=-1) + np.eye(48) * 1e9
    assert distances.min() == pytest.approx(5.0)             # triangular lattice pitch
    assert np.ptp(positions[:, 0]) > 50.0 and np.ptp(positions[:, 1]) < 26.0


def test_receptive_field_is_gaussian_with_the_stated_width():
    # One plate, a point contact, no pressed-span edges: response = exp(-d^2 / (2 sigma^2)), 4 sigma = 8 mm.
    sensor = TaxelSensor("one", np.array([[10.0, 0.0]]), receptive_field_mm=8.0, location_range_mm=(0.0, 20.0),
                         sweep_offset_mm=0.0, contact="point")
    r = receptive_field_response(sensor, [10.0, 12.0, 14.0, 6.0])[:, 0]
    np.testing.assert_allclose(r, np.exp(-np.array([0.0, 4.0, 16.0, 16.0]) / 8.0), rtol=1e-12)
    assert r[2] == pytest.approx(np.exp(-2.0))               # "8 mm across": +-4 mm at exp(-2)


def test_fingertip_responds_in_the_middle_and_not_at_the_ends_of_the_range():
    sensor = taxel_sensor("fingertip")
    r = receptive_field_response(sensor, np.linspace(0, 30, 301))
    x = np.linspace(0, 30, 301)
    assert r[(x < 3) | (x > 27)].max() < 0.01              # rigid base / missing the rod: no response
    strongest = r.max(axis=1)
    assert strongest[(x > 8) & (x < 21)].min() > 0.7         # the sensing span is covered without holes
    # overlapping fields: a contact between rows excites several taxels at once
    assert ((r > 0.3).sum(axis=1)[(x > 8) & (x < 21)] >= 3).all()


def test_skin_responds_over_its_whole_range():
    r = receptive_field_response(taxel_sensor("skin"), np.linspace(0, 50, 201))
    assert r.max(axis=1).min() > 0.5 and ((r > 0.2).sum(axis=1) >= 2).all()


def test_contact_profile_rises_holds_and_releases():
    t = np.linspace(-0.1, 0.4, 501)
    p = contact_profile(t, rise_s=0.1, hold_s=0.05, release_s=0.1)
    assert p[t < 0].max() == 0 and p[t > 0.25].max() == 0
    assert np.all(np.diff(p[(t >= 0) & (t <= 0.1)]) >= 0) and p[(t >= 0.1) & (t <= 0.15)].min() == pytest.approx(1)
    assert np.all(np.diff(p[(t >= 0.15) & (t <= 0.25)]) <= 0)


def test_stream_is_8bit_at_50hz_and_contact_lowers_the_reading():
    sim = TaxelSimulator("fingertip", seed=3)
    stream = sim.stream([2.0, 14.0], seed=1)
    assert stream.readings.dtype == np.uint8 and stream.readings.shape == (200, 12)
    np.testing.assert_allclose(np.diff(stream.timestamps_s), 0.02)
    np.testing.assert_allclose(stream.tap_starts_s, [0.0, 2.0])
    rest = stream.readings[:100].astype(float)              # tap at 2 mm: no contact
    np.testing.assert_allclose(rest.mean(axis=0), sim.rest_counts, atol=6.0)   # drift is a few counts
    tap = stream.readings[100:200].astype(float)
    drop = rest.mean(axis=0) - tap.min(axis=0)
    assert drop.max() > 40                                   # strong contact lowers the reading


def test_rest_noise_is_white_plus_common_mode():
    # No contact anywhere: the readings minus their slow drift show the read noise.
    sim = TaxelSimulator("fingertip", seed=0, drift_counts=0.0)
    readings = sim.stream(np.zeros(200), seed=5).readings.astype(float)
    residual = readings - readings.mean(axis=0)
    white, common = sim.white_noise_counts, sim.common_noise_counts
    expected = np.sqrt(white**2 + common**2 + 1 / 12)        # white, common, rounding
    assert residual.std() == pytest.approx(expected, rel=0.1)
    correlation = np.corrcoef(residual.T)[np.triu_indices(12, 1)].mean()
    assert correlation == pytest.approx(common**2 / expected**2, abs=0.06)


def test_taps_peak_where_the_receptive_fields_say():
    sim = TaxelSimulator("fingertip", seed=2, white_noise_counts=0.0, common_noise_counts=0.0, drift_counts=0.0,
                         amplitude_jitter=0.0, position_noise_mm=0.0, gain_spread=0.0)
    x = np.array([6.0, 10.0, 14.0, 18.0, 22.0])
    taps = sim.taps(x, seed=1)
    assert taps.shape == (5, 50, 12) and taps.dtype == np.float32
    np.testing.assert_allclose(taps[:, :8], 0.0, atol=0.6 / FULL_SCALE_COUNTS)   # rest before contact
    peak = taps.max(axis=1) * FULL_SCALE_COUNTS
    field = receptive_field_response(sim.sensor, x) * sim.sensor.peak_counts
    # the peaks follow the fields (to the rounding of counts); the foam's lag takes a little off the top
    np.testing.assert_allclose(peak / peak.max(axis=1, keepdims=True),
                               field / field.max(axis=1, keepdims=True), atol=0.02)
    assert np.all((peak.max(axis=1) > 0.8 * field.max(axis=1)) & (peak.max(axis=1) <= field.max(axis=1) + 0.5))
    # the strongest taxel is one whose field is the largest (flank plates of a row tie)
    np.testing.assert_allclose(field[np.arange(5), peak.argmax(axis=1)], field.max(axis=1))
    assert 0.25 < taps[2].max(axis=1).argmax() * 0.02 < 0.5  # peak ~0.1-0.2 s after contact onset at 0.25 s


def test_deterministic_given_seeds_and_collections_are_independent():
    locations = sweep_locations(taxel_sensor("fingertip"), 40)
    a = TaxelSimulator("fingertip", seed=7)
    b = TaxelSimulator("fingertip", seed=7)
    np.testing.assert_array_equal(a.stream(locations, seed=1).readings, b.stream(locations, seed=1).readings)
    np.testing.assert_array_equal(a.gains, b.gains)
    other = a.stream(locations, seed=2).readings
    assert not np.array_equal(other, b.stream(locations, seed=1).readings)
    assert not np.array_equal(TaxelSimulator("fingertip", seed=8).gains, a.gains)
    # the simulator's own generator continues: two calls without a seed differ
    assert not np.array_equal(a.taps(locations[:3]), a.taps(locations[:3]))


def test_taps_are_the_stream_through_the_public_preprocessing():
    sim = TaxelSimulator("skin", seed=4)
    locations = np.linspace(5, 45, 30)
    stream = sim.stream(locations, seed=9)
    pressure = taxel_pressure(stream.readings)
    expected = segment_taps(stream.timestamps_s, pressure, starts_s=stream.tap_starts_s).taps
    np.testing.assert_allclose(sim.taps(locations, seed=9), expected, atol=1e-6)


def test_simulate_datasets_writes_independent_train_and_test(tmp_path):
    paths = simulate_taxel_datasets(tmp_path, sensor="fingertip", seed=3, locations=300)
    train, test = load_dataset(paths.train), load_dataset(paths.test)
    for ds in (train, test):
        assert ds.front_end == "taxel" and ds.taps.shape == (300, 50, 12)
        assert ds.location_unit == "mm" and ds.identity_unit == "none" and np.all(ds.identity == 0.0)
        assert ds.sensor["kind"] == "taxel" and ds.sensor["preset"] == "fingertip" and ds.sensor["taxels"] == 12
        np.testing.assert_allclose(ds.location, (np.arange(300) + 0.5) * 0.1)
    assert (train.sensor["collection"], test.sensor["collection"]) == ("train", "test")
    # same sensor, same locations, fresh noise: close on average, never identical
    assert not np.array_equal(train.taps, test.taps)
    np.testing.assert_allclose(train.taps.max(axis=1).mean(axis=0), test.taps.max(axis=1).mean(axis=0), atol=0.01)


def test_cli_simulate_taxel(tmp_path, capsys):
    out = tmp_path / "skin"
    assert main(["simulate", "taxel", "--sensor", "skin", "--out", str(out), "--locations", "100",
                 "--seed", "2", "--quiet", "--csv"]) == 0
    text = capsys.readouterr().out
    assert "train.h5" in text and "test.h5" in text and "test_stream.csv" in text
    assert load_dataset(out / "test.h5").taps.shape == (100, 50, 48)
    assert (out / "test_stream.csv").stat().st_size > 0
    with pytest.raises(SystemExit) as exc:
        main(["simulate", "taxel", "--sensor", "palm", "--out", str(out)])
    assert exc.value.code == 2
