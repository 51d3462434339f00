"""Detection without a count over many seeds: every preset, seeds 0-11, at rest and under the 5 mm tap.

The detection tests (tests/pins/test_lattice.py) hold the bars on seed 0; the guide asks every claim to
be judged over many seeds. For each preset of `tactip.sim.synthetic.PRESETS` and each seed this renders
the rest frame and the tests' 5 mm tap (`tests.pins.conftest.TAP`), runs `pins.find_pin_field` with no
count and the polarity decided, and scores it as the tests do (`tests.pins.conftest.score`, gate 3 px or
0.4 of the true pitch). Printed per preset: worst recall, precision, count error (detected - drawn) and
RMSE (px) over the seeds with the seed where each is worst, the frames failing the bars (recall and
precision >= 0.99, RMSE <= 0.1 px, polarity right) and the mean CPU time of one field search.

With ``--scale`` it also compares the mm/px of `tactip detect` (`pins.sensor_scale` on the field) with
`calibration.calibrate_sensor` on the rest frame of each seed (replay derives its scale through the same
`sensor_scale` path; tests/tactip/test_one_scale.py runs all three on seeds 0-1).

Figures on seeds 36-39, which no session had looked at (session 16's audit8, 2-core VM, ``--scale``,
1.6 min): every preset's recall and precision 1.000 at rest and tapped, the polarity right; the count
exact but for rim-ring-331 (up to 12 off, its partly hidden rim pins); RMSE <= 0.029 px except
radial-led-120's 0.101-0.130 px (5 of its 8 frames over the 0.1 px bar, as on the seeds before:
tests/pins/test_lattice.py's xfail). Detect and calibrate agree within 0.00 %; against the renderer's
apex scale detect is 0.4-0.8 % off on tactip-532 and dense-1000 but 4.2-5.2 % on the others (tactip-127
and brown-127 5.1-5.2 % on seed 36: over tests/tactip/test_one_scale.py's 5 %, which holds on its seeds
0-1); on seeds 6-15, 3.0-5.4 %.

Session 22's glare22 (brown-127's skin lit by the casing glare, between the outer ring and the rim, kept as pins:
`pins._judge._Neighbourhood.beyond_ring`), missed/false pins against the renderer's truth over every preset, main
fb192f9 -> glare22 (a script of this bench's kind: raw rest frames and the 5 mm tap as here, and webcam-like rest
frames as the user chain's, `bench_conditions.Camera` with `bench_user_chain.condition`, JPEG 75):
- seeds 0-35: brown-127 rest 0/9 -> 0/1, tap 0/8 -> 0/2, webcam 0/30 -> 0/0; every other preset the same
  before and after (rest and webcam: radial-led-120 4/0 and 38/4, small-pad-100 0/0 and 21/0, the others 0/0;
  tap: radial-led-120 4/0, small-pad-100 5/0, the others 0/0);
- held out, seeds 48-59: brown-127 rest 0/0 -> 0/0, webcam 0/3 -> 0/1; radial-led-120 and small-pad-100 the same
  (rest 1/0, 0/0; webcam 11/1, 10/0); every other preset 0/0 after;
- `bench_issue20_bars.py --bars agree --presets brown-127`, audit21's seeds 61, 63, 64: pins 128, 129, 129 ->
  128, 127, 127; seed 64 max 0.59 px (not met) -> 0.39 px (met).
Left: a glare blob beyond a corner of the outer ring (a true corner pin's edges run at 120 degrees too; its contrast
0.80-0.86 of its neighbours', as pins'): brown-127 seed 11 at rest and tapped; seed 7 tapped and the audit's
seed 61 keep one each too (not looked at).

Session 23's probe23 (tips a fit left beyond its reach fitted again where it ended, `pins._tipfit`): radial-led-120
seeds 0-35, the frames' RMSE (rms over frames) rest 0.1050 -> 0.1015 px, tapped 0.1098 -> 0.1051, worst frame 0.177 ->
0.148 (seed 9 at rest, a probed tip 1.3 px off its truth) and 0.169 -> 0.126; frames over 0.1 px 20 -> 16 and 26 ->
25 of 36; held out 48-59: 0.0996 -> 0.0997, 0.1034 -> 0.1029, 5 -> 5 and 9 -> 8 of 12. Fitted from the true centres
0.097 and 0.103 (12 and 21 frames over): the bar of 0.1 px on every frame lies at the noise limit of a fit per pin
(`bench_tip_bound.py`: 0.083-0.093 per frame with the membrane and tip level known); the faint outer ring (a sixth of
the pins, 0.15-0.16 px, at 1.2 times its bound) carries a third of the squared error. Every other preset's fields the
same to 0.1 mpx (seeds 0-11: recall, precision and worst RMSE as before).

Run: .venv/bin/python bench/bench_detect_seeds.py [--seeds 0-11] [--presets a,b] [--scale] [--failures]
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))

from pins import find_pin_field  # noqa: E402
from tactip.sim import SyntheticTacTip, preset_names  # noqa: E402
from tests.pins.conftest import TAP, score  # noqa: E402

CONTACTS = {"rest": None, "tap5mm": TAP}


def gate_px(frame) -> float:
    """The tests' matching gate: 3 px, or 0.4 of the true pitch on dense or small pads."""
    centres = frame.centres[frame.visible]
    distance, _ = cKDTree(centres).query(centres, 2)
    return min(3.0, 0.4 * float(np.median(distance[:, 1])))


