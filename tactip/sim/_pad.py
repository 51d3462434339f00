"""Pad geometry and contact mechanics of the synthetic TacTip (the model is argued in `tactip.sim.synthetic`).

Pad coordinates are mm: the hemispherical pad of radius R is centred on the origin with its apex at
``z = R``; the camera sits on the axis at ``z = -h`` looking up (+z), image x along X, image y along Y.
"""

from __future__ import annotations

import numpy as np

STALK_MM = 1.5  # pin stalk length L, mm
CAMERA_DISTANCE = 2.0  # h / R: camera below the pad's base plane
PIN_POLAR_MAX_DEG = 80.0  # polar angle of the outermost pins
CASING_POLAR_DEG = 86.0  # the casing hides the membrane beyond this polar angle: edge of the dark disc
RADIAL_FLOW = 0.5  # u_r = RADIAL_FLOW * u_z * r / R
MEMBRANE_RHO_MM = 1.0  # tension / contact pressure of the skin spanning a gap, mm
BENDING_MM = 0.5  # bending length of the skin, mm
STALK_BASE_MM = 1.5  # half-width over which the membrane slope under a stalk is averaged, mm
CLAMP_POWER = 6  # displacement x (1 - (r / R)^CLAMP_POWER): zero at the clamped base of the pad


def hexagonal_number(rings: int) -> int:
    """Number of pins in ``rings`` hexagonal rings around a centre pin: 1 + 3 K (K + 1)."""
    return 1 + 3 * rings * (rings + 1)


def pin_lattice(n_pins: int) -> np.ndarray:
    """Pin positions on the unrolled pad in ring units, (N, 2); the centre pin first.

    A hexagonal number of pins (127, 331, ...) fills K hexagonal rings (ring k walks the six sides of a
    hexagon of corner radius k, k pins per side). Any other count uses K concentric circles, K the
    smallest ring count whose hexagonal number reaches N: circle k gets a share of the N - 1 outer
    pins proportional to k (largest-remainder rounding), odd circles rotated by half a step.
    """
    rings = 0
    while hexagonal_number(rings) < n_pins:
        rings += 1
    k = np.arange(1, rings + 1)
    if hexagonal_number(rings) == n_pins:
        ring = np.repeat(k, 6 * k)
        step = np.concatenate([np.arange(6 * kk) for kk in k])
        side, along = np.divmod(step, ring)
        corner = np.exp(1j * np.pi / 3 * side)
        following = np.exp(1j * np.pi / 3 * (side + 1))
        z = ring * (corner + (following - corner) * along / ring)
    else:
        quota = (n_pins - 1) * k / k.sum()
        counts = np.floor(quota).astype(int)
        counts[np.argsort(counts - quota, kind="stable")[: n_pins - 1 - counts.sum()]] += 1
        ring = np.repeat(k, counts)
        index = np.concatenate([np.arange(c) for c in counts])
        count = np.repeat(counts, counts)
        z = ring * np.exp(1j * np.pi * (2 * index + ring % 2) / count)
    z = np.concatenate([[0j], z])
    return np.column_stack([z.real, z.imag])


RADIAL_SPOKE_RATIO = 2.4  # radial layout: spokes / rings aimed at (17 spokes on 7 rings for 120 pins)


def radial_rings(n_pins: int) -> tuple[int, int, bool]:
    """Rings, spokes and centre pin of a radial layout of ``n_pins``: ``n_pins = rings * spokes (+ 1)``.

    Of the factorisations with 3-20 rings and at least 6 spokes (with or without a centre pin), the one
    whose spokes / rings is nearest `RADIAL_SPOKE_RATIO` (on a log scale); a centre pin breaks ties.

    Raises
    ------
    ValueError
        When ``n_pins`` has no such factorisation.
    """
    best = None
    for centre in (1, 0):
        for rings in range(3, 21):
            spokes, rest = divmod(n_pins - centre, rings)
            if rest == 0 and spokes >= 6:
                score = abs(np.log(spokes / rings / RADIAL_SPOKE_RATIO))
                if best is None or score < best[0] - 1e-12:
                    best = (score, rings, spokes, bool(centre))
    if best is None:
        raise ValueError(f"pins must be rings x spokes (+ 1 centre pin) with 3-20 rings and >= 6 spokes "
                         f"for the radial layout, got {n_pins}")
    return best[1:]


