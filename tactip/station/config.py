"""The station configuration: one TOML file, validated on load; every error names its key.

Tables (see ``samples/station_sim.toml`` for a documented example):

``[station]``
    ``name``; ``results`` (an SQLite file path, or a ``postgresql://user@host:port/db`` URL: one
    database for a line of stations); ``data_dir`` (where calibration, datasets and models go).
``[sensor]``
    ``source`` (``"synthetic"``, a camera index such as ``0``, ``/dev/videoN``, or a video file);
    ``pins`` (expected pin count / synthetic preset); ``pad_diameter_mm``; ``frame_rate`` (frames/s);
    ``calibration`` (file written by ``tactip calibrate``); ``selected_pins``; ``min_separation_mm``;
    ``preset`` (optional: a named sensor of ``pins.SENSOR_PRESETS``, e.g. ``"radial-120"``, whose pin
    layout gives the pin pitch of the scale, as ``tactip detect/replay --sensor`` does).
``[arm]``
    validated by the arm package (``arm.config``): backend, host, tcp, work_frame, workspace, caps.
``[[gaps]]``
    one table per gap to inspect: ``name``, ``x``, ``y`` (mm, work frame), ``nominal_width`` (mm),
    ``tolerance`` (mm), and for the simulated station ``true_width`` (mm, default nominal).
``[protocol]``
    the tap protocol: ``depth_min``/``depth_max``/``depth_step`` (mm, the paper's 0-5.5 mm at
    0.05 mm), ``reference_height_mm``, ``samples`` (per tap), ``lateral_jitter_mm``, ``repeats``
    (taps per depth and gap), ``seed``. A protocol depth ``d`` puts the bottom of the tap at
    ``z = reference_height_mm - d`` in the work frame (whose origin is on the part's surface
    reference), so the top of the range taps air, as in the paper (about 1.5 mm of no contact).
    How the arm moves during a tap (approach height, stroke speed, dwell) is ``[arm.tap]``.
``[perception]``
    ``model`` (file), ``decision_threshold`` and ``fixation_depth`` (mm) (each omitted: the model's
    recommendation from ``tactip validate --sweep-fixation``), ``start_depth`` (mm: where each
    inspection starts; omitted: a random protocol depth, the paper's unknown start), ``policy`` (active|stationary|random), ``max_taps``, ``locations`` (depth
    classes), ``bins``, ``likelihood`` (the kind of model the station trains: ``gaussian``, the
    default, ``calibrated-histogram``, the papers' ``histogram``, or ``torch``, an ensemble of small
    networks, which needs torch to train: ``pip install torch==2.13.0``), ``target_accuracy`` (fraction
    of decisions within the gaps' tolerance the chosen threshold must reach; omitted: 0.95 for the
    calibrated kinds, and the papers' lowest error within 12 taps for ``histogram``).
``[sim]``
    the simulated station only: ``noise_sigma`` (camera noise, grey levels) and ``seed`` of the
    synthetic TacTip. The simulated arm's own settings (placement noise, realtime) are ``[arm.sim]``;
    its plate has the ``[[gaps]]`` (at ``true_width``) unless ``[arm.sim]`` lists gaps of its own.

Relative paths are resolved against the configuration file's folder.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from _shared import outside_range, parse_toml
from _shared.ranges import MAX_BINS, MAX_LOCATIONS, MAX_SAMPLES, MAX_SEED, MAX_TAPS
from perception.choices import MODEL_KINDS, POLICIES
from tactip.errors import ConfigError

__all__ = ["simulated_station_config", "SIM_PRESET", "StationConfig", "SensorConfig", "GapConfig", "ProtocolConfig", "PerceptionConfig",
           "SimConfig", "load_station_config", "parse_station_config"]

# Ranges of the keys whose extremes would hang or exhaust a station (the paper's protocol is 111 depths
# of 40 samples, 11 depth classes, 100 bins, a 331-pin TacTip).
MIN_PINS, MAX_PINS = 7, 2000            # [sensor] pins: one ring of six around a centre .. a dense pad
MAX_DEPTH_MM = 100.0                     # [protocol] depths and reference height, mm
MAX_DEPTHS = 10_000                      # protocol depths per gap
MAX_REPEATS = 1000                       # taps per depth and gap
MAX_COLLECTION_TAPS = 200_000            # taps per collection, all gaps
MAX_GAP_MM = 100.0                       # gap widths and tolerances, mm
MAX_CAMERA_INDEX = 63                    # [sensor] source given as a whole number
SIM_PRESET = Path(__file__).with_name("presets") / "station_sim.toml"


@dataclass(frozen=True)
class SensorConfig:
    """The optical front end: where frames come from and what the sensor is."""

    source: str = "synthetic"
    pins: int = 331
    pad_diameter_mm: float = 40.0
    frame_rate: float = 20.0
    calibration: Path | None = None
    selected_pins: int = 40
    min_separation_mm: float = 4.0
    preset: str = ""  # a pins.SENSOR_PRESETS name for the scale's pin pitch ("": pins on a hexagonal pad)


@dataclass(frozen=True)
class GapConfig:
    """One gap to inspect: position in the work frame (mm), nominal width and tolerance (mm)."""

    name: str
    x: float
    y: float
    nominal_width: float
    tolerance: float
    true_width: float | None = None


@dataclass(frozen=True)
class ProtocolConfig:
    """The tap protocol (paper 002 III-A.2: 0-5.5 mm at 0.05 mm steps, 40 samples per tap)."""

    depth_min: float = 0.0
    depth_max: float = 5.5
    depth_step: float = 0.05
    reference_height_mm: float = 1.5
    samples: int = 40
    lateral_jitter_mm: float = 0.0
    repeats: int = 1
    seed: int = 0

    @property
    def depths(self) -> list[float]:
        """The protocol's tap depths, mm, from ``depth_min`` to ``depth_max`` inclusive."""
        n = int(math.floor((self.depth_max - self.depth_min) / self.depth_step + 1e-6)) + 1
        return [round(self.depth_min + k * self.depth_step, 9) for k in range(n)]

    def arm_depth_mm(self, depth: float) -> float:
        """The arm's tap depth below the surface reference (``z = -value``) for protocol depth ``depth``."""
        return float(depth) - self.reference_height_mm


