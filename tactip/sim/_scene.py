"""Image-fixed light inside the pad: internal LED reflections, a glare gradient, and their shimmer.

On home-built TacTips the LEDs shine through a clear window and reflect in it (and in the gel's
inner surface): the camera sees soft bright blobs inside the pad and a glare that brightens one side
of the pad more than the other. Both are fixed in the CAMERA's frame: they are light paths between
the LEDs, the window and the lens, which do not move when the membrane behind them is pressed or
dragged, so pins slide under and out of them. Their brightness flickers a little from frame to
frame (LED current ripple, the gel's surface moving under the window): "shimmer".
"""

from __future__ import annotations

import math

import numpy as np

PIN_LIGHT_SHARE = 0.7  # a pin under the light gains this share of it (its white paint is near the knee
#                        of the camera's response), so it stands out less there: 50 -> 35 grey under 50 of light
REFLECTION_RADIUS_FRACTION = (0.2, 0.7)  # reflection centres, fraction of the disc radius from its centre
REFLECTION_SIZE_SPACINGS = (0.75, 1.5)  # reflection radius (half maximum), pin spacings: 1.5-3 across
REFLECTION_POWER = 4.0  # flat-topped profile 2^-(r / radius)^4: within 15 % of the peak out to 0.7 radius
GRADIENT_SHIMMER = 0.5  # the glare gradient shimmers half as much as a reflection
JITTER_PX_PER_GREY = 0.05  # reflection centres jitter by this x shimmer px (std) per frame...
JITTER_MAX_PX = 0.25  # ...at most this


class PadLight:
    """LED reflections and the glare gradient inside the pad disc, optionally shimmering.

    Parameters
    ----------
    image_size : (int, int)
        (width, height), px.
    disc : (float, float, float)
        The pad disc (cx, cy, radius), px.
    rng : numpy.random.Generator
        Draws the reflections' positions, sizes and the gradient's direction (once).
    reflections : int
        Number of reflection blobs.
    reflection_level : float
        Grey levels each reflection adds at its centre.
    spacing_px : float
        Pin spacing at the apex, px (sets the reflections' size).
    gradient_level : float
        Grey levels the glare adds on the brightest side of the disc (0 on the opposite side).
    shimmer : float
        Per-frame standard deviation of each reflection's peak brightness, grey levels.

    Attributes
    ----------
    centres : (K, 2) float64 ndarray
        Reflection centres (x, y), px (at rest; shimmer jitters them by a fraction of a px).
    radii_px : (K,) float64 ndarray
        Radius at half maximum of each reflection, px.
    gradient_direction_rad : float
        Direction from the dim to the bright side of the glare gradient, radians from image x.
    """

    def __init__(self, image_size, disc, rng: np.random.Generator, *, reflections: int, reflection_level: float,
                 spacing_px: float, gradient_level: float, shimmer: float):
        width, height = image_size
        cx, cy, radius = disc
        self.image_size, self.disc = (int(width), int(height)), disc
        count = int(reflections)
        azimuth = rng.uniform(0, 2 * np.pi) + 2 * np.pi * np.arange(count) / max(count, 1)
        azimuth += rng.normal(0.0, 0.1 * 2 * np.pi / max(count, 1), count)
        distance = radius * rng.uniform(*REFLECTION_RADIUS_FRACTION, count)
        self.centres = np.column_stack([cx + distance * np.cos(azimuth), cy + distance * np.sin(azimuth)])
        self.radii_px = spacing_px * rng.uniform(*REFLECTION_SIZE_SPACINGS, count)
        self.levels = float(reflection_level) * rng.uniform(0.85, 1.15, count)
        self.gradient_direction_rad = float(rng.uniform(0, 2 * np.pi))
        self.gradient_level, self.shimmer = float(gradient_level), float(shimmer)
        yy, xx = np.mgrid[0:height, 0:width].astype(np.float32)
        r = np.hypot(xx - cx, yy - cy) / np.float32(radius)
        self._inside = np.clip(0.5 + (1.0 - r) * radius / 1.5, 0.0, 1.0).astype(np.float32)
        along = ((xx - cx) * math.cos(self.gradient_direction_rad)
                 + (yy - cy) * math.sin(self.gradient_direction_rad)) / np.float32(radius)
        self._ramp = (0.5 + 0.5 * np.clip(along, -1.0, 1.0)) * self._inside  # 0..1 across the disc
        self._static = None
        self._static = self.frame_layer(None) if self.shimmer == 0 else None

    @property
    def active(self) -> bool:
        """Whether there is any light to add."""
        return bool(len(self.centres) and self.levels.max() > 0) or self.gradient_level > 0

    def frame_layer(self, rng: np.random.Generator | None) -> np.ndarray:
        """The light of one frame, (H, W) float32 grey levels; ``rng`` draws the shimmer (None: none)."""
        if rng is None and self._static is not None:
            return self._static
        levels, gradient, centres = self.levels, self.gradient_level, self.centres
        if rng is not None and self.shimmer > 0:
            levels = np.clip(levels + self.shimmer * rng.standard_normal(len(levels)), 0.0, None)
            gradient = max(gradient + GRADIENT_SHIMMER * self.shimmer * float(rng.standard_normal()), 0.0) \
                if gradient > 0 else 0.0
            jitter = min(JITTER_PX_PER_GREY * self.shimmer, JITTER_MAX_PX)
            centres = centres + jitter * rng.standard_normal(centres.shape)
        layer = np.float32(gradient) * self._ramp
        width, height = self.image_size
        for (x, y), radius, level in zip(centres, self.radii_px, levels):
            half = int(math.ceil(2.5 * radius))  # 2^-(2.5^4) < 1e-11
            x0, x1 = max(int(x) - half, 0), min(int(x) + half + 2, width)
            y0, y1 = max(int(y) - half, 0), min(int(y) + half + 2, height)
            if x0 >= x1 or y0 >= y1:
                continue
            yy, xx = np.mgrid[y0:y1, x0:x1].astype(np.float32)
            rho = np.hypot(xx - np.float32(x), yy - np.float32(y)) / np.float32(radius)
            layer[y0:y1, x0:x1] += np.float32(level) * np.exp2(-rho ** REFLECTION_POWER) * self._inside[y0:y1, x0:x1]
        return layer