def radial_lattice(n_pins: int) -> np.ndarray:
    """Pin positions of a radial layout on the unrolled pad in ring units, (N, 2); the centre pin first.

    Pins sit where equally spaced rings (one ring unit apart) cross straight spokes: every ring holds
    the same number of pins, so the spacing along a ring grows with its radius, as on home-built TacTips
    whose pins are placed with a rotary jig. The innermost ring is at ``max(1, spokes / 2 pi)`` ring
    units, so neighbours along it are at least one unit apart; a centre pin, if any, sits alone inside.
    """
    rings, spokes, centre = radial_rings(n_pins)
    inner = max(1.0, spokes / (2 * np.pi))
    radius = np.repeat(inner + np.arange(rings), spokes)
    azimuth = np.tile(2 * np.pi * np.arange(spokes) / spokes, rings)
    z = radius * np.exp(1j * azimuth)
    if centre:
        z = np.concatenate([[0j], z])
    return np.column_stack([z.real, z.imag])


def membrane_points(x, y, contact, radius_mm: float):
    """Positions of membrane material points (skin texture) under the plate, mm, (N, 3)."""
    u_n, u_r = membrane_displacement(x, y, contact, radius_mm)
    z0 = np.sqrt(np.clip(radius_mm ** 2 - x * x - y * y, 1e-9, None))
    r = np.hypot(x, y)
    outward = np.divide(u_r, r, out=np.zeros_like(r), where=r > 0)
    return np.stack([x * (1 + outward), y * (1 + outward), z0 - u_n], axis=-1)


def membrane_displacement(x, y, contact, radius_mm: float):
    """Displacement of membrane points at lateral position (x, y), mm, under the plate.

    Parameters
    ----------
    x, y : ndarray
        Lateral positions of membrane points at rest, mm (any shape).
    contact : Contact
        Plate state (indentation, gap width, offset and angle).
    radius_mm : float
        Pad radius R, mm.

    Returns
    -------
    u_n, u_r : ndarray, shaped like ``x``
        Displacement towards the camera (along -z) and radially outward from the axis, mm.
    """
    d = contact.indentation_mm
    if d <= 0:
        zero = np.zeros(np.shape(x))
        return zero, zero
    r2 = x * x + y * y
    ratio2 = r2 / (radius_mm * d)  # (r / a)^2 with the Hertz contact radius a^2 = R d
    safe = np.maximum(ratio2, 1.0)
    # Hertz: u_z = d - r^2 / 2R inside; (d / pi) [(2 - r^2/a^2) asin(a/r) + sqrt(r^2/a^2 - 1)] outside
    outside = d / np.pi * ((2.0 - safe) * np.arcsin(1.0 / np.sqrt(safe)) + np.sqrt(safe - 1.0))
    u_z = np.where(ratio2 <= 1.0, d - r2 / (2.0 * radius_mm), outside)
    u_r = RADIAL_FLOW * u_z * np.sqrt(r2) / radius_mm
    w = contact.gap_width_mm
    if w > 0:
        angle = np.deg2rad(contact.gap_angle_deg)
        t = -x * np.sin(angle) + y * np.cos(angle) - contact.gap_offset_mm  # distance from the gap line
        # skin over a slot: sag w^2 / (8 rho), spread over the gap and the bending length, scaled by pressure
        spread = w / 4.0 + BENDING_MM
        pressure = np.clip(1.0 - ratio2, 0.0, None) ** 1.5
        sag = w * w / (8.0 * MEMBRANE_RHO_MM) * np.exp(-0.5 * (t / spread) ** 2) * pressure
        sag = u_z * -np.expm1(-sag / np.maximum(u_z, 1e-12))  # soft cap: sag <= u_z (no rise above rest)
        u_z = u_z - sag
    # the pad is clamped to the casing at its base: fade the half-space field to zero at the rim
    clamp = 1.0 - np.minimum(r2 / radius_mm ** 2, 1.0) ** (CLAMP_POWER / 2)
    return u_z * clamp, u_r * clamp


