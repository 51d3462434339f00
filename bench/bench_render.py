"""Cost of rendering one 640x480 synthetic TacTip frame (ms/frame), at 127, 331 and 532 pins, and per preset.

Prints the median over repeated renders of an indented contact over a gap, with the default
appearance (noise, glare, gradient), and the cost of the ground truth alone (``pin_centres``); then
the same for every preset of `tactip.sim.synthetic.PRESETS` (image size, pins; target < 40 ms for
``dense-1000``, 1000 pins at 1280x720), with the default 331-pin render beside it as the yardstick.
Last, CPU ms per frame of the simulated station's taps (`SimulatedCamera`, 331 pins, depths 0-5.5 mm):
a tap films the same contact through its rests and plateau, which the renderer draws once.
Run: ``.venv/bin/python bench/bench_render.py``
"""

import time

import numpy as np

from tactip.sim import PRESETS, Contact, SyntheticTacTip
from tactip.sim.camera import SimulatedCamera

REPEATS = 60


def per_call_ms(function, repeats=REPEATS):
    """Median wall time of ``function()`` over ``repeats`` calls, ms (after one warm-up call)."""
    function()
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return 1e3 * float(np.median(times))


def main():
    """Print the table."""
    contact = Contact(indentation_mm=4.0, gap_width_mm=2.0, gap_offset_mm=1.0)
    print("pins  render ms/frame  pin_centres ms  (640x480, noise 4, glare, gradient)")
    for pins in (127, 331, 532):
        sensor = SyntheticTacTip(pins=pins, seed=0)
        render = per_call_ms(lambda: sensor.render(contact))
        truth = per_call_ms(lambda: sensor.pin_centres(contact))
        print(f"{pins:4d}  {render:15.2f}  {truth:14.2f}")
    sensor = SyntheticTacTip(pins=331, seed=0, blur_sigma=0.8, jpeg_quality=80)
    print(f"331 with blur 0.8 px and JPEG q80: {per_call_ms(lambda: sensor.render(contact)):.2f} ms/frame")
    print("\npreset          size       pins  render ms/frame  x default-331")
    default = SyntheticTacTip(pins=331, seed=0)
    for name in PRESETS:
        sensor = SyntheticTacTip.from_preset(name)
        yardstick = per_call_ms(lambda: default.render(contact), repeats=20)
        render = per_call_ms(lambda: sensor.render(contact), repeats=20)
        size = "x".join(map(str, sensor.image_size))
        print(f"{name:14s}  {size:9s}  {sensor.n_pins:4d}  {render:15.2f}  {render / yardstick:13.2f}")
    print(f"\nstation taps: {station_tap_ms():.2f} CPU ms/frame (SimulatedCamera, 331 pins, 23 depths x 2 gaps)")


def station_tap_ms():
    """CPU ms per frame of the simulated station's taps: 23 depths (0-5.5 mm, 1.5 mm of air) x 2 gaps."""
    from types import SimpleNamespace

    camera = SimulatedCamera(pins=331, approach_height_mm=2.5, seed=0)
    frames, start = 0, time.process_time()
    for seed, (depth, width) in enumerate((d, w) for d in np.arange(0.0, 5.51, 0.25) for w in (1.0, 3.0)):
        event = SimpleNamespace(contact=Contact(indentation_mm=max(depth - 1.5, 0.0), gap_width_mm=width))
        camera.begin_tap(event, seed=seed)
        frames += len(camera.end_tap(event)[0])
    return 1e3 * (time.process_time() - start) / frames


if __name__ == "__main__":
    main()
