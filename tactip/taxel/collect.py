"""Simulated taxel datasets: the data collection of paper 000 written in the ``tactip-dataset/1`` format.

The robot sweeps the sensor over its location range in small steps, one tap per step (paper 000:
0.01 mm steps, 3000 taps over the fingertip's 30 mm, 5000 over the skin's 50 mm), and the whole
collection is done twice, giving independent training and test sets on the same sensor. The task is
pure localisation: every tap has the same identity (0.0, unit ``"none"``).
"""

from __future__ import annotations

import pathlib
from dataclasses import dataclass

import numpy as np

from _shared.ranges import MAX_TAXEL_TAPS
from perception.dataset import Dataset, save_dataset

from tactip.taxel.sensors import TaxelSensor
from tactip.taxel.sim import TaxelSimulator, sweep_locations
from tactip.taxel.sources import write_taxel_csv

__all__ = ["DEFAULT_TAPS", "MAX_TAPS", "TaxelDatasetPaths", "simulate_taxel_dataset", "simulate_taxel_datasets",
           "write_taxel_test_stream", "simulate_stimulus_dataset"]

#: Taps per collection in paper 000 (0.01 mm steps over the sensor's range).
DEFAULT_TAPS = {"fingertip": 3000, "skin": 5000}
#: Most taps per collection (locations x taps per location): 20 times the paper's skin collection,
#: about a minute per 50000 taps and 1 GB per file.
MAX_TAPS = MAX_TAXEL_TAPS  # taps per collection


def simulate_taxel_dataset(simulator: TaxelSimulator, locations_mm, *, seed=None, collection: str = "",
                           progress=None) -> Dataset:
    """Collect one simulated dataset: a tap at each location, pre-processed, labelled in mm.

    Parameters
    ----------
    simulator : TaxelSimulator
    locations_mm : (N,) array_like
        Commanded location of each tap, mm, in collection order.
    seed : int or sequence of int, optional
        Noise seed of this collection (`TaxelSimulator.stream`).
    collection : str
        Name stored in the sensor description (e.g. ``"train"``).
    progress : callable, optional
        Called with the number of taps done.

    Returns
    -------
    Dataset
        ``front_end="taxel"``, taps ``(N, 50, K)`` float32 (pressure, fraction of full scale),
        location in mm, identity 0.0 (unit ``"none"``).
    """
    locations = np.asarray(locations_mm, dtype=np.float64).reshape(-1)
    taps = simulator.taps(locations, seed=seed, progress=progress)
    sensor: TaxelSensor = simulator.sensor
    description = {
        **sensor.describe(),
        "simulated": True,
        "simulator_seed": simulator.seed,
        "collection": collection,
        "units": "pressure, fraction of 8-bit full scale (high-pass filtered, per-tap baseline removed)",
    }
    return Dataset(taps, locations, np.zeros(len(locations)), None, "taxel", location_unit="mm",
                   identity_unit="none", dim_names=sensor.dim_names, sensor=description)


@dataclass(frozen=True)
class TaxelDatasetPaths:
    """Files written by `simulate_taxel_datasets`."""

    train: pathlib.Path
    test: pathlib.Path


def simulate_taxel_datasets(out_dir, *, sensor: str = "fingertip", seed: int = 0, locations: int | None = None,
                            taps_per_location: int = 1, quiet: bool = True) -> TaxelDatasetPaths:
    """Simulate the two collections of paper 000 and write ``train.h5`` and ``test.h5``.

    Parameters
    ----------
    out_dir : str or os.PathLike
        Output folder, created if missing.
    sensor : str
        ``"fingertip"`` (30 mm range, rod) or ``"skin"`` (50 mm range, sphere).
    seed : int
        Seed of the simulated sensor; the two collections use the noise seeds ``(seed, 2)`` (train) and
        ``(seed, 3)`` (test).
    locations : int, optional
        Locations per collection, evenly spaced over the range (default: the paper's 3000 / 5000).
    taps_per_location : int
        Taps at each location.
    quiet : bool
        Hide the progress bars.

    Returns
    -------
    TaxelDatasetPaths

    Examples
    --------
    >>> paths = simulate_taxel_datasets("data/fingertip", sensor="fingertip", seed=1)   # doctest: +SKIP
    """
    from _shared.progress import progress_bar as tqdm

    simulator, where = _plan(sensor, seed, locations, taps_per_location)
    out = pathlib.Path(out_dir)
    paths = TaxelDatasetPaths(out / "train.h5", out / "test.h5")
    for path in (paths.train, paths.test):
        _refuse_replacing_other_data(path)
    out.mkdir(parents=True, exist_ok=True)
    for index, (name, path) in enumerate((("train", paths.train), ("test", paths.test))):
        with tqdm(total=len(where), unit="tap", desc=f"{sensor} {name}", disable=quiet, leave=False) as bar:
            def advance(done, bar=bar):
                bar.update(done - bar.n)
            dataset = simulate_taxel_dataset(simulator, where, seed=_noise_seed(seed, name), collection=name,
                                             progress=advance)
        save_dataset(path, dataset)
    return paths