@dataclass(frozen=True)
class PerceptionConfig:
    """The classifier and its decision settings."""

    model: Path | None = None
    decision_threshold: float | None = None
    fixation_depth: float | None = None
    start_depth: float | None = None
    policy: str = "active"
    max_taps: int = 20
    locations: int = 11
    bins: int = 100
    likelihood: str = "gaussian"
    target_accuracy: float | None = None


@dataclass(frozen=True)
class SimConfig:
    """The synthetic TacTip of the simulated station."""

    noise_sigma: float = 4.0
    seed: int = 0


@dataclass(frozen=True)
class StationConfig:
    """A whole station, as loaded from its TOML file."""

    name: str
    results: Path | str  # an SQLite file, or a postgresql:// URL (str)
    data_dir: Path
    sensor: SensorConfig
    arm: Any  # arm.config.ArmConfig
    gaps: tuple[GapConfig, ...]
    protocol: ProtocolConfig
    perception: PerceptionConfig
    sim: SimConfig
    path: Path | None = None
    raw: dict = field(default_factory=dict, repr=False)

    @property
    def simulated(self) -> bool:
        """True when the arm backend is the simulation (the synthetic sensor is then used too)."""
        return getattr(self.arm, "backend", None) == "sim"

    def gap(self, name: str) -> GapConfig:
        """The gap called ``name``; ConfigError listing the names when there is none."""
        for g in self.gaps:
            if g.name == name:
                return g
        raise ConfigError(f"no gap named {name!r}; gaps: {', '.join(g.name for g in self.gaps)}")


