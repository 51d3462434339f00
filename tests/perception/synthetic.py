"""Small synthetic tap datasets with known structure, for the perception tests (not a test module)."""

import numpy as np

from perception import Dataset


def gap_dataset(*, depths=6, widths=3, taps_per_class=4, samples=10, dims=8, seed=0,
                legible_from=0.0, noise=0.05, width_gain=1.0, lateral=None, structure_seed=0,
                contact_floor=0.0):
    """Taps over a (depth, width) grid; the width is legible only where depth > `legible_from`.

    Each tap is a rise-and-release profile times per-dimension amplitudes: half the dimensions
    encode depth everywhere, the other half encode width scaled by contact strength, which is zero
    at depths up to `legible_from` (a fraction of the depth range) and grows linearly beyond
    (`contact_floor` > 0 keeps some width signal everywhere: 1 makes every class separable).
    Depths are 0..depths-1 mm, widths 1..widths mm. `lateral`, if given, is an array of lateral
    offsets (mm): every class gets `taps_per_class` taps at each offset, the width signal fading
    with |lateral|. `seed` draws the noise; `structure_seed` the per-dimension codes, so a
    training and a test set with different seeds come from the same sensor.
    """
    rng = np.random.default_rng(seed)
    structure = np.random.default_rng(structure_seed)
    depth_values = np.arange(depths, dtype=float)
    width_values = np.arange(1, widths + 1, dtype=float)
    offsets = np.zeros(1) if lateral is None else np.asarray(lateral, dtype=float)
    d, w, lat, _ = np.meshgrid(depth_values, width_values, offsets, np.arange(taps_per_class), indexing="ij")
    d, w, lat = d.ravel(), w.ravel(), lat.ravel()
    half = dims // 2
    depth_code = structure.uniform(0.5, 1.5, half)
    width_code = structure.uniform(0.5, 1.5, dims - half)
    fraction = d / max(depths - 1, 1)
    contact = np.clip((fraction - legible_from) / max(1 - legible_from, 1e-9), 0, 1)
    contact = contact_floor + (1 - contact_floor) * contact
    amplitude = np.concatenate([
        fraction[:, None] * depth_code,
        width_gain * (contact * w / widths * np.exp(-np.abs(lat)))[:, None] * width_code,
    ], axis=1)
    profile = np.sin(np.pi * (np.arange(samples) + 0.5) / samples) ** 2
    taps = profile[None, :, None] * amplitude[:, None, :] + noise * rng.normal(size=(len(d), samples, dims))
    return Dataset(taps, d, w, None if lateral is None else lat, "tactip",
                   sensor={"kind": "synthetic", "seed": seed})
