"""The pin field on sensors no preset describes: random mixes of the phenomena, scored on ground truth.

`bench/bench_pins.py` scores `pins.find_pin_field` on the named presets of the synthetic TacTip (the
bars of issue 8). This script asks whether the rules hold beyond them ("never tune to one picture"):
each trial draws a sensor from the whole space the renderer allows, 100-1000 pins, 320x240 to
1280x720, a pad from 1/4 to 9/10 of the frame, hexagonal or radial layout, bright or dark pins, and
at random a black rim ring with LED glare, a brown textured skin, a bright surround with veil and
strong glare; at rest or in a tap. Detection runs without and with the visible count.

Printed per trial: the median pin pitch of the drawn pins (px), recall, precision and centroid RMSE
(px) without | with the count, and whether it meets the bars (recall and precision >= 99 %, RMSE <=
0.1 px). Then a table by pitch band: below about 4 px pitch the tips are 1-2 px across and beyond
what any blob detector samples, so the bands say where the rules hold.

Run: .venv/bin/python bench/bench_pin_field_sweep.py [--trials 80] [--seed 2]
"""

from __future__ import annotations

import argparse
import pathlib
import sys

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial import cKDTree
from scipy.spatial.distance import cdist

from pins import find_pin_field
from tactip.sim import Contact, SyntheticTacTip

BROWN = dict(colour=True, skin_tint="brown", membrane_level=70.0, pin_level=140.0, skin_texture=12.0, pin_shadows=22.0)
BRIGHT = dict(surround_level=240.0, glare_gain=1.6, veil=40.0)
RIM = dict(rim_polar_deg=77.0, ring_glare=18, glare=False)
BANDS = (0.0, 4.0, 6.0, 10.0, 20.0, np.inf)


def score(detected: np.ndarray, frame, gate_px: float = 3.0) -> tuple[float, float, float]:
    """Recall (of visible pins), precision (partial pins count for neither) and RMSE, px; as tests/pins/conftest.score."""
    detected = np.asarray(detected, float).reshape(-1, 2)
    visible, partial = np.asarray(frame.visible, bool), np.asarray(frame.partial, bool)
    drawn = np.asarray(frame.centres)[visible | partial]
    is_visible = visible[visible | partial]
    if len(detected) == 0:
        return 0.0, float(len(drawn) == 0), np.inf
    distance = cdist(drawn, detected)
    cost = np.where(distance <= gate_px, distance, 1e6)
    rows, cols = linear_sum_assignment(cost)
    ok = cost[rows, cols] <= gate_px
    recall = np.sum(ok & is_visible[rows]) / max(int(is_visible.sum()), 1)
    precision = ok.sum() / len(detected)
    matched = ok & is_visible[rows]
    errors = detected[cols[matched]] - drawn[rows[matched]]
    rmse = float(np.sqrt(np.mean(np.sum(errors**2, axis=1)))) if matched.any() else np.inf
    return float(recall), float(precision), rmse


def draw_sensor(rng: np.random.Generator) -> tuple[dict, list[str]]:
    """Keyword arguments of one random sensor, and the names of the phenomena mixed in."""
    dark = bool(rng.random() < 0.3)
    kw = dict(pins=int(rng.choice([100, 127, 200, 331, 532, 800, 1000])),
              image_size=[(320, 240), (640, 480), (1280, 720)][rng.integers(3)],
              pad_fraction=float(rng.uniform(0.25, 0.9)), layout=str(rng.choice(["auto", "radial"])),
              dark_pins=dark, seed=int(rng.integers(1000)))
    mixed = ["dark"] if dark else []
    for name, extra, p in (("rim", RIM, 0.3), ("brown", BROWN, 0.25), ("bright", BRIGHT, 0.25)):
        if rng.random() < p and not dark:
            kw.update(extra)
            mixed.append(name)
    return kw, mixed


def main(argv=None) -> int:
    """Run the sweep and print one line per trial and a table by pitch band."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=80)
    parser.add_argument("--seed", type=int, default=2)
    args = parser.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    rows = []
    for _ in range(args.trials):
        kw, mixed = draw_sensor(rng)
        contact = None if rng.random() < 0.5 else Contact(indentation_mm=float(rng.uniform(1, 5)), gap_width_mm=2.0)
        frame = SyntheticTacTip(**kw).render(contact)
        truth = np.asarray(frame.centres)[np.asarray(frame.visible, bool)]
        pitch = float(np.median(cKDTree(truth).query(truth, 2)[0][:, 1])) if len(truth) > 2 else np.nan
        figures = []
        for expected in (None, int(len(truth))):
            try:
                field = find_pin_field(frame.image, dark_pins=kw["dark_pins"], expected_pins=expected)
                figures.extend(score(field.centres, frame))
            except Exception as exc:  # noqa: BLE001 - a bench reports every failure and goes on
                figures.extend([0.0, 0.0, np.inf])
                mixed.append(f"{type(exc).__name__}")
        recall, precision, rmse, recall_n, precision_n, rmse_n = figures
        ok = min(recall, precision, recall_n, precision_n) >= 0.99 and max(rmse, rmse_n) <= 0.1
        rows.append((pitch, ok, figures))
        print(f"{'ok ' if ok else 'BAD'} pitch {pitch:5.1f} px  {kw['pins']:4d} pins {kw['image_size'][0]}x{kw['image_size'][1]} "
              f"pad {kw['pad_fraction']:.2f} {kw['layout']:6s} {'tap' if contact else 'rest'} {'+'.join(mixed) or 'plain':18s} "
              f"recall {recall:.3f} precision {precision:.3f} RMSE {rmse:.3f} | with count {recall_n:.3f} {precision_n:.3f} {rmse_n:.3f}",
              flush=True)
    print("\npitch band px   trials  meet the bars   min recall  min precision  max RMSE px")
    pitches = np.array([r[0] for r in rows])
    for lo, hi in zip(BANDS[:-1], BANDS[1:]):
        inside = [r for r, p in zip(rows, pitches) if lo <= p < hi]
        if not inside:
            continue
        f = np.array([r[2] for r in inside])
        print(f"{lo:5.0f} - {hi:<5.0f}  {len(inside):7d}  {sum(r[1] for r in inside):13d}  "
              f"{f[:, [0, 3]].min():10.3f}  {f[:, [1, 4]].min():13.3f}  {f[:, [2, 5]].max():11.3f}")
    return 0


if __name__ == "__main__":
    sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
    sys.exit(main())
