"""Raster layers of the synthetic TacTip image: static scene, anti-aliased pin tips, sensor noise.

All images here are float32 grey levels (0-255 scale); `tactip.sim.synthetic` composes them.
"""

from __future__ import annotations

import math
import sys
import threading

import numpy as np

EDGE_PX = 1.0  # width of the linear coverage ramp across a pin's edge, px
PIN_LEVEL = 215.0  # grey level of a pin tip at the apex under uniform light
MEMBRANE_LEVEL = 25.0  # grey level of the black membrane
CASING_LEVEL = 200.0  # grey level of the casing around the pad
LED_COUNT = 6  # LEDs on a ring around the base of the pad (paper 002, III-A)


RING_LEVEL = 8.0  # grey level of the black rim ring (matt black casing lip)
SKIN_BGR = (0.6, 0.95, 1.3)  # brown skin: B, G, R gains (normalised to keep the grey level)
PIN_BGR = (0.92, 1.0, 1.05)  # the pins' cream paint on a brown skin


def scene_layers(image_size, disc, *, gradient: bool, glare: bool, membrane_level: float = MEMBRANE_LEVEL,
                 casing_level: float = CASING_LEVEL, glare_gain: float = 1.0, veil: float = 0.0,
                 glare_scale: float = 1.0):
    """Static layers of a frame (`_scene_layers`), new arrays each call, computed once per process for
    the same arguments (of the same types): 0.2-0.6 s of CPU a sensor, and a station, a test or a
    collection builds sensors of the same layers again and again."""
    arguments = (tuple(image_size), tuple(disc), gradient, glare, membrane_level, casing_level, glare_gain, veil,
                 glare_scale)
    key = tuple((type(value), value) for value in (*arguments[0], *arguments[1], *arguments[2:]))
    with _LAYERS_LOCK:
        layers = _LAYERS.get(key)
    if layers is None:
        layers = _scene_layers(image_size, disc, gradient=gradient, glare=glare, membrane_level=membrane_level,
                               casing_level=casing_level, glare_gain=glare_gain, veil=veil, glare_scale=glare_scale)
        for layer in layers:
            layer.flags.writeable = False
        with _LAYERS_LOCK:
            if len(_LAYERS) >= _LAYERS_KEPT:
                _LAYERS.pop(next(iter(_LAYERS)))  # the oldest
            _LAYERS[key] = layers
    return tuple(layer.copy() for layer in layers)


#: `scene_layers` kept per process (3 float32 frames each: 3.7 MB at 640 x 480 px), oldest dropped first.
_LAYERS: dict = {}
_LAYERS_KEPT = 8
_LAYERS_LOCK = threading.Lock()


def _scene_layers(image_size, disc, *, gradient: bool, glare: bool, membrane_level: float = MEMBRANE_LEVEL,
                  casing_level: float = CASING_LEVEL, glare_gain: float = 1.0, veil: float = 0.0,
                  glare_scale: float = 1.0):
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
    membrane_level, casing_level : float
        Grey levels of the membrane and of the casing around the disc.
    glare_gain : float
        Brightness of the LED glare spots relative to the default (190 grey at the core).
    glare_scale : float
        Size of the LED glare spots relative to the default (a core 5 px across the rim, 16 px along).
    veil : float
        Veiling glare: light of a bright surround scattered in the lens, grey levels added at the disc
        edge and fading into the disc over a tenth of its radius (0: none).

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
        membrane = membrane_level - 4.0 + 32.0 * np.clip(r, 0, 1) ** 3
        casing = casing_level + 15.0 - 50.0 * np.clip((r - 1.0) / max(corner - 1.0, 1e-6), 0, 1) ** 2
    else:
        illumination = np.ones_like(r)
        membrane = np.full_like(r, membrane_level)
        casing = np.full_like(r, casing_level)
    background = membrane * inside + casing * (1.0 - inside)
    light = np.zeros_like(r)
    if glare:
        phi = np.arctan2(yy - cy, xx - cx)
        for k in range(LED_COUNT):
            centre = np.pi / LED_COUNT + 2 * np.pi * k / LED_COUNT
            dphi = np.angle(np.exp(1j * (phi - centre)))
            # a bright core on the rim, elongated along it, with a faint halo reaching into the disc
            if glare_scale == 1.0:
                core = np.exp(-0.5 * ((r - 0.98) * radius / 5.0) ** 2 - 0.5 * (dphi * radius / 16.0) ** 2)
                halo = np.exp(-0.5 * ((r - 0.97) * radius / 14.0) ** 2 - 0.5 * (dphi * radius / 35.0) ** 2)
            else:
                size = radius / glare_scale
                core = np.exp(-0.5 * ((r - 0.98) * size / 5.0) ** 2 - 0.5 * (dphi * size / 16.0) ** 2)
                halo = np.exp(-0.5 * ((r - 0.97) * size / 14.0) ** 2 - 0.5 * (dphi * size / 35.0) ** 2)
            light += 190.0 * core + 25.0 * halo
        if glare_gain != 1.0:
            light *= np.float32(glare_gain)
    if veil > 0:
        light += np.float32(veil) * np.exp(-np.abs(1.0 - r) / np.float32(0.1))
    return background.astype(np.float32), light.astype(np.float32), illumination.astype(np.float32)


