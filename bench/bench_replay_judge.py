"""The lattice judgement compiled (`pins._jit_judge`) against its NumPy reference, on the field search's own blob sets.

Runs `pins.find_pin_field` on rest frames twice, with the NumPy reference (``pins._kernels.choose("numpy")``) and
with the compiled kernels, recording every lattice judgement (`pins._judge._judge_lattice`: blobs, sharpness,
verdicts, pitch and its thread's CPU time). Prints, per frame set: judgements, those the kernel left to the
reference (a tie between neighbours or a value at a threshold: status 1-4 of `pins._jit_judge.judge_passes`),
verdicts or pitch that differ (each recorded judgement of the reference judged again compiled), fields that
differ (centres, parameters), and the median and mean CPU per judgement, ms, of each.

Frames: ``--detect``, `bench_detect_seeds`' rest frames (every preset, noise reseeded as the tests'); ``--conditions``,
`bench_conditions`' rest frames filmed under each of its camera conditions (its default presets).

Run: .venv/bin/python bench/bench_replay_judge.py [--seeds 0-35] [--presets a,b] [--detect] [--conditions]
"""

from __future__ import annotations

import argparse
import pathlib
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

import pins._candidates as candidates  # noqa: E402
import pins._judge as judge  # noqa: E402
from pins import _kernels, find_pin_field  # noqa: E402
from tactip.sim import SyntheticTacTip, preset_names  # noqa: E402


def _recorded(image: np.ndarray, kernels: str):
    """`find_pin_field` on `image` with `kernels` ("numpy" or "compiled"): (field, [(blobs, sharpness, reason,
    pitch, cpu s)])."""
    calls = []
    real = judge._judge_lattice

    def spy(blobs, sharpness):
        start = time.thread_time()
        reason, pitch = real(blobs, sharpness)
        calls.append((blobs, sharpness, reason, pitch, time.thread_time() - start))
        return reason, pitch

    before = _kernels.choose(kernels)
    candidates._judge_lattice = spy
    try:
        field = find_pin_field(image)
    finally:
        candidates._judge_lattice = real
        _kernels.choose(before)
    return field, calls


def _same_field(a, b) -> bool:
    return (np.array_equal(a.centres, b.centres) and a.params == b.params
            and np.array_equal(a.pitch_px, b.pitch_px, equal_nan=True))


def compare(frames) -> dict:
    """The figures over `frames` (an iterable of (label, image))."""
    figures = dict(frames=0, judgements=0, referred=0, verdicts=0, fields=0, ref_ms=[], jit_ms=[])
    kernels = _kernels.compiled("_jit_judge")
    for label, image in frames:
        field_ref, calls_ref = _recorded(image, "numpy")
        field_jit, calls_jit = _recorded(image, "compiled")
        figures["frames"] += 1
        figures["ref_ms"] += [1e3 * call[-1] for call in calls_ref]
        figures["jit_ms"] += [1e3 * call[-1] for call in calls_jit]
        if not _same_field(field_ref, field_jit):
            figures["fields"] += 1
            print(f"  field differs: {label}")
        for blobs, sharpness, reason, pitch, _ in calls_ref:
            figures["judgements"] += 1
            if len(blobs.centres) >= judge._MIN_PINS:
                status = kernels.judge_passes(np.ascontiguousarray(blobs.centres, dtype=np.float64),
                                              blobs.areas.astype(np.float64), np.asarray(blobs.fills, np.float64),
                                              np.maximum(blobs.contrasts, 1e-6), np.asarray(sharpness, np.float64),
                                              *judge._judge_logs())[-1]
                figures["referred"] += int(status > 0)
            got_reason, got_pitch = judge._judge_lattice(blobs, sharpness)
            if not (np.array_equal(got_reason, reason) and np.array_equal(got_pitch, pitch, equal_nan=True)):
                figures["verdicts"] += 1
                print(f"  verdicts differ: {label}, {len(blobs.centres)} blobs")
    return figures


def report(name: str, figures: dict) -> None:
    ref, jit = np.array(figures["ref_ms"]), np.array(figures["jit_ms"])
    print(f"{name}: {figures['frames']} frames, {figures['judgements']} judgements, {figures['referred']} left to "
          f"the reference, verdicts differ {figures['verdicts']}, fields differ {figures['fields']}; CPU per "
          f"judgement, ms: reference median {np.median(ref):.2f} mean {ref.mean():.2f}, compiled median "
          f"{np.median(jit):.2f} mean {jit.mean():.2f}", flush=True)


def detect_frames(presets, seeds):
    for name in presets:
        for seed in seeds:
            sensor = SyntheticTacTip.from_preset(name, seed=seed)
            sensor.reseed_noise(seed)
            yield f"{name} seed {seed}", sensor.render(None).image


def condition_frames(presets, seeds):
    from bench_conditions import CONDITIONS, Camera

    for name in presets:
        for condition, options in CONDITIONS.items():
            for seed in seeds:
                camera = Camera(name, seed, options)
                yield f"{name} {condition} seed {seed}", camera.film(camera.sensor.render())[0]


def seed_range(text: str) -> list[int]:
    if "-" in text:
        first, last = text.split("-")
        return list(range(int(first), int(last) + 1))
    return [int(s) for s in text.split(",")]


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", default="0-35")
    parser.add_argument("--presets", default=None, help="default: every preset (--detect), bench_conditions' (--conditions)")
    parser.add_argument("--detect", action="store_true")
    parser.add_argument("--conditions", action="store_true")
    args = parser.parse_args(argv)
    seeds = seed_range(args.seeds)
    if args.detect or not args.conditions:
        presets = args.presets.split(",") if args.presets else preset_names()
        report("detect rest frames", compare(detect_frames(presets, seeds)))
    if args.conditions:
        presets = args.presets.split(",") if args.presets else ["tactip-331", "dark-331", "radial-led-120"]
        report("conditions' rest frames", compare(condition_frames(presets, seeds)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