def seed_range(text: str) -> list[int]:
    """'0-11' or '0,3,5' to a list of seeds."""
    if "-" in text:
        first, last = text.split("-")
        return list(range(int(first), int(last) + 1))
    return [int(s) for s in text.split(",")]


def run_one(name: str, seed: int, contact: str):
    """(recall, precision, count error, rmse px, polarity right, cpu s, field) for one frame."""
    sensor = SyntheticTacTip.from_preset(name, seed=seed)
    sensor.reseed_noise(seed)  # as tests/pins/conftest.preset_frame
    frame = sensor.render(CONTACTS[contact])
    start = time.process_time()
    field = find_pin_field(frame.image)
    cpu = time.process_time() - start
    recall, precision, rmse = score(field.centres, frame, gate_px=gate_px(frame))
    drawn = int(np.sum(frame.visible) + np.sum(frame.partial))
    return recall, precision, field.count - drawn, rmse, field.params.dark_pins == sensor.dark_pins, cpu, field


def scale_pair(name: str, seed: int) -> tuple[float, float, float]:
    """(detect, calibrate, true) mm/px on the preset's rest frame."""
    from calibration import calibrate_sensor
    from pins import sensor_scale

    sensor = SyntheticTacTip.from_preset(name, seed=seed)
    image = sensor.render().image
    detect = sensor_scale(find_pin_field(image).centres, sensor=name).mm_per_px
    calibrate = calibrate_sensor([image], expected_pins=sensor.n_pins, description=name).mm_per_px
    return detect, calibrate, sensor.mm_per_px


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", default="0-11")
    parser.add_argument("--presets", default=",".join(preset_names()))
    parser.add_argument("--contacts", default=",".join(CONTACTS))
    parser.add_argument("--scale", action="store_true", help="also detect/calibrate mm/px agreement")
    parser.add_argument("--failures", action="store_true", help="print each frame missing a bar")
    args = parser.parse_args(argv)
    seeds = seed_range(args.seeds)
    print(f"seeds {seeds[0]}-{seeds[-1]}, contacts {args.contacts}")
    print(f"{'preset':16s} {'frames':>6s} {'recall(seed)':>14s} {'precision(seed)':>16s} "
          f"{'|count err|(seed)':>18s} {'rmse px(seed)':>14s} {'fail':>5s} {'cpu s':>6s}")
    failing = []
    for name in args.presets.split(","):
        rows = []
        for seed in seeds:
            for contact in args.contacts.split(","):
                recall, precision, error, rmse, polarity, cpu, field = run_one(name, seed, contact)
                ok = recall >= 0.99 and precision >= 0.99 and rmse <= 0.1 and polarity
                rows.append((seed, contact, recall, precision, error, rmse, ok, cpu))
                if not ok:
                    failing.append((name, seed, contact, recall, precision, error, rmse, polarity))
        seed_of = lambda k, worst: f"{rows[k][0]}{'t' if rows[k][1] != 'rest' else 'r'}"  # noqa: E731
        recall = np.array([r[2] for r in rows])
        precision = np.array([r[3] for r in rows])
        error = np.array([abs(r[4]) for r in rows])
        rmse = np.array([r[5] for r in rows])
        k_r, k_p, k_e, k_m = recall.argmin(), precision.argmin(), error.argmax(), rmse.argmax()
        print(f"{name:16s} {len(rows):6d} {recall[k_r]:8.3f}({seed_of(k_r, 0):>4s}) "
              f"{precision[k_p]:10.3f}({seed_of(k_p, 0):>4s}) {error[k_e]:12d}({seed_of(k_e, 0):>4s}) "
              f"{rmse[k_m]:8.3f}({seed_of(k_m, 0):>4s}) {sum(not r[6] for r in rows):5d} "
              f"{np.mean([r[7] for r in rows]):6.2f}", flush=True)
    print("(seed: the seed where the figure is worst, r = rest, t = 5 mm tap)")
    if args.failures and failing:
        print("\nframes missing a bar: preset seed contact recall precision count-error rmse polarity-right")
        for name, seed, contact, recall, precision, error, rmse, polarity in failing:
            print(f"  {name:16s} {seed:3d} {contact:7s} {recall:.3f} {precision:.3f} {error:+5d} {rmse:.3f} {polarity}")
    if args.scale:
        print("\nscale mm/px: preset, worst detect/calibrate disagreement (seed), worst |detect/true - 1| (seed)")
        for name in args.presets.split(","):
            pairs = [scale_pair(name, seed) for seed in seeds]
            agree = np.array([max(d, c) / min(d, c) - 1 for d, c, _ in pairs])
            truth = np.array([abs(d / t - 1) for d, _, t in pairs])
            print(f"  {name:16s} {agree.max():6.2%} ({seeds[agree.argmax()]}) {truth.max():6.2%} ({seeds[truth.argmax()]})",
                  flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
