"""The pad scale (mm/px) against the renderer's truth, per preset and seed, with its bias split by cause.

`pins.sensor_scale` divides the sensor description's pitch (mm) by the central pin pitch measured in the
image (px); the renderer (`tactip.sim.SyntheticTacTip`) knows the true apex scale ``mm_per_px``, the true
pitch ``pin_spacing_mm`` and every pin's position. The ratio estimate / truth factors exactly into

- description:  the description's pitch / the renderer's pitch (mm);
- projection:   true apex pitch (px) / the estimator on the true pins of a layout without jitter (the dome
                seen from the camera, and the layout's own geometry: circles, spokes);
- jitter:       the estimator on the layout without jitter / on the true (jittered) pins (the renderer
                scatters every pin by 0.02 pitch: a nearest-neighbour distance, the least of ~6, is short);
- detection:    the estimator on the true visible pins / on the pins `find_pin_field` detects.

The layout without jitter is the same renderer with its lattice scaled by 1000 (the jitter, 0.02 lattice
units, then scatters by 2e-5 pitch). Stage 1 renders and caches the pin sets (``--cache``); stage 2 applies
each estimator to them, so estimators compare on the very same pins.

Session 21's detect21, small-pad-100 (issue 20's outcome 5; 100 pins 4.6 px apart, 1 px tips), seeds 0-35: total
+1.63 % [-1.01, +4.62], of which jitter +1.30 [-1.64, +4.55] and detection +0.28 [-1.30, +1.37] (tactip-127, the
same lattice and pitch: jitter +0.00 [-0.89, +0.83]); through bench_user_chain's webcam the pitch of the true
centres is already > 2 % off on 12 of 36 seeds, of the detected pins on 11. A better detector cannot mend it: the
estimator on the central third's few pins spreads by their 2 % scatter, and is biased by it here (not on
tactip-127: why is not known). Fitting the spacing
against radius^2 over half the field (to use more pins past the dome's foreshortening) put dense-1000 and tactip-532
5-6 % off: dropped.

Run: .venv/bin/python bench/bench_scale_truth.py [--seeds 0-39] [--presets a,b] [--cache /tmp/scale_pins.npz]
     [--estimators nearest,pitch]
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from pins import find_pin_field, sensor_preset  # noqa: E402
from pins import scale as _scale  # noqa: E402
from tactip.sim import SyntheticTacTip, preset_names  # noqa: E402
from tactip.sim import _pad  # noqa: E402
from tactip.sim import synthetic as _synthetic  # noqa: E402


def seed_range(text: str) -> list[int]:
    """'0-39' or '6,8,9' to a list of seeds."""
    if "-" in text:
        first, last = text.split("-")
        return list(range(int(first), int(last) + 1))
    return [int(s) for s in text.split(",")]


def _without_jitter(name: str, seed: int) -> np.ndarray:
    """Visible rest pins of the preset with the layout's jitter made negligible (lattice x 1000)."""
    hexagonal, radial = _pad.pin_lattice, _pad.radial_lattice
    _synthetic._pad.pin_lattice = lambda n: hexagonal(n) * 1000.0
    _synthetic._pad.radial_lattice = lambda n: radial(n) * 1000.0
    try:
        sensor = SyntheticTacTip.from_preset(name, seed=seed)
        centres, visible = sensor.pin_centres()
    finally:
        _synthetic._pad.pin_lattice, _synthetic._pad.radial_lattice = hexagonal, radial
    return centres[visible]


def collect(names, seeds) -> dict:
    """Per preset and seed: truth, pitches, and the three pin sets (no jitter, true, detected)."""
    out = {}
    for name in names:
        for seed in seeds:
            sensor = SyntheticTacTip.from_preset(name, seed=seed)
            centres, visible = sensor.pin_centres()
            field = find_pin_field(sensor.render().image)
            key = f"{name}/{seed}"
            out[key + "/truth"] = np.array([sensor.mm_per_px, sensor.pin_spacing_mm,
                                            sensor_preset(name).pitch_mm, *sensor.disc[:2]])
            out[key + "/nojitter"] = _without_jitter(name, seed)
            out[key + "/true"] = centres[visible]
            out[key + "/detected"] = field.centres
    return out


def nearest_spacing_px(rest: np.ndarray, fraction: float = 1.0 / 3.0) -> float:
    """The estimator before session 16's scale9: the median nearest-neighbour spacing of the central pins, px."""
    rest = rest[np.isfinite(rest).all(axis=1)]
    distance = np.hypot(*(rest - rest.mean(axis=0)).T)
    inner = distance <= fraction * distance.max()
    if inner.sum() < 7:
        inner = distance <= np.sort(distance)[min(6, len(rest) - 1)]
    return float(np.median(cKDTree(rest).query(rest[inner], k=2)[0][:, 1]))


ESTIMATORS = {"nearest": nearest_spacing_px, "pitch": _scale.central_spacing_px}


def report(data: dict, names, seeds, estimator: str) -> None:
    """One row per preset: mean (min, max) of each factor of estimate / truth, %."""
    measure = ESTIMATORS[estimator]
    print(f"\nestimator {estimator}: estimate / truth - 1, %: mean [min, max] over seeds "
          f"{seeds[0]}-{seeds[-1]} ({len(seeds)})")
    print(f"{'preset':16s} {'total':>22s} {'description':>12s} {'projection':>22s} {'jitter':>22s} "
          f"{'detection':>22s}")
    worst = 0.0
    for name in names:
        rows = []
        for seed in seeds:
            key = f"{name}/{seed}"
            truth, spacing, pitch_mm, *_ = data[key + "/truth"]
            apex_px = spacing / truth
            ideal, true, detected = (measure(data[f"{key}/{part}"]) for part in ("nojitter", "true", "detected"))
            factors = [pitch_mm / spacing, apex_px / ideal, ideal / true, true / detected]
            rows.append([np.prod(factors)] + factors)
        rows = (np.array(rows) - 1) * 100
        worst = max(worst, np.abs(rows[:, 0]).max())
        cells = [f"{c.mean():+6.2f} [{c.min():+6.2f},{c.max():+6.2f}]" for c in rows.T]
        print(f"{name:16s} {cells[0]:>22s} {rows[:, 1].mean():+12.2f} {cells[2]:>22s} {cells[3]:>22s} "
              f"{cells[4]:>22s}")
    print(f"worst |total|: {worst:.2f} %")


def main() -> None:
    """Collect (or load) the pin sets, then report each estimator."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="0-39")
    parser.add_argument("--presets", default=",".join(preset_names()))
    parser.add_argument("--cache", default="")
    parser.add_argument("--estimators", default=",".join(ESTIMATORS))
    parser.add_argument("--split", default="", help="report these seeds apart too, e.g. 20-39")
    args = parser.parse_args()
    names, seeds = args.presets.split(","), seed_range(args.seeds)
    cache = pathlib.Path(args.cache) if args.cache else None
    data = dict(np.load(cache)) if cache and cache.exists() else {}
    missing = [n for n in names if any(f"{n}/{s}/truth" not in data for s in seeds)]
    if missing:
        start = time.process_time()
        data.update(collect(missing, seeds))
        print(f"collected {len(missing)} presets x {len(seeds)} seeds: {time.process_time() - start:.0f} s CPU")
        if cache:
            np.savez(cache, **data)
    for estimator in args.estimators.split(","):
        report(data, names, seeds, estimator)
        if args.split:
            split = seed_range(args.split)
            report(data, names, [s for s in seeds if s not in split], estimator)
            report(data, names, split, estimator)


if __name__ == "__main__":
    main()
