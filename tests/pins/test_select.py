"""pins.select: 40 pins at least 4 mm apart, greedy from the centre, deterministic."""

import numpy as np
import pytest
from scipy.spatial.distance import pdist

from pins import PinsError, ShapeError, select_feature_pins, select_pins
from tests.pins.conftest import sensor


@pytest.mark.parametrize("pins", [331, 532])
def test_selection_respects_the_separation(pins):
    s = sensor(pins)
    rest = s.rest_centres
    chosen = select_pins(rest, n_pins=40, min_separation_mm=4.0, mm_per_px=s.mm_per_px)
    assert chosen.shape == (40,) and len(set(chosen.tolist())) == 40
    assert pdist(rest[chosen]).min() * s.mm_per_px >= 4.0


def test_greedy_from_the_centre():
    s = sensor(532)
    rest = s.rest_centres
    chosen = select_pins(rest, n_pins=40, min_separation_mm=4.0, mm_per_px=s.mm_per_px)
    distance = np.linalg.norm(rest - rest.mean(axis=0), axis=1)
    assert chosen[0] == np.argmin(distance)
    assert np.all(np.diff(distance[chosen]) >= -1e-9)
    # Maximal: every pin nearer the centre than the last chosen one was blocked by a chosen pin.
    separation_px = 4.0 / s.mm_per_px
    nearer = np.flatnonzero(distance < distance[chosen[-1]])
    skipped = np.setdiff1d(nearer, chosen)
    gaps = np.linalg.norm(rest[skipped][:, None] - rest[chosen][None], axis=2).min(axis=1)
    assert np.all(gaps < separation_px)


def test_deterministic_and_independent_of_input_order(rng):
    s = sensor(331)
    rest = s.rest_centres
    chosen = select_pins(rest, mm_per_px=s.mm_per_px)
    assert np.array_equal(chosen, select_pins(rest.copy(), mm_per_px=s.mm_per_px))
    # A jittered copy in a shuffled order selects the same physical pins.
    permutation = rng.permutation(len(rest))
    jittered = rest + rng.normal(0, 1e-3, rest.shape)
    shuffled = select_pins(jittered[permutation], mm_per_px=s.mm_per_px)
    assert set(permutation[shuffled].tolist()) == set(chosen.tolist())


def test_too_many_pins_is_a_clear_error():
    s = sensor(331)
    with pytest.raises(PinsError, match="at least 4 mm apart"):
        select_pins(s.rest_centres, n_pins=300, min_separation_mm=4.0, mm_per_px=s.mm_per_px)


def test_arguments_checked():
    rest = np.zeros((10, 2))
    with pytest.raises(ValueError, match="mm_per_px"):
        select_pins(rest, mm_per_px=0.0)
    with pytest.raises(ValueError, match="n_pins"):
        select_pins(rest, n_pins=0, mm_per_px=0.1)
    with pytest.raises(ShapeError):
        select_pins(np.zeros((10, 3)), mm_per_px=0.1)
    with pytest.raises(PinsError, match="finite"):
        select_pins(np.full((10, 2), np.nan), mm_per_px=0.1)


def test_median_spacing_of_a_square_grid_is_its_pitch():
    from pins import median_spacing_px

    x, y = np.meshgrid(np.arange(5) * 12.5, np.arange(4) * 12.5)
    assert median_spacing_px(np.column_stack([x.ravel(), y.ravel()])) == pytest.approx(12.5)
    assert np.isnan(median_spacing_px(np.zeros((1, 2))))


# select_feature_pins: never fails for lack of room.

def test_feature_pins_as_requested_equal_select_pins():
    s = sensor(331)
    rest = s.rest_centres
    chosen = select_feature_pins(rest, n_pins=40, min_separation_mm=4.0, mm_per_px=s.mm_per_px)
    assert chosen.as_requested and chosen.warning == "" and chosen.n_pins == 40
    assert np.array_equal(chosen.indices, select_pins(rest, n_pins=40, min_separation_mm=4.0, mm_per_px=s.mm_per_px))
    assert chosen.separation_mm == pytest.approx(pdist(rest[chosen.indices]).min() * s.mm_per_px)
    assert chosen.separation_mm >= 4.0


def test_feature_pins_spread_as_far_as_the_pad_allows():
    s = sensor(331)
    rest = s.rest_centres
    # 300 pins cannot be 4 mm apart (about 36 can): 300 pins, as far apart as the greedy rule allows.
    chosen = select_feature_pins(rest, n_pins=300, min_separation_mm=4.0, mm_per_px=s.mm_per_px)
    assert chosen.n_pins == 300 and len(set(chosen.indices.tolist())) == 300
    reached = pdist(rest[chosen.indices]).min() * s.mm_per_px
    assert chosen.separation_mm == pytest.approx(reached) and reached < 4.0
    assert "cannot be 4 mm apart" in chosen.warning and f"{reached:.2f} mm" in chosen.warning
    # Largest: a hair more separation and the same rule no longer finds 300.
    with pytest.raises(PinsError):
        select_pins(rest, n_pins=300, min_separation_mm=reached * 1.001, mm_per_px=s.mm_per_px)


def test_feature_pins_fewer_than_asked_with_a_warning():
    s = sensor(127)
    rest = s.rest_centres[:30]
    chosen = select_feature_pins(rest, n_pins=40, min_separation_mm=4.0, mm_per_px=s.mm_per_px)
    assert chosen.n_pins == 30 and sorted(chosen.indices.tolist()) == list(range(30))
    assert "only 30 pins" in chosen.warning and not chosen.as_requested
    single = select_feature_pins(rest[:1], n_pins=40, mm_per_px=1.0)
    assert single.n_pins == 1 and single.separation_mm == np.inf


def test_feature_pins_deterministic():
    s = sensor(532)
    a = select_feature_pins(s.rest_centres, n_pins=120, mm_per_px=s.mm_per_px)
    b = select_feature_pins(s.rest_centres.copy(), n_pins=120, mm_per_px=s.mm_per_px)
    assert np.array_equal(a.indices, b.indices) and a.separation_mm == b.separation_mm