def _refuse_replacing_other_data(path: pathlib.Path) -> None:
    """`TactipError` when ``path`` exists and is not an earlier taxel simulation (collected data is never replaced)."""
    import json

    import h5py

    from tactip.errors import TactipError

    if not path.exists():
        return
    what = "a file that is not a dataset"
    try:
        with h5py.File(path, "r") as f:
            front_end = f.attrs.get("front_end")
            front_end = front_end.decode() if isinstance(front_end, bytes) else front_end
            sensor = json.loads(f.attrs.get("sensor", "{}"))
            if front_end == "taxel" and isinstance(sensor, dict) and "simulator_seed" in sensor:
                return  # an earlier simulation: simulating again replaces it
            what = f"a {front_end!r} dataset" if front_end else what
    except (OSError, ValueError, TypeError):
        pass
    raise TactipError(f"{path} already holds {what}, not a taxel simulation: simulating would replace it; "
                      f"choose another --out folder")


def write_taxel_test_stream(path, *, sensor: str = "fingertip", seed: int = 0, locations: int | None = None,
                            taps_per_location: int = 1) -> pathlib.Path:
    """Write the raw readings of the test collection of `simulate_taxel_datasets` as a CSV recording.

    The same arguments give the very readings ``test.h5`` was made from, so the file exercises the
    recorded-data path (`CsvTaxelSource`, `segment_taps`) against a known dataset.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    simulator, where = _plan(sensor, seed, locations, taps_per_location)
    stream = simulator.stream(where, seed=_noise_seed(seed, "test"))
    write_taxel_csv(path, stream.timestamps_s, stream.readings)
    return pathlib.Path(path)


def _plan(sensor: str, seed: int, locations: int | None, taps_per_location: int):
    """The simulator and the sweep of locations of one collection."""
    simulator = TaxelSimulator(sensor, seed=seed)
    n = DEFAULT_TAPS.get(simulator.sensor.name, 3000) if locations is None else int(locations)
    if int(taps_per_location) < 1 or n * int(taps_per_location) > MAX_TAPS:
        raise ValueError(f"locations x taps_per_location must be in 1..{MAX_TAPS} taps per collection, got "
                         f"{n} x {taps_per_location}")
    return simulator, sweep_locations(simulator.sensor, n, taps_per_location=taps_per_location)


def _noise_seed(seed: int, collection: str) -> tuple[int, int]:
    return (int(seed), {"train": 2, "test": 3}[collection])


def simulate_stimulus_dataset(stimulus, *, seed: int = 0, collection: str = "train", taps_per_identity: int,
                              identities=None, progress=None) -> Dataset:
    """Collect one session of a paper's stimulus (`tactip.reproduce.stimuli`): a sweep per identity.

    For each identity the fingertip taps at ``taps_per_identity`` evenly spaced locations over the
    stimulus's range (paper 001: 320 taps over 16 mm per rod; 003: 150 over 3 mm per texture; 004:
    90 over 18 mm per edge angle). The training and test collections are separate sessions: each
    draws its own session constants (rod placement and indentation, `Stimulus.session`) and noise.

    Parameters
    ----------
    stimulus : tactip.reproduce.stimuli.Stimulus
    seed : int
        Seed of the simulated sensor (gains, rest levels); the session and noise seeds follow from
        it and ``collection``.
    collection : {"train", "test"}
    taps_per_identity : int
    identities : sequence of float, optional
        A subset of the stimulus's identities (default all).
    progress : callable, optional

    Returns
    -------
    Dataset
        ``front_end="taxel"``, location in mm, identity in the stimulus's unit.
    """
    identities = np.asarray(stimulus.identities if identities is None else identities, dtype=np.float64)
    if int(taps_per_identity) < 2 or len(identities) * int(taps_per_identity) > MAX_TAPS:
        raise ValueError(f"taps_per_identity must be >= 2 with at most {MAX_TAPS} taps in all, got {taps_per_identity}")
    simulator = TaxelSimulator(stimulus.sensor, seed=seed, **stimulus.tap)
    lo, hi = stimulus.location_range_mm
    step = (hi - lo) / int(taps_per_identity)
    sweep = lo + step * (np.arange(int(taps_per_identity)) + 0.5)
    location = np.tile(sweep, len(identities))
    identity = np.repeat(identities, len(sweep))
    session = stimulus.session(np.random.default_rng([int(seed), _noise_seed(seed, collection)[1], 7]))

    def field(x, rows):
        return stimulus.field(x, identity[rows], session), stimulus.contact_delay_s(x, identity[rows])

    taps = simulator.taps(location, seed=_noise_seed(seed, collection), progress=progress, field=field)
    description = {**stimulus.sensor.describe(), **stimulus.describe(), "simulated": True, "simulator_seed": seed,
                   "collection": collection, "units": "pressure, fraction of 8-bit full scale"}
    return Dataset(taps, location, identity, None, "taxel", location_unit="mm", identity_unit=stimulus.identity_unit,
                   dim_names=stimulus.sensor.dim_names, sensor=description)
