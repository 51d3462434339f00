"""How close pin-centre RMSE is to the noise limit on radial-led-120 (issue 20): the Cramer-Rao bound.

For each seed (rest and a 5 mm tap) prints, px:

- bound:      the Cramer-Rao lower bound on the RMSE of an unbiased centre estimate from the preset's
              camera noise: per visible pin, Fisher information I = J^T J / sigma^2 over the pixels of
              its tip (within the tip radius + 2 px), with J the noise-free render's change as every tip
              moves by +-`STEP_PX` and nothing else does (the membrane, its light and the reflections stay);
              the bound is sqrt(mean over pins of trace(I^-1)). The tip's level and the membrane are
              treated as known, so the true bound is, if anything, higher;
- measured:   `find_pin_field`'s centres against the renderer's ground truth (matched pins);
- from truth: `pins._tipfit.fit_tip_centres` started from the true centres (what the tip fit reaches
              when detection is perfect).

Measured and from-truth near each other and above the bound by well under 2x: the centres are at the
noise limit of a per-pin estimate, and a lower RMSE needs a prior across pins (a smooth displacement
field), not a better tip fit. Also prints the time of `probe_lattice_holes` and `flat_pins` per
preset (the checks `find_pin_field` added for this pad) beside find_pin_field's own, ms, mean of 3 runs.

(Session 23: the moved renders drop the sensor's cached scene, which had made every one the first one since the
renders were cached, and the bound a singular matrix.) Seeds 0-35: bound 0.083-0.093 per frame; the field 0.086-0.148
at rest, 0.092-0.126 tapped (`bench_detect_seeds.py`).

Run: .venv/bin/python bench/bench_tip_bound.py [--seeds N]
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

import pins.lattice as lattice  # noqa: E402
from pins import find_pin_field  # noqa: E402
from pins._tipfit import fit_tip_centres  # noqa: E402
from tactip.sim import Contact, SyntheticTacTip, preset_names  # noqa: E402
from tactip.sim import _render  # noqa: E402
from tests.pins.conftest import score  # noqa: E402

TAP = Contact(indentation_mm=5.0, gap_width_mm=2.0)
# Tips moved by +-this, px, for the central difference: 0.5 spreads the blurred edge's slope (0.095 px
# on seed 0 at rest), 0.25 / 0.1 / 0.05 give 0.090 / 0.087 / 0.083 (the last inflated by the uint8 steps).
STEP_PX = 0.1


def moved_tips(quiet: SyntheticTacTip, contact, shift_px) -> np.ndarray:
    """The noise-free render with every pin tip moved by `shift_px` (dx, dy) and nothing else (the
    membrane, its light and the reflections stay), as float64."""
    paint = _render.paint_pins

    def shifted(scene, image_size, centres, shape, levels):
        paint(scene, image_size, np.asarray(centres) + np.asarray(shift_px, np.float64), shape, levels)

    _render.paint_pins = shifted
    # (The sensor keeps its last scene per contact: dropped, so the tips are painted again where moved.)
    quiet._scenes.clear()
    try:
        return quiet.render(contact).image.astype(np.float64)
    finally:
        _render.paint_pins = paint
        quiet._scenes.clear()


def cramer_rao_rmse_px(quiet: SyntheticTacTip, contact, centres: np.ndarray, reach_px: float,
                       noise_sigma: float) -> float:
    """Cramer-Rao bound on centre RMSE, px, for the tips at `centres` (N, 2) of `quiet`'s noise-free render.

    The image's change as the tips move (J, per pixel within `reach_px` of a centre) is the central
    difference of renders with every tip moved by +-`STEP_PX` (tips do not overlap, so each window sees
    its own tip move); I = J^T J / noise_sigma^2 per tip.
    """
    step = STEP_PX
    jx = (moved_tips(quiet, contact, (step, 0.0)) - moved_tips(quiet, contact, (-step, 0.0))) / (2 * step)
    jy = (moved_tips(quiet, contact, (0.0, step)) - moved_tips(quiet, contact, (0.0, -step))) / (2 * step)
    half = int(np.ceil(reach_px))
    dy, dx = np.mgrid[-half:half + 1, -half:half + 1]
    inside = np.hypot(dx, dy) <= reach_px
    dx, dy = dx[inside], dy[inside]
    x = np.clip(np.rint(centres[:, 0, None]) + dx, 0, jx.shape[1] - 1).astype(int)
    y = np.clip(np.rint(centres[:, 1, None]) + dy, 0, jx.shape[0] - 1).astype(int)
    ax, ay = jx[y, x], jy[y, x]  # (N, P)
    info = np.stack([np.stack([(ax * ax).sum(1), (ax * ay).sum(1)], -1),
                     np.stack([(ax * ay).sum(1), (ay * ay).sum(1)], -1)], -2) / noise_sigma ** 2
    trace = np.trace(np.linalg.inv(info), axis1=1, axis2=2)
    return float(np.sqrt(np.mean(trace)))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=12, help="seeds 0..N-1 (default 12)")
    seeds = range(parser.parse_args().seeds)
    print("radial-led-120: centre RMSE, px")
    print(f"{'seed':>4} {'contact':>7} {'bound':>7} {'measured':>9} {'from truth':>11}")
    for seed in seeds:
        sensor = SyntheticTacTip.from_preset("radial-led-120", seed=seed)
        # No noise and no shimmer: the renders differ only where the tips moved.
        quiet = SyntheticTacTip.from_preset("radial-led-120", seed=seed, noise_sigma=0.0, shimmer=0.0)
        for contact in (None, TAP):
            sensor.reseed_noise(seed)
            frame = sensor.render(contact)
            truth = frame.centres[frame.visible]
            bound = cramer_rao_rmse_px(quiet, contact, truth, sensor.pin_radius_px + 2.0, sensor.noise_sigma)
            _, _, measured = score(find_pin_field(frame.image).centres, frame, gate_px=3.0)
            fitted = fit_tip_centres(frame.image, truth, sensor.pin_radius_px)
            from_truth = float(np.sqrt(np.mean(np.sum((fitted - truth) ** 2, axis=1))))
            print(f"{seed:>4} {'tap' if contact else 'rest':>7} {bound:7.3f} {measured:9.3f} {from_truth:11.3f}",
                  flush=True)
    print("\nfind_pin_field's added checks, ms per find_pin_field (mean of 3, rest frame, seed 0)")
    for name in preset_names():
        frame = SyntheticTacTip.from_preset(name, seed=0).render()
        spent = {"probe_lattice_holes": [], "flat_pins": []}
        originals = {key: getattr(lattice, key) for key in spent}

        def timed(key):
            def run(*args, **kwargs):
                start = time.perf_counter()
                out = originals[key](*args, **kwargs)
                spent[key].append(1e3 * (time.perf_counter() - start))
                return out
            return run

        try:
            for key in spent:
                setattr(lattice, key, timed(key))
            start = time.perf_counter()
            for _ in range(3):
                find_pin_field(frame.image)
            whole = 1e3 * (time.perf_counter() - start) / 3
        finally:
            for key, original in originals.items():
                setattr(lattice, key, original)
        # One call per polarity searched: the sum per find_pin_field.
        per = {key: sum(v) / 3 for key, v in spent.items()}
        print(f"{name:>16}: probe {per['probe_lattice_holes']:6.1f}  flat {per['flat_pins']:6.1f}  "
              f"find_pin_field {whole:7.1f}")


if __name__ == "__main__":
    main()
