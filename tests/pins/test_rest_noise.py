"""The Refiner's rest-noise draws (`pins._rest._standard_draws`) are `rng.normal(0, sigma, shape)` of seed 0, bit for bit.

The draws are made once per crop shape and scaled by each rest crop's noise level; numpy's normal is
``0.0 + sigma * z`` of the same stream's standard normal draws, so every tap start sees the draws it
would have drawn itself (were that to change in numpy, this fails and the cache must go).
"""

import numpy as np
import pytest

from pins._rest import _NOISE_DRAWS, _standard_draws


@pytest.mark.parametrize("shape", [(468, 468), (37, 101)])
@pytest.mark.parametrize("sigma", [0.4, 4.694835662841797, 11.0])
def test_cached_draws_times_sigma_are_the_normal_draws_of_seed_0(shape, sigma):
    rng = np.random.default_rng(0)
    draws = _standard_draws(shape)
    assert len(draws) == _NOISE_DRAWS
    for draw in draws:
        expected = rng.normal(0.0, sigma, shape)
        assert np.multiply(draw, sigma).tobytes() == (expected + 0.0).tobytes()
        assert not draw.flags.writeable   # shared by every tap start: nobody may change them
