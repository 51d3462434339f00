"""Stimuli of papers 001, 003 and 004 for the simulated iCub fingertip (12 taxels).

Each stimulus gives, for a tap at location ``x`` on identity ``w``, the fraction of its peak that
each taxel reads (`Stimulus.field`); `tactip.taxel.sim.TaxelSimulator` turns it into readings with
the contact profile, gains, noise and pre-processing of paper 000. The taxel layout is the
fingertip's (`tactip.taxel.sensors`: rows at u = 2, 6, 10, 13 mm, v up to +-4.5 mm; receptive
field sigma 2 mm). The physics below is a documented simplification, not a finite-element model.

Rods (paper 001): steel rods of 4-12 mm diameter lie across the fingertip; the fingertip sweeps
    16 mm from its base to its tip (location x = u, mm), 16 position classes of 1 mm. A rod of
    radius R indents the fingertip (radius along the sweep R_pad = 20 mm: the 14.5 mm long pad
    is flat along its length) by delta = 1 mm over a strip of half width a = sqrt(2 R_eff delta),
    1 / R_eff = 1 / R + 1 / R_pad (Hertz, two cylinders): wider rods press a wider strip. A taxel
    reads the strip through its receptive field, so along u the response is a Gaussian of sigma
    sqrt(sigma_rf^2 + (a / 2)^2), and the foam (a bed of springs) pushes back in proportion to the
    strip: the tap's force grows as a / a_8mm. The fingertip presses for most of each 1 s tap
    window ("1 tap/sec", Fig. 2: 0.15 s to contact, 0.55 s held). Session to session (the training and the
    test collection are separate sessions, "one training and one test set was collected for each
    of the five rods"), each rod is mounted anew: its indentation differs by ``session_depth_mm``
    (s.d.), its axis is tilted against the sweep by ``session_tilt`` (s.d., mm of indentation
    per mm of sweep) and its placement along the sweep differs by ``session_shift_mm`` (s.d.).
    This limits shape acuity, and more at some positions than at others (paper 001 Fig. 8).
Textures (paper 003): ten abrasive papers p60-p800 (mean particle size 269-22 um, Table I) on a
    plane tapped at depths 0-3 mm (15 depth classes of 0.2 mm), each tap held 0.4 s. Thicker
    papers have larger grains ("texture thickness increases with mean particle size"): the
    effective depth is d + ``grain_height`` x size (0.3: the grains sink partly into the backing).
    Contact starts at ``onset_mm`` (0.2 mm) and the foam saturates: compression
    tanh((d_eff - onset) / saturation_mm), saturation 1.5 mm. The contact disc grows as
    sqrt(2 R_tip saturation compression) from the pad centre (u = 8 mm), so deeper taps reach
    more taxels. Coarser grains press harder (fewer contact points): peak x (1 + 0.5 size /
    269 um). The fingertip comes down at ``tap_speed_mm_s`` (8 mm/s), so a deeper surface is met
    sooner (0.2 mm: 25 ms earlier). The texture's signature is a fixed per-taxel pattern of the
    grains under each plate (s.d. ``signature`` (0.6) x size / 269 um), which grows with the
    compression (deeper taps, stronger signature): texture and depth are confounded in the peak
    pressure, separable by the pattern.
Edge (paper 004): a plate with a straight edge at angle theta (72 classes of 5 deg over 360 deg)
    under the fingertip pad, pressed 2 mm; location x (18 classes of 1 mm over -9..9 mm) is the
    pad centre's distance past the edge along its outward normal (negative: over the plate,
    positive: over air). A taxel is pressed where the plate is under it (a logistic step of
    0.5 mm at the edge) and within the pad's contact disc (radius 6 mm), with the pressure
    concentrated along the edge (a ridge of 0.8 mm s.d., half the flat pressure). For |x| > 6 mm
    the pad is all on the plate or all in air: neither the angle nor the place can be told there.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.special import expit

from tactip.taxel.sensors import TaxelSensor, taxel_sensor

__all__ = ["STIMULI", "Stimulus", "Rods", "Textures", "Edge", "make_stimulus", "TEXTURE_GRADES",
           "TEXTURE_PARTICLE_UM"]

#: Stimulus names of ``tactip simulate taxel --stimulus`` (``rod`` is paper 000's single 8 mm rod).
STIMULI = ("rod", "rods", "textures", "edge")
#: Paper 003 Table I: ISO grit designations and mean particle sizes (um).
TEXTURE_GRADES = ("p60", "p80", "p100", "p150", "p180", "p240", "p320", "p400", "p600", "p800")
TEXTURE_PARTICLE_UM = (269.0, 201.0, 162.0, 100.0, 82.0, 58.0, 46.0, 35.0, 26.0, 22.0)
_TIP_RADIUS_MM = 7.0
_PAD_RADIUS_MM = 20.0
_PAD_CENTRE_MM = (8.0, 0.0)


def _fingertip(range_mm: tuple[float, float], sweep_offset_mm: float) -> TaxelSensor:
    from dataclasses import replace

    return replace(taxel_sensor("fingertip"), location_range_mm=range_mm, sweep_offset_mm=sweep_offset_mm)


@dataclass(frozen=True)
class Stimulus:
    """What a sensor taps: the identities, the location range and each taxel's response.

    Attributes
    ----------
    name : str
    sensor : TaxelSensor
    identities : (I,) ndarray
        Identity values, ``identity_unit``.
    identity_unit : str
    location_range_mm : tuple of float
        ``(start, stop)`` of the location sweep, mm.
    location_classes : int
        Location classes of the paper.
    identity_period : float or None
        Period of circular identities (edge angles: 360 deg).
    tap : dict
        `TaxelSimulator` settings of the paper's taps (e.g. how long the contact is held, s).
    """

    name: str
    sensor: TaxelSensor
    identities: np.ndarray
    identity_unit: str
    location_range_mm: tuple[float, float]
    location_classes: int
    identity_period: float | None = None
    tap: dict = field(default_factory=dict)

    def session(self, rng: np.random.Generator) -> dict:
        """Constants of one collection session (placement, indentation); none by default."""
        return {}

    def field(self, location_mm, identity, session: dict) -> np.ndarray:
        """(N, K) fraction of its peak each taxel reads, for taps at ``location_mm`` on ``identity``."""
        raise NotImplementedError

    def contact_delay_s(self, location_mm, identity) -> np.ndarray:
        """(N,) delay of the contact past the simulator's ``contact_delay_s``, s (none by default)."""
        return np.zeros(np.shape(location_mm))

    def describe(self) -> dict:
        """JSON-ready description for dataset files."""
        return {"stimulus": self.name, "identities": self.identities.tolist(), "identity_unit": self.identity_unit,
                "location_range_mm": list(self.location_range_mm), "location_classes": self.location_classes}


