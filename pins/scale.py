"""Image scale at the pad (mm per px) from the pin pitch and a description of the sensor.

A TacTip's pins stand on a hemispherical pad on a lattice of known pitch, so the pins measure the
scale themselves: ``mm_per_px = pitch_mm / pitch_px``, with ``pitch_px`` the pin pitch of the rest
pins near the centre of the field (where the dome faces the camera: towards the rim it is seen
obliquely and the spacing shrinks in the image; `central_spacing_px`: on a hexagonal lattice or
spokes the median distance to the first shell of neighbours, not the nearest, which pins scattered
by 2 % of the pitch make 3-4 % short) and ``pitch_mm`` from a description of the sensor. The
disc's diameter is a poorer ruler: where the membrane ends in the image depends on the casing, a
black rim ring or LED glare, and differs between TacTips.

Geometry assumed for ``pitch_mm`` from a pin count and a pad diameter (`pin_pitch_mm`): the pad is a
hemisphere of radius ``R = pad_diameter / 2``; the pins' bases lie on a hexagonal lattice laid out
in arc length from the apex, ring k (k = 1 .. K) holding about 6 k pins, so K rings hold
``1 + 3 K (K + 1)`` pins (127 = 6 rings, 331 = 10, 1027 = 18); the outermost ring lies at polar
angle ``field_polar_deg`` (80 degrees: the TacTip's pins stop short of the clamped rim). Then
``pitch_mm = R * radians(field_polar_deg) / K``, measured along the pad surface, with K the
fewest rings that hold the pins (a count up to 3 % above a full hexagonal number is taken as
that number with a few spurious detections; any count a few rings short of full, as when rim
pins are hidden, rounds up to the same K). A radial layout (home-built TacTips whose pins are set
with a rotary jig: ``rings`` rings one pitch apart, each crossed by the same ``spokes`` spokes, the
innermost at ``max(1, spokes / 2 pi)`` pitches so that its neighbours are one pitch apart) has
``pitch_mm = R * radians(field_polar_deg) / (max(1, spokes / 2 pi) + rings - 1)``. Millimetres
are pad-surface mm at the apex, the scale of the paper's "4 mm apart".

A flat gel (GelSight and its kind: dark markers on a rectangular grid on a gel filling the frame)
has no pad to derive a pitch from: its description gives the marker pitch in mm outright
(``marker_pitch_mm``), with its grid (rows x columns in view) and frame rate; the rule is the same,
``mm_per_px = pitch_mm / pitch_px`` (on a square grid the nearest neighbour is one pitch away).

Named sensors (`SENSOR_PRESETS`) give pin count, pad diameter and the field's extent in one word;
`pad_scale` turns any of these (or an explicit ``mm_per_px``) into a `PadScale` that says how it
was derived. `sensor_scale` is the one rule ``tactip detect``, ``tactip calibrate`` and ``tactip
replay`` apply to a rest frame's pins (with their defaults: the pins on the pad are the sensor's, else
the expected count, else the pins detected; the pad is 40 mm when nothing says otherwise), so the
three agree on mm/px for the same frames.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from .errors import PinsError, ShapeError

__all__ = ["SensorDescription", "SENSOR_PRESETS", "sensor_preset", "pin_pitch_mm", "central_spacing_px",
           "PadScale", "pad_scale", "sensor_scale", "DEFAULT_PAD_DIAMETER_MM"]

FIELD_POLAR_DEG = 80.0
#: Pad diameter assumed, mm, when nothing describes the sensor (the common TacTip; said in the scale's source).
DEFAULT_PAD_DIAMETER_MM = 40.0
# A count this much above a full hexagonal number is that number plus spurious detections.
_OVERCOUNT = 0.03


def pin_pitch_mm(pins: int, pad_diameter_mm: float, *, field_polar_deg: float = FIELD_POLAR_DEG) -> float:
    """Pin pitch along the pad surface, mm, of `pins` pins in hexagonal rings on a hemispherical pad.

    Parameters
    ----------
    pins : int
        Pins on the pad (>= 7).
    pad_diameter_mm : float
        Diameter of the hemispherical pad, mm.
    field_polar_deg : float
        Polar angle of the outermost ring of pins from the pad's apex, degrees (0, 90].

    Returns
    -------
    pitch_mm : float
        ``R * radians(field_polar_deg) / K``, K the fewest hexagonal rings holding the pins.

    Examples
    --------
    >>> round(pin_pitch_mm(331, 40.0), 3)      # 10 rings out to 80 degrees of a 20 mm hemisphere
    2.793
    """
    if int(pins) != pins or pins < 7:
        raise ValueError(f"pins must be an integer >= 7 (at least one ring), got {pins}")
    if not (pad_diameter_mm > 0 and math.isfinite(pad_diameter_mm)):
        raise ValueError(f"pad_diameter_mm must be a finite number > 0, got {pad_diameter_mm}")
    if not 0 < field_polar_deg <= 90:
        raise ValueError(f"field_polar_deg must be in (0, 90], got {field_polar_deg}")
    # Fewest rings K with 1 + 3 K (K + 1) >= pins (allowing a small overcount).
    target = pins * (1.0 - _OVERCOUNT)
    rings = max(1, math.ceil((-3.0 + math.sqrt(9.0 + 12.0 * (target - 1.0))) / 6.0 - 1e-9))
    return pad_diameter_mm / 2.0 * math.radians(field_polar_deg) / rings


@dataclass(frozen=True)
class SensorDescription:
    """What `pad_scale` needs to know about a sensor: a TacTip's pad, or a flat gel's marker grid.

    Attributes
    ----------
    name : str
    pins : int
        Pins on the whole pad (a flat gel: markers in view, rows x columns).
    pad_diameter_mm : float
        Diameter of the hemispherical pad, mm (a flat gel: 0, it has no pad).
    field_polar_deg : float
        Polar angle of the outermost ring of pins, degrees.
    rings, spokes : int
        A radial layout's rings and spokes (0: hexagonal rings, the pitch from the pin count).
    note : str
        Where the sensor comes from.
    marker_pitch_mm : float
        A flat gel's marker pitch, mm: the scale's pitch, given outright (0: a TacTip's, from its pad).
    grid : (int, int)
        A flat gel's markers in view, (rows, columns) ((0, 0) for a TacTip).
    frame_rate : float
        The camera's frames per second (0: not known; a video's own rate wins).
    """

    name: str
    pins: int
    pad_diameter_mm: float
    field_polar_deg: float = FIELD_POLAR_DEG
    rings: int = 0
    spokes: int = 0
    note: str = ""
    marker_pitch_mm: float = 0.0
    grid: tuple[int, int] = (0, 0)
    frame_rate: float = 0.0

    @property
    def flat(self) -> bool:
        """Whether this is a flat gel (a marker grid with its pitch given), not a TacTip's pad."""
        return self.marker_pitch_mm > 0

    @property
    def pitch_mm(self) -> float:
        """Pin pitch along the pad surface, mm (`pin_pitch_mm`, or the radial layout's ring spacing), or
        a flat gel's marker pitch."""
        if self.flat:
            return float(self.marker_pitch_mm)
        if self.spokes:
            span = max(1.0, self.spokes / (2 * math.pi)) + self.rings - 1
            return self.pad_diameter_mm / 2.0 * math.radians(self.field_polar_deg) / span
        return pin_pitch_mm(self.pins, self.pad_diameter_mm, field_polar_deg=self.field_polar_deg)

    def describe(self) -> str:
        """One line: pins, pad (or a flat gel's grid), pitch and frame rate when known."""
        rate = f", {self.frame_rate:g} frames/s" if self.frame_rate else ""
        if self.flat:
            return (f"{self.name}: flat gel, {self.grid[0]} x {self.grid[1]} markers, pitch "
                    f"{self.pitch_mm:.2f} mm{rate}")
        return (f"{self.name}: {self.pins} pins on a {self.pad_diameter_mm:g} mm pad, pitch "
                f"{self.pitch_mm:.2f} mm{rate}")

    def brief(self) -> str:
        """A few words for a list of sensors: "331 pins, 40 mm pad" or "flat gel, 8 x 10 markers 1.8 mm apart"."""
        if self.flat:
            return f"flat gel, {self.grid[0]} x {self.grid[1]} markers {self.pitch_mm:g} mm apart"
        return f"{self.pins} pins, {self.pad_diameter_mm:g} mm pad"


