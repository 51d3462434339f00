"""Pin centres by fitting each tip as an opaque ellipse over a curved local background.

An intensity-weighted centroid assumes the tip adds light to a flat background. A pin tip is paint:
it hides the membrane behind it, and whatever light lies on the membrane (an LED reflection, a bright
surround's veil, a glare gradient, the gel's shading) shows round the tip but not through it. On
such a slope no background subtracted before a centroid is right for the tip and its surround at
once, and small tips (radius 2 px) on the flank of a reflection were placed 0.2-0.7 px off.

Here each tip is modelled in its own window as what the camera sees::

    m(x) = (1 - c(x)) * s(x) + c(x) * (L + D * q(x))

- ``c``: the tip's coverage, an ellipse ``q(x) = (x - mu)^T Q (x - mu) <= 1`` with a soft edge
  (an error function of the distance beyond the boundary along the ray from the centre, `_EDGE_PX`);
- ``s``: the membrane behind it, a quadratic surface (a reflection's or a veil's flank, curved);
- ``L + D q``: the tip's own grey level, slightly domed.

The linear parameters (surface, level, dome) are solved in closed form for each guess of the centre
and ellipse (variable projection), and those five are refined by damped Gauss-Newton with analytic
derivatives, all windows at once as (N, P) arrays. Noise on faint tips would let the ellipse wander,
so a second pass fixes each tip's ellipse to the median of its neighbours' (foreshortening changes
smoothly over the pad, and under a contact) and fits the centre alone.

A fit that fails (moves beyond `_REACH_PX` of its start, an ellipse outside [0.5, 2] times the pin
radius, not finite) keeps the starting centre. A tip whose fit moved it more than `_REFIT_PX` was fitted
in a window centred off it and could go no further than `_REACH_PX`: it is fitted again (centre only)
in a window centred where it ended, up to `_REFIT_ROUNDS` times. On ``radial-led-120`` a blob's
centroid on a reflection's flank starts 1-1.8 px off a tip, a probed tip up to 2 px: one fit left
them 0.5-1.5 px off; refitted, seeds 0-35, the field's RMSE at rest 0.1050 -> 0.1015 px (frames'
worst 0.177 -> 0.148), tapped 0.1098 -> 0.1051 (0.169 -> 0.126), against 0.097 and 0.103 fitted from
the true centres. Other presets' fields are unchanged to 0.1 mpx.

The tracker fits a few lost tips every frame (`pins._recover`'s `fit_tips`): one centre-only step,
`_centre_step`, the first pass of `_gauss_newton` in about half its NumPy calls (on a few windows
each call's fixed cost, not the pixels, sets the time).
"""

from __future__ import annotations

import functools

import numpy as np
from numpy.linalg import _umath_linalg
from scipy.spatial import cKDTree
from scipy.special import erf

from ._kernels import compiled
from ._noise import noise_sigma
from ._window import _squared_norm

__all__ = ["fit_tip_centres", "tip_shapes"]

_EDGE_PX = 0.55  # soft edge of the coverage: erf of (distance beyond the boundary) / this, px
_REACH_PX = 0.8  # a fitted centre farther than this from its start is not trusted, px
_AXIS_RANGE = (0.5, 2.0)  # fitted semi-axes within these factors of the pin radius
_FULL_PASSES = 3  # damped Gauss-Newton passes with the ellipse free ...
_CENTRE_PASSES = 3  # ... then with each ellipse fixed to its neighbours' median
_SHAPE_NEIGHBOURS = 7  # tips (with itself) whose median ellipse a tip takes
_EYE = {2: np.eye(2), 5: np.eye(5)}  # the free parameters' identities, by their number
_RIDGE = 1e-6 * np.eye(8)  # keeps the linear parameters' normal equations regular
_ERF_SLOPE = 1.0 / (np.sqrt(np.pi) * _EDGE_PX)  # d coverage / d beyond at the boundary, px^-1 (times the Gaussian)
_MARGIN_PX = 1.0  # the window reaches this far beyond 1.5 pin radii (the tip's foot and a ring of membrane)
_REFIT_PX = 0.2  # a tip whose fit moved it farther than this is fitted again where it ended, px ...
_REFIT_ROUNDS = 2  # ... at most this many times


