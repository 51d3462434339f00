"""Where a simulated station tap's CPU goes (ms/tap): render, reference-pin placement, tracker start
(and its rest-noise scatter), tracking; the station's taps dominate `make test`.

Calibrates the packaged simulated station in a temporary folder, then taps its gaps at depths over
0-5.5 mm (seeded) in one process and reports CPU time (`time.process_time`) per tap, whole and by part
(the parts are timed by wrapping the functions the station calls; what is left is the arm, features
and glue). Use it to compare two trees: run it from each, interleaved, and say how loaded the machine
was (``uptime``).

    python bench/bench_tap_parts.py [--taps N]
"""

from __future__ import annotations

import argparse
import tempfile
import time
import tomllib
from collections import defaultdict
from pathlib import Path

import numpy as np


def _timed(owner, name: str, spent: dict, label: str) -> None:
    """Replace ``owner.name`` with a wrapper adding its CPU seconds to ``spent[label]``."""
    function = getattr(owner, name)

    def wrapper(*args, **kwargs):
        start = time.process_time()
        try:
            return function(*args, **kwargs)
        finally:
            spent[label] += time.process_time() - start

    setattr(owner, name, wrapper)


def main() -> None:
    """Run the benchmark and print its figures."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--taps", type=int, default=48, help="taps timed (after one warm-up tap)")
    args = parser.parse_args()

    import cv2

    import calibration
    import pins._rest
    import pins.track
    from tactip.sim import _render
    from tactip.sim.synthetic import SyntheticTacTip
    from tactip.station import station as station_module
    from tactip.station.config import SIM_PRESET, parse_station_config
    from tactip.station.procedures import calibrate_station

    cv2.setNumThreads(1)
    folder = Path(tempfile.mkdtemp(prefix="bench_tap_parts_"))
    table = tomllib.loads(SIM_PRESET.read_text())
    table["station"].update(data_dir=str(folder), results=str(folder / "results.sqlite"))
    table["perception"]["model"] = str(folder / "model.h5")
    config = parse_station_config(table, base_dir=folder)
    calibration_, _ = calibrate_station(config, log=lambda line: None)

    spent: dict = defaultdict(float)
    parts = [(SyntheticTacTip, "render", "render (camera frames)"),
             (_render, "expose", "  of which camera noise (expose)"),
             (SyntheticTacTip, "_draw", "  of which scene drawn (_draw)"),
             (calibration, "place_reference_pins", "reference pins placed (detect_pins)"),
             (pins.track.PinTracker, "start", "tracker start (rest frame)"),
             (pins._rest._AtRest, "_noise_scatter_sq_px2", "  of which rest-noise scatter"),
             (pins._rest, "noise_sigma", "    of which noise_sigma"),
             (pins.track, "surround_pixels", "  of which surround pixels"),
             (pins.track.PinTracker, "update", "tracking (later frames)")]
    for owner, name, label in parts:
        _timed(owner, name, spent, label)
    with station_module.Station(config, calibration=calibration_) as station:
        station.tap(config.gaps[0], 2.0, seed=0)
        spent.clear()
        start = time.process_time()
        for k, depth in enumerate(np.linspace(0.0, 5.5, args.taps)):
            station.tap(config.gaps[k % len(config.gaps)], float(depth), seed=1000 + k)
        total = time.process_time() - start
    print(f"{args.taps} simulated station taps (331 pins, 640x480), one process: "
          f"{1e3 * total / args.taps:.1f} ms CPU per tap")
    for _, _, label in parts:
        print(f"  {label:<40} {1e3 * spent[label] / args.taps:6.1f} ms/tap")
    print(f"  {'the rest (arm, features, glue)':<40} "
          f"{1e3 * (total - sum(v for k, v in spent.items() if not k.startswith('  '))) / args.taps:6.1f} ms/tap")


if __name__ == "__main__":
    main()