SENSOR_PRESETS: dict[str, SensorDescription] = {d.name: d for d in (
    SensorDescription("tactip-127", 127, 40.0, note="TacTip, 40 mm pad, 127 pins (6 rings)"),
    SensorDescription("tactip-331", 331, 40.0, note="TacTip, 40 mm pad, 331 pins (10 rings)"),
    SensorDescription("tactip-532", 532, 40.0, note="TacTip, 40 mm pad, 532 pins (paper 002)"),
    SensorDescription("dark-331", 331, 40.0, note="331-pin TacTip with dark markers on a light membrane"),
    SensorDescription("rim-ring-331", 331, 40.0, note="331-pin TacTip behind a black rim ring with LED glare"),
    SensorDescription("brown-127", 127, 40.0, note="127-pin TacTip with a brown, low-contrast skin"),
    SensorDescription("radial-120", 120, 40.0, rings=7, spokes=17,
                      note="home-built TacTip: 7 rings x 17 spokes + a centre pin"),
    SensorDescription("radial-led-120", 120, 40.0, rings=7, spokes=17,
                      note="the home-built radial TacTip with 4 LED reflections inside the pad"),
    SensorDescription("white-dark-331", 331, 40.0, note="331 white pins on a dark membrane in a dark casing"),
    SensorDescription("small-pad-100", 100, 40.0, note="100-pin pad, small in the image"),
    SensorDescription("dense-1000", 1000, 40.0, note="dense 1000-pin pad"),
    SensorDescription("gelsight-mini", 80, 0.0, marker_pitch_mm=1.8, grid=(8, 10), frame_rate=25.0,
                      note="GelSight-Mini-like flat gel: 8 x 10 dark markers 1.8 mm apart, 320x240 at 25 frames/s"),
)}


