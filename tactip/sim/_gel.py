"""Mechanics and light of the flat gel (the model is argued in `tactip.sim`, "Flat gels").

Gel coordinates are mm in the gel's plane, origin at the image centre, x along image x and y along
image y; the camera looks at the gel square on through the clear backing, at a fixed scale.
"""

from __future__ import annotations

import math

import numpy as np

PATCH_MM_PER_MM = 2.5  # contact radius a = sqrt(PATCH_MM_PER_MM * d), mm: 3.5 mm at d = 5 mm
FLOW = 0.1  # peak outward flow of the gel round the patch, x the indentation (0.5 mm at d = 5 mm)
SLIDE_DECAY_MM = 6.0  # shortest fall-off of a slide outside the patch, mm of gel
DECAY_PER_SLIDE = 4.0  # the fall-off is at least this x the slide: markers stay 0.6 pitch apart


def patch_radius_mm(indentation_mm: float) -> float:
    """Radius of the contact patch, mm, at an indentation (0 without contact)."""
    return math.sqrt(PATCH_MM_PER_MM * indentation_mm) if indentation_mm > 0 else 0.0


def slide_share(r_mm, indentation_mm: float, slide_mm: float):
    """Share of a slide each gel point takes, by its distance from the patch centre at rest, mm.

    1 in the patch (radius `patch_radius_mm`), falling as a raised cosine to 0 over
    ``max(SLIDE_DECAY_MM, DECAY_PER_SLIDE * slide_mm)`` beyond it: the map's Jacobian stays
    ``>= 1 - pi / 4``, so markers never cross.
    """
    if indentation_mm <= 0 or slide_mm == 0:
        return np.zeros(np.shape(r_mm))
    decay = max(SLIDE_DECAY_MM, DECAY_PER_SLIDE * slide_mm)
    t = np.clip((np.asarray(r_mm) - patch_radius_mm(indentation_mm)) / decay, 0.0, 1.0)
    return 0.5 * (1.0 + np.cos(np.pi * t))


def outward_flow_mm(r_mm, indentation_mm: float):
    """Outward displacement of the gel's surface round the patch, mm, at distance ``r_mm`` from its centre.

    ``FLOW d (r / a) exp((1 - r^2 / a^2) / 2)``: zero at the centre, largest (``FLOW d``) at the patch
    edge, fading beyond it; its slope stays above ``-0.74 FLOW d / a > -1``, so the map never folds.
    """
    a = patch_radius_mm(indentation_mm)
    if a == 0:
        return np.zeros(np.shape(r_mm))
    rho = np.asarray(r_mm) / a
    return FLOW * indentation_mm * rho * np.exp(0.5 * (1.0 - rho * rho))


def deform(x_mm, y_mm, contact):
    """Gel points at rest (x, y), mm, under a contact: where they are now, mm.

    The indenter, pressed in by ``contact.indentation_mm`` at the gel's centre, drags the gel under
    it by the slide (``slide_x_mm``, ``slide_y_mm``: the patch moves by all of it, the gel round it
    less, `slide_share`), then squeezes the gel outward from where the patch now is
    (`outward_flow_mm`). No contact, no motion.
    """
    d = contact.indentation_mm
    if d <= 0:
        return np.asarray(x_mm, float), np.asarray(y_mm, float)
    sx, sy = contact.slide_x_mm, contact.slide_y_mm
    share = slide_share(np.hypot(x_mm, y_mm), d, math.hypot(sx, sy))
    x, y = x_mm + sx * share, y_mm + sy * share
    dx, dy = x - sx, y - sy  # from the patch centre, which moved with the slide
    r = np.hypot(dx, dy)
    push = np.divide(outward_flow_mm(r, d), r, out=np.zeros_like(r), where=r > 0)
    return x + dx * push, y + dy * push


def depth_mm(x_mm, y_mm, contact):
    """How far the indenter pushes the gel's surface in at image-plane points (x, y), mm (a smooth dome).

    A Gaussian of height ``d`` and standard deviation ``0.6 a`` centred on the patch (which moves with
    the slide): what the photometric shading of the gel sees.
    """
    d = contact.indentation_mm
    if d <= 0:
        return np.zeros(np.broadcast_shapes(np.shape(x_mm), np.shape(y_mm)))
    sigma = 0.6 * patch_radius_mm(d)
    r2 = (x_mm - contact.slide_x_mm) ** 2 + (y_mm - contact.slide_y_mm) ** 2
    return d * np.exp(-0.5 * r2 / sigma ** 2)


# Three coloured lights from three sides of the gel (as GelSight's red, green and blue LEDs): each
# channel brightest on its own side (B from the left, G from the top, R from the right).
LIGHT_DIRECTIONS = {0: (-1.0, 0.0), 1: (0.0, -1.0), 2: (1.0, 0.0)}


def gel_light(image_size, *, level: float, gradient: float, vignette: float) -> np.ndarray:
    """The lit gel without markers, (H, W, 3) float32 BGR grey levels.

    Each channel is ``level`` at the centre, ``+- gradient / 2`` towards and away from its light,
    darkened towards the corners by up to ``vignette`` (a quadratic fall-off).
    """
    width, height = image_size
    yy, xx = np.mgrid[0:height, 0:width].astype(np.float32)
    u = (xx - (width - 1) / 2) / ((width - 1) / 2)  # -1 .. 1 across
    v = (yy - (height - 1) / 2) / ((height - 1) / 2)
    fall = np.float32(vignette) * (u * u + v * v) / 2
    layers = []
    for channel in range(3):
        lx, ly = LIGHT_DIRECTIONS[channel]
        toward = lx * u + ly * v  # 1 on the light's own side
        layers.append(np.float32(level) + np.float32(gradient / 2) * toward - fall)
    return np.stack(layers, axis=-1)


def shading(image_size, mm_per_px: float, contact, *, gain: float) -> np.ndarray:
    """Photometric shading of the pressed gel, (H, W, 3) float32 grey levels to add (zeros without contact).

    Each channel brightens where the pressed surface faces its light and darkens where it faces
    away: ``gain`` x the surface's slope towards the light (``gain`` grey levels at a slope of 1).
    """
    width, height = image_size
    if contact.indentation_mm <= 0 or gain == 0:
        return np.zeros((height, width, 3), np.float32)
    x = (np.arange(width) - (width - 1) / 2) * mm_per_px
    y = (np.arange(height) - (height - 1) / 2) * mm_per_px
    depth = depth_mm(x[None, :], y[:, None], contact)
    gy, gx = np.gradient(depth, mm_per_px)
    # the surface pushed in (towards the camera) is a dent seen from behind: its slope faces the light
    layers = [gain * (lx * gx + ly * gy) for lx, ly in (LIGHT_DIRECTIONS[c] for c in range(3))]
    return np.stack(layers, axis=-1).astype(np.float32)
