"""Issue 20's bars on given seeds and presets: one row per bar, preset and seed (figure, met?).

Past sessions tuned detection and tracking on seeds 0-2 (some on 0-11 or 0-35); the bars are to be judged
on seeds nobody tuned on (``--seeds 6-15``). Each bar, against the renderer's ground truth (`tactip.sim`):

- same:      `PinTracker.update` on the very frame it started from (replay's start: `find_pin_field` with
             the polarity decided, its detection parameters and disc) loses no pin, on every preset of
             `tactip.sim.preset_names()`; the figure is pins lost / pins started, and of the lost, those on
             a bright background (local background above the 90th percentile of the started pins': the
             reflections, glare);
- still, swaps, return, contacts, count: `bench_phenomena.measure` on its presets (no pin lost on still
             frames, none retired; zero identity swaps through 8 slides of 3 pitches; all pins within
             1 px of rest after the return; contacts found = rendered for slides and taps; the radial
             count (pins found against the true visible pins) within 1 %);
- missing:   a dataset whose taps each miss 5 of 40 feature pins is classified through `tactip validate`
             within 2 points of the complete data (`tests/tactip/cli/test_cli_missing_pins.py`'s data and
             procedure, on other seeds; the histogram, Gaussian and torch models); met per seed when the
             drop is <= 0.02 (the test's bar is the mean over seeds); with one tap per decision beside it
             (repeated taps decide every class right on both: the one-tap drop shows what the missing
             pins cost);
- scale:     `tactip detect --sensor NAME --json`, `tactip replay --sensor NAME` (a folder of three rest
             frames) and `calibration.calibrate_sensor` (what `tactip calibrate` runs on its rest frames)
             on the same frames agree within 2 % (largest / smallest - 1);
- agree:     `tactip detect` and `tactip replay` decide the same polarity and the same pad (the same pins:
             replay's rest positions within 0.5 px of detect's, one to one), and on a frame with no sensor
             (a blank frame; a dozen pins of a preset) both refuse with the same message.

Figures (session 16's audit8, 2-core VM; seeds 0-5 tuned on, 6-35 held out; CPU per row in the table):
- same, every preset: met on seeds 16-35 (1.5 min); on 6-15 radial-led-120 loses 1 of 120 on seeds 6 and 8
  (a faint tip by an LED reflection, in the brightest tenth of backgrounds), every other preset 0;
- phenomena, seeds 6-15 (5.5 min): white-dark-331, radial-120, tactip-331 meet every bar; radial-led-120
  meets the count (120/120), swaps (0), contacts (8/8 slides, 6/6 taps) but loses 1-2 pins on still
  frames on 8 of 10 seeds (16-25: 3 of 10; 0-5: seed 5) and 1 after the return on seeds 8 and 10 (the
  same faint pins); on tuned seed 1 one faint pin ends 1.8 px off its rest position;
- missing, seeds 6-15 (1 min): every drop 0.000 (both decide every tap right); one tap per decision:
  mean drops histogram 0.020, Gaussian 0.011, torch -0.001;
- scale, every preset, seeds 6-15 (with agree: 6 min): detect = replay on the same frame, calibrate
  (three frames averaged) within 1.18 % (radial-led-120; small-pad-100 1.13 %, the others <= 0.25 %);
  `tactip calibrate --sensor NAME` on the simulated station within 1.12 % of detect;
  against the renderer's true scale (session 16's scale9, `bench/bench_scale_truth.py`, seeds 0-39, 20-39
  held out): the three sat 2.0-5.4 % high on hexagonal and radial pads (the nearest of several tied
  neighbours, short by the pins' 2 % scatter: +3.4 % hexagonal, +2.3 % spokes; the dome +0.4 / +0.9 %;
  description 0; detection +-0.1 %); with the first shell's median there, -0.7 to +1.6 % (mean +0.2 %
  hexagonal, +0.8 % spokes); concentric circles (532, 1000, small pad) keep the nearest, -1.4 to +4.6 %;
- agree, every preset, seeds 6-15: polarity and pins the same everywhere; the no-sensor frames refused
  by both with one message on every seed.
The mends behind these figures (before -> after): replay's pitch from the pin field, not the tracker's
windows (radial-led-120 seed 6: 2.13 % -> 1.18 %); the simulated station filming the named preset
(calibrate 55-86 % off -> <= 1.12 %); a borrowed disc's lattice must be regular (a dozen bright pins taken
for 58-154 dark markers on seeds 5, 8, 15 of 0-15 -> refused).

Session 16's faint9 (main 794cd9b -> a faint tip judged by its contrast alone, `pins._like`): the faint pin
by an LED reflection of radial-led-120 had bounds on a tip like at rest (half and twice its one noisy rest
frame's measures) above those measures themselves. Now its contrast may fall to its own at rest less 5
scatters of the contrast in the rest frame's own noise, where that is below half, and a tip within that
reach of nothing is judged by its contrast alone. ``--bars same,phenomena`` on radial-led-120, seeds 6-35
(the reach chosen seeing 0-25; 26-35 held out): every bar met on every seed (before: same 1 lost on seeds
6 and 8; still 1-2 lost on 8 of 10 seeds 6-15 and 3 of 10 on 16-25; the return 1 lost on seeds 8 and
10); same on every preset, seeds 6-15: met (110 of 110). On the other presets no tip's bounds change (no
tip below twice the reach, seeds 0-5). Left: tuned seed 1's pin 118 ends 1.79 px from its true rest
centre before and after: the tracker returns it to its own rest position, which the pin field
(`find_pin_field`) placed 1.7 px off a faint tip on a reflection's flank (the window's fixed point lay
beyond the plausibility bound, so the given position stood). What got worse: `bench/bench_slides.py` on
radial-led-120, seeds 0-5, pin-frames > 3 px off their centres 18 -> 87 on the realistic skin (79 -> 80 on
the model skin): faint tips placed off their centres where they were lost before (swaps 1 -> 1 and
277 -> 269; lost per frame 2.91 -> 2.77 and 3.41 -> 3.24; see `pins._like`).

Session 18's faint12 (main 8510ee8 -> a faint tip learns its level on a pad at rest, `pins._rest._AtRest._learn_levels`):
on main ``--bars phenomena --presets radial-led-120`` lost pins on still frames of seeds 37 (2 pin-frames; and 1
pin after the return) and 46 (14 pin-frames: a tip judged by its contrast alone, read 9.6 at rest and 4.2 +- 2.8
later, lost on frame 20 and not found again for 14 frames), both faint tips whose rest frame read them well above
their level. Now, seeds 0-47 (developed on): every bar met on every seed but seed 1's return (pin 118, 1.79 px:
its rest position from the pin field, before and after); slides 8/8 and taps 6/6 on every seed, count 120/120 but
seed 17 (119). Held out, seeds 48-59 (`bench_phenomena.py`, raw): still 0 -> 0 lost, the return > 1 px on seeds
48 and 50 before and after. radial-120, tactip-331, white-dark-331 (seeds 0-5): no faint tip; every bar met.
bench/bench_slides.py, radial-led-120 seeds 0-5 (main -> now): realistic skin identical but lost per frame on seed 5
(2.90 -> 2.91): > 3 px 87 -> 87, apart 1 -> 1; model skin > 3 px 80 -> 79, apart 34 -> 35, swaps 269 -> 256, > 1 px
1306 -> 1284, lost per frame 3.14 -> 3.17 (seed 5 2.95 -> 3.08: tracks diverge by hundredths of a px from the
faint tips' first frames and three non-faint pins are lost 25-35 frames more in one slide); tactip-331 unchanged.

Run: .venv/bin/python bench/bench_issue20_bars.py [--bars same,phenomena,missing,scale,agree] [--seeds 6-15]
     [--presets a,b] [--phenomena-presets radial-led-120,white-dark-331,radial-120,tactip-331]
     [--missing-seeds 6-9] [--models histogram,gaussian,torch]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import pathlib
import sys
import tempfile
import time

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

from pins import NoSensorError, PinTracker, find_pin_field  # noqa: E402
from tactip.sim import SyntheticTacTip, preset_names  # noqa: E402


def seed_range(text: str) -> list[int]:
    """'6-15' or '6,8,9' to a list of seeds."""
    if "-" in text:
        first, last = text.split("-")
        return list(range(int(first), int(last) + 1))
    return [int(s) for s in text.split(",")]


def row(bar: str, preset: str, seed, figure: str, met: bool, cpu_s: float) -> None:
    """Print one row of the table."""
    print(f"{bar:9s} {preset:16s} {str(seed):>4s}  {figure:58s} {'yes' if met else 'NO':>4s} {cpu_s:7.1f}",
          flush=True)


def local_background(image: np.ndarray, centres: np.ndarray, radius_px: float) -> np.ndarray:
    """Median grey level in a ring of 1.5-2.5 ``radius_px`` around each centre (grey frames)."""
    grey = image if image.ndim == 2 else image.mean(axis=2)
    angles = np.linspace(0, 2 * np.pi, 24, endpoint=False)
    radii = np.array([1.5, 2.0, 2.5]) * radius_px
    dx = (radii[:, None] * np.cos(angles)).ravel()
    dy = (radii[:, None] * np.sin(angles)).ravel()
    x = np.clip(np.rint(centres[:, :1] + dx).astype(int), 0, grey.shape[1] - 1)
    y = np.clip(np.rint(centres[:, 1:] + dy).astype(int), 0, grey.shape[0] - 1)
    return np.median(grey[y, x], axis=1)


def bar_same(name: str, seed: int) -> None:
    """`PinTracker.update` on the frame it started from: pins lost (of them, on a bright background)."""
    start = time.process_time()
    sensor = SyntheticTacTip.from_preset(name, seed=seed)
    image = sensor.render().image
    try:
        field = find_pin_field(image)
    except NoSensorError as exc:
        row("same", name, seed, f"no sensor: {exc}"[:58], False, time.process_time() - start)
        return
    tracker = PinTracker(detection=field.params, disc=field.disc)
    rest = tracker.start(image, field.centres)
    tracker.update(image)
    lost = np.asarray(tracker.lost, bool)
    pitch = float(np.median(cKDTree(rest).query(rest, 2)[0][:, 1]))
    background = local_background(image, rest, 0.25 * pitch)
    bright = background > np.percentile(background, 90)
    again = tracker.update(image)
    lost_again = int(np.isnan(again[:, 0]).sum())
    row("same", name, seed, f"lost {int(lost.sum())}/{len(rest)} (bright {int((lost & bright).sum())}/"
        f"{int(bright.sum())}), next {lost_again}", not lost.any() and lost_again == 0, time.process_time() - start)


def bar_phenomena(name: str, seed: int) -> None:
    """`bench_phenomena.measure`: still frames, slides, the return, contacts, the count."""
    from bench_phenomena import measure

    start = time.process_time()
    r = measure(name, seed, contacts=True)
    cpu = time.process_time() - start
    if "same" not in r:
        row("phenomena", name, seed, f"found {r.get('found')}", False, cpu)
        return
    row("still", name, seed, f"max lost {r['still_max']}, median {r['still_median']}, retired {r['retired']}",
        r["still_max"] == 0 and r["retired"] == 0, cpu)
    row("swaps", name, seed, f"swaps {r['swaps']} (of {r['matched']} matched)", r["swaps"] == 0, 0.0)
    row("return", name, seed, f">1px {r['over_1px']}, >10px {r['over_10px']}, lost {r['lost_after']}",
        r["over_1px"] == 0 and r["lost_after"] == 0, 0.0)
    for kind in ("slides", "taps"):
        found = str(r[f"{kind}_found"])
        parts = found.split("/")
        met = len(parts) == 2 and parts[0] == parts[1]
        row("contacts", name, seed, f"{kind} {found}", met, 0.0)
    if name.startswith("radial"):
        error = (r["found"] - r["true"]) / r["true"]
        row("count", name, seed, f"found {r['found']} of {r['true']} ({error:+.1%}), spurious {r['spurious']}",
            abs(error) <= 0.01, 0.0)


def bar_missing(kind: str, seed: int, folder: pathlib.Path) -> None:
    """The missing-pins validation of tests/tactip/cli/test_cli_missing_pins.py on one seed."""
    from perception import save_dataset
    from tactip.cli import main
    from tests.perception.synthetic import gap_dataset
    from tests.tactip.cli.test_cli_missing_pins import EPOCHS, GRID, accuracy, lose_pins

    start = time.process_time()
    train = gap_dataset(seed=10 + seed, taps_per_class=8, structure_seed=seed, **GRID)
    test = gap_dataset(seed=100 + seed, taps_per_class=10, structure_seed=seed, **GRID)
    save_dataset(folder / "complete.h5", test)
    save_dataset(folder / "missing.h5", lose_pins(test, seed))
    save_dataset(folder / "train.h5", lose_pins(train, seed + 50))
    with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
        assert main(["train", str(folder / "train.h5"), "--out", str(folder / "model.h5"), "--locations", "4",
                     "--model", kind, "--overwrite", *EPOCHS.get(kind, [])]) == 0
        complete = accuracy(folder, folder / "model.h5", folder / "complete.h5", seed)
        missing = accuracy(folder, folder / "model.h5", folder / "missing.h5", seed)
        # One tap per decision (the evidence of a single tap: repeated taps saturate at 1.000).
        one = [accuracy(folder, folder / "model.h5", folder / f"{name}.h5", seed, "--max-taps", "1")
               for name in ("complete", "missing")]
    drop = complete - missing
    row("missing", kind, seed, f"{complete:.3f} -> {missing:.3f} ({drop:+.3f}); 1 tap {one[0]:.3f} -> {one[1]:.3f}",
        drop <= 0.02, time.process_time() - start)
    return drop, one[0] - one[1]


def _cli(argv: list[str]) -> tuple[int, str, str]:
    """`tactip.cli.main(argv)`: (exit status, standard output, standard error)."""
    from tactip.cli import main

    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main(argv)
    return status, out.getvalue(), err.getvalue()


def _still(folder: pathlib.Path, images) -> tuple[pathlib.Path, pathlib.Path]:
    """The first image as a PNG file and all of them as a folder of frames (a lossless still video)."""
    import cv2

    video = folder / "video"
    video.mkdir(parents=True)
    for k, image in enumerate(images):
        cv2.imwrite(str(video / f"{k:03d}.png"), image)
    cv2.imwrite(str(folder / "frame.png"), images[0])
    return folder / "frame.png", video


def station_calibrate(name: str, seed: int, folder: pathlib.Path) -> float:
    """`tactip calibrate --sensor NAME` on the simulated station (samples/station_sim.toml, [sim] seed =
    ``seed``): its mm/px (NaN when it refuses; the message is printed)."""
    import re

    from calibration import load_calibration

    root = pathlib.Path(__file__).resolve().parents[1]
    text = (root / "samples" / "station_sim.toml").read_text()
    text = re.sub(r'(?m)^data_dir = .*$', f'data_dir = "{folder}/station"', text)
    text = re.sub(r'(?m)^results = .*$', f'results = "{folder}/station/results.sqlite"', text)
    text = re.sub(r'(?m)^model = .*$', f'model = "{folder}/station/model.h5"', text)
    text = re.sub(r'(?ms)^(\[sim\].*?^seed = )\d+', rf'\g<1>{seed}', text)
    config = folder / "station.toml"
    config.write_text(text)
    status, _, err = _cli(["calibrate", "--config", str(config), "--sensor", name, "--rest-frames", "3",
                           "--out", str(folder / "cal.h5")])
    if status != 0:
        print(f"  calibrate (station) refused: {err.strip()}", flush=True)
        return float("nan")
    return float(load_calibration(folder / "cal.h5").mm_per_px)


def bar_scale_agree(name: str, seed: int, folder: pathlib.Path, bars: set[str]) -> None:
    """detect, calibrate and replay on one preset's rest frames: scale, polarity, pad."""
    import h5py

    from calibration import calibrate_sensor

    start = time.process_time()
    sensor = SyntheticTacTip.from_preset(name, seed=seed)
    images = [sensor.render().image for _ in range(3)]
    frame, video = _still(folder, images)
    status, out, err = _cli(["detect", str(frame), "--sensor", name, "--json"])
    if status != 0:
        row("scale", name, seed, f"detect refused: {err.strip()}"[:58], False, time.process_time() - start)
        return
    detected = json.loads(out)
    status, _, err = _cli(["replay", str(video), "--out", str(folder / "r.h5"), "--sensor", name, "--quiet"])
    if status != 0:
        row("scale", name, seed, f"replay refused: {err.strip()}"[:58], False, time.process_time() - start)
        return
    with h5py.File(folder / "r.h5") as h5:
        replayed = json.loads(h5.attrs["scale"])["mm_per_px"]
        dark = json.loads(h5.attrs["detection_params"])["dark_pins"]
        rest = h5["rest_positions"][()]
    try:
        calibrated = calibrate_sensor(images, expected_pins=sensor.n_pins, description=name).mm_per_px
    except Exception as exc:  # noqa: BLE001 - a refusal is a result here
        calibrated = float("nan")
        print(f"  calibrate refused: {exc}", flush=True)
    station = station_calibrate(name, seed, folder) if "scale" in bars else float("nan")
    cpu = time.process_time() - start
    if "scale" in bars:
        scales = np.array([detected["scale"]["mm_per_px"], calibrated, replayed])
        spread = scales.max() / scales.min() - 1
        truth = np.abs(scales / sensor.mm_per_px - 1).max()
        row("scale", name, seed, f"d/c/r {scales[0]:.4f}/{scales[1]:.4f}/{scales[2]:.4f}, {spread:.2%} "
            f"(true {truth:.1%})", bool(spread <= 0.02), cpu)
        # The command line's calibrate renders its own rest frames (the simulated station's camera, of the
        # preset and seed): judged against the truth and detect's scale.
        off = station / scales[0] - 1
        row("scale", name, seed, f"calibrate (station) {station:.4f}: {off:+.2%} of detect, true "
            f"{sensor.mm_per_px:.4f}", bool(abs(off) <= 0.02), 0.0)
    if "agree" in bars:
        pins = np.asarray(detected["pins"], float).reshape(-1, 2)
        distance, index = cKDTree(pins).query(rest) if len(pins) else (np.full(len(rest), np.inf), None)
        same_pad = len(rest) == len(pins) and bool(np.all(distance < 0.5)) and len(set(index)) == len(pins)
        polarity = detected["dark_pins"] is dark is sensor.dark_pins
        row("agree", name, seed, f"polarity {'same' if detected['dark_pins'] is dark else 'DIFFERENT'}"
            f"{'' if dark is sensor.dark_pins else ' (wrong)'}, pins {len(pins)}/{len(rest)}, "
            f"max {float(np.max(distance, initial=0)):.2f} px", polarity and same_pad, 0.0)


