"""Station procedures: calibrate the sensor and collect the training and test taps.

These compose a `Station` (arm + camera + front end) with the `calibration` package (which knows
the protocol but no hardware). The CLI commands ``tactip calibrate`` and ``tactip collect`` call
them; so can a script.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Callable, Iterable, Sequence

import numpy as np

from tactip.station.config import StationConfig
from tactip.errors import TactipError
from tactip.station.station import Station

__all__ = ["prepare_model", "model_is_prepared", "calibration_path", "calibrate_station", "load_station_calibration", "collect_station",
           "default_sim_workers",
           "sensor_description", "protocol_description"]


def calibration_path(config: StationConfig) -> Path:
    """Where the station's calibration file is: ``[sensor] calibration`` or ``data_dir/calibration.h5``."""
    return config.sensor.calibration or (config.data_dir / "calibration.h5")


def calibrate_station(config: StationConfig, *, rest_frames: int = 10, out: Path | None = None,
                      log: Callable[[str], None] = print):
    """Take rest frames off contact, tune detection, choose the feature pins, write the calibration file.

    Returns
    -------
    (calibration.SensorCalibration, Path)
        The calibration and the file it was written to.
    """
    from calibration import calibrate_sensor, save_calibration

    from tactip._output import refuse_overwriting_inputs

    out = Path(out) if out is not None else calibration_path(config)
    refuse_overwriting_inputs([out], [config.path, config.perception.model, config.results])
    with Station(config) as station:
        log(f"taking {rest_frames} rest frames off contact ...")
        frames = station.rest_frames(rest_frames)
    sensor = config.sensor
    calibration = calibrate_sensor(frames, expected_pins=sensor.pins, pad_diameter_mm=sensor.pad_diameter_mm,
                                   description=sensor.preset or None,  # the scale's pin pitch, as replay --sensor
                                   selected_pins=sensor.selected_pins, min_separation_mm=sensor.min_separation_mm,
                                   sensor={"source": sensor.source, "pins": sensor.pins, "station": config.name})
    save_calibration(out, calibration)
    log(f"calibrated: {calibration.describe()}")
    log(f"wrote {out}")
    return calibration, out


def load_station_calibration(config: StationConfig):
    """The station's calibration file, read and checked against ``[sensor]``."""
    from calibration import CalibrationError, load_calibration

    calibration = load_calibration(calibration_path(config))
    if calibration.expected_pins != config.sensor.pins:
        raise CalibrationError(f"{calibration_path(config)} was made for {calibration.expected_pins} pins but "
                               f"[sensor] pins = {config.sensor.pins}: run 'tactip calibrate' again")
    return calibration


def sensor_description(config: StationConfig, calibration) -> dict:
    """What datasets and models record about the sensor (a rerun must match it)."""
    return {"kind": "tactip", "pins": int(calibration.expected_pins), "selected_pins": calibration.n_selected,
            "min_separation_mm": float(calibration.min_separation_mm),
            "mm_per_px": round(float(calibration.mm_per_px), 6), "source": config.sensor.source,
            "samples": config.protocol.samples}


def protocol_description(config: StationConfig) -> dict:
    """The collection settings stored in the datasets: resuming with other settings is refused, naming them."""
    p = config.protocol
    return {"seed": int(p.seed), "depth_min": float(p.depth_min), "depth_max": float(p.depth_max),
            "depth_step": float(p.depth_step), "repeats": int(p.repeats),
            "lateral_jitter_mm": float(p.lateral_jitter_mm), "gaps": [g.name for g in config.gaps]}


def collect_station(config: StationConfig, out_dir: Path, *, progress: bool = True, workers: int | None = None,
                    log: Callable[[str], None] = print, sets: Sequence[str] = ("train", "test")) -> dict[str, Path]:
    """Collect ``out_dir/train.h5`` and ``out_dir/test.h5`` by the configured protocol (resumable).

    Parameters
    ----------
    config : StationConfig
    out_dir : Path
    progress : bool
        Progress bar with ETA.
    workers : int, optional
        Processes rendering taps on the simulated station (default: `default_sim_workers`, the CPU
        count, at most 4); a real station always taps one at a time.
    sets : sequence of str
        The collections to take (e.g. only ``("test",)``: a test set with lateral placement noise for
        paper 002 Fig. 11, beside a model trained without it).

    Returns
    -------
    dict of set name -> dataset path
    """
    from calibration import collect_datasets, collection_plan

    from tactip._output import refuse_overwriting_inputs

    refuse_overwriting_inputs([Path(out_dir) / f"{name}.h5" for name in sets],
                              [config.path, calibration_path(config), config.perception.model, config.results])
    calibration = load_station_calibration(config)
    p = config.protocol
    plan = collection_plan(config.gaps, p.depths, repeats=p.repeats, lateral_jitter_mm=p.lateral_jitter_mm,
                           seed=p.seed, sets=tuple(sets))
    total = sum(len(v) for v in plan.values())
    log(f"collecting {total} taps: {len(config.gaps)} gaps x {len(p.depths)} depths "
        f"({p.depth_min:g}-{p.depth_max:g} mm at {p.depth_step:g} mm) x {p.repeats} repeat(s) x {len(plan)} sets "
        f"into {out_dir}")
    dims = 2 * calibration.n_selected
    from pins import feature_dim_names

    common = dict(samples=p.samples, dims=dims, dim_names=feature_dim_names(calibration.n_selected),
                  sensor=sensor_description(config, calibration), progress=progress,
                  protocol=protocol_description(config))
    if workers is None:
        workers = default_sim_workers()
    if config.simulated and workers > 1:
        with _SimPool(config, calibration, workers) as pool:
            return collect_datasets(None, plan, out_dir, tap_many=pool.map, **common)
    with Station(config, calibration=calibration) as station:
        return collect_datasets(lambda t: station.tap(t.gap, t.depth_mm, lateral_mm=t.lateral_mm, seed=t.seed).features,
                                plan, out_dir, **common)


