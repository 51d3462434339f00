"""Raster layers of the synthetic TacTip image: static scene, anti-aliased pin tips, sensor noise.

All images here are float32 grey levels (0-255 scale); `tactip.synthetic` composes them.
"""

from __future__ import annotations

import math

import numpy as np

EDGE_PX = 1.0  # width of the linear coverage ramp across a pin's edge, px
PIN_LEVEL = 215.0  # grey level of a pin tip at the apex under uniform light
MEMBRANE_LEVEL = 25.0  # grey level of the black membrane
CASING_LEVEL = 200.0  # grey level of the casing around the pad
LED_COUNT = 6  # LEDs on a ring around the base of the pad (paper 002, III-A)


def scene_layers(image_size, disc, *, gradient: bool, glare: bool):
    """Static layers of a frame.

    Parameters
    ----------
    image_size : (int, int)
        (width, height), px.
    disc : (float, float, float)
        Dark membrane disc (cx, cy, radius), px.
    gradient : bool
        Radial illumination gradient (brighter towards the LED ring) and vignetting of the casing.
    glare : bool
        Glare spots of the LEDs on the rim of the disc.

    Returns
    -------
    background : (H, W) float32
        Membrane inside the disc (1.5 px soft edge), bright casing outside.
    glare : (H, W) float32
        Additive light of the LED glare (zeros when ``glare`` is False).
    illumination : (H, W) float32
        Relative illumination of the pin tips (1 at the centre).
    """
    width, height = image_size
    cx, cy, radius = disc
    yy, xx = np.mgrid[0:height, 0:width].astype(np.float32)
    r = np.hypot(xx - cx, yy - cy) / np.float32(radius)
    inside = np.clip(0.5 + (1.0 - r) * radius / 1.5, 0.0, 1.0)
    if gradient:
        corner = math.hypot(max(cx, width - 1 - cx), max(cy, height - 1 - cy)) / radius
        illumination = 0.85 + 0.15 * r ** 2
        membrane = MEMBRANE_LEVEL - 4.0 + 32.0 * np.clip(r, 0, 1) ** 3
        casing = CASING_LEVEL + 15.0 - 50.0 * np.clip((r - 1.0) / max(corner - 1.0, 1e-6), 0, 1) ** 2
    else:
        illumination = np.ones_like(r)
        membrane = np.full_like(r, MEMBRANE_LEVEL)
        casing = np.full_like(r, CASING_LEVEL)
    background = membrane * inside + casing * (1.0 - inside)
    light = np.zeros_like(r)
    if glare:
        phi = np.arctan2(yy - cy, xx - cx)
        for k in range(LED_COUNT):
            centre = np.pi / LED_COUNT + 2 * np.pi * k / LED_COUNT
            dphi = np.angle(np.exp(1j * (phi - centre)))
            # a bright core on the rim, elongated along it, with a faint halo reaching into the disc
            core = np.exp(-0.5 * ((r - 0.98) * radius / 5.0) ** 2 - 0.5 * (dphi * radius / 16.0) ** 2)
            halo = np.exp(-0.5 * ((r - 0.97) * radius / 14.0) ** 2 - 0.5 * (dphi * radius / 35.0) ** 2)
            light += 190.0 * core + 25.0 * halo
    return background.astype(np.float32), light.astype(np.float32), illumination.astype(np.float32)


def paint_pins(scene, image_size, centres, shape, levels) -> None:
    """Paint anti-aliased elliptical pin tips into a flat (H*W,) float32 scene, in place.

    Each pin is evaluated on a square patch around its nearest pixel, all pins at once. Coverage
    ramps linearly over `EDGE_PX` across the edge (signed distance along the ray from the centre), and
    the tip is slightly domed, so the profile is point-symmetric about the true centre and its
    intensity-weighted centroid is that centre. Pins do not overlap, so painting adds
    ``coverage * (pin - scene)`` over the patches.

    Parameters
    ----------
    scene : (H * W,) float32 ndarray, modified in place
    image_size : (int, int)
        (width, height), px.
    centres : (M, 2) ndarray
        Ellipse centres (x, y), px.
    shape : (M, 2, 2) ndarray
        Ellipse matrices S (``e^T S^-1 e <= 1`` inside), px^2.
    levels : (M,) ndarray
        Grey level of each tip at its centre.
    """
    if len(centres) == 0:
        return
    width, height = image_size
    inverse = np.linalg.inv(shape).astype(np.float32)
    half = int(np.ceil(np.sqrt(np.linalg.eigvalsh(shape)[:, 1].max()) + 0.5 * EDGE_PX + 1))
    offsets = np.arange(-half, half + 1)
    anchor = np.rint(centres).astype(np.int64)
    frac = (anchor - centres).astype(np.float32)
    dx = offsets.astype(np.float32)[None, None, :] + frac[:, 0, None, None]  # (M, 1, S)
    dy = offsets.astype(np.float32)[None, :, None] + frac[:, 1, None, None]  # (M, S, 1)
    q = (2 * inverse[:, 0, 1, None, None] * dx) * dy
    q += inverse[:, 0, 0, None, None] * (dx * dx)
    q += inverse[:, 1, 1, None, None] * (dy * dy)  # (M, S, S): (normalised radius)^2
    rho = np.sqrt(q)
    edge = np.sqrt(dx * dx + dy * dy)  # then the signed distance to the edge, in ramp widths, + 1/2
    edge *= 1.0 - rho
    edge /= np.maximum(rho, np.float32(1e-6)) * np.float32(EDGE_PX)
    edge += np.float32(0.5)
    coverage = np.clip(edge, 0.0, 1.0, out=edge)
    px = anchor[:, 0, None, None] + offsets[None, None, :]
    py = anchor[:, 1, None, None] + offsets[None, :, None]
    pixel = py * width + px  # (M, S, S)
    if (anchor - half < 0).any() or (anchor[:, 0] + half >= width).any() or (anchor[:, 1] + half >= height).any():
        coverage *= (px >= 0) & (px < width) & (py >= 0) & (py < height)
        pixel = np.clip(pixel, 0, width * height - 1)
    np.minimum(q, 1.0, out=q)
    value = np.asarray(levels, dtype=np.float32)[:, None, None] * (1.0 - np.float32(0.15) * q)
    value -= scene[pixel]
    value *= coverage
    np.add.at(scene, pixel.reshape(-1), value.reshape(-1))


def byte_noise(rng: np.random.Generator, shape, sigma: float) -> np.ndarray:
    """Zero-mean near-Gaussian noise of standard deviation ``sigma``, float32.

    The sum of four uniform random bytes (Irwin-Hall, within 1 % of Gaussian in the bulk, tails
    bounded at 3.5 sigma), about twice as fast as ``rng.standard_normal`` for a whole frame.
    """
    n = int(np.prod(shape))
    octets = np.frombuffer(rng.bytes(4 * n), dtype=np.uint8).reshape(4, n)
    total = octets[0].astype(np.int16)
    total += octets[1]
    total += octets[2]
    total += octets[3]
    scale = np.float32(sigma / math.sqrt(4 * (256 ** 2 - 1) / 12))  # std of a sum of four uniform bytes
    noise = total.astype(np.float32)
    noise -= np.float32(4 * 255 / 2)
    noise *= scale
    return noise.reshape(shape)