def sensor_preset(name: str) -> SensorDescription:
    """The named sensor of `SENSOR_PRESETS`; `ValueError` listing the names when unknown."""
    try:
        return SENSOR_PRESETS[name]
    except KeyError:
        raise ValueError(f"unknown sensor {name!r}; choose from {', '.join(SENSOR_PRESETS)}") from None


def central_spacing_px(rest_positions: np.ndarray, *, centre: tuple[float, float] | None = None,
                       fraction: float = 1.0 / 3.0) -> float:
    """Pin pitch near the centre of the field, px: the first shell's median distance on a lattice, else the
    median nearest-neighbour spacing.

    Where several neighbours of a pin tie for nearest (a hexagonal lattice: six; spokes: the pins one ring
    out and along the ring), the nearest is the least of them, so any scatter of the pins (moulding,
    detection) makes it short: by 3-4 % on the synthetic TacTip's 0.02-pitch scatter, the scale as much
    too large. There the pitch is the median of every distance in the first shell (neighbours within
    `_SHELL` x the median nearest spacing), which the scatter leaves unbiased. A lattice is recognised
    by its pins' hexagonal bond order (`_hexagonal`) or by spokes (`_spokes`: the pins' azimuths about the
    centre repeat with one period). Other layouts (concentric circles of unequal counts: neighbours along a
    ring further apart than the rings) have the ring spacing in the nearest neighbour alone: there it is
    kept.

    Parameters
    ----------
    rest_positions : (N, 2) ndarray
        Pin positions (x, y) at rest, px; NaN rows are ignored.
    centre : (x, y), optional
        Centre of the field, px; the mean of the pins by default.
    fraction : float
        Pins within this fraction of the field's radius count (at least the 7 nearest the centre),
        in (0, 1]; neighbours are searched among all pins.

    Returns
    -------
    pitch_px : float
        NaN with fewer than 2 pins.
    """
    rest = np.asarray(rest_positions, dtype=np.float64)
    if rest.ndim != 2 or rest.shape[1] != 2:
        raise ShapeError(f"rest_positions must have shape (N, 2), got {rest.shape}")
    if not 0 < fraction <= 1:
        raise ValueError(f"fraction must be in (0, 1], got {fraction}")
    rest = rest[np.isfinite(rest).all(axis=1)]
    if len(rest) < 2:
        return float("nan")
    rest = _without_crowders(rest)
    middle = rest.mean(axis=0) if centre is None else np.asarray(centre, dtype=np.float64)
    distance = np.hypot(*(rest - middle).T)
    inner = distance <= fraction * distance.max()
    if inner.sum() < 7:
        inner = distance <= np.sort(distance)[min(6, len(rest) - 1)]
    k = min(_SHELL_NEIGHBOURS, len(rest) - 1)
    spacing, index = cKDTree(rest).query(rest[inner], k=k + 1)
    spacing, index = spacing[:, 1:], index[:, 1:]
    nearest = float(np.median(spacing[:, 0]))
    shell = spacing <= _SHELL * nearest
    if _hexagonal(rest[index] - rest[inner][:, None], shell) or _spokes(rest - middle, nearest):
        return float(np.median(spacing[shell]))
    return nearest


