"""Detection and tracking on the flat-gel preset (issue 26): figures over seeds, and the time they take.

    python bench/bench_flat_gel.py [--seeds 5] [--shading 25]

Per seed and contact (rest, a 5 mm press, shears): recall, precision and RMSE (px) of `pins.find_pin_field`
without a count against the ground truth, and the time of the search; then a run of a press and three
shears tracked from the rest frame: identity swaps, the worst and RMS error, markers lost at most, and how
far from rest the markers end. Figures vary with the machine only in their times.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist

from pins import PinTracker, find_pin_field
from tactip.sim import Contact, Stroke, SyntheticGel

CONTACTS = {"rest": None, "press 5 mm": Contact(5.0), "shear 1.8 mm": Contact(3.0, slide_x_mm=1.5, slide_y_mm=-1.0),
            "shear 3 mm": Contact(2.0, slide_x_mm=-3.0), "shear 2 mm": Contact(4.0, slide_y_mm=2.0)}


def score(found: np.ndarray, frame) -> tuple[float, float, float]:
    """Recall (visible markers), precision (visible or partial) and RMSE (px) within a 3 px gate."""
    drawn = frame.visible | frame.partial
    distance = cdist(frame.centres[drawn], found)
    rows, cols = linear_sum_assignment(np.where(distance <= 3.0, distance, 1e6))
    ok = distance[rows, cols] <= 3.0
    visible = frame.visible[drawn][rows[ok]]
    rmse = float(np.sqrt(np.mean(distance[rows[ok], cols[ok]][visible] ** 2)))
    return visible.sum() / frame.visible.sum(), ok.sum() / max(len(found), 1), rmse


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--shading", type=float, default=25.0, help="contact shading, grey levels per unit slope")
    args = parser.parse_args()
    print(f"detection without a count, gelsight-mini, shading {args.shading:g}")
    for seed in range(args.seeds):
        sensor = SyntheticGel.from_preset("gelsight-mini", seed=seed, shading=args.shading)
        for name, contact in CONTACTS.items():
            frame = sensor.render(contact)
            start = time.perf_counter()
            field = find_pin_field(frame.image)
            took = time.perf_counter() - start
            recall, precision, rmse = score(field.centres, frame)
            print(f"  seed {seed} {name:13s} recall {recall:.3f} precision {precision:.3f} RMSE {rmse:.3f} px "
                  f"({field.count} markers, {took * 1e3:.0f} ms)")
    print("tracking a press and three shears")
    for seed in range(args.seeds):
        sensor = SyntheticGel.from_preset("gelsight-mini", seed=seed, shading=args.shading)
        frames = list(sensor.sequence([Stroke(5.0), Stroke(3.0, 0.0, 1.5), Stroke(3.0, 90.0, 1.5),
                                       Stroke(3.0, 225.0, 1.5)], rest_s=0.2))
        field = find_pin_field(frames[0].image)
        tracker = PinTracker(detection=field.params, disc=field.disc)
        rest = tracker.start(frames[0].image, field.centres)
        identity = cdist(rest, frames[0].centres).argmin(axis=1)
        swaps, worst, squares, lost, start = 0, 0.0, [], 0, time.perf_counter()
        for frame in frames[1:]:
            positions = tracker.update(frame.image)
            seen = np.isfinite(positions[:, 0])
            error = np.linalg.norm(positions[seen] - frame.centres[identity[seen]], axis=1)
            swaps += int(np.sum(error > 0.5 * sensor.pitch_px))
            worst, lost = max(worst, float(error.max())), max(lost, int((~seen).sum()))
            squares.append(error ** 2)
        took = (time.perf_counter() - start) / (len(frames) - 1)
        back = np.linalg.norm(positions - rest, axis=1)
        print(f"  seed {seed}: {len(rest)} markers, swaps {swaps}, worst {worst:.3f} px, RMSE "
              f"{np.sqrt(np.mean(np.concatenate(squares))):.3f} px, lost at most {lost}, back at rest within "
              f"{np.nanmax(back):.3f} px ({took * 1e3:.1f} ms/frame)")


if __name__ == "__main__":
    main()