def paint_pins(scene, image_size, centres, shape, levels) -> None:
    """Paint anti-aliased elliptical pin tips into a flat (H*W,) float32 scene, in place.

    Each pin is evaluated on a square patch around its nearest pixel, all pins at once. Coverage
    ramps linearly over `EDGE_PX` across the edge (signed distance along the ray from the centre), and
    the tip is slightly domed, so the profile is point-symmetric about the true centre and its
    intensity-weighted centroid is that centre. Painting adds ``coverage * (pin - scene)`` over the
    patches; where tips overlap (a squeezed skin), one tip occludes the other (`_occlude`): the pixel
    keeps at most the brighter tip's light (bright tips; the darker for dark tips), never the sum.

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
    tip = np.asarray(levels, dtype=np.float32)[:, None, None] * (1.0 - np.float32(0.15) * q)
    under = scene[pixel]
    value = tip - under
    value *= coverage
    np.add.at(scene, pixel.reshape(-1), value.reshape(-1))
    _occlude(scene, pixel, coverage, tip, under)


def _occlude(scene, pixel, coverage, tip, under) -> None:
    """Where tips overlap, the pixel shows tip, never the sum of the tips' light: clip it in place.

    `paint_pins` adds each tip's ``coverage * (tip - under)``, which is exact for tips that share a pixel
    only along their anti-aliased edges (coverages summing to at most 1: the sum is a blend of the
    tips and what lies under them). Where coverages sum past 1 the tips overlap, and a real skin shows
    one tip occluding the other: at most the brighter (bright tips) or the darker (dark tips) of the
    tips there. Each such pixel is clipped to the range of what lies under it and the tips covering it,
    so two white tips merged into one blob show no saturated seam. Pixels of one tip stay bit-identical.

    Parameters are `paint_pins`' patches: ``pixel`` (M, S, S) flat indices, ``coverage`` (M, S, S) in
    0-1, ``tip`` (M, S, S) each tip's grey level, ``under`` (M, S, S) the scene before painting.
    """
    covered = coverage > 0
    where = pixel[covered]
    sum_coverage = np.bincount(where, weights=coverage[covered], minlength=scene.size)
    shared = sum_coverage[where] > 1.0  # one tip's coverage is at most 1
    if not shared.any():
        return
    where = where[shared]
    tip = tip[covered][shared]
    under = under[covered][shared]
    unique, slot = np.unique(where, return_inverse=True)
    high = np.full(len(unique), -np.inf, dtype=np.float32)
    low = np.full(len(unique), np.inf, dtype=np.float32)
    np.maximum.at(high, slot, np.maximum(tip, under))
    np.minimum.at(low, slot, np.minimum(tip, under))
    scene[unique] = np.clip(scene[unique], low, high)


def paint_spots(scene, image_size, centres, sigmas, amplitudes, angles=None, *, ring_px: float = 0.0) -> None:
    """Add elliptical Gaussian spots (or round Gaussian rings) to a flat (H*W,) float32 scene, in place.

    Parameters
    ----------
    scene : (H * W,) float32 ndarray, modified in place
    image_size : (int, int)
        (width, height), px.
    centres : (M, 2) ndarray
        Spot centres (x, y), px.
    sigmas : (M,) or (M, 2) ndarray
        Standard deviations, px: one for round spots, or (along, across) the direction ``angles``.
    amplitudes : (M,) ndarray
        Grey levels added at each centre (negative for shadows).
    angles : (M,) ndarray or None
        Direction of each spot's first axis, radians from image x (None: 0).
    ring_px : float
        If > 0, draw round rings instead: the Gaussian profile (first sigma) is across a circle of this
        radius, px, centred on each centre.
    """
    centres = np.asarray(centres, dtype=np.float64).reshape(-1, 2)
    if len(centres) == 0:
        return
    width, height = image_size
    sigmas = np.broadcast_to(np.asarray(sigmas, dtype=np.float64).reshape(len(centres), -1), (len(centres), 2))
    angles = np.zeros(len(centres)) if angles is None else np.asarray(angles, dtype=np.float64)
    half = int(np.ceil(ring_px + 3.0 * sigmas.max()))
    offsets = np.arange(-half, half + 1)
    anchor = np.rint(centres).astype(np.int64)
    frac = (anchor - centres).astype(np.float32)
    dx = offsets.astype(np.float32)[None, None, :] + frac[:, 0, None, None]  # (M, 1, S)
    dy = offsets.astype(np.float32)[None, :, None] + frac[:, 1, None, None]  # (M, S, 1)
    cos, sin = (v.astype(np.float32)[:, None, None] for v in (np.cos(angles), np.sin(angles)))
    if ring_px > 0:
        across = (np.sqrt(dx * dx + dy * dy) - np.float32(ring_px)) / sigmas[:, 0, None, None].astype(np.float32)
        along = np.zeros_like(across)
    else:
        along = (dx * cos + dy * sin) / sigmas[:, 0, None, None].astype(np.float32)
        across = (dy * cos - dx * sin) / sigmas[:, 1, None, None].astype(np.float32)
    value = np.asarray(amplitudes, dtype=np.float32)[:, None, None] * np.exp(-0.5 * (along ** 2 + across ** 2))
    px = anchor[:, 0, None, None] + offsets[None, None, :]
    py = anchor[:, 1, None, None] + offsets[None, :, None]
    value *= (px >= 0) & (px < width) & (py >= 0) & (py < height)
    pixel = np.clip(py * width + px, 0, width * height - 1)
    np.add.at(scene, pixel.reshape(-1), value.reshape(-1))


def rim_ring(image_size, disc, inner_px: float, *, rng: np.random.Generator, glare_count: int,
             spot_px: float, level: float = RING_LEVEL):
    """The black rim ring (the casing lip) between the pin field and the surround, with LED glare on it.

    The ring covers radii ``inner_px`` to the disc's edge with a 1 px anti-aliased inner edge; it hides
    the membrane (and the pins) behind it. An LED ring reflects on its glossy black surface as
    ``glare_count`` irregular bright blobs: each is one to three elongated Gaussian lobes along the ring
    (main lobe 0.6-1.8 ``spot_px`` long, 0.4-0.8 ``spot_px`` wide, 110-230 grey), at evenly spaced
    azimuths with jitter, and the light stays on the ring.

    Returns
    -------
    alpha : (H, W) float32
        Coverage of the ring (1 on it, 0 inside its inner edge).
    value : (H, W) float32
        ``alpha`` times the ring's own grey (its level plus the glare).
    glare_centres : (K, 2) float64
        Centre (x, y) px of each glare blob's main lobe.
    """
    width, height = image_size
    cx, cy, radius = disc
    yy, xx = np.mgrid[0:height, 0:width].astype(np.float32)
    r = np.hypot(xx - cx, yy - cy)
    alpha = np.clip(r - np.float32(inner_px) + np.float32(0.5), 0.0, 1.0)
    alpha *= np.clip(np.float32(radius) - r + np.float32(0.5), 0.0, 1.0)  # the surround stays in view
    ring_width = radius - inner_px
    light = np.full(height * width, level, dtype=np.float32)
    if glare_count > 0:
        azimuth = rng.uniform(0, 2 * np.pi) + 2 * np.pi * np.arange(glare_count) / glare_count
        azimuth += rng.normal(0.0, 0.12 * 2 * np.pi / glare_count, glare_count)
        middle = inner_px + ring_width * rng.uniform(0.4, 0.6, glare_count)
        along = spot_px * rng.uniform(0.6, 1.8, glare_count)
        across = np.minimum(spot_px * rng.uniform(0.4, 0.8, glare_count), ring_width / 4.0)
        amplitude = rng.uniform(110.0, 230.0, glare_count)
        lobes = rng.integers(1, 4, glare_count)  # an irregular blob: 1-3 overlapping lobes
        main = np.column_stack([cx + middle * np.cos(azimuth), cy + middle * np.sin(azimuth)])
        owner = np.repeat(np.arange(glare_count), lobes)
        first = np.concatenate([[0], np.cumsum(lobes)[:-1]])
        is_main = np.zeros(len(owner), bool)
        is_main[first] = True
        shift = np.where(is_main, 0.0, rng.choice([-1.0, 1.0], len(owner)) * rng.uniform(0.6, 1.4, len(owner)))
        lobe_azimuth = azimuth[owner] + shift * along[owner] / middle[owner]
        lobe_radius = middle[owner] + np.where(is_main, 0.0, rng.normal(0.0, 0.15 * ring_width, len(owner)))
        centres = np.column_stack([cx + lobe_radius * np.cos(lobe_azimuth), cy + lobe_radius * np.sin(lobe_azimuth)])
        scale = np.where(is_main, 1.0, rng.uniform(0.5, 0.9, len(owner)))
        sigmas = np.column_stack([along[owner] * scale, across[owner] * scale])
        paint_spots(light, image_size, centres, sigmas, amplitude[owner] * np.where(is_main, 1.0,
                    rng.uniform(0.4, 0.9, len(owner))), angles=lobe_azimuth + np.pi / 2)
    else:
        main = np.zeros((0, 2))
    value = alpha * light.reshape(height, width)
    return alpha.astype(np.float32), value.astype(np.float32), main


def mottling(rng: np.random.Generator, image_size, scale_px: float) -> np.ndarray:
    """Smooth random field of unit standard deviation varying over about ``scale_px``, (H, W) float32."""
    import cv2

    width, height = image_size
    cells = (max(2, int(np.ceil(width / scale_px)) + 1), max(2, int(np.ceil(height / scale_px)) + 1))
    coarse = rng.standard_normal((cells[1], cells[0])).astype(np.float32)
    field = cv2.resize(coarse, (width, height), interpolation=cv2.INTER_CUBIC)
    field -= field.mean()
    field /= max(float(field.std()), 1e-6)
    return field


def tint_table(skin_level: float, pin_level: float) -> np.ndarray:
    """BGR gains for each grey level 0-255, (256, 3) float32: brown skin below ``skin_level``, cream
    paint above ``pin_level``, blended between; each row keeps the grey level (BT.601 weights)."""
    weights = np.array([0.114, 0.587, 0.299])
    skin = np.array(SKIN_BGR) / (np.array(SKIN_BGR) @ weights)
    pin = np.array(PIN_BGR) / (np.array(PIN_BGR) @ weights)
    t = np.clip((np.arange(256) - skin_level) / max(pin_level - skin_level, 1.0), 0.0, 1.0)[:, None]
    return ((1 - t) * skin + t * pin).astype(np.float32)


def scene_slot(contact, hidden: np.ndarray | None) -> tuple[str, tuple]:
    """Where a sensor keeps its last frame before noise for ``contact``, and the key it is kept under.

    Two slots, ``"rest"`` and ``"pressed"``: a tap films the same contact through its rests and its
    plateau, so those frames differ only in camera noise (`expose`). The key is the contact's repr
    (so -0.0 is not 0.0) and the hidden pins' bytes.
    """
    slot = "rest" if contact.indentation_mm <= 0 else "pressed"
    return slot, (repr(contact), None if hidden is None else hidden.tobytes())


def expose(scene, *, rng: np.random.Generator, noise_sigma: float, jpeg_quality: int | None) -> np.ndarray:
    """The camera's frame of a float32 scene (grey levels): sensor noise, rounding to uint8, JPEG.

    ``scene`` ((H, W) or (H, W, 3) float32) is overwritten; the noise is `byte_noise` of ``noise_sigma``
    drawn from ``rng`` (none at 0), and ``jpeg_quality`` (1-100 or None) compresses the frame like an
    MJPG webcam. Returns the uint8 frame, the shape of ``scene``.
    """
    if noise_sigma > 0:
        scene += byte_noise(rng, scene.shape, noise_sigma)
    scene += np.float32(0.5)  # round to nearest on conversion
    image = np.clip(scene, 0, 255, out=scene).astype(np.uint8)
    if jpeg_quality is not None:
        import cv2

        _, buffer = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, int(jpeg_quality)])
        image = cv2.imdecode(buffer, cv2.IMREAD_UNCHANGED)
    return image


def _random_bytes(rng: np.random.Generator, count: int) -> np.ndarray:
    """``rng.bytes(count)`` as a (count,) uint8 array, and ``rng`` left in the same state.

    ``Generator.bytes`` draws 32-bit words, two from each 64-bit output of the bit generator, low half
    first, so on a little-endian machine a PCG64 with no half word buffered gives the same bytes as
    its raw outputs (the same stream after), which it returns several times faster.
    """
    bits = rng.bit_generator
    if (type(bits) is np.random.PCG64 and count % 8 == 0 and sys.byteorder == "little"
            and not bits.state["has_uint32"]):
        return bits.random_raw(count // 8).view(np.uint8)
    return np.frombuffer(rng.bytes(count), dtype=np.uint8)


def byte_noise(rng: np.random.Generator, shape, sigma: float) -> np.ndarray:
    """Zero-mean near-Gaussian noise of standard deviation ``sigma``, float32.

    The sum of four uniform random bytes (Irwin-Hall, within 1 % of Gaussian in the bulk, tails
    bounded at 3.5 sigma), about twice as fast as ``rng.standard_normal`` for a whole frame.
    """
    n = int(np.prod(shape))
    octets = _random_bytes(rng, 4 * n).reshape(4, n)
    total = octets[0].astype(np.int16)
    total += octets[1]
    total += octets[2]
    total += octets[3]
    scale = np.float32(sigma / math.sqrt(4 * (256 ** 2 - 1) / 12))  # std of a sum of four uniform bytes
    noise = total.astype(np.float32)
    noise -= np.float32(4 * 255 / 2)
    noise *= scale
    return noise.reshape(shape)
