"""Geometry of the two capacitive taxel sensors of paper 000 and their spatial receptive fields.

Both sensors are iCub tactile sensors (paper 000, Sec. III-A; Schmitz et al. [5]): a flexible PCB of
round taxel plates under 2 mm of silicone foam and a conductive outer layer. A contact compresses the
foam over the plates it reaches, so each taxel sees the contact through a broad receptive field that
peaks over the plate and falls off smoothly around it (paper 000, Figs 9 and 12: "Gaussian-shaped,
about 8 mm across" on the fingertip, "about 16 mm across" on the skin, centres about 4 mm apart).

Coordinates are on the unrolled sensing surface, in mm: ``u`` along the direction the sensor sweeps
across the object (the location axis of the dataset), ``v`` across it. A location ``x`` of the
experiment (0 at the start of the sweep) puts the contact at ``u = x + sweep_offset_mm``.

Fingertip (12 taxels, 14.5 mm long, 13 mm wide) tapping an 8 mm steel rod
    The rod lies across the fingertip (along ``v``), so the contact is a line at ``u``; the fingertip
    is rounded across its width, so the line only presses over ``|v| <= contact_half_width_mm``
    (about sqrt(2 R d) for a 6.5 mm radius and ~1 mm indentation). The taxels are not on a line: we
    approximate the PCB of Fig. 2a by four rows of three plates across the width, rows 4 mm apart
    (the tip row 3 mm, as the PCB wraps over the rounded tip), the middle plate of each row 1 mm
    nearer the tip than its two flank plates (a staggered, hexagon-like packing). The paper gives no
    drawing with dimensions; this layout is our assumption and is documented as such in the sensor
    description written to datasets. The foam is only compressed while the rod is under the
    fingertip: it meets the rigid base behind ``u = -2.5`` mm and slips off the rounded tip past
    ``u = 16.5`` mm, so the first and last few mm of the 30 mm sweep give little or no response
    ("contacts either at the fingertip's non-sensitive base or missing the object entirely").
Skin (48 taxels) tapped by an 8 mm stone sphere
    Four equilateral triangles (30 mm sides) of 12 taxels each in a flat strip, alternately pointing
    up and down (75 mm long, 26 mm wide). In each triangle the plates sit on a triangular lattice of
    five rows 5 mm apart with the three corners left out (12 plates). The sphere makes a point
    contact on a straight path 1 mm off the strip's centre line and sweeps its middle 50 mm.

A taxel's response to a contact at distance ``d`` (mm) from its plate centre is
``exp(-d**2 / (2 sigma**2))`` with ``sigma = receptive_field_mm / 4``: we read "about 8 mm across" as the
width over which the response stays above ``exp(-2)``, i.e. 14 % of its peak. For the rod, ``d`` is
the distance from the plate centre to the pressed part of the contact line.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.special import expit

__all__ = ["TaxelSensor", "TAXEL_SENSORS", "taxel_sensor", "receptive_field_response"]


@dataclass(frozen=True)
class TaxelSensor:
    """Geometry and contact constants of one capacitive taxel sensor (see the module docstring).

    Attributes
    ----------
    name : str
        Preset name, ``"fingertip"`` or ``"skin"``.
    taxel_positions_mm : (K, 2) ndarray
        Plate centres ``(u, v)`` on the unrolled sensing surface, mm.
    receptive_field_mm : float
        Width of a taxel's receptive field where its response falls to ``exp(-2)`` (4 sigma), mm.
    location_range_mm : tuple of float
        The experiment's location range ``(start, stop)``, mm (paper 000: 30 mm fingertip, 50 mm skin).
    sweep_offset_mm : float
        ``u`` of the contact at location 0, mm.
    path_v_mm : float
        ``v`` of the contact path (point contacts), mm.
    contact : str
        ``"line"`` (rod across the sensor) or ``"point"`` (sphere).
    contact_half_width_mm : float
        Half length of the pressed part of a line contact along ``v``, mm.
    pressed_span_mm : tuple of float
        ``(u_start, u_stop)`` over which the object compresses the foam, mm; infinite for the flat skin.
    span_edge_mm : float
        Width of the smooth (logistic) on/off edges of that span, mm.
    peak_counts : float
        Reading change of a taxel with a contact centred on its plate, 8-bit counts.
    rest_counts : float
        Mean reading without contact (the iCub skin reads about 235 at rest and lower under pressure).
    sample_rate_hz : float
        Readings per second (50 Hz).
    dim_names : tuple of str
        One name per taxel for datasets (default ``"taxel00"``, ``"taxel01"``, ...).
    """

    name: str
    taxel_positions_mm: np.ndarray
    receptive_field_mm: float
    location_range_mm: tuple[float, float]
    sweep_offset_mm: float
    path_v_mm: float = 0.0
    contact: str = "line"
    contact_half_width_mm: float = 0.0
    pressed_span_mm: tuple[float, float] = (-np.inf, np.inf)
    span_edge_mm: float = 1.0
    peak_counts: float = 100.0
    rest_counts: float = 235.0
    sample_rate_hz: float = 50.0
    dim_names: tuple[str, ...] = field(default=())

    def __post_init__(self):
        positions = np.asarray(self.taxel_positions_mm, dtype=np.float64)
        if positions.ndim != 2 or positions.shape[1] != 2 or len(positions) == 0:
            raise ValueError(f"taxel_positions_mm must have shape (K, 2), got {positions.shape}")
        if self.contact not in ("line", "point"):
            raise ValueError(f"contact must be 'line' or 'point', got {self.contact!r}")
        if not self.receptive_field_mm > 0:
            raise ValueError(f"receptive_field_mm must be > 0, got {self.receptive_field_mm}")
        positions.setflags(write=False)
        object.__setattr__(self, "taxel_positions_mm", positions)
        if not self.dim_names:
            object.__setattr__(self, "dim_names", tuple(f"taxel{k:02d}" for k in range(len(positions))))

    @property
    def n_taxels(self) -> int:
        """Number of taxels ``K``."""
        return len(self.taxel_positions_mm)

    @property
    def range_mm(self) -> float:
        """Length of the location range, mm."""
        return float(self.location_range_mm[1] - self.location_range_mm[0])

    def describe(self) -> dict:
        """JSON-serialisable description, stored as the ``sensor`` attribute of datasets."""
        return {
            "kind": "taxel",
            "preset": self.name,
            "taxels": self.n_taxels,
            "sample_rate_hz": self.sample_rate_hz,
            "bits": 8,
            "receptive_field_mm": self.receptive_field_mm,
            "taxel_positions_mm": self.taxel_positions_mm.round(3).tolist(),
            "location_range_mm": list(self.location_range_mm),
            "contact": self.contact,
            "layout": "assumed (paper 000 gives no dimensioned drawing)",
        }


def receptive_field_response(sensor: TaxelSensor, location_mm) -> np.ndarray:
    """Fraction of its peak that each taxel reads for a contact at each location.

    Parameters
    ----------
    sensor : TaxelSensor
    location_mm : (N,) array_like
        Contact locations along the sweep, mm (0 at the start of the range).

    Returns
    -------
    (N, K) ndarray of float64 in [0, 1]
        Receptive field of each taxel at the contact times how much the object presses there.

    Examples
    --------
    >>> r = receptive_field_response(taxel_sensor("fingertip"), [0.0, 15.0])
    >>> r.shape, bool(r[0].max() < 0.01), bool(r[1].max() > 0.5)
    ((2, 12), True, True)
    """
    x = np.atleast_1d(np.asarray(location_mm, dtype=np.float64))
    if x.ndim != 1:
        raise ValueError(f"location_mm must be 1-D, got shape {x.shape}")
    u = x + sensor.sweep_offset_mm                                       # (N,)
    du = sensor.taxel_positions_mm[None, :, 0] - u[:, None]              # (N, K)
    if sensor.contact == "line":
        # distance from the plate to the pressed segment {(u, v): |v| <= half width}
        dv = np.maximum(np.abs(sensor.taxel_positions_mm[:, 1]) - sensor.contact_half_width_mm, 0.0)
    else:
        dv = sensor.taxel_positions_mm[:, 1] - sensor.path_v_mm
    sigma = sensor.receptive_field_mm / 4.0
    field_ = np.exp(-(du**2 + dv[None, :] ** 2) / (2.0 * sigma**2))
    lo, hi = sensor.pressed_span_mm
    edge = sensor.span_edge_mm
    pressed = expit((u - lo) / edge) * expit((hi - u) / edge)            # (N,)
    return field_ * pressed[:, None]


def _fingertip() -> TaxelSensor:
    rows_u = (2.0, 6.0, 10.0, 13.0)
    flanks_v = (4.5, 4.5, 4.5, 3.0)
    positions = []
    for u, v in zip(rows_u, flanks_v):
        positions += [(u, -v), (u + 1.0, 0.0), (u, v)]
    return TaxelSensor(
        name="fingertip", taxel_positions_mm=np.array(positions), receptive_field_mm=8.0,
        location_range_mm=(0.0, 30.0), sweep_offset_mm=-7.0, contact="line",
        contact_half_width_mm=3.5, pressed_span_mm=(-2.5, 16.5), span_edge_mm=0.8,
        peak_counts=100.0,
    )


def _skin() -> TaxelSensor:
    side, pitch = 30.0, 5.0
    height = side * np.sqrt(3.0) / 2.0
    # triangular lattice of 5 rows (15 points) with apex at the top, centred on its centroid
    rows = [(r, c) for r in range(5) for c in range(r + 1)]
    corners = {(0, 0), (4, 0), (4, 4)}
    row_step = pitch * np.sqrt(3.0) / 2.0
    lattice = np.array([((c - r / 2.0) * pitch, -r * row_step) for r, c in rows if (r, c) not in corners])
    lattice -= np.array([0.0, -4 * row_step * 2.0 / 3.0])   # centroid of the full 15-point lattice at 0
    positions = []
    for i in range(4):
        up = i % 2 == 0
        centroid = np.array([side / 2.0 * (i + 1), (-height / 6.0) if up else (height / 6.0)])
        tri = lattice if up else lattice * np.array([1.0, -1.0])
        positions.append(tri + centroid)
    return TaxelSensor(
        name="skin", taxel_positions_mm=np.concatenate(positions), receptive_field_mm=16.0,
        location_range_mm=(0.0, 50.0), sweep_offset_mm=12.5, path_v_mm=1.0, contact="point",
        peak_counts=60.0,
    )


TAXEL_SENSORS = ("fingertip", "skin")


def taxel_sensor(name: str) -> TaxelSensor:
    """The preset sensor ``name`` (``"fingertip"`` or ``"skin"``).

    Raises
    ------
    ValueError
        For an unknown name; the message lists the choices.
    """
    if name == "fingertip":
        return _fingertip()
    if name == "skin":
        return _skin()
    raise ValueError(f"unknown taxel sensor {name!r}; choose from {', '.join(TAXEL_SENSORS)}")