def load_station_config(path: str | Path) -> StationConfig:
    """Read and validate a station TOML file; `ConfigError` names the file and the bad key."""
    path = Path(path)
    data = _read_toml(path, "station configuration")
    try:
        return parse_station_config(data, base_dir=path.parent, path=path)
    except ConfigError as exc:
        raise ConfigError(f"{path}: {exc}") from None


def parse_station_config(data: dict, *, base_dir: Path = Path("."), path: Path | None = None) -> StationConfig:
    """Validate a parsed TOML mapping into a `StationConfig` (relative paths against ``base_dir``)."""
    from arm.config import arm_config_from_table
    from arm.errors import ArmConfigError

    known = {"station", "sensor", "arm", "gaps", "protocol", "perception", "sim"}
    _no_unknown(data, known, "")
    station = _table(data, "station")
    _no_unknown(station, {"name", "results", "data_dir"}, "station")
    for key in ("name", "results", "data_dir"):
        if key in station and (not isinstance(station[key], str) or not station[key].strip()):
            what = "a name" if key == "name" else "a path string"
            raise ConfigError(f"station.{key} must be {what}, got {station[key]!r}")
    sensor = _section(data, "sensor", SensorConfig, base_dir, paths={"calibration"})
    protocol = _section(data, "protocol", ProtocolConfig, base_dir)
    perception = _section(data, "perception", PerceptionConfig, base_dir, paths={"model"})
    sim = _section(data, "sim", SimConfig, base_dir)
    try:
        arm = arm_config_from_table(_table(data, "arm", required=True))
    except ArmConfigError as exc:
        raise ConfigError(str(exc)) from None

    if arm.backend == "sim":  # the simulated arm's camera renders the synthetic TacTip: another source would be ignored
        _check(sensor.source == "synthetic", "sensor.source",
               f"must be \"synthetic\" with the simulated arm (arm.backend = \"sim\" renders the synthetic TacTip, "
               f"so a camera or video would be ignored), got {sensor.source!r}")
    _range(sensor.pins, "sensor.pins", MIN_PINS, MAX_PINS, "pins")
    _range(sensor.pad_diameter_mm, "sensor.pad_diameter_mm", 0, 500, "mm", low_open=True)
    _range(sensor.frame_rate, "sensor.frame_rate", 0, 1000, "frames/s", low_open=True)
    _range(sensor.selected_pins, "sensor.selected_pins", 1, sensor.pins, "pins")
    _range(sensor.min_separation_mm, "sensor.min_separation_mm", 0, sensor.pad_diameter_mm, "mm")
    if sensor.preset:
        from pins import SENSOR_PRESETS

        _check(sensor.preset in SENSOR_PRESETS, "sensor.preset",
               f"must be one of {', '.join(SENSOR_PRESETS)}, got {sensor.preset!r}")
    _range(protocol.depth_min, "protocol.depth_min", 0, MAX_DEPTH_MM, "mm")
    _range(protocol.depth_max, "protocol.depth_max", 0, MAX_DEPTH_MM, "mm")
    _check(protocol.depth_max > protocol.depth_min, "protocol.depth_max",
           "must exceed protocol.depth_min (both >= 0)")
    _range(protocol.depth_step, "protocol.depth_step", 0, protocol.depth_max - protocol.depth_min, "mm", low_open=True)
    depths = int(math.floor((protocol.depth_max - protocol.depth_min) / protocol.depth_step + 1e-6)) + 1
    _check(depths <= MAX_DEPTHS, "protocol.depth_step",
           f"{protocol.depth_step:g} mm gives {depths} depths over {protocol.depth_min:g}..{protocol.depth_max:g} mm; "
           f"at most {MAX_DEPTHS} (a step of at least "
           f"{(protocol.depth_max - protocol.depth_min) / (MAX_DEPTHS - 1):.3g} mm)")
    _range(protocol.reference_height_mm, "protocol.reference_height_mm", -MAX_DEPTH_MM, MAX_DEPTH_MM, "mm")
    _range(protocol.samples, "protocol.samples", 2, MAX_SAMPLES, "samples")
    _range(protocol.repeats, "protocol.repeats", 1, MAX_REPEATS, "taps per depth")
    _range(protocol.lateral_jitter_mm, "protocol.lateral_jitter_mm", 0, 10, "mm")
    _range(protocol.seed, "protocol.seed", 0, MAX_SEED, "")
    if perception.decision_threshold is not None:
        _check(0 < perception.decision_threshold <= 1, "perception.decision_threshold",
               f"must be in (0, 1], got {perception.decision_threshold:g}")
    _check(perception.policy in POLICIES, "perception.policy",
           f"must be one of {', '.join(POLICIES)}, got {perception.policy!r}")
    _range(perception.max_taps, "perception.max_taps", 1, MAX_TAPS, "taps")
    _range(perception.locations, "perception.locations", 1, MAX_LOCATIONS, "depth classes")
    _range(perception.bins, "perception.bins", 2, MAX_BINS, "bins")
    _check(perception.likelihood in MODEL_KINDS, "perception.likelihood",
           f"must be one of {', '.join(MODEL_KINDS)}, got {perception.likelihood!r}")
    if perception.target_accuracy is not None:
        _check(not isinstance(perception.target_accuracy, bool) and isinstance(perception.target_accuracy, (int, float))
               and 0 < perception.target_accuracy <= 1, "perception.target_accuracy",
               f"must be a fraction in (0, 1], got {perception.target_accuracy!r}")
    if perception.start_depth is not None:
        _check(protocol.depth_min <= perception.start_depth <= protocol.depth_max, "perception.start_depth",
               f"must lie in the protocol's depth range {protocol.depth_min}..{protocol.depth_max} mm, "
               f"got {perception.start_depth:g}")
    if perception.fixation_depth is not None:
        _check(protocol.depth_min <= perception.fixation_depth <= protocol.depth_max,
               "perception.fixation_depth", f"must lie in the protocol's depth range "
               f"{protocol.depth_min}..{protocol.depth_max} mm, got {perception.fixation_depth:g}")
    _range(sim.noise_sigma, "sim.noise_sigma", 0, 255, "grey levels")
    _range(sim.seed, "sim.seed", 0, MAX_SEED, "")

    gaps = tuple(_gap(g, k) for k, g in enumerate(_gap_list(data)))
    names = [g.name for g in gaps]
    dupes = sorted({n for n in names if names.count(n) > 1})
    _check(not dupes, "gaps", f"duplicate gap names: {', '.join(dupes)}")
    low, high = arm.workspace_min_mm, arm.workspace_max_mm
    for k, g in enumerate(gaps):
        for axis, value in ((0, g.x), (1, g.y)):
            _check(low[axis] <= value <= high[axis], f"gaps[{k}].{'xy'[axis]}",
                   f"{value:g} mm lies outside the arm workspace {'xy'[axis]} {low[axis]:g}..{high[axis]:g} mm "
                   f"([arm] workspace)")
    taps = depths * protocol.repeats * len(gaps)
    _check(taps <= MAX_COLLECTION_TAPS, "protocol",
           f"asks for {taps} taps per collection ({depths} depths x repeats {protocol.repeats} x {len(gaps)} gaps); "
           f"at most {MAX_COLLECTION_TAPS}: raise protocol.depth_step or lower protocol.repeats")
    deepest = protocol.arm_depth_mm(protocol.depth_max)
    _check(deepest <= arm.max_tap_depth_mm, "protocol.depth_max",
           f"{protocol.depth_max} mm taps {deepest:g} mm below the surface, deeper than "
           f"arm.max_tap_depth {arm.max_tap_depth_mm:g} mm")
    _check(protocol.arm_depth_mm(protocol.depth_min) > -arm.tap.approach_height_mm, "protocol.depth_min",
           "puts the bottom of the tap above arm.tap.approach_height")

    data_dir = _path(station.get("data_dir", "station_data"), base_dir)
    results = _results_location(station.get("results", data_dir / "results.sqlite"), base_dir)
    _check(not data_dir.exists() or data_dir.is_dir(), "station.data_dir", f"'{data_dir}' is a file, not a folder")
    for folder in (results.parents if isinstance(results, Path) else ()):  # created if missing: a file in the way cannot be
        if folder.exists():
            _check(folder.is_dir(), "station.results", f"'{results}': '{folder}' is a file, not a folder")
            break
    return StationConfig(
        name=str(station.get("name", path.stem if path else "station")),
        results=results,
        data_dir=data_dir, sensor=sensor, arm=arm, gaps=gaps, protocol=protocol,
        perception=perception, sim=sim, path=path, raw=data,
    )


