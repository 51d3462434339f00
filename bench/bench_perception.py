"""Speed of perception at the paper 002 scale, on one core; prints figures.

Bars: the likelihood of one tap against 220 classes (11 depths x 20 widths), 80 dims, 40 samples
<= 0.2 ms; Monte Carlo of 5000 runs x 20 thresholds on that model <= 5 s.

The taps are synthetic (smooth rise-and-release profiles whose amplitudes depend on depth and
width, plus noise), sized like the paper's data: 10 training and 10 test taps per class.

Run: .venv/bin/python bench/bench_perception.py
"""

import os

for _name in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_name, "1")  # one core

import time  # noqa: E402

import numpy as np  # noqa: E402

from perception import (DEFAULT_THRESHOLDS, Dataset, FixationPolicy, RandomPolicy, StationaryPolicy,  # noqa: E402
                        VirtualEnvironment, fit_model, monte_carlo)

DEPTHS, WIDTHS, TAPS, SAMPLES, DIMS = 11, 20, 10, 40, 80


def synthetic(seed: int, noise: float) -> Dataset:
    """Paper 002-sized taps: 11 depths x 20 widths x 10 taps, 40 samples x 80 dims."""
    structure = np.random.default_rng(0)
    rng = np.random.default_rng(seed)
    depth, width, _ = np.meshgrid(np.arange(DEPTHS) * 0.5, 0.25 * np.arange(1, WIDTHS + 1), np.arange(TAPS),
                                  indexing="ij")
    depth, width = depth.ravel(), width.ravel()
    depth_code, width_code = structure.uniform(0.5, 1.5, (2, DIMS))
    contact = depth / depth.max()
    amplitude = contact[:, None] * depth_code + (contact * width)[:, None] * width_code / 5
    profile = np.sin(np.pi * (np.arange(SAMPLES) + 0.5) / SAMPLES) ** 2
    taps = profile[None, :, None] * amplitude[:, None, :] + noise * rng.normal(size=(len(depth), SAMPLES, DIMS))
    return Dataset(taps, depth, width, None, "tactip")


def main() -> None:
    """Print the timing figures."""
    train, test = synthetic(1, 0.05), synthetic(2, 0.05)
    start = time.perf_counter()
    model = fit_model(train, n_locations=DEPTHS)
    print(f"fit: {model.summary()} in {time.perf_counter() - start:.2f} s")

    taps = test.taps[np.random.default_rng(3).permutation(len(test))[:500]]
    for tap in taps[:20]:
        model.log_likelihood(tap)  # warm up
    times = []
    for _ in range(5):
        start = time.perf_counter()
        for tap in taps:
            model.log_likelihood(tap)
        times.append((time.perf_counter() - start) / len(taps))
    print(f"likelihood of one tap ({model.n_classes} classes, {DIMS} dims, {SAMPLES} samples): "
          f"{1e3 * min(times):.3f} ms (best of 5 x 500 taps; median {1e3 * np.median(times):.3f} ms; bar 0.2 ms)")

    start = time.perf_counter()
    env = VirtualEnvironment(model, test)
    print(f"virtual environment: log likelihood of {len(test)} test taps x {model.n_classes} classes in "
          f"{time.perf_counter() - start:.2f} s")
    policies = (FixationPolicy(DEPTHS - 1), RandomPolicy(), StationaryPolicy())
    for policy in policies:
        start = time.perf_counter()
        result = monte_carlo(env, policy, thresholds=DEFAULT_THRESHOLDS, runs=5000, seed=1, max_taps=20)
        elapsed = time.perf_counter() - start
        best = result.best_within(12)
        print(f"Monte Carlo {policy.name:<10}: 5000 runs x {len(DEFAULT_THRESHOLDS)} thresholds in {elapsed:.2f} s "
              f"(bar 5 s); mean taps {result.mean_taps.min():.1f}-{result.mean_taps.max():.1f}; best within 12 "
              f"taps: {result.mean_identity_error[best]:.3f} mm at threshold {result.thresholds[best]:g}")


if __name__ == "__main__":
    main()