@dataclass(frozen=True)
class Rods(Stimulus):
    """Paper 001: rods of 4-12 mm diameter across the fingertip, 16 mm sweep (module docstring)."""

    session_depth_mm: float = 0.1
    session_tilt: float = 0.03
    session_shift_mm: float = 0.15
    indentation_mm: float = 1.0

    def session(self, rng):
        """Each rod's indentation offset (mm), tilt (mm/mm) and placement shift (mm) in one session."""
        n = len(self.identities)
        return {"depth_mm": self.session_depth_mm * rng.standard_normal(n),
                "tilt": self.session_tilt * rng.standard_normal(n),
                "shift_mm": self.session_shift_mm * rng.standard_normal(n)}

    def _half_width(self, diameter_mm, delta_mm):
        radius_eff = 1.0 / (2.0 / np.asarray(diameter_mm) + 1.0 / _PAD_RADIUS_MM)
        return np.sqrt(2.0 * radius_eff * np.maximum(delta_mm, 0.05))

    def field(self, location_mm, identity, session):
        """(N, K) taxel responses to rods of diameter ``identity`` (mm) at ``location_mm`` (see `Stimulus.field`)."""
        sensor = self.sensor
        rod = np.searchsorted(self.identities, identity)
        none = np.zeros(len(self.identities))
        x = np.asarray(location_mm, dtype=np.float64) + session.get("shift_mm", none)[rod]
        middle = np.mean(self.location_range_mm)
        delta = self.indentation_mm + session.get("depth_mm", none)[rod] + session.get("tilt", none)[rod] * (x - middle)
        a = self._half_width(identity, delta)                                        # (N,) mm
        sigma_rf = sensor.receptive_field_mm / 4.0
        sigma_u = np.sqrt(sigma_rf**2 + (a / 2.0) ** 2)[:, None]
        u = x + sensor.sweep_offset_mm
        du = sensor.taxel_positions_mm[None, :, 0] - u[:, None]
        dv = np.maximum(np.abs(sensor.taxel_positions_mm[:, 1]) - sensor.contact_half_width_mm, 0.0)[None, :]
        force = a / self._half_width(8.0, self.indentation_mm) * delta / self.indentation_mm
        lo, hi = sensor.pressed_span_mm
        pressed = expit((u - lo) / sensor.span_edge_mm) * expit((hi - u) / sensor.span_edge_mm)
        return (force * pressed)[:, None] * np.exp(-du**2 / (2 * sigma_u**2) - dv**2 / (2 * sigma_rf**2))


