"""The data collection protocol: training and test taps over every gap and depth, resumable.

Paper 002 (III-A.2): each gap is tapped over the depth range at a fixed step (0-5.5 mm at
0.05 mm), and everything is collected twice, to give independent training and test sets. The plan
is a fixed, ordered list of taps per set; each tap carries its own seed (for the lateral jitter of
the tap point and, on the simulated station, its camera noise), so the plan and every tap in it
depend only on the configuration, never on what ran before.

Each tap is appended to its dataset (`perception.DatasetWriter`) the moment it is taken and the
file is flushed, so a crash or Ctrl-C loses at most the tap in progress; rerunning the same
collection skips the taps already stored and continues where it stopped, giving the same files
as an uninterrupted run.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, Sequence

import numpy as np

from perception import DatasetWriter

from .errors import CalibrationError

__all__ = ["PlannedTap", "collection_plan", "collect_datasets", "tap_seed", "SETS"]

SETS = ("train", "test")


@dataclass(frozen=True)
class PlannedTap:
    """One tap of the collection plan.

    Attributes
    ----------
    set : str
        ``"train"`` or ``"test"``.
    index : int
        Position in its set's plan (0-based): the row it gets in the dataset.
    gap : object
        The gap to tap (the station's gap configuration: ``name``, ``x``, ``y``, ``nominal_width``).
    depth_mm : float
        Protocol depth, mm (the dataset's ``location``).
    width_mm : float
        Known width of the gap, mm (the dataset's ``identity``).
    repeat : int
        Repeat number at this gap and depth.
    lateral_mm : float
        Lateral offset of the tap point across the gap, mm (uniform in [-jitter, jitter]).
    seed : int
        The tap's own seed.
    """

    set: str
    index: int
    gap: object
    depth_mm: float
    width_mm: float
    repeat: int
    lateral_mm: float
    seed: int


def tap_seed(*keys) -> int:
    """A 63-bit seed that depends only on ``keys`` (ints and strings)."""
    words = []
    for key in keys:
        if isinstance(key, (int, np.integer)):
            words.append(int(key))
        else:
            words.extend(str(key).encode())
    return int(np.random.SeedSequence(words).generate_state(1, np.uint64)[0] >> np.uint64(1))


def collection_plan(gaps: Sequence, depths: Sequence[float], *, repeats: int = 1, lateral_jitter_mm: float = 0.0,
                    seed: int = 0, sets: Sequence[str] = SETS) -> dict[str, list[PlannedTap]]:
    """The ordered taps of each set: for each gap, each depth, each repeat.

    Parameters
    ----------
    gaps : sequence of gap configurations
        Each with ``name`` and ``nominal_width`` (mm), the known width of a training gap.
    depths : sequence of float
        Protocol depths, mm.
    repeats : int
        Taps per gap and depth in each set.
    lateral_jitter_mm : float
        Half-width of the uniform lateral placement jitter, mm (paper 002 Fig. 11).
    seed : int
        Seed of the whole plan.
    sets : sequence of str
        Names of the independent collections.

    Returns
    -------
    dict of set name -> list of PlannedTap
    """
    if not gaps:
        raise CalibrationError("no gaps to collect on")
    if len(depths) == 0:
        raise CalibrationError("no depths to collect at")
    if repeats < 1:
        raise CalibrationError(f"repeats must be at least 1, got {repeats}")
    plan = {}
    for set_name in sets:
        taps = []
        for g, gap in enumerate(gaps):
            for d, depth in enumerate(depths):
                for r in range(repeats):
                    s = tap_seed(seed, set_name, g, d, r)
                    lateral = 0.0
                    if lateral_jitter_mm > 0:
                        lateral = float(np.random.default_rng(s).uniform(-lateral_jitter_mm, lateral_jitter_mm))
                    taps.append(PlannedTap(set_name, len(taps), gap, float(depth), float(gap.nominal_width), r,
                                           lateral, s))
        plan[set_name] = taps
    return plan


def collect_datasets(tap: Callable[[PlannedTap], np.ndarray] | None, plan: dict[str, list[PlannedTap]], out_dir: str | Path,
                     *, samples: int, dims: int, dim_names: Sequence[str] = (), sensor: dict | None = None,
                     front_end: str = "tactip", progress: bool = True,
                     tap_many: Callable[[Iterable[PlannedTap]], Iterable[np.ndarray]] | None = None,
                     protocol: dict | None = None) -> dict[str, Path]:
    """Take the planned taps and append each to ``out_dir/<set>.h5``, resuming stored ones.

    Parameters
    ----------
    tap : callable(PlannedTap) -> (samples, dims) ndarray, or None
        Takes one tap (moves the arm, captures, extracts features); None when ``tap_many`` is given.
    plan : dict of set name -> list of PlannedTap
        From `collection_plan`.
    out_dir : path
        Folder of the datasets.
    samples, dims : int
        Shape of a tap's features.
    dim_names : sequence of str
        Names of the feature dimensions.
    sensor : dict
        Sensor description stored in the datasets; a rerun must match it.
    front_end : str
        ``"tactip"`` or ``"taxel"``.
    progress : bool
        Show a progress bar with ETA (tqdm, on stderr).
    tap_many : callable(iterable of PlannedTap) -> iterable of features, optional
        An ordered, lazy map over taps (e.g. the simulated station rendering on several cores);
        ``map(tap, ...)`` when omitted.
    protocol : dict, optional
        The settings the plan was made from (seed, depths, repeats, ...), stored in the datasets: a
        rerun with other settings is refused, naming the setting, rather than mixing two collections.

    Returns
    -------
    dict of set name -> dataset path
    """
    from _shared.progress import progress_bar as tqdm

    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    if (tap is None) == (tap_many is None):
        raise ValueError("give exactly one of tap and tap_many")
    mapper = tap_many or (lambda planned: map(tap, planned))
    paths = {}
    writers = {}
    try:
        for set_name, taps in plan.items():
            path = out_dir / f"{set_name}.h5"
            writers[set_name] = DatasetWriter(path, samples=samples, dims=dims, front_end=front_end,
                                              location_unit="mm", identity_unit="mm", dim_names=tuple(dim_names),
                                              sensor=sensor or {}, protocol=protocol)
            if writers[set_name].count > len(taps):
                raise CalibrationError(f"{path} holds {writers[set_name].count} taps but the plan has {len(taps)}: "
                                       f"it belongs to another protocol (use another --out)")
            _check_stored_labels(path, writers[set_name].labels(), taps)
            paths[set_name] = path
        total = sum(len(taps) for taps in plan.values())
        done = sum(w.count for w in writers.values())
        bar = tqdm(total=total, initial=done, unit="tap", desc="collect", disable=not progress, dynamic_ncols=True)
        with bar:
            for set_name, taps in plan.items():
                writer = writers[set_name]
                todo = taps[writer.count:]
                for planned, features in zip(todo, mapper(todo)):
                    writer.append(features, planned.depth_mm, planned.width_mm, planned.lateral_mm)
                    bar.set_postfix_str(f"{set_name} {planned.gap.name} {planned.depth_mm:.2f} mm", refresh=False)
                    bar.update(1)
    finally:
        for writer in writers.values():
            writer.close()
    return paths


def _check_stored_labels(path: Path, labels: dict, taps: Sequence[PlannedTap]) -> None:
    """The taps already stored must be the plan's first taps (depth, width, lateral offset), else refuse."""
    n = len(labels["location"])
    if n == 0:
        return
    planned = {"location": np.array([t.depth_mm for t in taps[:n]]), "identity": np.array([t.width_mm for t in taps[:n]]),
               "lateral": np.array([t.lateral_mm for t in taps[:n]])}
    names = {"location": "depth (mm)", "identity": "width (mm)", "lateral": "lateral offset (mm)"}
    for key, stored in labels.items():
        bad = np.flatnonzero(~np.isclose(stored, planned[key], rtol=0, atol=1e-9))
        if bad.size:
            k = int(bad[0])
            raise CalibrationError(f"{path}: stored tap {k} has {names[key]} {stored[k]:g} but the plan has "
                                   f"{planned[key][k]:g}: the file belongs to another protocol (seed, gaps or "
                                   f"depths changed); restore the settings or collect into another folder")
