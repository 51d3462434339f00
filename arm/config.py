"""The ``[arm]`` table of a station's TOML configuration: parsed, validated, frozen.

Keys (units in brackets; see ``samples/arm_sim.toml`` and ``samples/arm_ur.toml``)::

    [arm]
    backend = "sim"                  # "sim" or "ur"                                       required
    host = "192.168.1.10"            # controller address                                   required for "ur"
    tcp = [0, 0, 60, 0, 0, 0]        # TCP (pad apex) in the tool flange frame [mm, deg]     default zeros
    work_frame = [400, -150, 20, 180, 0, 0]   # work frame in the robot base frame [mm, deg] default zeros
    workspace = [[-10, -10, -8], [200, 40, 30]]  # min and max corners in the work frame [mm] required
    max_tap_depth = 6.0              # deepest point below the surface reference z = 0 [mm] required
    max_speed = 50.0                 # any move [mm/s]
    max_acceleration = 500.0         # any move [mm/s^2]
    max_tap_speed = 20.0             # any move that goes below z = 0 [mm/s]
    rtde_frequency = 125.0           # RTDE data rate, "ur" only [Hz]

    [arm.tap]                        # the tap primitive (arm.tap.TapMotion)
    approach_height = 5.0            # [mm] above z = 0
    speed = 10.0                     # stroke speed [mm/s]
    acceleration = 100.0             # [mm/s^2]
    dwell = 0.5                      # at the bottom [s]
    travel_speed = 30.0              # between tap points [mm/s]

    [arm.sim]                        # "sim" only
    realtime = false                 # true: moves take their real duration
    surface_z = 0.0                  # plate surface in the work frame [mm]
    placement_noise = 0.0            # lateral placement error per tap, standard deviation [mm]
    seed = 1
    home = [0, 0, 20, 180, 0, 0]     # initial TCP pose in the work frame [mm, deg]
    gaps = [{ name = "g1", x = 30.0, y = 0.0, width = 1.25, angle = 0.0 }]   # [mm, deg]

Orientation angles are extrinsic xyz Euler angles (roll, pitch, yaw) in degrees (`arm.pose.Pose`).
A missing or out-of-range key raises `arm.errors.ArmConfigError` naming the key.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

from _shared import outside_range, parse_toml
from _shared.ranges import MAX_SEED

from .errors import ArmConfigError
from .pose import Pose
from .tap import TapMotion
from .world import Gap, PlateWorld

__all__ = ["ArmConfig", "SafetyLimits", "SimSettings", "BACKENDS", "arm_config_from_table", "load_arm_config"]

BACKENDS = ("sim", "ur")

# Scalar limits: TOML key -> (dataclass field, default or None if required, low (exclusive), high, unit).
_SCALARS = {
    "max_tap_depth": ("max_tap_depth_mm", None, 0.0, 20.0, "mm"),
    "max_speed": ("max_speed_mm_s", 50.0, 0.0, 250.0, "mm/s"),
    "max_acceleration": ("max_acceleration_mm_s2", 500.0, 0.0, 2500.0, "mm/s^2"),
    "max_tap_speed": ("max_tap_speed_mm_s", 20.0, 0.0, 100.0, "mm/s"),
    "rtde_frequency": ("rtde_frequency_hz", 125.0, 0.0, 500.0, "Hz"),
}
_TAP_KEYS = {"approach_height": "approach_height_mm", "speed": "speed_mm_s",
             "acceleration": "acceleration_mm_s2", "dwell": "dwell_s", "travel_speed": "travel_speed_mm_s"}
# Ranges of the [arm.tap] keys: TOML key -> (low, high, low included, unit). A dwell of hours or a crawl
# of a micrometre per second would hang an inspection; the caps of [arm] bound speeds further.
_TAP_RANGES = {"approach_height": (0.0, 100.0, False, "mm"), "speed": (0.0, 250.0, False, "mm/s"),
               "acceleration": (0.0, 2500.0, False, "mm/s^2"), "dwell": (0.0, 10.0, True, "s"),
               "travel_speed": (0.0, 250.0, False, "mm/s")}
_MIN_SPEED_MM_S = 0.1   # slower strokes and travels take minutes per tap
_MAX_SEED = MAX_SEED
# [arm.sim] gaps: positions within a metre of the work frame origin, widths and lengths up to 100 / 1000 mm.
_SIM_GAP_RANGES = {"x": (-1000.0, 1000.0), "y": (-1000.0, 1000.0), "width": (0.0, 100.0), "angle": (-360.0, 360.0),
                   "length": (0.0, 1000.0)}
_SIM_KEYS = ("realtime", "surface_z", "placement_noise", "seed", "home", "gaps")
_GAP_KEYS = {"name": "name", "x": "x_mm", "y": "y_mm", "width": "width_mm", "angle": "angle_deg",
             "length": "length_mm"}
_KEYS = ("backend", "host", "tcp", "work_frame", "workspace", *_SCALARS, "tap", "sim")


@dataclass(frozen=True)
class SimSettings:
    """Settings of the simulated arm and its world (the ``[arm.sim]`` table).

    Attributes
    ----------
    realtime : bool
        Whether moves take their real (trapezoidal-profile) duration; otherwise they are instant.
    surface_z_mm : float
        Plate surface height in the work frame, mm.
    placement_noise_mm : float
        Standard deviation of the lateral placement error per tap, mm.
    seed : int or None
        Seed of the placement-error generator.
    home : Pose or None
        Initial TCP pose in the work frame; None: above the workspace centre, at its top, pad down.
    gaps : tuple of Gap
        The plate's gaps.
    """

    realtime: bool = False
    surface_z_mm: float = 0.0
    placement_noise_mm: float = 0.0
    seed: int | None = None
    home: Pose | None = None
    gaps: tuple[Gap, ...] = ()

    def make_world(self, default_gaps: Sequence[Gap] = ()) -> PlateWorld:
        """A fresh `PlateWorld` with these settings (its generator starts from ``seed``).

        Parameters
        ----------
        default_gaps : sequence of Gap
            The plate's gaps when ``gaps`` is empty (a station passes the gaps it inspects).
        """
        return PlateWorld(gaps=self.gaps or tuple(default_gaps), surface_z_mm=self.surface_z_mm,
                          placement_noise_mm=self.placement_noise_mm, seed=self.seed)


@dataclass(frozen=True)
class ArmConfig:
    """A validated ``[arm]`` table. Distances in mm, angles in degrees, in the frames named per field.

    Attributes
    ----------
    backend : {"sim", "ur"}
    host : str
        Controller address (``ur``).
    tcp : Pose
        TCP (pad apex) in the tool flange frame.
    work_frame : Pose
        Work frame in the robot base frame (z up, origin on the part's surface reference).
    workspace_min_mm, workspace_max_mm : (3,) tuple of float
        Corners of the safe box in the work frame.
    max_tap_depth_mm : float
        Deepest allowed point below ``z = 0``.
    max_speed_mm_s, max_acceleration_mm_s2 : float
        Caps on every move.
    max_tap_speed_mm_s : float
        Speed cap on every move that goes below ``z = 0``.
    rtde_frequency_hz : float
        RTDE data rate for the ``ur`` backend.
    tap : TapMotion
        The tap primitive's motion.
    sim : SimSettings
        The simulated arm's settings.
    """

    backend: str
    workspace_min_mm: tuple[float, float, float]
    workspace_max_mm: tuple[float, float, float]
    max_tap_depth_mm: float
    host: str = ""
    tcp: Pose = field(default_factory=lambda: Pose(0, 0, 0))
    work_frame: Pose = field(default_factory=lambda: Pose(0, 0, 0))
    max_speed_mm_s: float = 50.0
    max_acceleration_mm_s2: float = 500.0
    max_tap_speed_mm_s: float = 20.0
    rtde_frequency_hz: float = 125.0
    tap: TapMotion = field(default_factory=TapMotion)
    sim: SimSettings = field(default_factory=SimSettings)

    def __post_init__(self):
        if self.backend not in BACKENDS:
            raise ArmConfigError(f"[arm] backend {self.backend!r} is unknown; choose from {', '.join(BACKENDS)}")
        if self.backend == "ur" and not self.host:
            raise ArmConfigError("[arm] is missing the key 'host' (the controller address), required for backend 'ur'")
        low = _vector("workspace", self.workspace_min_mm, 3)
        high = _vector("workspace", self.workspace_max_mm, 3)
        if np.any(low >= high):
            axis = "xyz"[int(np.argmax(low >= high))]
            raise ArmConfigError(f"[arm] workspace: the min corner must be below the max corner on every axis "
                                 f"(axis {axis}: {low.tolist()} vs {high.tolist()})")
        object.__setattr__(self, "workspace_min_mm", tuple(low.tolist()))
        object.__setattr__(self, "workspace_max_mm", tuple(high.tolist()))
        for key, (name, _default, lo, hi, unit) in _SCALARS.items():
            object.__setattr__(self, name, _in_range(key, getattr(self, name), lo, hi, unit))
        if self.max_tap_speed_mm_s > self.max_speed_mm_s:
            raise ArmConfigError(f"[arm] max_tap_speed ({self.max_tap_speed_mm_s} mm/s) must not exceed "
                                 f"max_speed ({self.max_speed_mm_s} mm/s)")
        tap = self.tap
        for key, value, cap, cap_key in (("speed", tap.speed_mm_s, self.max_tap_speed_mm_s, "max_tap_speed"),
                                         ("travel_speed", tap.travel_speed_mm_s, self.max_speed_mm_s, "max_speed"),
                                         ("acceleration", tap.acceleration_mm_s2, self.max_acceleration_mm_s2,
                                          "max_acceleration")):
            if value > cap:
                raise ArmConfigError(f"[arm.tap] {key} ({value}) must not exceed [arm] {cap_key} ({cap})")
        if tap.approach_height_mm > self.workspace_max_mm[2]:
            raise ArmConfigError(f"[arm.tap] approach_height ({tap.approach_height_mm} mm) is above the "
                                 f"workspace top (z = {self.workspace_max_mm[2]} mm)")

    @property
    def limits(self) -> SafetyLimits:
        """The `SafetyLimits` of this configuration (`arm.safety` checks every move against them)."""
        return SafetyLimits.from_config(self)


@dataclass(frozen=True)
class SafetyLimits:
    """The limits every move is checked against (work frame, mm, mm/s, mm/s^2)."""

    workspace_min_mm: tuple[float, float, float]
    workspace_max_mm: tuple[float, float, float]
    max_tap_depth_mm: float
    max_speed_mm_s: float
    max_acceleration_mm_s2: float
    max_tap_speed_mm_s: float

    @classmethod
    def from_config(cls, config: ArmConfig) -> SafetyLimits:
        """The limits of a validated `ArmConfig`."""
        return cls(config.workspace_min_mm, config.workspace_max_mm, config.max_tap_depth_mm,
                   config.max_speed_mm_s, config.max_acceleration_mm_s2, config.max_tap_speed_mm_s)


def load_arm_config(path: str | Path) -> ArmConfig:
    """Read the ``[arm]`` table of a TOML file (other tables are ignored).

    Raises
    ------
    OSError
        The file cannot be read.
    ArmConfigError
        The file is not valid TOML, has no ``[arm]`` table, or the table is invalid (the key is named).
    """
    path = Path(path)
    document = parse_toml(path.read_bytes(), path, error=ArmConfigError)
    if "arm" not in document:
        raise ArmConfigError(f"{path}: no [arm] table")
    return arm_config_from_table(document["arm"])


def arm_config_from_table(table: Mapping[str, Any]) -> ArmConfig:
    """An `ArmConfig` from the contents of an ``[arm]`` table (as `tomllib` returns it)."""
    if not isinstance(table, Mapping):
        raise ArmConfigError("[arm] must be a table")
    _reject_unknown("[arm]", table, _KEYS)
    for key in ("backend", "workspace", "max_tap_depth"):
        if key not in table:
            raise ArmConfigError(f"[arm] is missing the key {key!r}")
    backend = table["backend"]
    if not isinstance(backend, str):
        raise ArmConfigError(f"[arm] backend must be a string, got {backend!r}")
    host = table.get("host", "")
    if not isinstance(host, str):
        raise ArmConfigError(f"[arm] host must be a string, got {host!r}")
    workspace = table["workspace"]
    if not (isinstance(workspace, list) and len(workspace) == 2):
        raise ArmConfigError("[arm] workspace must be [[x_min, y_min, z_min], [x_max, y_max, z_max]] in mm")
    scalars = {name: _number(key, table.get(key, default))
               for key, (name, default, *_rest) in _SCALARS.items()}
    return ArmConfig(
        backend=backend, host=host,
        tcp=_pose("tcp", table.get("tcp", [0.0] * 6)),
        work_frame=_pose("work_frame", table.get("work_frame", [0.0] * 6)),
        workspace_min_mm=tuple(_vector("workspace", workspace[0], 3).tolist()),
        workspace_max_mm=tuple(_vector("workspace", workspace[1], 3).tolist()),
        tap=_tap(table.get("tap", {})), sim=_sim(table.get("sim", {})), **scalars)


def _reject_unknown(where: str, table: Mapping[str, Any], known) -> None:
    unknown = sorted(set(table) - set(known))
    if unknown:
        raise ArmConfigError(f"{where} has unknown key {unknown[0]!r}; known keys: {', '.join(known)}")


def _number(key: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ArmConfigError(f"[arm] {key} must be a number, got {value!r}")
    return float(value)


def _in_range(key: str, value: float, low: float, high: float, unit: str) -> float:
    value = float(value)
    accepted = outside_range(value, low, high, low_open=True, unit=unit)
    if accepted:
        raise ArmConfigError(f"[arm] {key} {accepted}, got {value:g}")
    return value


def _vector(key: str, values: Any, size: int) -> np.ndarray:
    try:
        array = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise ArmConfigError(f"[arm] {key} must be {size} numbers, got {values!r}") from None
    if array.shape != (size,) or not np.all(np.isfinite(array)):
        raise ArmConfigError(f"[arm] {key} must be {size} finite numbers, got {values!r}")
    return array


def _pose(key: str, values: Any) -> Pose:
    return Pose(*_vector(key, values, 6).tolist())


def _tap(table: Any) -> TapMotion:
    if not isinstance(table, Mapping):
        raise ArmConfigError("[arm.tap] must be a table")
    _reject_unknown("[arm.tap]", table, _TAP_KEYS)
    kwargs = {}
    for key, value in table.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise ArmConfigError(f"[arm.tap] {key} must be a number, got {value!r}")
        low, high, closed, unit = _TAP_RANGES[key]
        if key.endswith("speed"):
            low, closed = _MIN_SPEED_MM_S, True
        value = float(value)
        accepted = outside_range(value, low, high, low_open=not closed, unit=unit)
        if accepted:
            raise ArmConfigError(f"[arm.tap] {key}: {accepted}, got {value:g}")
        kwargs[_TAP_KEYS[key]] = value
    try:
        return TapMotion(**kwargs)
    except ValueError as exc:
        name = str(exc).split()[0]
        key = next(k for k, v in _TAP_KEYS.items() if v == name)
        raise ArmConfigError(f"[arm.tap] {key}: {str(exc).split(' ', 1)[1]}") from None


def _sim(table: Any) -> SimSettings:
    if not isinstance(table, Mapping):
        raise ArmConfigError("[arm.sim] must be a table")
    _reject_unknown("[arm.sim]", table, _SIM_KEYS)
    realtime = table.get("realtime", False)
    if not isinstance(realtime, bool):
        raise ArmConfigError(f"[arm.sim] realtime must be true or false, got {realtime!r}")
    seed = table.get("seed")
    if seed is not None and (isinstance(seed, bool) or not isinstance(seed, int) or not 0 <= seed <= _MAX_SEED):
        raise ArmConfigError(f"[arm.sim] seed must be a whole number in 0..{_MAX_SEED}, got {seed!r}")
    noise = _number("sim.placement_noise", table.get("placement_noise", 0.0))
    if not (math.isfinite(noise) and 0 <= noise <= 10):
        raise ArmConfigError(f"[arm.sim] placement_noise must be in [0, 10] mm, got {noise:g}")
    home = table.get("home")
    gaps = table.get("gaps", [])
    if not isinstance(gaps, list):
        raise ArmConfigError("[arm.sim] gaps must be a list of tables")
    names = [gap.get("name") for gap in gaps if isinstance(gap, Mapping)]
    for index, name in enumerate(names):
        if not isinstance(name, str) or not name.strip():
            raise ArmConfigError(f"[arm.sim] gaps[{index}] name must be a non-empty string, got {name!r}")
    if len(set(names)) != len(names):
        raise ArmConfigError(f"[arm.sim] gaps: names must be unique, got {names}")
    surface_z = _number("sim.surface_z", table.get("surface_z", 0.0))
    if not (math.isfinite(surface_z) and abs(surface_z) <= 100):
        raise ArmConfigError(f"[arm.sim] surface_z must be in [-100, 100] mm, got {surface_z:g}")
    return SimSettings(realtime=realtime, surface_z_mm=surface_z,
                       placement_noise_mm=noise, seed=seed,
                       home=None if home is None else _pose("sim.home", home),
                       gaps=tuple(_gap(i, gap) for i, gap in enumerate(gaps)))


def _gap(index: int, table: Any) -> Gap:
    where = f"[arm.sim] gaps[{index}]"
    if not isinstance(table, Mapping):
        raise ArmConfigError(f"{where} must be a table")
    _reject_unknown(where, table, _GAP_KEYS)
    for key in ("name", "x", "y", "width"):
        if key not in table:
            raise ArmConfigError(f"{where} is missing the key {key!r}")
    kwargs = {_GAP_KEYS[key]: value for key, value in table.items()}
    if not isinstance(kwargs["name"], str):
        raise ArmConfigError(f"{where} name must be a string")
    for key, value in table.items():
        if key == "name":
            continue
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ArmConfigError(f"{where} {key} must be a finite number, got {value!r}")
        low, high = _SIM_GAP_RANGES[key]
        if not low <= value <= high or (key in ("width", "length") and value == 0):
            raise ArmConfigError(f"{where} {key} must be in {'(' if key in ('width', 'length') else '['}{low:g}, "
                                 f"{high:g}] {'deg' if key == 'angle' else 'mm'}, got {value:g}")
    try:
        return Gap(**kwargs)
    except (TypeError, ValueError) as exc:
        raise ArmConfigError(f"{where}: {exc}") from None