@dataclass(frozen=True)
class Textures(Stimulus):
    """Paper 003: ten abrasive papers tapped at 0-3 mm depth (module docstring)."""

    onset_mm: float = 0.2
    saturation_mm: float = 1.5
    signature: float = 0.6
    grain_height: float = 0.3
    tap_speed_mm_s: float = 8.0

    def contact_delay_s(self, location_mm, identity):
        """(N,) contact delay, s: earlier for deeper taps and thicker papers (see `Stimulus.contact_delay_s`)."""
        # the fingertip comes down at a constant speed: a deeper (or thicker) surface is met sooner
        depth = np.asarray(location_mm, dtype=np.float64) + self.grain_height * self.particle_um[
            np.asarray(identity, dtype=np.intp)] / 1000.0
        return -(depth - self.location_range_mm[1] / 2) / self.tap_speed_mm_s
    particle_um: np.ndarray = field(default_factory=lambda: np.array(TEXTURE_PARTICLE_UM))

    def field(self, location_mm, identity, session):
        """(N, K) taxel responses to texture class ``identity`` at depth ``location_mm`` (see `Stimulus.field`)."""
        sensor = self.sensor
        index = np.asarray(identity, dtype=np.intp)
        size = self.particle_um[index] / TEXTURE_PARTICLE_UM[0]                    # (N,) relative to p60
        depth = np.asarray(location_mm, dtype=np.float64) + self.grain_height * self.particle_um[index] / 1000.0
        compression = np.tanh(np.maximum(depth - self.onset_mm, 0.0) / self.saturation_mm)       # (N,)
        radius = np.sqrt(2.0 * _TIP_RADIUS_MM * self.saturation_mm * compression)
        r = np.hypot(sensor.taxel_positions_mm[:, 0] - _PAD_CENTRE_MM[0], sensor.taxel_positions_mm[:, 1])
        reach = expit((radius[:, None] - r[None, :]) / 0.7)
        # the grains under each plate: a fixed pattern per texture (a physical property, same every session)
        pattern = np.random.default_rng([7, 3]).standard_normal((len(self.particle_um), sensor.n_taxels))
        signature = 1.0 + self.signature * (size * compression)[:, None] * pattern[index]
        return ((1.0 + 0.5 * size) * compression)[:, None] * reach * np.clip(signature, 0.0, None)


@dataclass(frozen=True)
class Edge(Stimulus):
    """Paper 004: a straight edge at 72 angles under the fingertip pad, 18 positions (module docstring)."""

    pad_radius_mm: float = 6.0
    ridge: float = 1.0
    edge_mm: float = 0.25
    ridge_mm: float = 0.5

    def field(self, location_mm, identity, session):
        """(N, K) taxel responses to an edge at angle ``identity`` (deg), pad centre ``location_mm`` past it."""
        sensor = self.sensor
        theta = np.radians(np.asarray(identity, dtype=np.float64))
        p = sensor.taxel_positions_mm - np.array(_PAD_CENTRE_MM)                     # (K, 2) from the pad centre
        # signed distance of each plate past the edge (positive: over air)
        s = np.cos(theta)[:, None] * p[None, :, 0] + np.sin(theta)[:, None] * p[None, :, 1] \
            + np.asarray(location_mm, dtype=np.float64)[:, None]
        on_plate = expit(-s / self.edge_mm)
        in_pad = expit((self.pad_radius_mm - np.hypot(p[:, 0], p[:, 1])) / 0.7)[None, :]
        return in_pad * on_plate * (1.0 + self.ridge * np.exp(-s**2 / (2 * self.ridge_mm**2)))


def make_stimulus(name: str) -> Stimulus:
    """The stimulus ``name`` of paper 001 (``"rods"``), 003 (``"textures"``) or 004 (``"edge"``).

    Raises
    ------
    ValueError
        For another name; the message lists the choices.
    """
    if name == "rods":
        return Rods("rods", _fingertip((0.0, 16.0), -1.5), np.arange(4.0, 13.0, 2.0), "mm", (0.0, 16.0), 16,
                    tap={"hold_s": 0.55, "contact_delay_s": 0.15})
    if name == "textures":
        return Textures("textures", _fingertip((0.0, 3.0), 0.0), np.arange(10.0), "texture class (p60..p800)",
                        (0.0, 3.0), 15, tap={"hold_s": 0.4, "contact_delay_s": 0.15})
    if name == "edge":
        return Edge("edge", _fingertip((-9.0, 9.0), 0.0), np.arange(0.0, 360.0, 5.0), "deg", (-9.0, 9.0), 18,
                    identity_period=360.0, tap={"hold_s": 0.55, "contact_delay_s": 0.15})
    raise ValueError(f"unknown stimulus {name!r}; choose from rods, textures, edge")
