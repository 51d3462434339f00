"""`SyntheticTacTip`: frames of the pin array with exact ground truth (model and presets: `tactip.sim`).
>>> frames = list(SyntheticTacTip(pins=331, seed=0).tap(Contact(indentation_mm=4.0, gap_width_mm=2.0)))
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Iterator

import numpy as np

from tactip.sim import _options, _pad, _render, _scene, _slide
from tactip.sim.contact import Contact, SyntheticFrame, tap_profile
from tactip.sim.presets import PRESETS, build_preset
from tactip.sim.sequence import ContactSequences

__all__ = ["SyntheticTacTip"]

_DISC_FRACTION = 0.435  # radius of the dark membrane disc / image height
_DARK_INVERSION = 240.0  # dark_pins: grey level g becomes 240 - g (light membrane, dark tips)
_PIN_SPACING_FRACTION = _options.PIN_SPACING_FRACTION  # pin radius / pin spacing at the apex (at most 6 px)
_TEXTURE_POLAR_DEG = 84.0  # skin texture is drawn out to this polar angle (inside the casing edge)
_SHADOW_RING = 1.4  # pin shadows: a soft dark ring of this radius round each tip, in pin radii
_SHADOW_SIGMA = 0.35  # pin shadows: Gaussian sigma across the ring, in pin radii


class SyntheticTacTip(ContactSequences):
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
    reflections : int
        Internal LED reflections: soft bright blobs inside the pad (0-16), fixed in the image.
    reflection_level : float
        Grey levels a reflection adds at its centre (each +-15 %).
    glare_gradient : float
        Glare across the pad: grey levels added on its brightest side, fading linearly to 0 across it.
    shimmer : float
        Per-frame std of the reflections' brightness, grey levels (half that on the glare gradient),
        with sub-pixel jitter of their centres; a still pad's frames then differ by more than noise.

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
    reflection_centres : (K, 2) float64 ndarray
        Centres (x, y) px of the internal LED reflections (empty without them).
    reflection_radii_px : (K,) float64 ndarray
        Their radii at half maximum, px.
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
                 frame_rate: float = 20.0, reflections: int = 0, reflection_level: float = 50.0,
                 glare_gradient: float = 0.0, shimmer: float = 0.0):
        _options.check_options(
            pins=pins, pad_diameter_mm=pad_diameter_mm, image_size=image_size, noise_sigma=noise_sigma,
            blur_sigma=blur_sigma, jpeg_quality=jpeg_quality, layout=layout, pad_fraction=pad_fraction,
            pin_fraction=pin_fraction, rim_polar_deg=rim_polar_deg, ring_glare=ring_glare,
            membrane_level=membrane_level, pin_level=pin_level, surround_level=surround_level,
            glare_gain=glare_gain, veil=veil, skin_texture=skin_texture, pin_shadows=pin_shadows,
            skin_tint=skin_tint, frame_rate=frame_rate, reflections=reflections,
            reflection_level=reflection_level, glare_gradient=glare_gradient, shimmer=shimmer)
        width, height = (int(v) for v in image_size)
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
        self.reflections, self.reflection_level = int(reflections), float(reflection_level)
        self.glare_gradient, self.shimmer = float(glare_gradient), float(shimmer)
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
        self._light = None  # LED reflections and glare gradient inside the pad: image-fixed (see _scene)
        if self.reflections or self.glare_gradient:
            self._light = _scene.PadLight(
                self.image_size, self.disc, np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(3,))),
                reflections=self.reflections, reflection_level=self.reflection_level,
                spacing_px=centre_spacing_px, gradient_level=self.glare_gradient, shimmer=self.shimmer)
        self.reflection_centres = np.zeros((0, 2)) if self._light is None else self._light.centres
        self.reflection_radii_px = np.zeros(0) if self._light is None else self._light.radii_px
        self._shimmer_rng = None
        # the last frames before noise at rest and pressed, (key, (centres, visible, partial, scene)): a tap
        # films the same contact in its rests and plateau, and only the camera noise differs between them
        self._scenes = {}
        self.reseed_noise(None)
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
        return build_preset(cls, PRESETS, "synthetic TacTip", name, overrides)

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
        point = _pad.membrane_points(*_slide.slid_points(x, y, contact, self._radius), contact, self._radius)
        return np.asarray(self.disc[:2]) + self._f * point[:, :2] / (point[:, 2:] + self._h)

    @property
    def n_pins(self) -> int:
        """Number of pins, N."""
        return self._n

    def __repr__(self) -> str:
        extra = "".join(f", {name}={getattr(self, name)!r}" for name, default in _options.REPR_DEFAULTS.items()
                        if getattr(self, name) != default)
        return (f"SyntheticTacTip(pins={self._n}, pad_diameter_mm={self.pad_diameter_mm}, "
                f"image_size={self.image_size}, noise_sigma={self.noise_sigma}, glare={self.glare}, "
                f"gradient={self.gradient}, blur_sigma={self.blur_sigma}, jpeg_quality={self.jpeg_quality}, "
                f"colour={self.colour}, dark_pins={self.dark_pins}, seed={self.seed}{extra})")

    def _project(self, contact: Contact):
        """Pin tips through the camera: centres (N, 2) px, ellipse matrices (N, 2, 2) px^2, facing (N,) bool."""
        x, y = _slide.slid_points(self._base_x, self._base_y, contact, self._radius)  # skin dragged sideways
        base, normal = _pad.deformed_surface(x, y, contact, self._radius)
        return _pad.project_discs(base + _pad.STALK_MM * normal, normal, focal_px=self._f,
                                  principal_px=self.disc[:2], camera_mm=self._h,
                                  disc_radius_mm=self._tip_radius_mm)

    def reseed_noise(self, seed: int | None) -> None:
        """Restart the camera-noise generator from ``seed`` (the pin layout is unchanged).

        The simulated station reseeds before each tap, so a tap's frames depend only on the tap
        (a resumed collection renders exactly what an uninterrupted one would have). The shimmer's
        generator restarts from ``seed`` too; None restarts it alone from the sensor's seed.
        """
        if seed is not None:
            self._noise_rng = np.random.default_rng(seed)
        if self.shimmer > 0:  # shimmer has a stream of its own, so the noise stays what it was
            key = self.seed if seed is None else seed
            self._shimmer_rng = np.random.default_rng(np.random.SeedSequence(key, spawn_key=(4,)))

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
        if hidden is not None:
            hidden = np.asarray(hidden, dtype=bool)
            if hidden.shape != (self._n,):
                raise ValueError(f"hidden must have shape ({self._n},), got {hidden.shape}")
        slot, key = _render.scene_slot(contact, hidden)
        cached = self._scenes.get(slot)
        if cached is not None and cached[0] == key:
            centres, visible, partial, scene = cached[1]
        else:
            centres, shape, facing = self._project(contact)
            visible, partial = self._visibility(centres, shape, facing)
            if hidden is not None:
                visible &= ~hidden
                partial &= ~hidden
            drawn = visible | partial
            scene = self._draw(centres[drawn], shape[drawn], self._brightness[drawn], contact)
            if self._shimmer_rng is None:  # a shimmering pad's light differs in every frame
                self._scenes[slot] = (key, (centres, visible, partial, scene))
        image = _render.expose(scene.copy(), rng=self._noise_rng, noise_sigma=self.noise_sigma,
                               jpeg_quality=self.jpeg_quality)
        return SyntheticFrame(image=image, centres=centres.copy(), visible=visible.copy(),
                              timestamp_s=float(timestamp_s), contact=contact, partial=partial.copy())

    def _draw(self, centres, shape, brightness, contact):
        """Composite pins over the static scene and blur: the frame before noise, (H, W[, 3]) float32."""
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
        if self._light is not None:  # image-fixed light over skin and pins; the pins gain only a share of it
            light = self._light.frame_layer(self._shimmer_rng)
            levels = levels + _scene.PIN_LIGHT_SHARE * light.reshape(-1)[anchor[:, 1] * width + anchor[:, 0]]
            flat += light.reshape(-1)
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
        return scene

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
            state = dataclasses.replace(contact, indentation_mm=contact.indentation_mm * fraction)
            yield self.render(state, timestamp_s=t)