#: Fraction of decisions within the gaps' tolerance a calibrated model's threshold is chosen for.
DEFAULT_TARGET_ACCURACY = 0.95


# -- the simulated station on several processes ---------------------------------------------------

#: Environment variable that sets `default_sim_workers` (the test suite's conftest sets it to the CPUs
#: its pytest-xdist workers leave free: 1, no process pool, when they already use every core).
SIM_WORKERS_VARIABLE = "TACTIP_SIM_WORKERS"


def default_sim_workers() -> int:
    """Processes a simulated station's collection renders taps on unless told: ``$TACTIP_SIM_WORKERS``
    when set, else the CPU count, at most 4 (1 taps in this process, without a pool)."""
    value = os.environ.get(SIM_WORKERS_VARIABLE, "").strip()
    if not value:
        return min(os.cpu_count() or 1, 4)
    try:
        workers = int(value)
    except ValueError:
        workers = 0
    if workers < 1:
        raise TactipError(f"{SIM_WORKERS_VARIABLE}={value!r}: give a whole number of processes, 1 or more")
    return workers


_worker_station: Station | None = None


def _worker_init(config: StationConfig, calibration) -> None:
    import cv2

    cv2.setNumThreads(1)
    global _worker_station
    _worker_station = Station(config, calibration=calibration).__enter__()


def _worker_tap(planned) -> np.ndarray:
    return _worker_station.tap(planned.gap, planned.depth_mm, lateral_mm=planned.lateral_mm,
                               seed=planned.seed).features


class _SimPool:
    """Simulated stations in worker processes; `map` is ordered and lazy (results as they come)."""

    def __init__(self, config: StationConfig, calibration, workers: int):
        import multiprocessing

        if not config.simulated:
            raise TactipError("only the simulated station can tap in parallel")
        self._pool = multiprocessing.get_context("spawn").Pool(workers, initializer=_worker_init,
                                                               initargs=(config, calibration))

    def map(self, planned: Iterable) -> Iterable[np.ndarray]:
        """Features of each planned tap, in order."""
        return self._pool.imap(_worker_tap, list(planned), chunksize=1)

    def __enter__(self) -> "_SimPool":
        return self

    def __exit__(self, *exc) -> None:
        self._pool.terminate()
        self._pool.join()


def prepare_model(config: StationConfig, *, progress: bool = True, log: Callable[[str], None] = print) -> Path:
    """The whole calibration utility in one call: calibrate (unless calibrated), collect (resuming),
    train and pick the fixation depth, threshold and tempering on held-out folds of the training
    collection (`calibration.prepare_station_model`: no peeking at the test collection), then report
    the model's figures on the test collection, used once; returns the model path. ``tactip inspect --sim`` runs it on
    first use, and again after an interrupted first use (`model_is_prepared`).

    The model is trained and given its recommended settings under a temporary name and renamed into
    place only when both are done: an interruption (Ctrl-C, SIGTERM, a full disk) during training or
    the fixation sweep leaves no half-prepared model, and the next run resumes the preparation
    (the collected taps are kept and resumed, only training and the sweep are repeated).
    """
    from calibration import final_figures, prepare_station_model
    from perception import load_dataset

    from tactip._output import atomic_output

    model_path = config.perception.model
    if model_path is None:
        raise TactipError("no [perception] model path in the configuration")
    _require_model_kind(config.perception.likelihood)   # before any calibration or collection work
    if not calibration_path(config).exists():
        calibrate_station(config, log=log)
    paths = collect_station(config, config.data_dir / "datasets", progress=progress, log=log)
    p = config.perception
    target = p.target_accuracy
    if target is None and p.likelihood != "histogram":
        target = DEFAULT_TARGET_ACCURACY
    tolerance = min(g.tolerance for g in config.gaps)
    with atomic_output(model_path, inputs=list(paths.values())) as partial:
        log(f"training the model ({p.likelihood} likelihood) ...")
        model = prepare_station_model(paths["train"], partial, kind=p.likelihood, n_locations=p.locations,
                                      bins=p.bins, target_accuracy=target, tolerance=tolerance, max_taps=p.max_taps,
                                      log=log, progress=_progress(progress))
    # The test collection, used once: the figures of the model as the station will run it.
    log(final_figures(model, load_dataset(paths["test"]), tolerance=tolerance, max_taps=p.max_taps).describe(model))
    return model_path


def _progress(shown: bool):
    """The progress factory of the training and fixation sweep (`_shared.progress.progress_bar`), or None."""
    if not shown:
        return None
    import functools

    from _shared.progress import progress_bar

    return functools.partial(progress_bar, leave=False, desc="fixations", unit="fixation")


def _require_model_kind(kind: str) -> None:
    """Refuse, in one line, a kind the station cannot train here (torch not installed)."""
    if kind == "torch":
        from perception.learned import require_torch

        try:
            require_torch()
        except ImportError as exc:
            raise TactipError(f'[perception] likelihood = "torch": {exc}') from None


def model_is_prepared(path: Path) -> bool:
    """Whether ``path`` holds a model with its recommended settings (fixation depth and threshold).

    False for a missing file and for a model an interrupted preparation left without its settings
    (written by versions that trained in place); `load_model`'s errors propagate for a bad file.
    """
    from perception import load_model

    if not Path(path).exists():
        return False
    recommended = load_model(path).recommended
    return "decision_threshold" in recommended and "fixation_location" in recommended