def _without_crowders(rest: np.ndarray) -> np.ndarray:
    """`rest` (N, 2) px without the points whose nearest neighbour is closer than `_CROWDED` x the median
    nearest spacing (both of each such pair), when at least 7 are left.

    A spurious point (a noise blob between radial spokes, a speck) sits between pins, closer to one than
    any pin is to another; a few of them near the centre made the central pitch 28 % short (radial-led-120
    through a noisy webcam, 18 of 136 points spurious: 5.97 px for 8.32 -> 8.08) and broke the spokes'
    periodicity. On a clean field no pin is so crowded (nearest spacings scatter by 2-3 %; rim pins
    foreshortened across a ring still have neighbours along it), so it is unchanged."""
    nearest = cKDTree(rest).query(rest, k=2)[0][:, 1]
    kept = nearest >= _CROWDED * np.median(nearest)
    return rest[kept] if kept.sum() >= 7 else rest


# Points whose nearest neighbour is closer than this fraction of the median nearest spacing are not pins
# of the lattice, or sit next to one that is not (`_without_crowders`).
_CROWDED = 0.7
# First shell: neighbours within this factor of the median nearest spacing (a hexagonal lattice's second
# shell is at sqrt(3), a square grid's at sqrt(2); the synthetic scatter spreads the first by ~3 % a side).
_SHELL = 1.2
_SHELL_NEIGHBOURS = 8
# Hexagonal bond order above which the pins are a hexagonal lattice (synthetic hexagonal pads 0.98-1.00,
# concentric circles 0.42-0.66, spokes 0.04-0.13 over seeds 0-39, detected pins).
_HEXATIC = 0.8
# Spokes: the pins' azimuths about the centre repeat every 2 pi / S for some S in _SPOKE_COUNTS with an
# order above _SPOKE_ORDER (synthetic 17 spokes 1.00; hexagonal 0.35-0.62, circles 0.08-0.47, seeds 0-39).
_SPOKE_COUNTS = np.arange(6, 65)
_SPOKE_ORDER = 0.8
_SPOKE_SHIFT = 0.5  # the spokes' centre is looked for up to this many pitches either way of the pins' mean