def fit_tip_centres(grey: np.ndarray, centres: np.ndarray, radius_px: float, *, dark_pins: bool = False,
                    prior: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Sub-pixel centres of pin tips, each fitted as an opaque ellipse over a quadratic background.

    Parameters
    ----------
    grey : (H, W) ndarray of uint8
        Grey frame.
    centres : (N, 2) ndarray
        Starting centres (x, y), px (blob centroids: within a few tenths of a px).
    radius_px : float
        Pin tip radius, px (half-height radius; the fit finds each tip's own ellipse).
    dark_pins : bool
        Dark markers on a light membrane (the image is inverted).
    prior : ((N, 2) ndarray, (N,) ndarray), optional
        Where the lattice puts each tip and how sure it is (a Gaussian of that many px per axis; inf:
        no prior): the tips found by probing a lattice hole (`pins._rescue.probe_lattice_holes`), faint,
        whose squared residual a pixel off the truth may be within a few noise variances of the truth's.
        Their centres (the ellipse fixed) minimise the squared residual plus the noise variance
        (`pins._noise.noise_sigma`) times ``|centre - prior|^2 / sigma^2``.

    Returns
    -------
    centres : (N, 2) ndarray of float64
        Fitted centres, px; a starting centre is kept where its fit fails. Fewer than two pins, or a
        radius that is not positive: the starting centres.

    Examples
    --------
    >>> import numpy as np
    >>> from tactip.sim import SyntheticTacTip
    >>> sensor = SyntheticTacTip(pins=127, seed=0)
    >>> frame = sensor.render()
    >>> truth = frame.centres[frame.visible]
    >>> fitted = fit_tip_centres(frame.image, truth + 0.3, sensor.pin_radius_px)
    >>> error_px = np.hypot(*(fitted - truth).T)
    >>> bool(np.sqrt(np.mean(error_px ** 2)) < 0.05)
    True
    """
    start = np.asarray(centres, dtype=np.float64).reshape(-1, 2)
    if len(start) < 2 or not (np.isfinite(radius_px) and radius_px > 0):
        return start.copy()
    window, theta = _free_fit(grey, start, radius_px, dark_pins)
    tree = cKDTree(start)
    _, near = tree.query(theta[:, :2], min(_SHAPE_NEIGHBOURS, len(start)))
    fixed = theta.copy()
    fixed[:, :2] = start
    fixed[:, 2:] = np.median(theta[near, 2:], axis=1)
    pull = None
    if prior is not None:
        mean, sigma = (np.asarray(a, dtype=np.float64) for a in prior)
        weight = np.where(np.isfinite(sigma), noise_sigma(grey) ** 2 / np.maximum(sigma, 1e-3) ** 2, 0.0)
        pull = (np.where(weight[:, None] > 0, mean, 0.0), weight) if np.any(weight > 0) else None
    fixed = _gauss_newton(window, fixed, start, radius_px, free=2, passes=_CENTRE_PASSES, prior=pull)
    # A tip whose fit moved it off its start was fitted in a window centred off it (a blob's centroid pulled
    # up a reflection's flank, a probed tip placed a pixel off), and no further than `_REACH_PX`: it is
    # fitted again, its ellipse kept, in a window centred where it ended (every pin's latest place a
    # neighbour whose foot is left out).
    image = window.image
    here = start
    for _ in range(_REFIT_ROUNDS):
        moved = np.flatnonzero(np.hypot(*(fixed[:, :2] - here).T) > _REFIT_PX)
        if not len(moved):
            break
        here = fixed[:, :2].copy()
        again = _windows(image, here, radius_px, moved)
        part = None if pull is None else (pull[0][moved], pull[1][moved])
        fixed[moved] = _gauss_newton(again, fixed[moved], here[moved], radius_px, free=2, passes=_CENTRE_PASSES,
                                     prior=part)
    return fixed[:, :2].copy()


def tip_shapes(grey: np.ndarray, centres: np.ndarray, radius_px: float, *, dark_pins: bool = False,
               which: np.ndarray | None = None) -> np.ndarray:
    """Tips' ellipses as the first pass of `fit_tip_centres` fits them (the ellipse free): a tip covers
    ``{e : e^T shape^-1 e <= 1}``, (M, 2, 2) px^2, for the pins `which` (indices into `centres`; all
    when None), their windows clear of every other pin's foot; ``radius_px^2 I`` where a fit fails,
    for fewer than two pins or no radius. Noisy for a faint tip: take a median over neighbours."""
    start = np.asarray(centres, dtype=np.float64).reshape(-1, 2)
    which = np.arange(len(start)) if which is None else np.asarray(which, dtype=np.intp)
    circle = np.repeat((radius_px ** 2 * np.eye(2))[None], len(which), axis=0)
    if len(start) < 2 or not len(which) or not (np.isfinite(radius_px) and radius_px > 0):
        return circle
    _, theta = _free_fit(grey, start, radius_px, dark_pins, which)
    q = np.stack([theta[:, 2:4], theta[:, 3:5]], axis=1)
    good = np.isfinite(q).all(axis=(1, 2)) & (np.linalg.det(q) > 0)
    circle[good] = np.linalg.inv(q[good])
    return circle


def _free_fit(grey: np.ndarray, start: np.ndarray, radius_px: float, dark_pins: bool, which: np.ndarray | None = None):
    """The windows of the tips `which` (all when None) and their fit with the ellipse free:
    (`_Windows`, theta (M, 5)); every pin of `start` is a neighbour whose foot is left out."""
    image = grey.astype(np.float64)
    if dark_pins:
        image = 255.0 - image
    which = np.arange(len(start)) if which is None else which
    window = _windows(image, start, radius_px, which)
    own = start[which]
    theta = np.zeros((len(own), 5))
    theta[:, :2] = own
    theta[:, 2] = theta[:, 4] = 1.0 / radius_px ** 2
    return window, _gauss_newton(window, theta, own, radius_px, free=5, passes=_FULL_PASSES)


def _windows(image: np.ndarray, start: np.ndarray, radius_px: float, which: np.ndarray) -> "_Windows":
    """The windows of the tips `which` of `start` (N, 2) px in `image` (float64, bright tips): each reaches
    1.5 pin radii and `_MARGIN_PX` beyond the tip's foot, no nearer its nearest neighbour than half a radius;
    every other pin of `start` is a neighbour whose foot is left out."""
    distance, index = cKDTree(start).query(start[which], min(8, len(start)))
    nearest = distance[:, 1]
    reach = np.minimum(1.5 * radius_px + 1.0 + _MARGIN_PX, nearest - 0.5 * radius_px)
    return _Windows(image, start[which], reach, start[index[:, 1:]], nearest)


class _Windows:
    """The pixels round each tip: grey levels (N, P), coordinates (N, P) and which may count.

    Gathered when first asked for: `_centre_step`'s compiled kernel (`pins._kernels`) reads the
    image itself, from the arguments kept as they were given.
    """

    _GATHERED = frozenset(("xy", "x", "y", "values", "usable"))

    def __init__(self, image, start, reach, neighbours, nearest):
        self.image, self.start, self.neighbours, self.nearest = image, start, neighbours, nearest
        self.reach = reach
        self.half = int(np.ceil(reach.max())) + 1

    def __getattr__(self, name):
        # (Only called for an attribute not yet set: the gathered arrays, on first use.)
        if name not in _Windows._GATHERED:
            raise AttributeError(name)
        self._gather()
        return self.__dict__[name]

    def _gather(self) -> None:
        """The windows' coordinates, grey levels and usable pixels, as attributes."""
        image, start, neighbours, nearest, half = self.image, self.start, self.neighbours, self.nearest, self.half
        height, width = image.shape
        offsets, flat = _disc_grid(half, width)
        # Whole pixels: the float anchor plus the offsets are the integer coordinates, exactly.
        anchor = np.rint(start)
        self.xy = anchor[:, :, None] + offsets  # (N, 2, P), px
        self.x, self.y = self.xy[:, 0], self.xy[:, 1]
        # Every window's square inside the image (most calls): its pixels are a flat gather.
        low, high = anchor.min(axis=0), anchor.max(axis=0)
        if low[0] >= half and low[1] >= half and high[0] <= width - 1 - half and high[1] <= height - 1 - half:
            corner = anchor.astype(np.intp)
            values = image.reshape(-1)[corner[:, 1, None] * width + corner[:, 0, None] + flat]
            inside = None
        else:
            gx, gy = _disc_offsets(half)
            ix, iy = corner_x, corner_y = anchor.astype(np.intp).T
            ix, iy = corner_x[:, None] + gx, corner_y[:, None] + gy  # (N, P) int
            # (A negative index, read as unsigned, lies beyond the bound: one comparison a side.)
            inside = (ix.view(np.uintp) <= width - 1) & (iy.view(np.uintp) <= height - 1)
            values = image[np.clip(iy, 0, height - 1), np.clip(ix, 0, width - 1)]
        self.values = values.astype(np.float64)
        # A pixel counts when it lies in the image and nearer to its own tip than half the distance
        # to the nearest neighbour from every neighbour (no neighbour's foot), within the reach.
        apart = self.xy[:, None] - neighbours[:, :, :, None]  # (N, k, 2, P), px
        apart *= apart
        own = np.add(apart[:, :, 0], apart[:, :, 1])  # (N, k, P), px^2
        usable = np.minimum.reduce(own, axis=1) > np.square(0.5 * nearest)[:, None]
        self.usable = usable if inside is None else inside & usable


@functools.lru_cache(maxsize=8)
def _disc_offsets(half: int) -> tuple[np.ndarray, np.ndarray]:
    """Offsets (x, y), px, of the pixels of a square of half side `half` px no farther than `half` from its
    centre (no pixel beyond the reach counts: the square's corners are left out), row by row: (P,) int each."""
    offsets = np.arange(-half, half + 1)
    gy, gx = (a.ravel() for a in np.meshgrid(offsets, offsets, indexing="ij"))
    disc = np.hypot(gx, gy) <= half
    gx, gy = gx[disc], gy[disc]
    gx.flags.writeable = gy.flags.writeable = False
    return gx, gy


@functools.lru_cache(maxsize=16)
def _disc_grid(half: int, width: int) -> tuple[np.ndarray, np.ndarray]:
    """`_disc_offsets(half)` as (2, P) float64 offsets (x, y), px, and as (P,) offsets into a flattened
    image `width` px wide (``y * width + x``). Cached: the same few a frame, frame after frame."""
    gx, gy = _disc_offsets(half)
    offsets = np.stack([gx, gy]).astype(np.float64)
    flat = gy * width + gx
    offsets.flags.writeable = flat.flags.writeable = False
    return offsets, flat


def _gauss_newton(window: _Windows, theta: np.ndarray, start: np.ndarray, radius_px: float, *, free: int,
                  passes: int, prior: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Refine the first `free` of (mu_x, mu_y, Q_xx, Q_xy, Q_yy) by damped Gauss-Newton (N, 5).

    `prior` (with ``free=2``): centres (N, 2) px and weights (N,) grey^2 / px^2 (0: none): each centre's
    objective adds its weight times its squared distance from its prior centre."""
    damping = np.full(len(theta), 1e-3)
    lowest, highest = (1.0 / (_AXIS_RANGE[1] * radius_px) ** 2, 1.0 / (_AXIS_RANGE[0] * radius_px) ** 2)
    eye = _EYE[free]
    n, pixels = window.x.shape
    basis = np.empty((n, 8, pixels))
    weighted, surface_rows = np.empty_like(basis), np.empty((n, 6, pixels))
    jacobian = np.empty((n, free, pixels))
    if free == 2:
        # The ellipses stay as they are: whether each is acceptable is known before the passes.
        ellipse_bad = ~_ellipse_ok(theta, lowest, highest)
    for _ in range(passes):
        ex, ey = window.x - theta[:, 0, None], window.y - theta[:, 1, None]
        length = np.hypot(ex, ey)
        weight = (window.usable & (length <= window.reach[:, None])).astype(np.float64)
        qx = theta[:, 2, None] * ex + theta[:, 3, None] * ey  # (Q e)_x
        qy = theta[:, 3, None] * ex + theta[:, 4, None] * ey
        q = np.maximum(ex * qx + ey * qy, 1e-12)
        root = np.sqrt(q)
        beyond = length * (1.0 - root) / root  # distance inside the boundary along the ray, px
        coverage = 0.5 + 0.5 * erf(beyond / _EDGE_PX)
        dome = np.minimum(q, 1.0)
        # Linear parameters: quadratic background behind the tip, the tip's level and dome: the basis
        # (N, 8, P), filled in place (one allocation for all passes).
        rows = basis[:, :6]
        rows[:, 0] = 1.0
        rows[:, 1], rows[:, 2] = ex, ey
        np.multiply(ex, ex, out=rows[:, 3])
        np.multiply(ex, ey, out=rows[:, 4])
        np.multiply(ey, ey, out=rows[:, 5])
        surface_rows[...] = rows
        rows *= (1.0 - coverage)[:, None, :]
        basis[:, 6] = coverage
        np.multiply(coverage, dome, out=basis[:, 7])
        np.multiply(basis, weight[:, None, :], out=weighted)
        normal = weighted @ basis.transpose(0, 2, 1) + _RIDGE
        beta = np.linalg.solve(normal, weighted @ window.values[..., None])[..., 0]
        model = np.einsum("nkp,nk->np", basis, beta)
        residual = window.values - model
        surface = np.einsum("nkp,nk->np", surface_rows, beta[:, :6])
        tip = beta[:, 6, None] + beta[:, 7, None] * dome
        # d m / d beyond, and d beyond / d theta (q's own derivatives: dq/dmu = -2 Q e, dq/dQ = e e^T).
        slope = (tip - surface) * np.exp(-(beyond / _EDGE_PX) ** 2) / (np.sqrt(np.pi) * _EDGE_PX)
        per_q = -length / (2.0 * q * root)
        safe = np.maximum(length, 1e-9)
        factor = 1.0 / root - 1.0
        under = beta[:, 7, None] * coverage * (q < 1.0)  # the dome's own change
        by_q = slope * per_q + under  # d m / d q
        np.subtract(slope * (-ex / safe * factor), 2.0 * qx * by_q, out=jacobian[:, 0])
        np.subtract(slope * (-ey / safe * factor), 2.0 * qy * by_q, out=jacobian[:, 1])
        if free == 5:
            for row, dq in enumerate((ex * ex, 2.0 * ex * ey, ey * ey), start=2):
                np.multiply(by_q, dq, out=jacobian[:, row])
        jw = jacobian * weight[:, None, :]
        hessian = jw @ jacobian.transpose(0, 2, 1)
        gradient = (jw @ residual[..., None])[..., 0]
        if prior is not None:
            hessian = hessian + prior[1][:, None, None] * eye
            gradient = gradient + prior[1][:, None] * (prior[0] - theta[:, :2])
        hessian = hessian + damping[:, None, None] * np.diagonal(hessian, axis1=1, axis2=2)[:, :, None] * eye
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            step = np.linalg.solve(hessian + 1e-9 * eye, gradient[..., None])[..., 0]
        step[:, :2] = np.clip(step[:, :2], -0.5, 0.5)
        new = theta.copy()
        new[:, :free] += step
        if free == 2:
            bad = ellipse_bad | ~np.isfinite(new[:, :2]).all(axis=1)
        else:
            bad = ~_ellipse_ok(new, lowest, highest)
        bad |= np.hypot(*(new[:, :2] - start).T) > _REACH_PX
        theta[~bad] = new[~bad]
        damping = np.where(bad, damping * 10.0, damping / 3.0)
    return theta


def _centre_step(window: _Windows, theta: np.ndarray, start: np.ndarray) -> np.ndarray:
    """One damped Gauss-Newton step of the tips' centres alone, their ellipses fixed: the first pass of
    `_gauss_newton(..., free=2)`, the same model and step in about half its NumPy calls (the (x, y)
    rows as one array, the 2 x 2 step in closed form), for `pins._recover`'s fits every frame.

    `theta` (N, 5) as there, its ellipses acceptable (`_ellipse_ok`; the caller checks them once);
    returns the centres (N, 2), px: each moved by its step where that stays finite and within
    `_REACH_PX` of `start`, else as in `theta`. By the compiled kernel (`pins._jit.centre_step`, one
    call) unless ``TACTIP_KERNELS=numpy`` or Numba is missing (`pins._kernels`); else in NumPy.
    """
    kernels = compiled()
    # (The kernel gathers its own pixels; a window already gathered, by a caller that read its pixels,
    # takes the NumPy step on them.)
    if kernels is not None and "values" not in window.__dict__:
        gx, gy = _disc_offsets(window.half)
        image = np.ascontiguousarray(window.image)
        return kernels.centre_step(image, np.ascontiguousarray(start, dtype=np.float64),
                                   np.ascontiguousarray(window.reach, dtype=np.float64),
                                   np.ascontiguousarray(window.neighbours, dtype=np.float64),
                                   np.ascontiguousarray(window.nearest, dtype=np.float64),
                                   np.ascontiguousarray(theta, dtype=np.float64), gx, gy)
    return _centre_step_numpy(window, theta, start)


def _centre_step_numpy(window: _Windows, theta: np.ndarray, start: np.ndarray) -> np.ndarray:
    """`_centre_step` in NumPy: the reference of the compiled kernel."""
    n, pixels = window.x.shape
    e = window.xy - theta[:, :2, None]  # (N, 2, P): each pixel from the centre, px
    ex, ey = e[:, 0], e[:, 1]
    # (Both rows of each product at once: the same products and sums, in fewer NumPy calls.)
    square = e * e
    length = np.sqrt(np.add(square[:, 0], square[:, 1]))
    weight = (window.usable & (length <= window.reach[:, None])).astype(np.float64)
    # Q e: the columns (Q_xx, Q_xy) and (Q_xy, Q_yy) of Q, (N, 2, 1) each.
    qe = theta[:, 2:4, None] * ex[:, None] + theta[:, 3:5, None] * ey[:, None]
    product = e * qe
    q = np.maximum(np.add(product[:, 0], product[:, 1]), 1e-12)
    root = np.sqrt(q)
    beyond = length * (1.0 - root) / root  # distance inside the boundary along the ray, px
    edge = beyond / _EDGE_PX
    coverage = 0.5 + 0.5 * erf(edge)
    dome = np.minimum(q, 1.0)
    # The linear parameters (quadratic background behind the tip, the tip's level and dome) in closed
    # form; the grey levels ride along as a ninth row, so one product gives the normal equations.
    surface_rows = np.empty((n, 6, pixels))
    surface_rows[:, 0] = 1.0
    surface_rows[:, 1:3] = e
    surface_rows[:, 3::2] = square  # x^2 and y^2
    np.multiply(ex, ey, out=surface_rows[:, 4])
    basis = np.empty((n, 9, pixels))
    np.multiply(surface_rows, (1.0 - coverage)[:, None, :], out=basis[:, :6])
    basis[:, 6] = coverage
    np.multiply(coverage, dome, out=basis[:, 7])
    basis[:, 8] = window.values
    weighted = basis[:, :8] * weight[:, None, :]
    products = weighted @ basis.transpose(0, 2, 1)  # (N, 8, 9)
    beta = _solve(products[:, :, :8] + _RIDGE, products[:, :, 8:])
    surface = (beta[:, None, :6, 0] @ surface_rows)[:, 0]
    rise = beta[:, 6] + beta[:, 7] * dome - surface  # the tip above the membrane behind it
    # d m / d beyond, and d beyond / d mu (dq/dmu = -2 Q e); the dome's own change.
    slope = rise * np.exp(-(edge * edge)) * _ERF_SLOPE
    by_q = slope * (length / (-2.0 * q * root)) + beta[:, 7] * coverage * (q < 1.0)
    inward = slope * (1.0 - 1.0 / root) / np.maximum(length, 1e-9)  # (the radial term, negated: exact)
    jacobian = np.empty((n, 3, pixels))  # d m / d mu (x, y), then the residual r
    np.subtract(e * inward[:, None, :], 2.0 * qe * by_q[:, None, :], out=jacobian[:, :2])
    np.subtract(window.values, surface + coverage * rise, out=jacobian[:, 2])
    jw = jacobian[:, :2] * weight[:, None, :]
    (a, b, g0), (c, d, g1) = (jw @ jacobian.transpose(0, 2, 1)).transpose(1, 2, 0)  # J^T J and J^T r
    # Damped as `_gauss_newton`'s first pass; the determinant is positive (a Gram matrix, damped).
    a, d = a * (1.0 + 1e-3) + 1e-9, d * (1.0 + 1e-3) + 1e-9
    det = a * d - b * c
    step = np.empty((n, 2))
    np.divide(d * g0 - b * g1, det, out=step[:, 0])
    np.divide(a * g1 - c * g0, det, out=step[:, 1])
    new = theta[:, :2] + np.minimum(np.maximum(step, -0.5), 0.5)
    good = _squared_norm(new - start) <= _REACH_PX ** 2  # (NaN compares False)
    return np.where(good[:, None], new, theta[:, :2])


def _solve(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.linalg.solve(a, b)`` of float64 stacks (..., M, M) and (..., M, K), bit for bit (the same LAPACK
    gufunc), without its checks and conversions: a third of its cost on a few small systems. Raises
    `numpy.linalg.LinAlgError` on a singular matrix, as it does."""
    with np.errstate(call=_singular, invalid="call", over="ignore", divide="ignore", under="ignore"):
        return _umath_linalg.solve(a, b, signature="dd->d")


def _singular(error: str, flag: int) -> None:
    raise np.linalg.LinAlgError("Singular matrix")


def _fittable(ellipses: np.ndarray, radius_px: float) -> np.ndarray:
    """Whether tips of ellipses (Q_xx, Q_xy, Q_yy) (N, 3), px^-2, can be fitted with their ellipses fixed
    (`_centre_step`): finite, with semi-axes within `_AXIS_RANGE` of `radius_px` (no fit of another moves);
    none without a radius (a blank frame's). (N,) bool."""
    if not (np.isfinite(radius_px) and radius_px > 0):
        return np.zeros(len(ellipses), dtype=bool)
    lowest, highest = (1.0 / (_AXIS_RANGE[1] * radius_px) ** 2, 1.0 / (_AXIS_RANGE[0] * radius_px) ** 2)
    return _ellipse_ok(np.concatenate([np.zeros((len(ellipses), 2)), ellipses], axis=1), lowest, highest)


def _ellipse_ok(theta: np.ndarray, lowest: float, highest: float) -> np.ndarray:
    """Whether each row of (mu_x, mu_y, Q_xx, Q_xy, Q_yy) (N, 5) is finite with Q's eigenvalues in
    [lowest, highest], px^-2 (semi-axes within `_AXIS_RANGE` of the pin radius): (N,) bool."""
    trace = theta[:, 2] + theta[:, 4]
    det = theta[:, 2] * theta[:, 4] - theta[:, 3] ** 2
    spread = np.sqrt(np.maximum(trace * trace / 4.0 - det, 0.0))
    return (np.isfinite(theta).all(axis=1) & (det > 0) & (trace / 2.0 - spread >= lowest)
            & (trace / 2.0 + spread <= highest))
