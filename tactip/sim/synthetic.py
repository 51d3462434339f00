"""Synthetic TacTip frames with exact ground truth, for tests, the demo and the simulated station.

The renderer draws what the internal camera of a TacTip sees (paper 002, III-A): the inside of a
hemispherical silicone pad whose white-tipped pins stand on the black membrane, lit by six LEDs on a
ring around the pad's base. Every frame comes with the true centre of every pin tip, in px.

>>> sensor = SyntheticTacTip(pins=331, seed=0)
>>> frames = list(sensor.tap(Contact(indentation_mm=4.0, gap_width_mm=2.0)))  # 20 frames at 20 fps

Model and its assumptions
-------------------------
Geometry (mm; helpers in `tactip.sim._pad`). The pad is a hemisphere of radius ``R`` (default 20 mm)
centred on the origin, apex at ``z = R``. The camera is a pinhole on the axis at ``z = -h``,
``h = 2 R``, looking up; image x runs along pad X, image y along pad Y, principal point at the image
centre. The focal length makes the dark membrane disc, whose edge is where the casing hides the
membrane (polar angle 86 degrees), 0.435 x the image height in radius (209 px at 640x480), so a bright
surround shows on every side.

Pins. Their bases sit on the membrane on a lattice laid out in pad-surface coordinates (arc length
``s = R theta`` from the apex, azimuth ``phi``), out to ``theta = 80`` degrees. A hexagonal number of
pins (127, 331 = 1 + 3K(K+1)) fills K hexagonal rings of 6k pins; any other count (532) uses K
concentric circles, K the smallest ring count whose hexagonal number reaches N, circle k getting a
share of the N - 1 outer pins proportional to k (largest remainder), odd circles rotated half a step.
Bases jitter by 2 % of the spacing (seeded). Each pin is a stalk of length ``L = 1.5 mm`` along the
membrane's inward normal, ending in a flat white disc facing along the stalk. The disc is sized to
0.3 x the pin spacing in the image at the apex (6, 5.7 and 4.4 px for 127, 331 and 532 pins), which
keeps neighbours at least 2.6 radii apart at rest. Its image is the exact affine image of a circle: an
ellipse centred on the projected tip, foreshortened (radially narrower) towards the rim. The drawn
blob is point-symmetric about that centre, so its intensity-weighted centroid is the ground truth
(within 0.03 px after 8-bit rounding).

Contact (`tactip.sim._pad.membrane_displacement`). A rigid flat plate, normal to the pad axis, presses
the apex in by ``d`` mm. The pad is an elastic, incompressible half-space in Hertz contact: contact
radius ``a = sqrt(R d)``; displacement towards the camera ``u_z = d - r^2 / 2R`` inside the patch
(which is then flat to parabolic order) and ``(d / pi) [(2 - r^2/a^2) asin(a/r) + sqrt(r^2/a^2 - 1)]``
outside, continuous in value and slope. (Geometric overlap alone would give ``a = sqrt(2 R d)``; in
Hertz contact the surrounding gel sinks too, taking half the approach, and gives the smooth decay
outside the patch.) The incompressible gel flows outward under the plate and drags the skin with it:
``u_r = 0.5 u_z r / R``. The pad is clamped to the casing at its base, so both displacements are
multiplied by ``1 - (r / R)^6``: zero at the rim, within 2 % of the half-space field where the plate
touches (r < R / 2 up to d = 5 mm). A straight gap (width ``w``, centre line ``gap_offset`` from the axis along
image y, direction ``gap_angle``) leaves the skin over it unsupported: like a tensioned membrane over
a slot under pressure it bulges into the gap by ``w^2 / (8 rho)`` (``rho = 1 mm``, the ratio of skin
tension to contact pressure: a thin skin on a very soft gel carries little tension, so a slot a few mm
wide is almost unsupported in the middle of the contact), spread across the line with a Gaussian of width ``w/4 + 0.5 mm`` (the
skin's bending length smooths the slot's edges), weighted by the pressure ``(1 - r^2/a^2)^1.5`` in the
patch, and softly capped by the local indentation (the skin cannot rise above its rest shape).
Each tip moves with its base plus the lever: ``L`` times the change of the membrane normal, the slope
being averaged over +-1.5 mm (the stalk's base and the skin's thickness). Flattening tilts stalks
outward and brings the patch nearer the camera, so pins spread from the contact: the peak tip motion
is about 10.5 px at d = 4 mm and 14 px at d = 5 mm. The gap's imprint is subtle and grows with ``w``:
at d = 4 mm the fields for w = 1 and w = 2 mm differ by at most about 1 px, for w = 1 and 3 mm by
about 2.7 px and for w = 1 and 5 mm by about 6 px, on the pins right over the gap (331 pins); the 40
feature pins 4 mm apart see at most about 2.4 px between 0.25 and 5 mm, and 0.15 px between adjacent
widths 0.25 mm apart, against about 1 px for 0.25 mm more depth. (With ``rho = 8 mm`` adjacent widths
differed by 0.02 px and no classifier could tell them apart.) Neighbouring tips stay separated (at least 1.8 px between the
ellipses' edges) up to d = 5 mm on every preset; beyond about 6 mm the densest pad's tips begin
to touch at the contact edge. A tap follows `tap_profile`: raised-cosine rise, plateau and release,
250 ms each by default (paper 002, IV-A).

Appearance (`tactip.sim._render`). Bright casing around the disc (about 200 grey, vignetted); a dark
membrane (about 25) with a radial illumination gradient towards the LED ring; six LED glare spots on
the rim; white pin tips (about 215, +-5 % per pin, lit like the membrane, slightly domed) with an
anti-aliased 1 px edge ramp; sensor noise of ``noise_sigma`` grey levels (near-Gaussian, a sum of four
uniform bytes, fresh every frame and deterministic given the seed); optional optical blur and JPEG
compression (as from an MJPG webcam). ``dark_pins`` inverts the scene for dark-marker sensors.
Rendering is vectorised over pins: about 2-5 ms per 640x480 frame.

What broke the front end on real TacTips (issue 8), as options
--------------------------------------------------------------
Real recordings differ from the clean default in ways that each fooled detection or tracking; each is
an option (all off by default, so the default frames are unchanged byte for byte) and a preset below.

- Layout ``layout="radial"``: home-built TacTips place pins with a rotary jig, on rings crossed by
  straight spokes, the same count on every ring, so the spacing along a ring grows with its radius
  while the ring spacing stays one pitch; a lattice-consistency test tuned to hexagons sees a pitch
  that varies across the pad. ``pins = rings x spokes (+ 1 centre pin)``, spokes / rings near 2.4
  (120 = 1 + 7 x 17); the innermost ring sits at ``spokes / 2 pi`` pitches so its pins are a pitch
  apart, leaving an empty zone round the centre pin.
- Pad size ``pad_fraction``: the dark disc's diameter over the image height (default 0.87). The
  camera's focal length follows from it (the casing edge at 86 degrees lands on the disc edge), so
  a small pad is a wide-angle view of the same pad: everything, pins included, shrinks with it. A pin
  is never smaller than 1 px in radius, so on the smallest pads (``small-pad-100``: 60 px across at
  320x240, pitch 3.7-4.4 px) ``pin_fraction`` must drop to keep neighbouring tips apart. The six LED
  glare spots scale with a pad whose size is given (at the default they keep their historical size).
- Black rim ring ``rim_polar_deg``, ``ring_glare``: on many TacTips the casing lip in front of the
  membrane's edge is matt or glossy black plastic. It is drawn as an opaque ring (level 8) from the
  disc edge in to where the pin tips at polar angle ``rim_polar_deg`` are seen, with a 1 px
  anti-aliased inner edge; it is composited over the pins, so the outermost pins are cut by it (on a
  hexagonal pad a circular lip cuts the hexagon's corners first). An LED ring facing the lip reflects
  in it as ``ring_glare`` bright blobs: one to three elongated Gaussian lobes each, one to a few pins
  in size (main lobe sigma 0.6-1.8 pin radii along the ring, 0.4-0.8 across), 110-230 grey,
  irregular in shape and brightness, at evenly spaced azimuths with jitter. Their light stays on the
  ring: they lie outside the pin field, and their true centres are ``ring_glare_centres``.
- Low-contrast coloured skin ``membrane_level``, ``pin_level``, ``skin_texture``, ``pin_shadows``,
  ``skin_tint``: a pigmented (brown) skin reflects far more than black rubber, so the pins stand only
  40-70 grey levels above it. The skin carries texture: a static low-frequency mottling (pigment and
  thickness, standard deviation 0.6 x ``skin_texture`` over five pitches), soft highlights between
  the pins (about one per pin, 0.6-1.1 pin radii, 1.5-3.5 x ``skin_texture`` grey, where the skin
  bulges between stalks) and small specks (two per pin, 0.5-0.9 px, dust and bubbles, 60 % dark).
  Highlights and specks are material points of the skin: they move with it under contact. Lit by
  LEDs all round the pad, each stalk casts several faint shadows that together shade a soft ring of
  skin round its tip (``pin_shadows`` deep at 1.4 pin radii, Gaussian 0.35 pin radii across), so the
  skin between pins breaks into blob-like light patches at the lattice's interstices, ringed by dark.
  Texture stays 3 sigma clear of the tips at rest and the shadow rings are centred on the tips, so a
  tip's weighted centroid is still its true centre. In colour frames ``skin_tint="brown"`` colours each
  pixel by its grey level, from brown skin (B, G, R gains 0.6, 0.95, 1.3) to cream paint on the pins,
  each gain triple normalised so that the BT.601 grey of the colour frame is the grey scene.
- Bright surround and strong glare ``surround_level``, ``glare_gain``, ``veil``: a small pad in a very
  bright surround (an open, white-lit casing near saturation) with LED glare made stronger, and a
  veil of scattered light that brightens the disc edge (grey levels ``veil`` at the edge, fading
  inward over a tenth of the radius). Pins near the edge lose contrast.
- Pin count 100-1000: any count works (``dense-1000``: 1000 pins at 1280x720, 5 px tips about 16 px
  apart); rendering stays vectorised: about 3x the default 331-pin frame for 1000 pins at 1280x720
  (15-20 ms), 4x for a textured colour frame at 640x480 (20-30 ms; ``bench/bench_render.py``).

Ground truth and scoring
------------------------
``SyntheticFrame.centres`` holds every pin's true tip centre. ``visible`` marks pins whose whole tip
(ellipse plus its 1 px edge ramp) is drawn, clear of the image edge and a pixel clear of the rim
ring's inner edge; ``partial`` marks pins drawn but cut by the rim ring or the image edge; the others
(hidden by ``render(hidden=...)``, wholly behind the ring, facing away) are not drawn. Scoring
convention for detection and tracking: a detector must find the ``visible`` pins (recall is over
them); a ``partial`` pin may be found or not (a detection matched to one counts neither for nor
against); any other detection (glare, texture, shadow, rim) is a false positive. The
intensity-weighted centroid of a visible pin over its ellipse, above a constant local background,
is its true centre to about 0.03 px on noise-free renders (0.05 px on the 1 px tips of the smallest
pad and with skin texture under contact), whatever the options.

Presets
-------
`PRESETS` names the sensors that tests, benches and ``open_source("synthetic:NAME")`` use;
`SyntheticTacTip.from_preset` builds one with any option overridden:

- ``tactip-331``, ``tactip-127``, ``tactip-532``: the default renderer (exactly) with 331, 127, 532 pins.
- ``dark-331``: dark markers on a light membrane.
- ``rim-ring-331``: a black rim ring cutting the outer pins (12 partial at rest, seed 0) with 18 LED
  glare blobs on it; no glare on the membrane's rim.
- ``brown-127``: colour frames of a brown skin, pins about 60 grey above it (median; 33-78), texture 12
  and shadows 22 grey.
- ``radial-120``: 120 small pins (2 px) on 7 rings x 17 spokes plus a centre pin, the pad a third of the
  frame height in a near-saturated surround (245) with strong glare and a veil, noise 5, 120 frames/s.
- ``small-pad-100``: 100 pins, the pad a quarter of the frame height, 320x240, bright surround (1 px tips).
- ``dense-1000``: 1000 pins at 1280x720, the pad 0.9 of the frame height.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from tactip.sim import _pad, _render

__all__ = ["Contact", "PRESETS", "SyntheticFrame", "SyntheticTacTip", "preset_names", "tap_profile"]

_DISC_FRACTION = 0.435  # radius of the dark membrane disc / image height
_DARK_INVERSION = 240.0  # dark_pins: grey level g becomes 240 - g (light membrane, dark tips)
_PIN_SPACING_FRACTION = 0.3  # pin radius / pin spacing at the apex, both in px (at most 6 px)
_LAYOUTS = ("auto", "radial")
_SKIN_TINTS = (None, "brown")
_TEXTURE_POLAR_DEG = 84.0  # skin texture is drawn out to this polar angle (inside the casing edge)
_SHADOW_RING = 1.4  # pin shadows: a soft dark ring of this radius round each tip, in pin radii
_SHADOW_SIGMA = 0.35  # pin shadows: Gaussian sigma across the ring, in pin radii


@dataclass(frozen=True)
class Contact:
    """State of the pad against the plate.

    Attributes
    ----------
    indentation_mm : float
        How far the plate presses into the pad apex, mm; ``<= 0`` means no contact.
    gap_width_mm : float
        Width of the straight gap in the plate, mm (0 = flat plate).
    gap_offset_mm : float
        Lateral position of the gap centre line from the pad axis, along image y, mm.
    gap_angle_deg : float
        Direction of the gap line in the plate, degrees (0: along image x).
    """

    indentation_mm: float = 0.0
    gap_width_mm: float = 0.0
    gap_offset_mm: float = 0.0
    gap_angle_deg: float = 0.0

    def __post_init__(self):
        for name in ("indentation_mm", "gap_width_mm", "gap_offset_mm", "gap_angle_deg"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite, got {getattr(self, name)!r}")
        if self.gap_width_mm < 0:
            raise ValueError(f"gap_width_mm must be >= 0, got {self.gap_width_mm}")


@dataclass(frozen=True, eq=False)
class SyntheticFrame:
    """One rendered frame and its ground truth.

    Attributes
    ----------
    image : (H, W) uint8 ndarray, or (H, W, 3) uint8 BGR when the renderer has ``colour=True``
    centres : (N, 2) float64 ndarray
        True pin-tip centres (x, y), px; pixel centres at integer coordinates (OpenCV convention).
    visible : (N,) bool ndarray
        Whether each pin's whole tip is drawn (False when hidden, cut or outside the image).
    timestamp_s : float
        Time within the sequence, s.
    contact : Contact
        The contact state that was rendered.
    partial : (N,) bool ndarray
        Pins drawn but partly hidden: cut by the black rim ring (casing lip) or by the image edge.
        A detector may find them or not; see "Scoring" in the module docstring. All False when not given.
    """

    image: np.ndarray
    centres: np.ndarray
    visible: np.ndarray
    timestamp_s: float
    contact: Contact
    partial: np.ndarray | None = field(default=None)

    def __post_init__(self):
        if self.partial is None:
            object.__setattr__(self, "partial", np.zeros(len(self.visible), bool))


def tap_profile(t_s, *, rise_s: float = 0.25, plateau_s: float = 0.25, release_s: float = 0.25):
    """Fraction of full indentation at time ``t_s`` into a tap (0 before and after).

    A raised-cosine rise over ``rise_s``, a plateau of ``plateau_s`` at 1, and a raised-cosine
    release over ``release_s`` (paper 002, IV-A: about 250 ms each). Smooth (C1) throughout.

    Parameters
    ----------
    t_s : float or ndarray
        Time since the start of the rise, s.
    rise_s, plateau_s, release_s : float
        Phase durations, s (rise and release > 0, plateau >= 0).

    Returns
    -------
    float or ndarray
        Fraction in [0, 1], same shape as ``t_s``.

    Examples
    --------
    >>> tap_profile([0.0, 0.125, 0.3, 0.625, 0.8])
    array([0. , 0.5, 1. , 0.5, 0. ])
    """
    if not rise_s > 0 or not release_s > 0:
        raise ValueError(f"rise_s and release_s must be > 0, got {rise_s}, {release_s}")
    if not plateau_s >= 0:
        raise ValueError(f"plateau_s must be >= 0, got {plateau_s}")
    t = np.asarray(t_s, dtype=float)
    rise = 0.5 * (1.0 - np.cos(np.pi * np.clip(t / rise_s, 0.0, 1.0)))
    t_release = t - rise_s - plateau_s
    release = 0.5 * (1.0 + np.cos(np.pi * np.clip(t_release / release_s, 0.0, 1.0)))
    fraction = np.where(t_release > 0, release, rise)
    return float(fraction) if fraction.ndim == 0 else fraction


class SyntheticTacTip:
    """A simulated TacTip camera: renders frames of the pin array with exact ground truth.

    Parameters
    ----------
    pins : int
        Number of pins; presets 127, 331 (hexagonal) and 532 (concentric); any count >= 7 works.
    pad_diameter_mm : float
        Diameter of the hemispherical pad, mm.
    image_size : (int, int)
        (width, height) of the frames, px.
    noise_sigma : float
        Sensor noise, grey levels (standard deviation).
    glare, gradient : bool
        Draw the LED glare spots on the rim; draw the radial illumination gradient and vignetting.
    blur_sigma : float
        Optical blur (Gaussian sigma, px); 0 for none.
    jpeg_quality : int or None
        Pass each frame through JPEG compression at this quality (1-100), like an MJPG webcam.
    colour : bool
        Return (H, W, 3) BGR frames instead of grey.
    dark_pins : bool
        Invert the scene: dark pins on a light membrane (dark-marker sensors).
    seed : int
        Seed of the instance's own random generator (pin jitter, brightness, noise).
    layout : {"auto", "radial"}
        "auto": hexagonal rings for a hexagonal number of pins, else concentric circles; "radial": pins
        where equally spaced rings cross straight spokes (``pins = rings x spokes (+ 1 centre pin)``).
    pad_fraction : float
        Diameter of the dark disc (membrane, with the rim ring if any) / image height, 0.25-0.9.
    pin_fraction : float
        Pin-tip radius / pin spacing at the apex, 0.1-0.4 (the radius is kept within 1-6 px).
    rim_polar_deg : float or None
        Draw a black rim ring (the casing lip) from the disc edge in to where the pin tips at this
        polar angle, degrees (60-85.9), are seen; it hides the pins behind it. None: no ring.
    ring_glare : int
        Number of LED glare blobs on the rim ring (0-64); needs ``rim_polar_deg``.
    membrane_level, pin_level, surround_level : float or None
        Grey levels of the membrane, of a pin tip at the apex and of the casing around the disc
        (None: 25, 215 and 200).
    glare_gain : float
        Brightness of the six LED glare spots relative to the default (>= 0).
    veil : float
        Veiling glare of a bright surround: grey levels added at the disc edge, fading inward (>= 0).
    skin_texture : float
        Skin texture, grey levels (>= 0): low-frequency mottling, soft highlights between the pins
        and small specks, all in proportion; 0 for a clean skin.
    pin_shadows : float
        Depth of the soft shadow each pin casts on the skin towards the pad axis, grey levels (>= 0).
    skin_tint : {None, "brown"}
        Colour frames only: a brown skin with cream pins instead of the neutral tint.
    frame_rate : float
        The camera's frame rate, frames/s; `tap` uses it when not given one.

    Attributes
    ----------
    n_pins : int
    rest_centres : (N, 2) float64 ndarray, read-only
        True pin-tip centres (x, y) without contact, px.
    disc : (float, float, float)
        The dark membrane disc (cx, cy, radius), px.
    mm_per_px : float
        Pad-surface mm per image px at the apex (for pin separations in mm; the scale shrinks
        towards the rim, where the dome is seen obliquely).
    pin_radius_px : float
        Image radius of a pin tip at the apex, px.
    pin_spacing_mm : float
        Lattice spacing of the pins on the pad surface, mm.
    rim_radius_px : float or None
        Inner edge of the black rim ring, px from the disc centre (None without a ring).
    ring_glare_centres : (K, 2) float64 ndarray
        Centres (x, y) px of the LED glare blobs on the rim ring (empty without them).
    frame_rate : float
        Frames per second of `tap` by default.
    preset : str or None
        The preset's name when built by `from_preset`.

    Examples
    --------
    >>> sensor = SyntheticTacTip(pins=331, seed=0)
    >>> frame = sensor.render(Contact(indentation_mm=4.0, gap_width_mm=2.0))
    >>> frame.image.shape, frame.centres.shape
    ((480, 640), (331, 2))
    """

    def __init__(self, *, pins: int = 331, pad_diameter_mm: float = 40.0, image_size=(640, 480),
                 noise_sigma: float = 4.0, glare: bool = True, gradient: bool = True,
                 blur_sigma: float = 0.0, jpeg_quality: int | None = None, colour: bool = False,
                 dark_pins: bool = False, seed: int = 0, layout: str = "auto", pad_fraction: float = 0.87,
                 pin_fraction: float = _PIN_SPACING_FRACTION, rim_polar_deg: float | None = None,
                 ring_glare: int = 0, membrane_level: float | None = None, pin_level: float | None = None,
                 surround_level: float | None = None, glare_gain: float = 1.0, veil: float = 0.0,
                 skin_texture: float = 0.0, pin_shadows: float = 0.0, skin_tint: str | None = None,
                 frame_rate: float = 20.0):
        if int(pins) != pins or pins < 7:
            raise ValueError(f"pins must be an integer >= 7, got {pins!r}")
        if layout not in _LAYOUTS:
            raise ValueError(f"layout must be one of {_LAYOUTS}, got {layout!r}")
        if not 0.25 <= pad_fraction <= 0.9:
            raise ValueError(f"pad_fraction must be in 0.25..0.9, got {pad_fraction!r}")
        if not 0.1 <= pin_fraction <= 0.4:
            raise ValueError(f"pin_fraction must be in 0.1..0.4, got {pin_fraction!r}")
        if rim_polar_deg is not None and not 60.0 <= rim_polar_deg < _pad.CASING_POLAR_DEG:
            raise ValueError(f"rim_polar_deg must be None or in 60..{_pad.CASING_POLAR_DEG}, got {rim_polar_deg!r}")
        if int(ring_glare) != ring_glare or not 0 <= ring_glare <= 64:
            raise ValueError(f"ring_glare must be an integer in 0..64, got {ring_glare!r}")
        if ring_glare and rim_polar_deg is None:
            raise ValueError("ring_glare needs a rim ring: give rim_polar_deg")
        for name, value in (("membrane_level", membrane_level), ("pin_level", pin_level),
                            ("surround_level", surround_level)):
            if value is not None and not 0 <= value <= 255:
                raise ValueError(f"{name} must be None or in 0..255, got {value!r}")
        for name, value in (("glare_gain", glare_gain), ("veil", veil), ("skin_texture", skin_texture),
                            ("pin_shadows", pin_shadows)):
            if not (math.isfinite(value) and value >= 0):
                raise ValueError(f"{name} must be finite and >= 0, got {value!r}")
        if skin_tint not in _SKIN_TINTS:
            raise ValueError(f"skin_tint must be one of {_SKIN_TINTS}, got {skin_tint!r}")
        if not (math.isfinite(frame_rate) and frame_rate > 0):
            raise ValueError(f"frame_rate must be > 0, got {frame_rate!r}")
        if layout == "radial":
            _pad.radial_rings(int(pins))  # raises ValueError naming pins
        if not pad_diameter_mm > 4 * _pad.STALK_MM:
            raise ValueError(f"pad_diameter_mm must be > {4 * _pad.STALK_MM}, got {pad_diameter_mm!r}")
        width, height = (int(v) for v in image_size)
        if width < 64 or height < 64:
            raise ValueError(f"image_size must be at least (64, 64), got {image_size!r}")
        if not noise_sigma >= 0:
            raise ValueError(f"noise_sigma must be >= 0, got {noise_sigma!r}")
        if not blur_sigma >= 0:
            raise ValueError(f"blur_sigma must be >= 0, got {blur_sigma!r}")
        if jpeg_quality is not None and not 1 <= jpeg_quality <= 100:
            raise ValueError(f"jpeg_quality must be in 1..100 or None, got {jpeg_quality!r}")
        self._n = int(pins)
        self.pad_diameter_mm = float(pad_diameter_mm)
        self.image_size = (width, height)
        self.noise_sigma = float(noise_sigma)
        self.glare, self.gradient = bool(glare), bool(gradient)
        self.blur_sigma = float(blur_sigma)
        self.jpeg_quality = jpeg_quality
        self.colour, self.dark_pins = bool(colour), bool(dark_pins)
        self.seed = seed
        self.layout, self.pad_fraction, self.pin_fraction = layout, float(pad_fraction), float(pin_fraction)
        self.rim_polar_deg = None if rim_polar_deg is None else float(rim_polar_deg)
        self.ring_glare = int(ring_glare)
        self.membrane_level, self.pin_level, self.surround_level = membrane_level, pin_level, surround_level
        self.glare_gain, self.veil = float(glare_gain), float(veil)
        self.skin_texture, self.pin_shadows, self.skin_tint = float(skin_texture), float(pin_shadows), skin_tint
        self.frame_rate = float(frame_rate)
        self.preset = None
        layout_rng, self._noise_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(2))
        scene_rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(2,)))  # new layers only

        radius = self._radius = self.pad_diameter_mm / 2.0
        self._h = _pad.CAMERA_DISTANCE * radius
        casing = np.deg2rad(_pad.CASING_POLAR_DEG)
        disc_px = self.pad_fraction / 2.0 * height  # 0.87 / 2 == _DISC_FRACTION exactly
        self._f = disc_px * (radius * math.cos(casing) + self._h) / (radius * math.sin(casing))
        self._c = ((width - 1) / 2.0, (height - 1) / 2.0)
        self.disc = (self._c[0], self._c[1], float(disc_px))

        lattice = _pad.radial_lattice(self._n) if layout == "radial" else _pad.pin_lattice(self._n)
        ring_count = np.hypot(*lattice.T).max()
        spacing = radius * np.deg2rad(_pad.PIN_POLAR_MAX_DEG) / ring_count  # mm of pad surface
        lattice = lattice + layout_rng.normal(0.0, 0.02, lattice.shape)
        arc = np.hypot(*lattice.T) * spacing
        azimuth = np.arctan2(lattice[:, 1], lattice[:, 0])
        polar = arc / radius
        self._base_x = radius * np.sin(polar) * np.cos(azimuth)
        self._base_y = radius * np.sin(polar) * np.sin(azimuth)
        self.pin_spacing_mm = float(spacing)

        apex_depth = radius - _pad.STALK_MM + self._h
        # pin radius: a fixed fraction of the pin spacing at the apex, at most 6 px
        centre_spacing_px = spacing * (radius - _pad.STALK_MM) / radius * self._f / apex_depth
        pin_px = float(np.clip(self.pin_fraction * centre_spacing_px, 1.0, 6.0))
        self._tip_radius_mm = pin_px * apex_depth / self._f
        self.pin_radius_px = pin_px
        self.mm_per_px = float(apex_depth / self._f * radius / (radius - _pad.STALK_MM))
        self._brightness = 1.0 + 0.05 * layout_rng.standard_normal(self._n)
        self._pin_level = _render.PIN_LEVEL if pin_level is None else float(pin_level)
        levels = {} if membrane_level is None else {"membrane_level": float(membrane_level)}
        # the LED glare spots keep their size in px at the default pad; a pad given a size scales them with it
        scale = {} if self.pad_fraction == 0.87 else {"glare_scale": self.pad_fraction / 0.87 * height / 480.0}
        if surround_level is not None:
            levels["casing_level"] = float(surround_level)
        background, glare, self._illumination = _render.scene_layers(
            self.image_size, self.disc, gradient=self.gradient, glare=self.glare, glare_gain=self.glare_gain,
            veil=self.veil, **levels, **scale)
        if self.skin_texture > 0:  # low-frequency mottling of the skin (static: thickness and pigment)
            yy, xx = np.mgrid[0:height, 0:width]
            on_skin = np.hypot(xx - self._c[0], yy - self._c[1]) < disc_px
            spacing_px = centre_spacing_px
            background += (0.6 * self.skin_texture * on_skin * _render.mottling(scene_rng, self.image_size,
                                                                               5.0 * spacing_px))
        if self.dark_pins:  # dark markers on a light membrane: invert the lit scene, keep the glare
            background = _DARK_INVERSION - background
        self._static = background + glare
        self.rest_centres, _, _ = self._project(Contact())
        self.rest_centres.setflags(write=False)
        self.rim_radius_px = None
        self.ring_glare_centres = np.zeros((0, 2))
        self._ring = None
        if self.rim_polar_deg is not None:
            polar = np.deg2rad(self.rim_polar_deg)
            tip = radius - _pad.STALK_MM  # where the tips at this polar angle are seen
            self.rim_radius_px = float(self._f * tip * np.sin(polar) / (tip * np.cos(polar) + self._h))
            alpha, value, self.ring_glare_centres = _render.rim_ring(
                self.image_size, self.disc, self.rim_radius_px, rng=scene_rng, glare_count=self.ring_glare,
                spot_px=max(pin_px, 2.0))
            self._ring = ((1.0 - alpha).reshape(-1), value.reshape(-1))
        self._texture = self._skin_spots(scene_rng) if self.skin_texture > 0 else None
        self._tint = (_render.tint_table(self.membrane_level or _render.MEMBRANE_LEVEL, 0.85 * self._pin_level)
                      if self.skin_tint == "brown" else None)

    @classmethod
    def from_preset(cls, name: str, **overrides) -> "SyntheticTacTip":
        """A renderer of one of the named sensors in `PRESETS`, with any option overridden.

        Parameters
        ----------
        name : str
            A key of `PRESETS` (see `preset_names`).
        **overrides
            Constructor options replacing the preset's (e.g. ``seed=3``, ``noise_sigma=0.0``).

        Examples
        --------
        >>> sensor = SyntheticTacTip.from_preset("radial-120")
        >>> sensor.n_pins, sensor.frame_rate
        (120, 120.0)
        """
        if name not in PRESETS:
            raise ValueError(f"unknown synthetic TacTip preset {name!r}; choose from {', '.join(PRESETS)}")
        sensor = cls(**{**PRESETS[name], **overrides})
        sensor.preset = name
        return sensor

    def _skin_spots(self, rng: np.random.Generator):
        """Material points of the skin texture between the pins: x, y (mm), sigma (px), amplitude (grey)."""
        n_high, n_speck = self._n, 2 * self._n
        count = 4 * (n_high + n_speck)
        cos_polar = rng.uniform(np.cos(np.deg2rad(_TEXTURE_POLAR_DEG)), 1.0, count)  # uniform over the cap
        azimuth = rng.uniform(0.0, 2 * np.pi, count)
        sin_polar = np.sqrt(1.0 - cos_polar ** 2)
        x, y = self._radius * sin_polar * np.cos(azimuth), self._radius * sin_polar * np.sin(azimuth)
        highlight = np.arange(count) % (n_high + n_speck) < n_high
        sigma = np.where(highlight, rng.uniform(0.6, 1.1, count) * self.pin_radius_px, rng.uniform(0.5, 0.9, count))
        sign = np.where(highlight | (rng.uniform(size=count) < 0.4), 1.0, -1.0)
        amplitude = sign * self.skin_texture * np.where(highlight, rng.uniform(1.5, 3.5, count),
                                                        rng.uniform(1.5, 3.0, count))
        from scipy.spatial import cKDTree

        seen = self._skin_image(x, y, Contact())
        gap, _ = cKDTree(self.rest_centres).query(seen)
        keep = gap >= self.pin_radius_px + 3.0 * sigma + 1.0  # texture lies between the pins
        keep &= np.cumsum(keep & highlight) <= n_high
        keep &= np.cumsum(keep & ~highlight) <= n_speck
        return x[keep], y[keep], sigma[keep], amplitude[keep]

    def _skin_image(self, x, y, contact: Contact):
        """Image positions (M, 2) px of skin material points at rest lateral position (x, y) mm."""
        point = _pad.membrane_points(x, y, contact, self._radius)
        return np.asarray(self.disc[:2]) + self._f * point[:, :2] / (point[:, 2:] + self._h)

    @property
    def n_pins(self) -> int:
        """Number of pins, N."""
        return self._n

    def __repr__(self) -> str:
        extra = "".join(f", {name}={getattr(self, name)!r}" for name, default in _NEW_OPTIONS.items()
                        if getattr(self, name) != default)
        return (f"SyntheticTacTip(pins={self._n}, pad_diameter_mm={self.pad_diameter_mm}, "
                f"image_size={self.image_size}, noise_sigma={self.noise_sigma}, glare={self.glare}, "
                f"gradient={self.gradient}, blur_sigma={self.blur_sigma}, jpeg_quality={self.jpeg_quality}, "
                f"colour={self.colour}, dark_pins={self.dark_pins}, seed={self.seed}{extra})")

    def _project(self, contact: Contact):
        """Pin tips through the camera: centres (N, 2) px, ellipse matrices (N, 2, 2) px^2, facing (N,) bool."""
        base, normal = _pad.deformed_surface(self._base_x, self._base_y, contact, self._radius)
        return _pad.project_discs(base + _pad.STALK_MM * normal, normal, focal_px=self._f,
                                  principal_px=self.disc[:2], camera_mm=self._h,
                                  disc_radius_mm=self._tip_radius_mm)

    def reseed_noise(self, seed: int) -> None:
        """Restart the camera-noise generator from ``seed`` (the pin layout is unchanged).

        The simulated station reseeds before each tap, so a tap's frames depend only on the tap
        (a resumed collection renders exactly what an uninterrupted one would have).
        """
        self._noise_rng = np.random.default_rng(seed)

    def pin_centres(self, contact: Contact | None = None) -> tuple[np.ndarray, np.ndarray]:
        """True pin-tip centres for a contact state, without rendering.

        Parameters
        ----------
        contact : Contact or None
            None means no contact (rest).

        Returns
        -------
        centres : (N, 2) float64 ndarray of (x, y), px
        visible : (N,) bool ndarray
            True where the whole pin tip is drawn: it faces the camera and clears the image edge and
            the rim ring (the `SyntheticFrame.visible` of a render).
        """
        centres, shape, facing = self._project(contact or Contact())
        return centres, self._visibility(centres, shape, facing)[0]

    def pin_ellipses(self, contact: Contact | None = None) -> tuple[np.ndarray, np.ndarray]:
        """True pin-tip ellipses for a contact state: what each tip covers in the image.

        Parameters
        ----------
        contact : Contact or None
            None means no contact (rest).

        Returns
        -------
        centres : (N, 2) float64 ndarray of (x, y), px
        shape : (N, 2, 2) float64 ndarray, px^2
            The tip covers ``{c + e : e^T shape^-1 e <= 1}`` (semi-axes: square roots of the
            eigenvalues), plus a 1 px anti-aliased edge ramp centred on that boundary.
        """
        centres, shape, _ = self._project(contact or Contact())
        return centres, shape

    def _inside(self, centres, shape):
        """Whether each ellipse lies entirely inside the image."""
        width, height = self.image_size
        half = np.sqrt(np.stack([shape[:, 0, 0], shape[:, 1, 1]], axis=1)) + 1.0
        return np.all((centres - half >= 0) & (centres + half <= [width - 1, height - 1]), axis=1)

    def _visibility(self, centres, shape, facing):
        """Whole and partly hidden pins, (N,) bool each: by the image edge and the rim ring.

        A tip (its ellipse plus the 1 px edge ramp) is whole when it clears the image edge and the ring's
        inner edge by a pixel, hidden when it lies wholly beyond the ring or the image, partial between.
        """
        width, height = self.image_size
        inside = self._inside(centres, shape)
        half = np.sqrt(np.stack([shape[:, 0, 0], shape[:, 1, 1]], axis=1)) + 0.5 * _render.EDGE_PX
        touches = np.all((centres + half > -0.5) & (centres - half < [width - 0.5, height - 0.5]), axis=1)
        if self.rim_radius_px is not None:
            offset = centres - np.asarray(self.disc[:2])
            distance = np.linalg.norm(offset, axis=1)
            direction = offset / np.maximum(distance, 1e-9)[:, None]
            reach = np.sqrt(np.einsum("ni,nij,nj->n", direction, shape, direction)) + 0.5 * _render.EDGE_PX
            inside &= distance + reach + 0.5 <= self.rim_radius_px
            touches &= distance - reach - 0.5 < self.rim_radius_px
        visible = facing & inside
        return visible, facing & touches & ~visible

    def render(self, contact: Contact | None = None, *, hidden: np.ndarray | None = None,
               timestamp_s: float = 0.0) -> SyntheticFrame:
        """Render one frame.

        Parameters
        ----------
        contact : Contact or None
            Contact state; None means no contact (rest).
        hidden : (N,) bool ndarray or None
            Pins to leave out (occluded): not drawn, ``visible`` False.
        timestamp_s : float
            Time stamp stored in the frame, s.

        Returns
        -------
        SyntheticFrame
        """
        contact = contact or Contact()
        centres, shape, facing = self._project(contact)
        visible, partial = self._visibility(centres, shape, facing)
        if hidden is not None:
            hidden = np.asarray(hidden, dtype=bool)
            if hidden.shape != (self._n,):
                raise ValueError(f"hidden must have shape ({self._n},), got {hidden.shape}")
            visible &= ~hidden
            partial &= ~hidden
        drawn = visible | partial
        image = self._draw(centres[drawn], shape[drawn], self._brightness[drawn], contact)
        return SyntheticFrame(image=image, centres=centres, visible=visible, timestamp_s=float(timestamp_s),
                              contact=contact, partial=partial)

    def _draw(self, centres, shape, brightness, contact):
        """Composite pins over the static scene, add blur, noise and compression; returns uint8."""
        scene = self._static.copy()
        flat = scene.reshape(-1)
        width, height = self.image_size
        sign = -1.0 if self.dark_pins else 1.0
        if self._texture is not None:  # specks and highlights ride on the skin
            x, y, sigma, amplitude = self._texture
            seen = self._skin_image(x, y, contact)
            small = sigma < 1.0  # specks apart from highlights: each call paints patches sized for its largest
            for group in (small, ~small):
                _render.paint_spots(flat, self.image_size, seen[group], sigma[group], sign * amplitude[group])
        if self.pin_shadows > 0 and len(centres):  # LEDs all round: each pin shades a ring of skin round it
            _render.paint_spots(flat, self.image_size, centres,
                                np.full(len(centres), max(_SHADOW_SIGMA * self.pin_radius_px, 0.6)),
                                np.full(len(centres), -sign * self.pin_shadows),
                                ring_px=_SHADOW_RING * self.pin_radius_px)
        anchor = np.clip(np.rint(centres).astype(np.int64), 0, [width - 1, height - 1])
        levels = self._pin_level * brightness * self._illumination.reshape(-1)[anchor[:, 1] * width + anchor[:, 0]]
        if self.dark_pins:
            levels = _DARK_INVERSION - levels
        _render.paint_pins(flat, self.image_size, centres, shape, levels)
        if self._ring is not None:  # the casing lip in front of the membrane hides what lies behind it
            flat *= self._ring[0]
            flat += self._ring[1]
        if self.blur_sigma > 0:
            import cv2

            scene = cv2.GaussianBlur(scene, (0, 0), self.blur_sigma)
        if self._tint is not None and self.colour:
            scene = scene[:, :, None] * np.take(self._tint, np.clip(scene, 0, 255).astype(np.uint8), axis=0)
        elif self.colour:
            scene = scene[:, :, None] * np.array([1.0, 0.97, 0.93], dtype=np.float32)
        if self.noise_sigma > 0:
            scene += _render.byte_noise(self._noise_rng, scene.shape, self.noise_sigma)
        scene += np.float32(0.5)  # round to nearest on conversion
        image = np.clip(scene, 0, 255, out=scene).astype(np.uint8)
        if self.jpeg_quality is not None:
            import cv2

            _, buffer = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, int(self.jpeg_quality)])
            image = cv2.imdecode(buffer, cv2.IMREAD_UNCHANGED)
        return image

    def tap(self, contact: Contact, *, frame_rate: float | None = None, rise_s: float = 0.25, plateau_s: float = 0.25,
            release_s: float = 0.25, rest_before_s: float = 0.1,
            rest_after_s: float = 0.1) -> Iterator[SyntheticFrame]:
        """Frames of one tap: rest, rise, plateau, release, rest, at ``frame_rate``.

        The indentation follows ``contact.indentation_mm * tap_profile(t - rest_before_s)``; the gap
        stays as in ``contact``.

        Parameters
        ----------
        contact : Contact
            Contact at the deepest point of the tap.
        frame_rate : float or None
            Frames per second; None: the sensor's `frame_rate`.
        rise_s, plateau_s, release_s, rest_before_s, rest_after_s : float
            Phase durations, s.

        Yields
        ------
        SyntheticFrame
            Time stamps ``k / frame_rate`` from 0 to the end of the rest after, inclusive.
        """
        frame_rate = self.frame_rate if frame_rate is None else frame_rate
        if not frame_rate > 0:
            raise ValueError(f"frame_rate must be > 0, got {frame_rate!r}")
        if not (rest_before_s >= 0 and rest_after_s >= 0):
            raise ValueError(f"rest_before_s and rest_after_s must be >= 0, got {rest_before_s}, {rest_after_s}")
        tap_profile(0.0, rise_s=rise_s, plateau_s=plateau_s, release_s=release_s)  # validates the phases
        duration = rest_before_s + rise_s + plateau_s + release_s + rest_after_s
        for k in range(int(math.floor(duration * frame_rate + 1e-9)) + 1):
            t = k / frame_rate
            fraction = tap_profile(t - rest_before_s, rise_s=rise_s, plateau_s=plateau_s, release_s=release_s)
            state = Contact(contact.indentation_mm * fraction, contact.gap_width_mm, contact.gap_offset_mm,
                            contact.gap_angle_deg)
            yield self.render(state, timestamp_s=t)


# Options added after the first release, with their defaults (the repr names them only when changed).
_NEW_OPTIONS = {"layout": "auto", "pad_fraction": 0.87, "pin_fraction": _PIN_SPACING_FRACTION, "rim_polar_deg": None,
                "ring_glare": 0, "membrane_level": None, "pin_level": None, "surround_level": None,
                "glare_gain": 1.0, "veil": 0.0, "skin_texture": 0.0, "pin_shadows": 0.0, "skin_tint": None,
                "frame_rate": 20.0}

#: Named sensors: constructor options of `SyntheticTacTip` for each (see the module docstring, "Presets").
PRESETS = MappingProxyType({
    "tactip-331": MappingProxyType({"pins": 331}),
    "tactip-127": MappingProxyType({"pins": 127}),
    "tactip-532": MappingProxyType({"pins": 532}),
    "dark-331": MappingProxyType({"pins": 331, "dark_pins": True}),
    "rim-ring-331": MappingProxyType({"pins": 331, "glare": False, "rim_polar_deg": 77.0, "ring_glare": 18}),
    "brown-127": MappingProxyType({"pins": 127, "colour": True, "skin_tint": "brown", "membrane_level": 70.0,
                                   "pin_level": 140.0, "skin_texture": 12.0, "pin_shadows": 22.0}),
    "radial-120": MappingProxyType({"pins": 120, "layout": "radial", "pad_fraction": 1 / 3, "pin_fraction": 0.25,
                                    "surround_level": 245.0, "glare_gain": 1.6, "veil": 40.0, "noise_sigma": 5.0,
                                    "frame_rate": 120.0}),
    "small-pad-100": MappingProxyType({"pins": 100, "image_size": (320, 240), "pad_fraction": 0.25,
                                       "pin_fraction": 0.22, "surround_level": 235.0}),
    "dense-1000": MappingProxyType({"pins": 1000, "image_size": (1280, 720), "pad_fraction": 0.9}),
})


def preset_names() -> tuple[str, ...]:
    """Names of the synthetic TacTip presets, in `PRESETS` order.

    Examples
    --------
    >>> preset_names()[:3]
    ('tactip-331', 'tactip-127', 'tactip-532')
    """
    return tuple(PRESETS)