def _hexagonal(offset: np.ndarray, shell: np.ndarray) -> bool:
    """Whether the central pins form a hexagonal lattice: the median of each pin's bond order
    ``|mean exp(6 i angle)|`` over its first shell (`offset` (M, k, 2) px to its k nearest, `shell` (M, k)
    which of them are in it; pins with two or more) is above `_HEXATIC`."""
    members = shell.sum(axis=1)
    if not (members >= 2).any():
        return False
    angle = np.arctan2(offset[..., 1], offset[..., 0])
    bond = np.abs(np.where(shell, np.exp(6j * angle), 0).sum(axis=1)) / np.maximum(members, 1)
    return bool(np.median(bond[members >= 2]) > _HEXATIC)


def _spokes(radial: np.ndarray, pitch_px: float) -> bool:
    """Whether the pins lie on spokes: from the centre (`radial` (N, 2) px from it to each pin; those
    beyond a tenth of the furthest), their azimuths repeat every ``2 pi / S`` for some S in
    `_SPOKE_COUNTS` (``|mean exp(i S azimuth)|`` above `_SPOKE_ORDER`), about the given centre or else
    one moved by up to `_SPOKE_SHIFT` pitches (`pitch_px`, px) either way (a 9 x 9 grid, at most 256 pins).

    Pins missing on one side move the pins' mean: 3-4 of 120 (faint, through a webcam) by ~2 px, which turns
    an inner pin's phase by S x 0.2 rad; a radial pad's order fell from 0.99-1.00 to 0.79-0.90 (bench_user_chain,
    seeds 0-35) and at 0.79 the pitch fell back to the nearest spacing, 3 % short. No centre lines up pins on
    no spokes (rings of unequal counts; a hexagonal lattice's pitch is the same either way)."""
    if _spoke_order(radial[None]) > _SPOKE_ORDER:
        return True
    if len(radial) < 2 * _SPOKE_COUNTS[0] or not np.isfinite(pitch_px):
        return False
    sample = radial[::max(1, len(radial) // 256)]
    offsets = _SPOKE_SHIFT * pitch_px * np.linspace(-1.0, 1.0, 9)
    for dy in offsets:  # (a row of centres at a time: 9 x 59 x 256 complex at most)
        shifts = np.column_stack([offsets, np.full(9, dy)])
        if _spoke_order(sample[None] - shifts[:, None]) > _SPOKE_ORDER:
            return True
    return False


def _spoke_order(radial: np.ndarray) -> float:
    """The largest ``|mean exp(i S azimuth)|`` over S in `_SPOKE_COUNTS` and the C centres of `radial` (C, N, 2)
    px (to each pin), over the pins beyond a tenth of the furthest; 0 with fewer than twice the least S."""
    ray = np.hypot(radial[..., 0], radial[..., 1])
    outer = ray > 0.1 * ray.max(axis=1, keepdims=True)
    counts = outer.sum(axis=1)
    if counts.min() < 2 * _SPOKE_COUNTS[0]:
        return 0.0
    turn = np.where(outer, (radial[..., 0] + 1j * radial[..., 1]) / np.where(outer, ray, 1.0), 0.0)  # exp(i azimuth)
    # exp(i S azimuth) for S = 6, 7, ...: running products, cheaper than exponentials
    steps = np.broadcast_to(turn[:, None], (len(turn), len(_SPOKE_COUNTS) - 1, turn.shape[1]))
    powers = np.cumprod(np.concatenate([turn[:, None] ** _SPOKE_COUNTS[0], steps], axis=1), axis=1)
    return float((np.abs(powers.sum(axis=2)) / counts[:, None]).max())


@dataclass(frozen=True)
class PadScale:
    """The image scale at the pad and how it was found.

    Attributes
    ----------
    mm_per_px : float
    pitch_px : float
        Pin pitch of the central rest pins, px (`central_spacing_px`; NaN when not measured).
    pitch_mm : float
        Pin pitch of the sensor along the pad surface, mm (NaN when the scale was given).
    source : str
        How the scale was derived, for a person (e.g. "pin pitch 2.79 mm (sensor tactip-331) / 19.6 px").
    sensor : dict
        The description used: ``name``, ``pins``, ``pad_diameter_mm``, ``field_polar_deg`` (those known).
    """

    mm_per_px: float
    pitch_px: float
    pitch_mm: float
    source: str
    sensor: dict

    def describe(self) -> str:
        """One line: the scale and its derivation (with the central pin pitch, px, whenever measured)."""
        source = self.source
        if np.isfinite(self.pitch_px) and "px measured" not in source:
            source += f"; central pin pitch {self.pitch_px:.2f} px"
        return f"{self.mm_per_px:.4f} mm/px ({source})"

    def to_dict(self) -> dict:
        """JSON-ready: ``mm_per_px``, ``pitch_px``, ``pitch_mm`` (None when not known), ``source``, ``sensor``."""
        def number(value: float):
            return float(value) if np.isfinite(value) else None

        return {"mm_per_px": float(self.mm_per_px), "pitch_px": number(self.pitch_px),
                "pitch_mm": number(self.pitch_mm), "source": self.source, "sensor": dict(self.sensor)}


def pad_scale(rest_positions: np.ndarray, *, sensor: str | SensorDescription | None = None,
              pins: int | None = None, pad_diameter_mm: float | None = None, mm_per_px: float | None = None,
              centre: tuple[float, float] | None = None) -> PadScale:
    """The scale, mm/px, from the rest pins' pitch and the sensor's description (or given outright).

    Precedence: `mm_per_px` when given; else the pitch of `sensor` (a `SENSOR_PRESETS` name or a
    `SensorDescription`), with `pins` and `pad_diameter_mm` overriding its fields when given; else
    `pins` (default: the number of rest pins) on a pad of `pad_diameter_mm` (required then).

    Parameters
    ----------
    rest_positions : (N, 2) ndarray
        Pin positions at rest, px.
    sensor : str or SensorDescription, optional
    pins : int, optional
        Pins on the whole pad (not only those in view).
    pad_diameter_mm : float, optional
    mm_per_px : float, optional
        A measured scale: used as is.
    centre : (x, y), optional
        Centre of the pin field, px (for `central_spacing_px`).

    Returns
    -------
    PadScale

    Raises
    ------
    PinsError
        Fewer than 2 pins to measure the pitch from (when the scale is not given).
    ValueError
        An unknown sensor name or an out-of-range number.

    Examples
    --------
    >>> from pins import detect_pins
    >>> from tactip.sim import SyntheticTacTip
    >>> rest = detect_pins(SyntheticTacTip(pins=331, seed=0).render().image)
    >>> pad_scale(rest, sensor="tactip-331").describe()
    '0.14... mm/px (pin pitch 2.793 mm (tactip-331: 331 pins on a 40 mm pad) / ... px measured)'
    """
    pitch_px = central_spacing_px(rest_positions, centre=centre)
    if mm_per_px is not None:
        if not (mm_per_px > 0 and math.isfinite(mm_per_px)):
            raise ValueError(f"mm_per_px must be a finite number > 0, got {mm_per_px}")
        return PadScale(float(mm_per_px), pitch_px, float("nan"), "given (--mm-per-px)", {})
    if isinstance(sensor, str):
        sensor = sensor_preset(sensor)
    counted = pins is None and sensor is None
    if sensor is not None:
        description = dataclasses.replace(
            sensor, pins=int(pins if pins is not None else sensor.pins),
            pad_diameter_mm=float(pad_diameter_mm if pad_diameter_mm is not None else sensor.pad_diameter_mm))
    else:
        if pad_diameter_mm is None:
            raise ValueError("pad_diameter_mm is needed to derive the scale without a sensor preset or mm_per_px")
        count = len(np.asarray(rest_positions)) if pins is None else pins
        if count < 7:
            raise PinsError(f"{count} pins are too few to derive the scale from the pin pitch; give mm_per_px")
        description = SensorDescription("", int(count), float(pad_diameter_mm))
    if not np.isfinite(pitch_px) or pitch_px <= 0:
        raise PinsError("fewer than two distinct rest pins: cannot measure the pin pitch; give mm_per_px")
    pitch_mm = description.pitch_mm
    what = f"{description.pins} pins{' detected' if counted else ''} on a {description.pad_diameter_mm:g} mm pad"
    if description.flat:
        what = f"flat gel, {description.grid[0]} x {description.grid[1]} markers"
    if description.name:
        what = f"{description.name}: {what}"
    source = f"pin pitch {pitch_mm:.3f} mm ({what}) / central pin pitch {pitch_px:.2f} px measured"
    measured = int(np.isfinite(np.asarray(rest_positions, dtype=np.float64)).all(axis=1).sum())
    if not counted and not description.flat and measured > (1.0 + _OVERCOUNT) * description.pins:
        # More pins than the pad has: some are not pins (noise blobs, specks), and may have made the pitch short.
        source += (f"; {measured} pins measured, more than the {description.pins} the sensor has: some are not pins, "
                   f"check the pin field (tactip detect --annotate OUT.png)")
    info = {"pins": description.pins, "pad_diameter_mm": description.pad_diameter_mm,
            "field_polar_deg": description.field_polar_deg, "pins_counted": counted}
    if description.spokes:
        info.update(rings=description.rings, spokes=description.spokes)
    if description.flat:
        info.update(marker_pitch_mm=description.marker_pitch_mm, grid=list(description.grid))
    if description.frame_rate:
        info["frame_rate"] = description.frame_rate
    if description.name:
        info["name"] = description.name
    return PadScale(pitch_mm / pitch_px, pitch_px, pitch_mm, source, info)


def sensor_scale(rest_positions: np.ndarray, *, sensor: str | SensorDescription | None = None,
                 pins_on_pad: int | None = None, pad_diameter_mm: float | None = None,
                 mm_per_px: float | None = None, expected_pins: int | None = None) -> PadScale:
    """The scale of a rest frame's pins as ``detect``, ``calibrate`` and ``replay`` all derive it.

    `pad_scale` with their shared defaults: the pins on the whole pad are `pins_on_pad`, else the
    sensor's, else `expected_pins`, else the pins detected; the pad is `pad_diameter_mm`, else the
    sensor's, else `DEFAULT_PAD_DIAMETER_MM` (assumed, and the source says so).

    Parameters
    ----------
    rest_positions : (N, 2) ndarray
        Pin positions at rest, px (the pins the rest frame's pin field kept).
    sensor : str or SensorDescription, optional
        A `SENSOR_PRESETS` name or a description.
    pins_on_pad : int, optional
        Pins on the whole pad, in view or not.
    pad_diameter_mm : float, optional
    mm_per_px : float, optional
        A measured scale: used as is.
    expected_pins : int, optional
        The count the user expects (``--expected-pins``, ``[sensor] pins``): the pins on the pad
        when neither `pins_on_pad` nor `sensor` says.

    Returns
    -------
    PadScale

    Raises
    ------
    PinsError
        Too few pins to measure the pitch from (when the scale is not given).

    Examples
    --------
    >>> from tactip.sim import SyntheticTacTip
    >>> scale = sensor_scale(SyntheticTacTip(pins=127, seed=0).rest_centres)
    >>> scale.pitch_mm, scale.sensor["pins_counted"], "pad diameter assumed" in scale.source
    (4.654..., True, True)
    """
    pins = pins_on_pad if pins_on_pad is not None or sensor is not None else expected_pins
    assumed = sensor is None and pad_diameter_mm is None and mm_per_px is None
    scale = pad_scale(rest_positions, sensor=sensor, pins=pins, mm_per_px=mm_per_px,
                      pad_diameter_mm=DEFAULT_PAD_DIAMETER_MM if assumed else pad_diameter_mm)
    if assumed:
        scale = dataclasses.replace(scale, source=f"{scale.source}; pad diameter assumed "
                                                  f"({DEFAULT_PAD_DIAMETER_MM:g} mm): describe the sensor "
                                                  f"(its name or pad diameter)")
    return scale
