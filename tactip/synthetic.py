"""Synthetic TacTip frames with exact ground truth, for tests, the demo and the simulated station.

The renderer draws what the internal camera of a TacTip sees (paper 002, III-A): the inside of a
hemispherical silicone pad whose white-tipped pins stand on the black membrane, lit by LEDs on a ring
around the pad's base. Every frame comes with the true centre of every pin tip, in px.

Model and its assumptions
-------------------------
Geometry (pad coordinates, mm). The pad is a hemisphere of radius ``R`` (default 20 mm) centred on
the origin, apex at ``z = R``; the camera is a pinhole on the axis at ``z = -h`` (``h = 2 R``) looking
up, image x along pad X, image y along pad Y, principal point at the image centre. The focal length
is chosen so that the dark membrane disc, bounded by the casing at a polar angle of 86 degrees, has
a radius of 0.435 x the image height (209 px at 640x480), leaving a bright surround on every side.

Pins. Their bases sit on the membrane on a lattice laid out in pad-surface coordinates (arc length
``s = R theta`` from the apex, azimuth ``phi``), out to ``theta = 80`` degrees. A hexagonal number of
pins (127, 331, ... = 1 + 3K(K+1)) uses K hexagonal rings of 6k pins; any other count (532) uses K
concentric circles, K the smallest ring count whose hexagonal number reaches N, ring k getting a share
of the N - 1 outer pins proportional to k (largest-remainder rounding), odd rings rotated by half a
step. Bases jitter by 2 % of the spacing (seeded). Each pin is a stalk of length ``L = 2.5 mm``
along the membrane's inward normal ending in a flat white disc facing the camera, sized to a given
image radius at the apex (6, 5.5 and 4.2 px for 127, 331 and 532 pins) so that the image spacing
stays above 2.5 radii. The disc's image is the exact affine image of a circle, an ellipse that is
foreshortened (radially narrower) towards the rim; its centre is the projected tip centre, and,
being point-symmetric, the drawn blob's centroid is that centre: the ground truth.

Contact. A rigid flat plate, normal to the pad axis, presses the apex in by ``d`` mm. The pad is
treated as an elastic (incompressible) half-space in Hertz contact with the plate: contact radius
``a = sqrt(R d)``; vertical displacement towards the camera ``u_z = d - r^2 / (2R)`` inside the patch
(which makes it exactly flat to parabolic order) and the Hertz profile
``u_z = (d / pi) [(2 - r^2/a^2) asin(a/r) + sqrt(r^2/a^2 - 1)]`` outside, continuous in value and
slope. (Pure geometric overlap would give ``sqrt(2 R d)``; in Hertz contact half of the approach is
taken up by the surrounding gel sinking, which also gives the smooth decay outside the patch.)
The gel flows outward under the plate: the membrane moves radially by ``u_r = 0.1 u_z r / R``.
A straight gap (width ``w``, centre line at ``gap_offset`` along image y, direction ``gap_angle``)
leaves the membrane over it unsupported: like a tensioned membrane over a slot under pressure it bulges
into the gap by ``s0 = w^2 / (8 rho_m)`` (``rho_m = 10 mm``, the tension/pressure ratio), spread across
the gap with a Gaussian of width ``w/4 + 0.5 mm`` (the skin's bending length smooths the slot edges),
weighted by the pressure shape ``(1 - r^2/a^2)^(3/2)`` inside the patch and softly capped by the local
indentation (the skin cannot rise above its rest shape). So the imprint grows with ``w^2`` and is
subtle: tenths of a px for w = 1 mm, about 1-2 px at the pins nearest a 5 mm gap at d = 4 mm.
Pin tips move by the displacement of their base plus the lever ``L`` times the change of the
membrane normal (computed from the deformed surface by central differences), so flattening tilts
stalks outward: peak tip motion is about 13 px at d = 5 mm on a 331-pin pad. A tap follows a smooth
rise / plateau / release profile, 250 ms each by default (paper 002, IV-A).

Appearance. Bright casing around the disc (about 200 grey, vignetted), a dark membrane (about 25) with a
radial illumination gradient towards the LED ring, six LED glare spots on the rim, white pin tips
(about 215, +-5 % per pin, slightly domed) with an anti-aliased 1 px edge, sensor noise (sigma
``noise_sigma`` grey levels, near-Gaussian: a sum of four uniform bytes, fresh every frame and
deterministic given the seed), optional optical blur and JPEG compression.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

__all__ = ["Contact", "SyntheticFrame", "SyntheticTacTip", "tap_profile"]

_STALK_MM = 2.5  # pin stalk length L
_CAMERA_DISTANCE = 2.0  # h / R
_PIN_POLAR_MAX_DEG = 80.0  # outermost pins
_CASING_POLAR_DEG = 86.0  # where the casing hides the membrane: edge of the dark disc
_DISC_FRACTION = 0.435  # disc radius / image height
_RADIAL_FLOW = 0.1  # u_r = _RADIAL_FLOW * u_z * r / R
_MEMBRANE_RHO_MM = 10.0  # tension / contact pressure of the skin over a gap, mm
_BENDING_MM = 0.5  # bending length of the skin, mm
_EDGE_PX = 1.0  # width of the anti-aliased pin edge ramp, px


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


@dataclass(frozen=True)
class SyntheticFrame:
    """One rendered frame and its ground truth.

    Attributes
    ----------
    image : (H, W) uint8 ndarray, or (H, W, 3) uint8 BGR when the renderer has ``colour=True``
    centres : (N, 2) float64 ndarray
        True pin-tip centres (x, y), px; pixel centres at integer coordinates (OpenCV convention).
    visible : (N,) bool ndarray
        Whether each pin is drawn (False when hidden or outside the image).
    timestamp_s : float
        Time within the sequence, s.
    contact : Contact
        The contact state that was rendered.
    """

    image: np.ndarray
    centres: np.ndarray
    visible: np.ndarray
    timestamp_s: float
    contact: Contact


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
    >>> tap_profile([0.0, 0.125, 0.3, 0.875])
    array([0. , 0.5, 1. , 0.5])
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


def _pin_lattice(n_pins: int) -> np.ndarray:
    """Pin positions in ring units on the unrolled pad, (N, 2): hexagonal rings or concentric circles."""
    rings = 0
    while 1 + 3 * rings * (rings + 1) < n_pins:
        rings += 1
    k = np.arange(1, rings + 1)
    if 1 + 3 * rings * (rings + 1) == n_pins:
        # Hexagonal rings: ring k walks the 6 sides of a hexagon of corner radius k, k pins per side.
        ring = np.repeat(k, 6 * k)
        step = np.concatenate([np.arange(6 * kk) for kk in k])
        side, along = np.divmod(step, ring)
        c0 = np.exp(1j * np.pi / 3 * side)
        c1 = np.exp(1j * np.pi / 3 * (side + 1))
        z = ring * (c0 + (c1 - c0) * along / ring)
    else:
        # Concentric circles: ring k gets a share of the N - 1 outer pins proportional to k.
        quota = (n_pins - 1) * k / k.sum()
        counts = np.floor(quota).astype(int)
        counts[np.argsort(counts - quota, kind="stable")[: n_pins - 1 - counts.sum()]] += 1
        ring = np.repeat(k, counts)
        index = np.concatenate([np.arange(c) for c in counts])
        count = np.repeat(counts, counts)
        z = ring * np.exp(1j * np.pi * (2 * index + ring % 2) / count)
    z = np.concatenate([[0j], z])
    return np.column_stack([z.real, z.imag])


def _membrane_displacement(x, y, contact: Contact, radius_mm: float):
    """Displacement of membrane points (lateral position x, y in mm) under the plate.

    Returns ``(u_n, u_r)``: displacement towards the camera (along -z) and radially outward, mm,
    both shaped like ``x``. See the module docstring for the model.
    """
    d = contact.indentation_mm
    if d <= 0:
        zero = np.zeros_like(x)
        return zero, zero
    r2 = x * x + y * y
    a2 = radius_mm * d  # Hertz: a^2 = R d
    ratio2 = r2 / a2
    inside = ratio2 <= 1.0
    safe = np.maximum(ratio2, 1.0)
    outside_uz = d / np.pi * ((2.0 - safe) * np.arcsin(1.0 / np.sqrt(safe)) + np.sqrt(safe - 1.0))
    u_z = np.where(inside, d - r2 / (2.0 * radius_mm), outside_uz)
    u_r = _RADIAL_FLOW * u_z * np.sqrt(r2) / radius_mm
    w = contact.gap_width_mm
    if w > 0:
        angle = np.deg2rad(contact.gap_angle_deg)
        t = -x * np.sin(angle) + y * np.cos(angle) - contact.gap_offset_mm  # distance to the gap line
        spread = w / 4.0 + _BENDING_MM
        pressure = np.clip(1.0 - ratio2, 0.0, None) ** 1.5
        sag = w * w / (8.0 * _MEMBRANE_RHO_MM) * np.exp(-0.5 * (t / spread) ** 2) * pressure
        # soft cap: the skin cannot bulge above its rest shape (sag <= u_z)
        sag = u_z * -np.expm1(-sag / np.maximum(u_z, 1e-12))
        u_z = u_z - sag
    return u_z, u_r


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
                 dark_pins: bool = False, seed: int = 0):
        if int(pins) != pins or pins < 7:
            raise ValueError(f"pins must be an integer >= 7, got {pins!r}")
        if not pad_diameter_mm > 2 * _STALK_MM:
            raise ValueError(f"pad_diameter_mm must be > {2 * _STALK_MM}, got {pad_diameter_mm!r}")
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
        layout_rng, self._noise_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(seed).spawn(2))

        radius = self._radius = self.pad_diameter_mm / 2.0
        self._h = _CAMERA_DISTANCE * radius
        casing = np.deg2rad(_CASING_POLAR_DEG)
        disc_px = _DISC_FRACTION * height
        self._f = disc_px * (radius * math.cos(casing) + self._h) / (radius * math.sin(casing))
        self._c = ((width - 1) / 2.0, (height - 1) / 2.0)
        self.disc = (self._c[0], self._c[1], float(disc_px))

        lattice = _pin_lattice(self._n)
        ring_count = np.hypot(*lattice.T).max()
        spacing = radius * np.deg2rad(_PIN_POLAR_MAX_DEG) / ring_count  # mm of pad surface
        lattice = lattice + layout_rng.normal(0.0, 0.02, lattice.shape)
        arc = np.hypot(*lattice.T) * spacing
        azimuth = np.arctan2(lattice[:, 1], lattice[:, 0])
        polar = arc / radius
        self._base_x = radius * np.sin(polar) * np.cos(azimuth)
        self._base_y = radius * np.sin(polar) * np.sin(azimuth)
        self.pin_spacing_mm = float(spacing)

        apex_depth = radius - _STALK_MM + self._h
        # pin radius: 0.3 x the pin spacing at the apex, within 4-6 px (6, 5.5, 4.2 px at 127, 331, 532)
        centre_spacing_px = spacing * (radius - _STALK_MM) / radius * self._f / apex_depth
        pin_px = float(np.clip(0.3 * centre_spacing_px, 4.0, 6.0))
        self._tip_radius_mm = pin_px * apex_depth / self._f
        self.pin_radius_px = pin_px
        self.mm_per_px = float(apex_depth / self._f * radius / (radius - _STALK_MM))
        self._brightness = 1.0 + 0.05 * layout_rng.standard_normal(self._n)
        self._background, self._glare, self._illumination = self._scene()
        self.rest_centres, _, _ = self._project(Contact())
        self.rest_centres.setflags(write=False)

    @property
    def n_pins(self) -> int:
        """Number of pins, N."""
        return self._n

    def __repr__(self) -> str:
        return (f"SyntheticTacTip(pins={self._n}, pad_diameter_mm={self.pad_diameter_mm}, "
                f"image_size={self.image_size}, noise_sigma={self.noise_sigma}, glare={self.glare}, "
                f"gradient={self.gradient}, blur_sigma={self.blur_sigma}, jpeg_quality={self.jpeg_quality}, "
                f"colour={self.colour}, dark_pins={self.dark_pins}, seed={self.seed})")

    # -- geometry ------------------------------------------------------------------------------
    def _surface(self, x, y, contact: Contact):
        """Deformed membrane at material points (x, y): positions (..., 3) and inward unit normals (..., 3)."""
        radius = self._radius
        u_n, u_r = _membrane_displacement(x, y, contact, radius)
        z0 = np.sqrt(np.clip(radius ** 2 - x * x - y * y, 1e-9, None))
        if contact.indentation_mm > 0:
            eps = 1e-4
            gx = (_membrane_displacement(x + eps, y, contact, radius)[0]
                  - _membrane_displacement(x - eps, y, contact, radius)[0]) / (2 * eps)
            gy = (_membrane_displacement(x, y + eps, contact, radius)[0]
                  - _membrane_displacement(x, y - eps, contact, radius)[0]) / (2 * eps)
        else:
            gx = gy = 0.0
        # surface z = z0 - u_n; inward normal along (dz/dx, dz/dy, -1)
        normal = np.stack([-x / z0 - gx, -y / z0 - gy, -np.ones_like(x)], axis=-1)
        normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
        r = np.hypot(x, y)
        outward = np.divide(u_r, r, out=np.zeros_like(r), where=r > 0)
        base = np.stack([x * (1 + outward), y * (1 + outward), z0 - u_n], axis=-1)
        return base, normal

    def _project(self, contact: Contact):
        """Pin tips through the camera: centres (N, 2) px, inverse ellipse matrices (N, 2, 2), facing (N,) bool."""
        base, normal = self._surface(self._base_x, self._base_y, contact)
        tip = base + _STALK_MM * normal
        depth = tip[:, 2] + self._h
        f = self._f
        centres = np.column_stack([self._c[0] + f * tip[:, 0] / depth, self._c[1] + f * tip[:, 1] / depth])
        # Jacobian of the projection at the tip, (N, 2, 3); the disc's image is J (I - n n^T) J^T rho^2
        jac = np.zeros((self._n, 2, 3))
        jac[:, 0, 0] = jac[:, 1, 1] = f / depth
        jac[:, :, 2] = -f * tip[:, :2] / depth[:, None] ** 2
        plane = np.eye(3) - normal[:, :, None] * normal[:, None, :]
        shape = self._tip_radius_mm ** 2 * jac @ plane @ jac.transpose(0, 2, 1)
        to_camera = -tip - np.array([0.0, 0.0, self._h])
        facing = np.einsum("ij,ij->i", normal, to_camera) > 0.2 * np.linalg.norm(to_camera, axis=1)
        return centres, shape, facing

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
            True where the whole pin tip lies inside the image and faces the camera.
        """
        centres, shape, facing = self._project(contact or Contact())
        return centres, facing & self._inside(centres, shape)

    def _inside(self, centres, shape):
        """Whether each ellipse lies entirely inside the image."""
        width, height = self.image_size
        half = np.sqrt(np.stack([shape[:, 0, 0], shape[:, 1, 1]], axis=1)) + 1.0
        return np.all((centres - half >= 0) & (centres + half <= [width - 1, height - 1]), axis=1)

    # -- appearance ----------------------------------------------------------------------------
    def _scene(self):
        """Static layers: membrane/casing background, glare, and the illumination factor (all (H, W) float32)."""
        width, height = self.image_size
        cx, cy, disc = self.disc
        yy, xx = np.mgrid[0:height, 0:width].astype(np.float32)
        r = np.hypot(xx - cx, yy - cy) / disc
        corner = math.hypot(width / 2, height / 2) / disc
        inside = np.clip(0.5 + (1.0 - r) * disc / 1.5, 0.0, 1.0)  # 1.5 px soft edge of the disc
        if self.gradient:
            illumination = 0.85 + 0.15 * r ** 2
            membrane = 22.0 + 30.0 * np.clip(r, 0, 1) ** 3
            casing = 215.0 - 45.0 * ((r - 1.0) / (corner - 1.0)).clip(0, 1) ** 2
        else:
            illumination = np.ones_like(r)
            membrane = np.full_like(r, 25.0)
            casing = np.full_like(r, 200.0)
        background = membrane * inside + casing * (1.0 - inside)
        glare = np.zeros_like(r)
        if self.glare:
            phi = np.arctan2(yy - cy, xx - cx)
            for k in range(6):  # six LEDs on the ring around the base of the pad (paper 002, III-A)
                centre = np.pi / 6 + k * np.pi / 3
                dphi = np.angle(np.exp(1j * (phi - centre)))
                glare += 170.0 * np.exp(-0.5 * ((r - 0.985) * disc / 4.0) ** 2 - 0.5 * (dphi * disc / 12.0) ** 2)
        return background.astype(np.float32), glare.astype(np.float32), illumination.astype(np.float32)

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
        visible = facing & self._inside(centres, shape)
        if hidden is not None:
            hidden = np.asarray(hidden, dtype=bool)
            if hidden.shape != (self._n,):
                raise ValueError(f"hidden must have shape ({self._n},), got {hidden.shape}")
            visible &= ~hidden
        image = self._draw(centres[visible], shape[visible], self._brightness[visible])
        return SyntheticFrame(image=image, centres=centres, visible=visible, timestamp_s=float(timestamp_s),
                              contact=contact)

    def _draw(self, centres, shape, brightness):
        """Composite pins over the static scene, add blur, noise and compression; returns uint8."""
        width, height = self.image_size
        inverse = np.linalg.inv(shape).astype(np.float32)  # (M, 2, 2)
        half = int(np.ceil(np.sqrt(np.linalg.eigvalsh(shape)[:, 1].max(initial=1.0)) + _EDGE_PX + 1))
        offsets = np.arange(-half, half + 1)
        anchor = np.rint(centres).astype(np.int64)  # (M, 2)
        frac = (anchor - centres).astype(np.float32)
        dx = offsets[None, None, :] + frac[:, 0, None, None]  # (M, 1, S)
        dy = offsets[None, :, None] + frac[:, 1, None, None]  # (M, S, 1)
        q = (inverse[:, 0, 0, None, None] * dx * dx + 2 * inverse[:, 0, 1, None, None] * dx * dy
             + inverse[:, 1, 1, None, None] * dy * dy)  # (M, S, S): normalised radius squared
        rho = np.sqrt(q)
        dist = np.sqrt(dx * dx + dy * dy)
        # signed distance to the ellipse edge along the ray from the centre, px
        edge = dist * (1.0 - rho) / np.maximum(rho, 1e-6)
        coverage = np.clip(0.5 + edge / _EDGE_PX, 0.0, 1.0)
        level = 215.0 * brightness * self._illumination[np.clip(anchor[:, 1], 0, height - 1),
                                                        np.clip(anchor[:, 0], 0, width - 1)]
        value = coverage * (level[:, None, None] * (1.0 - 0.15 * np.minimum(q, 1.0)))
        px = anchor[:, 0, None, None] + offsets[None, None, :]
        py = anchor[:, 1, None, None] + offsets[None, :, None]
        ok = (px >= 0) & (px < width) & (py >= 0) & (py < height)
        index = np.broadcast_to(py * width + px, coverage.shape)[ok]
        covered = np.bincount(index, weights=coverage[ok], minlength=width * height)
        lit = np.bincount(index, weights=value[ok], minlength=width * height)
        covered = np.minimum(covered, 1.0).reshape(height, width).astype(np.float32)
        scene = self._background * (1.0 - covered) + lit.reshape(height, width).astype(np.float32) + self._glare
        if self.dark_pins:
            scene = 240.0 - scene
        if self.blur_sigma > 0:
            import cv2

            scene = cv2.GaussianBlur(scene, (0, 0), self.blur_sigma)
        if self.colour:
            scene = scene[:, :, None] * np.array([1.0, 0.97, 0.93], dtype=np.float32)
        if self.noise_sigma > 0:
            scene = scene + self._noise(scene.shape)
        image = np.clip(scene + 0.5, 0, 255).astype(np.uint8)
        if self.jpeg_quality is not None:
            import cv2

            ok_, buffer = cv2.imencode(".jpg", image, [cv2.IMWRITE_JPEG_QUALITY, int(self.jpeg_quality)])
            image = cv2.imdecode(buffer, cv2.IMREAD_UNCHANGED)
        return image

    def _noise(self, shape) -> np.ndarray:
        """Near-Gaussian noise of std ``noise_sigma``: a sum of four uniform random bytes (fast), float32."""
        n = int(np.prod(shape))
        octets = np.frombuffer(self._noise_rng.bytes(4 * n), dtype=np.uint8).reshape(4, n)
        total = octets[0].astype(np.int16)
        total += octets[1]
        total += octets[2]
        total += octets[3]
        # four uniform bytes: mean 510, std sqrt(4 (256^2 - 1) / 12)
        scale = np.float32(self.noise_sigma / math.sqrt(4 * (256 ** 2 - 1) / 12))
        return ((total.astype(np.float32) - np.float32(510.0)) * scale).reshape(shape)

    def tap(self, contact: Contact, *, frame_rate: float = 20.0, rise_s: float = 0.25, plateau_s: float = 0.25,
            release_s: float = 0.25, rest_before_s: float = 0.1,
            rest_after_s: float = 0.1) -> Iterator[SyntheticFrame]:
        """Frames of one tap: rest, rise, plateau, release, rest, at ``frame_rate``.

        The indentation follows ``contact.indentation_mm * tap_profile(t - rest_before_s)``; the gap
        stays as in ``contact``.

        Parameters
        ----------
        contact : Contact
            Contact at the deepest point of the tap.
        frame_rate : float
            Frames per second.
        rise_s, plateau_s, release_s, rest_before_s, rest_after_s : float
            Phase durations, s.

        Yields
        ------
        SyntheticFrame
            Time stamps ``k / frame_rate`` from 0 to the end of the rest after, inclusive.
        """
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