# -- helpers ------------------------------------------------------------------------------------

def _check(ok: bool, key: str, message: str) -> None:
    if not ok:
        raise ConfigError(f"{key} {message}")


def _range(value, key: str, low, high, unit: str, *, low_open: bool = False) -> None:
    """Refuse ``value`` outside ``[low, high]`` (``(low, high]`` with ``low_open``), naming the key and the range."""
    accepted = outside_range(value, low, high, low_open=low_open, unit=unit)
    if accepted:
        raise ConfigError(f"{key} {accepted}, got {value:g}")


def _read_toml(path: Path, what: str) -> dict:
    """The parsed TOML file at ``path``; `ConfigError` naming the path when it is missing, unreadable,
    not UTF-8 text or not valid TOML."""
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise ConfigError(f"{what} not found: {path}") from None
    except IsADirectoryError:
        raise ConfigError(f"{what} {path} is a folder, not a TOML file") from None
    except PermissionError:
        raise ConfigError(f"{what} {path}: permission denied") from None
    except OSError as exc:
        raise ConfigError(f"{what} {path}: cannot read ({exc.strerror or exc})") from None
    return parse_toml(raw, path, error=ConfigError)


def _no_unknown(table: dict, known: set[str], prefix: str) -> None:
    unknown = sorted(set(table) - known)
    if unknown:
        where = f"[{prefix}] " if prefix else ""
        raise ConfigError(f"{where}unknown key {', '.join(unknown)}; expected one of {', '.join(sorted(known))}")


