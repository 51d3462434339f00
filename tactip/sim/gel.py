"""`SyntheticGel`: frames of a flat gel carrying a grid of dark markers, with exact ground truth.

The GelSight-Mini-like sensor of ``tactip.sim`` ("Flat gels"): no pad, no disc, no casing; the gel
fills the whole frame, lit in colour from three sides.

>>> frame = SyntheticGel(seed=0).render(Contact(indentation_mm=3.0, slide_x_mm=1.0))
>>> frame.image.shape, int(frame.visible.sum()) >= 70
((240, 320, 3), True)
"""

from __future__ import annotations

import math

import numpy as np

from tactip.sim import _gel, _render
from tactip.sim.contact import Contact, SyntheticFrame
from tactip.sim.presets import GEL_PRESETS, build_preset
from tactip.sim.sequence import ContactSequences
from tactip.sim.synthetic import SyntheticTacTip

__all__ = ["SyntheticGel"]

_GRID_JITTER = 0.01  # marker positions jitter by this fraction of the pitch (seeded)
_PHASE = 0.2  # the grid's offset from the frame's centre: up to this fraction of the pitch (seeded)


class SyntheticGel(ContactSequences):
    """A simulated flat-gel sensor: renders frames of its dark marker grid with exact ground truth.

    Parameters
    ----------
    grid : (int, int)
        Rows and columns of markers across the frame (the grid goes on one row and column beyond
        each edge, so markers can slide into view).
    pitch_mm : float
        Marker pitch on the gel, mm (the frame shows ``grid`` pitches at most along each side).
    image_size : (int, int)
        (width, height) of the frames, px.
    marker_fraction : float
        Marker radius / pitch, 0.08-0.3.
    gel_level : float
        Grey level of the lit gel at the frame's centre, in each channel.
    gradient : float
        Colour gradient: each channel is ``gradient`` grey levels brighter on its light's side than
        on the opposite side (B from the left, G from the top, R from the right).
    vignette : float
        Grey levels lost in the corners.
    marker_reflectance : float
        A marker reflects this share of the light on it (0-1): dark markers at 0.3.
    shading : float
        Photometric shading of the pressed gel: grey levels per unit slope of the dent (0: none).
    noise_sigma : float
        Sensor noise, grey levels (standard deviation).
    blur_sigma : float
        Optical blur (Gaussian sigma, px); 0 for none.
    jpeg_quality : int or None
        Pass each frame through JPEG compression at this quality (1-100).
    colour : bool
        BGR frames (True) or their BT.601 grey.
    frame_rate : float
        Frames per second of `tap` and `sequence` by default.
    seed : int
        Seed of the grid's offset, the markers' jitter and the noise.

    Attributes
    ----------
    n_pins : int
        Markers on the gel, in view or not.
    rest_centres : (N, 2) float64 ndarray, read-only
        True marker centres at rest, px.
    disc : (float, float, float)
        A circle about the frame's centre that holds the whole frame (cx, cy, radius), px: the gel
        has no disc, the whole frame is its sensing area.
    mm_per_px : float
        Gel mm per image px.
    pin_radius_px : float
        Marker radius, px.
    pin_spacing_mm : float
        The marker pitch, mm.
    pitch_px : float
        The marker pitch, px.
    dark_pins : bool
        Always True: dark markers on a light gel.
    preset : str or None
        The preset's name when built by `from_preset`.

    Examples
    --------
    >>> sensor = SyntheticGel.from_preset("gelsight-mini", seed=1)
    >>> sensor.frame_rate, round(sensor.pitch_px, 1)
    (25.0, 30.0)
    """

    rim_radius_px = None
    dark_pins = True
    shimmer = 0.0
    ring_glare_centres = np.zeros((0, 2))
    reflection_centres = np.zeros((0, 2))
    reflection_radii_px = np.zeros(0)

    def __init__(self, *, grid=(8, 10), pitch_mm: float = 1.8, image_size=(320, 240), marker_fraction: float = 0.14,
                 gel_level: float = 150.0, gradient: float = 80.0, vignette: float = 30.0,
                 marker_reflectance: float = 0.3, shading: float = 25.0, noise_sigma: float = 3.0,
                 blur_sigma: float = 0.0, jpeg_quality: int | None = None, colour: bool = True,
                 frame_rate: float = 25.0, seed: int = 0):
        rows, cols = (int(v) for v in grid)
        width, height = (int(v) for v in image_size)
        if rows < 2 or cols < 2 or rows != grid[0] or cols != grid[1]:
            raise ValueError(f"grid must be two integers >= 2 (rows, columns), got {grid!r}")
        if width < 64 or height < 64:
            raise ValueError(f"image_size must be at least (64, 64), got {image_size!r}")
        if not (math.isfinite(pitch_mm) and pitch_mm > 0):
            raise ValueError(f"pitch_mm must be > 0, got {pitch_mm!r}")
        if not 0.08 <= marker_fraction <= 0.3:
            raise ValueError(f"marker_fraction must be in 0.08..0.3, got {marker_fraction!r}")
        if not 0 <= marker_reflectance <= 1:
            raise ValueError(f"marker_reflectance must be in 0..1, got {marker_reflectance!r}")
        for name, value in (("gel_level", gel_level), ("gradient", gradient), ("vignette", vignette),
                            ("shading", shading), ("noise_sigma", noise_sigma), ("blur_sigma", blur_sigma)):
            if not (math.isfinite(value) and 0 <= value <= 255):
                raise ValueError(f"{name} must be in 0..255, got {value!r}")
        if jpeg_quality is not None and not 1 <= jpeg_quality <= 100:
            raise ValueError(f"jpeg_quality must be in 1..100 or None, got {jpeg_quality!r}")
        if not (math.isfinite(frame_rate) and frame_rate > 0):
            raise ValueError(f"frame_rate must be > 0, got {frame_rate!r}")
        self.grid, self.image_size = (rows, cols), (width, height)
        self.pin_spacing_mm, self.marker_fraction = float(pitch_mm), float(marker_fraction)
        self.gel_level, self.gradient, self.vignette = float(gel_level), float(gradient), float(vignette)
        self.marker_reflectance, self.shading = float(marker_reflectance), float(shading)
        self.noise_sigma, self.blur_sigma, self.jpeg_quality = float(noise_sigma), float(blur_sigma), jpeg_quality
        self.colour, self.frame_rate, self.seed = bool(colour), float(frame_rate), seed
        self.preset = None
        layout_rng, self._noise_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(2))
        self._scenes = {}  # the last frames before noise at rest and pressed (see `render`)

        self.pitch_px = float(min(width / cols, height / rows))
        self.mm_per_px = self.pin_spacing_mm / self.pitch_px
        self.pin_radius_px = self.marker_fraction * self.pitch_px
        self._c = ((width - 1) / 2.0, (height - 1) / 2.0)
        self.disc = (self._c[0], self._c[1], float(math.hypot(width, height) / 2 + 1.0))
        # the grid, one row and column beyond the frame on every side, offset from the centre by a seeded phase
        phase = layout_rng.uniform(-_PHASE, _PHASE, 2)
        ix = np.arange(cols + 2) - (cols + 1) / 2 + phase[0]
        iy = np.arange(rows + 2) - (rows + 1) / 2 + phase[1]
        gx, gy = np.meshgrid(ix, iy)
        lattice = np.column_stack([gx.ravel(), gy.ravel()])
        lattice += layout_rng.normal(0.0, _GRID_JITTER, lattice.shape)
        self._rest_mm = lattice * self.pin_spacing_mm  # (N, 2) gel mm from the frame's centre
        self._n = len(lattice)
        self._light = _gel.gel_light(self.image_size, level=self.gel_level, gradient=self.gradient,
                                     vignette=self.vignette)
        self.rest_centres = self._project(Contact())
        self.rest_centres.setflags(write=False)

    @classmethod
    def from_preset(cls, name: str, **overrides) -> "SyntheticGel":
        """A renderer of one of the named flat gels in `GEL_PRESETS`, with any option overridden.

        Examples
        --------
        >>> SyntheticGel.from_preset("gelsight-mini").grid
        (8, 10)
        """
        return build_preset(cls, GEL_PRESETS, "synthetic gel", name, overrides)

    @property
    def n_pins(self) -> int:
        """Number of markers on the gel, N (in view or not)."""
        return self._n

    def __repr__(self) -> str:
        return (f"SyntheticGel(grid={self.grid}, pitch_mm={self.pin_spacing_mm}, image_size={self.image_size}, "
                f"noise_sigma={self.noise_sigma}, colour={self.colour}, seed={self.seed})")

    def _project(self, contact: Contact) -> np.ndarray:
        """Marker centres (N, 2) px under a contact."""
        x, y = _gel.deform(self._rest_mm[:, 0], self._rest_mm[:, 1], contact)
        return np.column_stack([x, y]) / self.mm_per_px + np.asarray(self._c)

    def reseed_noise(self, seed: int | None) -> None:
        """Restart the camera-noise generator from ``seed`` (None: leave it); the grid is unchanged."""
        if seed is not None:
            self._noise_rng = np.random.default_rng(seed)

    def _visibility(self, centres: np.ndarray):
        """Whole (ramp included, a pixel clear of the edge) and partly drawn markers, (N,) bool each."""
        width, height = self.image_size
        whole = self.pin_radius_px + 1.0
        visible = np.all((centres - whole >= 0) & (centres + whole <= [width - 1, height - 1]), axis=1)
        reach = self.pin_radius_px + 0.5 * _render.EDGE_PX
        touches = np.all((centres + reach > -0.5) & (centres - reach < [width - 0.5, height - 0.5]), axis=1)
        return visible, touches & ~visible

    def pin_centres(self, contact: Contact | None = None) -> tuple[np.ndarray, np.ndarray]:
        """True marker centres (N, 2) px for a contact state, and which are whole in view (N,) bool."""
        centres = self._project(contact or Contact())
        return centres, self._visibility(centres)[0]

    def pin_ellipses(self, contact: Contact | None = None) -> tuple[np.ndarray, np.ndarray]:
        """True marker centres (N, 2) px and shapes (N, 2, 2) px^2: discs of `pin_radius_px` (a flat gel
        seen square on), plus a 1 px anti-aliased edge ramp."""
        centres = self._project(contact or Contact())
        return centres, np.broadcast_to(self.pin_radius_px ** 2 * np.eye(2), (self._n, 2, 2)).copy()

    def render(self, contact: Contact | None = None, *, hidden: np.ndarray | None = None,
               timestamp_s: float = 0.0) -> SyntheticFrame:
        """Render one frame.

        Parameters
        ----------
        contact : Contact or None
            The indenter's state (depth, slide); None means no contact. A gap in the plate is not
            modelled on a flat gel.
        hidden : (N,) bool ndarray or None
            Markers to leave out: not drawn, ``visible`` False.
        timestamp_s : float
            Time stamp stored in the frame, s.

        Returns
        -------
        SyntheticFrame
            ``visible``: markers wholly in the frame; ``partial``: cut by the frame's edge.
        """
        contact = contact or Contact()
        if hidden is not None:
            hidden = np.asarray(hidden, dtype=bool)
            if hidden.shape != (self._n,):
                raise ValueError(f"hidden must have shape ({self._n},), got {hidden.shape}")
        # As SyntheticTacTip's: the last frames before noise at rest and pressed are drawn once.
        slot, key = _render.scene_slot(contact, hidden)
        cached = self._scenes.get(slot)
        if cached is not None and cached[0] == key:
            centres, visible, partial, scene = cached[1]
        else:
            centres = self._project(contact)
            visible, partial = self._visibility(centres)
            if hidden is not None:
                visible &= ~hidden
                partial &= ~hidden
            drawn = visible | partial
            scene = self._draw(centres[drawn], contact)
            self._scenes[slot] = (key, (centres, visible, partial, scene))
        image = _render.expose(scene.copy(), rng=self._noise_rng, noise_sigma=self.noise_sigma,
                               jpeg_quality=self.jpeg_quality)
        return SyntheticFrame(image=image, centres=centres.copy(), visible=visible.copy(),
                              timestamp_s=float(timestamp_s), contact=contact, partial=partial.copy())

    def _draw(self, centres: np.ndarray, contact: Contact) -> np.ndarray:
        """The lit gel, its shading under contact, the markers and blur: the frame before noise, float32."""
        width, height = self.image_size
        light = self._light + _gel.shading(self.image_size, self.mm_per_px, contact, gain=self.shading)
        shape = np.broadcast_to(self.pin_radius_px ** 2 * np.eye(2), (len(centres), 2, 2))
        anchor = np.clip(np.rint(centres).astype(np.int64), 0, [width - 1, height - 1])
        channels = []
        for c in range(3):
            scene = np.ascontiguousarray(light[:, :, c])
            # a marker reflects its share of the light on it (taken at its centre: the disc stays symmetric)
            levels = self.marker_reflectance * scene[anchor[:, 1], anchor[:, 0]]
            _render.paint_pins(scene.reshape(-1), self.image_size, centres, shape, levels)
            channels.append(scene)
        scene = np.stack(channels, axis=-1)
        if not self.colour:
            scene = scene @ np.array([0.114, 0.587, 0.299], np.float32)
        if self.blur_sigma > 0:
            import cv2

            scene = cv2.GaussianBlur(scene, (0, 0), self.blur_sigma)
        return scene

    tap = SyntheticTacTip.tap
