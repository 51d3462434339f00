"""Synthetic labelled taps as `tactip dataset build` makes them: one location, the label as the identity.

Not a test module. Each class has its own mean tap (a rise-and-release profile times a per-dimension
code), plus Gaussian noise; dims come in (x, y) pairs, one pair per pin, and a pin may be unseen for a
whole tap (NaN in both its dims), as in replayed recordings.
"""

import numpy as np

from perception import Dataset

#: Directions of the circular label, deg: eight, 45 deg apart, 0 and 315 beside each other across the wrap.
DIRECTIONS = np.arange(0, 360, 45.0)


def labelled_taps(label="circular", *, per_class=30, samples=6, pins=12, separation=1.0, noise=1.0, unseen=0.0,
                  seed=0, structure_seed=0, classes=6):
    """A labelled dataset of one location: taps drawn from class-dependent Gaussians.

    Parameters
    ----------
    label : {"circular", "numeric", "named"}
        ``circular``: eight slide directions (deg, period 360), the class mean moving round a circle
        (cos, sin) in feature space, so that neighbours across 0 deg are as alike as any others;
        ``numeric``: depths 1..`classes` mm whose mean tap grows linearly along one code (ridge's case);
        ``named``: `classes` shapes with unrelated random mean taps.
    per_class : int
        Taps per class.
    samples, pins : int
        Samples per tap; pins (two dims each).
    separation, noise : float
        Scale of the class means and of the noise (px).
    unseen : float
        Probability that a pin is unseen for a whole tap (its two dims NaN).
    seed, structure_seed : int
        Noise and unseen pins; the class codes (a training and a test set share them).
    classes : int
        Classes of a numeric or named label.
    """
    rng = np.random.default_rng(seed)
    structure = np.random.default_rng(structure_seed)
    dims = 2 * pins
    profile = np.sin(np.pi * (np.arange(samples) + 0.5) / samples) ** 2
    codes = structure.standard_normal((max(classes, 2), dims))
    extra = {}
    if label == "circular":
        values = DIRECTIONS
        angle = np.radians(values)
        means = np.cos(angle)[:, None] * codes[0] + np.sin(angle)[:, None] * codes[1]
        unit, extra = "deg", {"identity_period": 360.0}
    elif label == "numeric":
        values = np.arange(1.0, classes + 1)
        means = (values[:, None] - values.mean()) / classes * codes[0]
        unit = "mm"
    elif label == "named":
        values = np.arange(float(classes))
        means = codes[:classes] / np.sqrt(2)
        unit, extra = "none", {"identity_names": tuple(f"shape{k}" for k in range(classes))}
    else:
        raise ValueError(f"label must be circular, numeric or named, got {label!r}")
    identity = np.repeat(values, per_class)
    mean = separation * means[np.repeat(np.arange(len(values)), per_class)]
    taps = profile[None, :, None] * mean[:, None, :] + noise * rng.standard_normal((len(identity), samples, dims))
    hidden = rng.random((len(identity), pins)) < unseen
    hidden[hidden.all(axis=1), 0] = False                      # every tap keeps at least one pin
    taps[np.repeat(hidden, 2, axis=1)[:, None, :].repeat(samples, axis=1)] = np.nan
    return Dataset(taps, np.zeros(len(identity)), identity, None, "tactip", "none", unit, **extra)