def bar_no_sensor(seed: int, folder: pathlib.Path) -> None:
    """A frame with no sensor (blank; a dozen pins of a preset): detect and replay refuse alike."""
    cases = {"blank": np.full((240, 320), 40 + seed, np.uint8)}
    for name in ("tactip-331", "dark-331", "white-dark-331"):
        sensor = SyntheticTacTip.from_preset(name, seed=seed)
        hidden = np.ones(sensor.n_pins, dtype=bool)
        hidden[::30] = False
        cases[f"dozen {name}"] = sensor.render(hidden=hidden).image
    for case, image in cases.items():
        start = time.process_time()
        where = folder / case.replace(" ", "-")
        frame, video = _still(where, [image] * 3)
        status_d, _, err_d = _cli(["detect", str(frame)])
        status_r, _, err_r = _cli(["replay", str(video), "--out", str(where / "r.h5"), "--quiet"])
        detected = err_d.removeprefix("tactip detect: error: ").strip()
        replayed = err_r.removeprefix("tactip replay: error: ").strip()
        met = status_d == 1 and status_r == 1 and detected.startswith("no sensor") and detected in replayed
        figure = f"{case}: exit {status_d}/{status_r}, {'same message' if met else repr(replayed[:30])}"
        row("agree", "no sensor", seed, figure, met, time.process_time() - start)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bars", default="same,phenomena,missing,scale,agree")
    parser.add_argument("--seeds", default="6-15")
    parser.add_argument("--presets", default=",".join(preset_names()), help="for same, scale and agree")
    parser.add_argument("--phenomena-presets", default="radial-led-120,white-dark-331,radial-120,tactip-331")
    parser.add_argument("--missing-seeds", default="6-9")
    parser.add_argument("--models", default="histogram,gaussian,torch")
    args = parser.parse_args(argv)
    bars = set(args.bars.split(","))
    seeds = seed_range(args.seeds)
    os.environ.setdefault("TACTIP_SIM_WORKERS", "1")
    print(f"{'bar':9s} {'preset':16s} {'seed':>4s}  {'figure':58s} {'met':>4s} {'cpu s':>7s}")
    with tempfile.TemporaryDirectory() as tmp:
        tmp = pathlib.Path(tmp)
        if "same" in bars:
            for name in args.presets.split(","):
                for seed in seeds:
                    bar_same(name, seed)
        if bars & {"scale", "agree"}:
            for name in args.presets.split(","):
                for seed in seeds:
                    bar_scale_agree(name, seed, tmp / f"{name}-{seed}", bars)
            if "agree" in bars:
                for seed in seeds:
                    bar_no_sensor(seed, tmp / f"none-{seed}")
        if "missing" in bars:
            for kind in args.models.split(","):
                drops = np.array([bar_missing(kind, seed, tmp) for seed in seed_range(args.missing_seeds)])
                row("missing", kind, "mean", f"drop {np.mean(drops[:, 0]):+.3f}, 1 tap {np.mean(drops[:, 1]):+.3f} "
                    f"(seeds {args.missing_seeds})", bool(np.mean(drops[:, 0]) <= 0.02), 0.0)
        if "phenomena" in bars:
            for name in args.phenomena_presets.split(","):
                for seed in seeds:
                    bar_phenomena(name, seed)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