def _table(data: dict, name: str, required: bool = False) -> dict:
    if name not in data:
        if required:
            raise ConfigError(f"missing table [{name}]")
        return {}
    if not isinstance(data[name], dict):
        raise ConfigError(f"{name} must be a table [{name}]")
    return data[name]


def _results_location(value, base_dir: Path) -> Path | str:
    """A ``postgresql://`` URL as given (str), otherwise an SQLite path against ``base_dir``."""
    text = str(value)
    if text.lower().startswith(("postgresql://", "postgres://")):
        return text
    if "://" in text:
        raise ConfigError(f"station.results must be a file path or a postgresql:// URL, got {text.split('://')[0]}://...")
    return _path(value, base_dir)


def _path(value, base_dir: Path) -> Path:
    p = Path(value).expanduser()
    return p if p.is_absolute() else (base_dir / p)


def _section(data: dict, name: str, cls, base_dir: Path, paths: set[str] = frozenset()):
    """Fill dataclass ``cls`` from table ``name``, type-checking each key against its default."""
    table = _table(data, name)
    fields = cls.__dataclass_fields__
    _no_unknown(table, set(fields), name)
    values = {}
    for key, value in table.items():
        default = fields[key].default
        if key in paths:
            if not isinstance(value, str) or not value.strip():
                raise ConfigError(f"{name}.{key} must be a path string, got {value!r}")
            values[key] = _path(value, base_dir)
        elif isinstance(default, bool):
            if not isinstance(value, bool):
                raise ConfigError(f"{name}.{key} must be true or false")
            values[key] = value
        elif isinstance(default, int) and not isinstance(default, bool):
            if isinstance(value, bool) or not isinstance(value, int):
                raise ConfigError(f"{name}.{key} must be a whole number, got {value!r}")
            values[key] = value
        elif isinstance(default, float) or default is None:
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                raise ConfigError(f"{name}.{key} must be a number, got {value!r}")
            values[key] = float(value)
        elif isinstance(default, str):
            if isinstance(value, int) and not isinstance(value, bool) and key == "source":
                _range(value, f"{name}.{key}", 0, MAX_CAMERA_INDEX, "(a camera index)")
                values[key] = str(value)
            elif not isinstance(value, str) or not value.strip():
                raise ConfigError(f"{name}.{key} must be a non-empty string, got {value!r}")
            else:
                values[key] = value
        else:  # pragma: no cover - every field has a typed default
            raise ConfigError(f"{name}.{key}: unsupported value {value!r}")
    return cls(**values)