def deformed_surface(x, y, contact, radius_mm: float):
    """Deformed membrane at material points (x, y): positions and inward unit normals.

    The normal comes from the slope of the deformed surface ``z = z0 - u_n``, by central differences
    over +-`STALK_BASE_MM` (the stalk base and skin average the slope over about a pin's width).

    Parameters
    ----------
    x, y : (N,) ndarray
        Lateral positions of the points at rest, mm (on the sphere of radius ``radius_mm``).
    contact : Contact
    radius_mm : float

    Returns
    -------
    base : (N, 3) ndarray, mm
    normal : (N, 3) ndarray, unit, pointing inward (towards the camera side)
    """
    u_n, u_r = membrane_displacement(x, y, contact, radius_mm)
    z0 = np.sqrt(np.clip(radius_mm ** 2 - x * x - y * y, 1e-9, None))
    gx = gy = 0.0
    if contact.indentation_mm > 0:
        eps = STALK_BASE_MM
        gx = (membrane_displacement(x + eps, y, contact, radius_mm)[0]
              - membrane_displacement(x - eps, y, contact, radius_mm)[0]) / (2 * eps)
        gy = (membrane_displacement(x, y + eps, contact, radius_mm)[0]
              - membrane_displacement(x, y - eps, contact, radius_mm)[0]) / (2 * eps)
    # surface z = z0 - u_n; its inward normal is along (dz/dx, dz/dy, -1), dz0/dx = -x / z0
    normal = np.stack([-x / z0 - gx, -y / z0 - gy, -np.ones_like(x)], axis=-1)
    normal /= np.linalg.norm(normal, axis=-1, keepdims=True)
    r = np.hypot(x, y)
    outward = np.divide(u_r, r, out=np.zeros_like(r), where=r > 0)
    base = np.stack([x * (1 + outward), y * (1 + outward), z0 - u_n], axis=-1)
    return base, normal


def project_discs(centre_mm, normal, *, focal_px: float, principal_px, camera_mm: float, disc_radius_mm: float):
    """Pinhole images of flat discs (the pin tips): centres, ellipse shapes and whether they face the camera.

    A small disc of radius rho with unit normal n at point P images to the ellipse
    ``{c + e : e^T S^-1 e <= 1}`` with ``S = rho^2 J (I - n n^T) J^T``, J the Jacobian of the projection
    at P: the exact affine image of the circle, centred on the projection of P.

    Parameters
    ----------
    centre_mm : (N, 3) ndarray
        Disc centres in pad coordinates, mm.
    normal : (N, 3) ndarray
        Unit normals.
    focal_px : float
    principal_px : (float, float)
        Principal point (x, y), px.
    camera_mm : float
        Camera distance h below the base plane, mm.
    disc_radius_mm : float

    Returns
    -------
    centres : (N, 2) ndarray, px
    shape : (N, 2, 2) ndarray, px^2 (semi-axes are the square roots of its eigenvalues)
    facing : (N,) bool ndarray
        The disc faces the camera (angle between normal and line of sight below 78 degrees).
    """
    depth = centre_mm[:, 2] + camera_mm
    centres = np.asarray(principal_px) + focal_px * centre_mm[:, :2] / depth[:, None]
    jac = np.zeros((len(depth), 2, 3))
    jac[:, 0, 0] = jac[:, 1, 1] = focal_px / depth
    jac[:, :, 2] = -focal_px * centre_mm[:, :2] / depth[:, None] ** 2
    plane = np.eye(3) - normal[:, :, None] * normal[:, None, :]
    shape = disc_radius_mm ** 2 * jac @ plane @ jac.transpose(0, 2, 1)
    to_camera = -centre_mm - np.array([0.0, 0.0, camera_mm])
    facing = np.einsum("ij,ij->i", normal, to_camera) > 0.2 * np.linalg.norm(to_camera, axis=1)
    return centres, shape, facing
