"""Simulated stimuli of papers 001, 003, 004: the documented physics, and the two sessions."""

import numpy as np
import pytest

from tactip.taxel.collect import simulate_stimulus_dataset
from tactip.reproduce.stimuli import make_stimulus


def test_wider_rods_press_harder_and_wider():
    rods = make_stimulus("rods")
    x = np.full(5, 8.0)
    field = rods.field(x, rods.identities, {})                        # (5 rods, 12 taxels)
    assert (np.diff(field.sum(axis=1)) > 0).all()                     # more force for wider rods
    u = rods.sensor.taxel_positions_mm[:, 0]
    centre = (field * u).sum(axis=1) / field.sum(axis=1)
    spread = np.sqrt((field * (u - centre[:, None]) ** 2).sum(axis=1) / field.sum(axis=1))
    assert (np.diff(spread) > 0).all()                                # ... over a wider strip


def test_rod_sessions_differ_by_placement_and_indentation():
    rods = make_stimulus("rods")
    a, b = (rods.session(np.random.default_rng(s)) for s in (0, 1))
    assert set(a) == {"depth_mm", "tilt", "shift_mm"} and a["depth_mm"].shape == (5,)
    x, d = np.full(5, 8.0), rods.identities
    assert not np.allclose(rods.field(x, d, a), rods.field(x, d, b))
    train = simulate_stimulus_dataset(rods, seed=0, collection="train", taps_per_identity=16)
    test = simulate_stimulus_dataset(rods, seed=0, collection="test", taps_per_identity=16)
    np.testing.assert_array_equal(train.location, test.location)
    assert sorted(set(train.identity.tolist())) == [4.0, 6.0, 8.0, 10.0, 12.0] and train.location.max() < 16


def test_texture_contact_starts_saturates_and_its_signature_grows_with_depth():
    textures = make_stimulus("textures")
    depth = np.array([0.0, 0.5, 1.0, 2.0, 2.9])
    p60 = textures.field(depth, np.zeros(5), {})
    p800 = textures.field(depth, np.full(5, 9), {})
    assert p800[0].max() < 0.01 < p800[1].max()                       # no contact at zero depth
    assert (np.diff(p800.sum(axis=1)) > 0).all()
    gains = np.diff(p800.sum(axis=1)) / np.diff(depth)
    assert gains[-1] < 0.6 * gains[-2]                                # the foam saturates
    assert (p60.sum(axis=1)[1:] > p800.sum(axis=1)[1:]).all()         # coarse grains press harder
    # the signature: the taxel pattern of p60 relative to p800's, further from flat at depth
    contrast = [np.std(p60[k] / p800[k], where=p800[k] > 0.05) for k in (2, 4)]
    assert contrast[1] > contrast[0] > 0
    delay = textures.contact_delay_s(depth, np.zeros(5))
    assert (np.diff(delay) < 0).all()                                 # deeper surfaces are met sooner


def test_edge_angles_and_positions():
    edge = make_stimulus("edge")
    angles = np.arange(0.0, 360.0, 45.0)
    over_air = edge.field(np.full(8, 9.0), angles, {})
    over_plate = edge.field(np.full(8, -9.0), angles, {})
    at_edge = edge.field(np.zeros(8), angles, {})
    assert over_air.max() < 0.05                                      # nothing under the pad
    np.testing.assert_allclose(over_plate, np.broadcast_to(over_plate[0], (8, 12)), atol=0.01)  # no angle to tell
    assert np.min([np.abs(at_edge[i] - at_edge[j]).max() for i in range(8) for j in range(i)]) > 0.1
    assert edge.identity_period == 360.0 and len(edge.identities) == 72


def test_unknown_stimulus():
    with pytest.raises(ValueError, match="choose from rods, textures, edge"):
        make_stimulus("sphere")