def _gap_list(data: dict) -> list:
    gaps = data.get("gaps")
    if not gaps:
        raise ConfigError("no [[gaps]] to inspect: add at least one [[gaps]] table")
    if not isinstance(gaps, list) or not all(isinstance(g, dict) for g in gaps):
        raise ConfigError("gaps must be an array of tables [[gaps]]")
    return gaps


def _gap(table: dict, k: int) -> GapConfig:
    where = f"gaps[{k}]"
    _no_unknown(table, set(GapConfig.__dataclass_fields__), where)
    for key in ("x", "y", "nominal_width", "tolerance"):
        if key not in table:
            raise ConfigError(f"{where}.{key} is missing")
        value = table[key]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise ConfigError(f"{where}.{key} must be a number, got {value!r}")
    _range(table["nominal_width"], f"{where}.nominal_width", 0, MAX_GAP_MM, "mm", low_open=True)
    _range(table["tolerance"], f"{where}.tolerance", 0, MAX_GAP_MM, "mm")
    true_width = table.get("true_width")
    if true_width is not None:
        _check(not isinstance(true_width, bool) and isinstance(true_width, (int, float)) and
               math.isfinite(true_width), f"{where}.true_width", f"must be a number (mm), got {true_width!r}")
        _range(true_width, f"{where}.true_width", 0, MAX_GAP_MM, "mm", low_open=True)
    name = table.get("name", f"gap{k + 1:02d}")
    _check(isinstance(name, str) and bool(name.strip()), f"{where}.name", f"must be a non-empty string, got {name!r}")
    return GapConfig(name=name, x=float(table["x"]), y=float(table["y"]),
                     nominal_width=float(table["nominal_width"]), tolerance=float(table["tolerance"]),
                     true_width=None if true_width is None else float(true_width))


def default_sim_dir() -> Path:
    """Where the simulated station (``tactip inspect --sim``, ``serve --sim``) keeps its files unless told:
    ``$TACTIP_SIM_DIR``, else ``$XDG_DATA_HOME/tactip/sim`` (``~/.local/share/tactip/sim``): one place,
    whatever the current folder, so every run finds the model the first one trained."""
    import os

    if os.environ.get("TACTIP_SIM_DIR"):
        return Path(os.environ["TACTIP_SIM_DIR"]).expanduser().resolve()
    data_home = os.environ.get("XDG_DATA_HOME") or Path.home() / ".local" / "share"
    return (Path(data_home).expanduser() / "tactip" / "sim").resolve()


def simulated_station_config(data_dir: str | Path | None = None) -> StationConfig:
    """The packaged simulated station (``tactip inspect --sim``), keeping its files in ``data_dir``.

    The calibration, datasets, model and results database all live in ``data_dir`` (default
    `default_sim_dir`; a relative path is taken against the current folder), so a later run finds
    the model the first run trained.
    """
    data_dir = default_sim_dir() if data_dir is None else data_dir
    data = parse_toml(SIM_PRESET.read_bytes(), SIM_PRESET, error=ConfigError)
    data_dir = Path(data_dir).expanduser().resolve()
    data["station"]["data_dir"] = str(data_dir)
    data["station"]["results"] = str(data_dir / "results.sqlite")
    data["perception"]["model"] = str(data_dir / "model.h5")
    return parse_station_config(data, base_dir=data_dir, path=SIM_PRESET)
