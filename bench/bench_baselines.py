"""Issue 21: the likelihood models against simple baselines on synthetic labelled taps, over seeds.

For each kind of label (slide directions, circular; depths, numeric; shapes, named; and "xor", two
named classes told apart only by the sign of x * y of each pin, which no per-dimension or
shared-covariance model can see), over several seeds: trains every likelihood model kind on one
set and scores, on an independent test set, the model's exact 1-tap error (every test tap, from the
flat prior) and its decisions at threshold 0.9 (stationary: one location), beside the best of
k-nearest neighbours, logistic and ridge regression fitted on the same features
(`perception.baselines`). Prints the means over seeds and how often each model is worse than the
best baseline at 1 tap (by more than 5 %) and well below it at 0.9 (<= 0.75x).

    python bench/bench_baselines.py [--seeds 5] [--runs 2000] [--unseen 0.1] [--test-per-class 400] [--kinds ...]

Measured 2026-11-28, 5 seeds, 400 test taps per class (1-tap error, model / best baseline): circular
3.05 / 5.77 deg (ridge), numeric 0.025 / 0.116 mm (ridge), named 0.094 / 0.098 (logistic; the
Gaussian worse on 0 of 5 seeds), and at threshold 0.9 0.07-0.14x the baseline's. The named case's
"1.2x logistic" (0.088 / 0.073, worse on 4 of 5 seeds) came from 30 test taps per class: one tap
moves the error by 0.0067, more than the 5 % the bar resolves (0.0045). On xor every likelihood kind is at chance (0.49) and kNN is not (0.012).

The torch kind, 3 seeds (1-tap error / best baseline, before -> after the held-out choice of the
imputation rank, the input and the deviations, `perception.learned`): circular 1.03x -> 0.54x,
numeric 3.87x -> 0.30x, named 1.14x -> 1.14x (0.96-1.20x per seed), xor 3.5x -> 0.00x (kNN 0.011).
Named, other training choices (2026-11-28, 400 test taps per class, 1-tap error / logistic's, mean over
seeds 0-4): Adam (the default) 1.13x (1.20 / 1.12 / 1.09 / 0.87 / 1.19); SGD with Nesterov momentum 0.9,
learning rate 0.05, 1.12x (1.31 / 1.06 / 1.08 / 0.87 / 1.13); Adam with weight decay 1e-2 instead of 1e-3
1.14 / 1.16 / 1.26x on seeds 0-2. None adopted: the named classes are Gaussians about unrelated means with
one shared spread, the case a linear model is made for, and 150 training taps leave the network short.
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

KINDS = ("histogram", "calibrated-histogram", "gaussian")
#: Label -> the synthetic set's settings (tests/perception/labelled.py): baselines neither exact nor hopeless.
CASES = {
    "circular": dict(label="circular", per_class=30, separation=0.8),
    "numeric": dict(label="numeric", classes=6, per_class=30, separation=5.0),
    "named": dict(label="named", classes=5, per_class=30, separation=0.8),
}


def xor_pairs(seed, per_class=40, pins=6, samples=4):
    """Two named classes with the same per-dimension distributions: x = y on every pin, or x = -y."""
    from perception import Dataset

    rng = np.random.default_rng(seed)
    label = np.repeat([0.0, 1.0], per_class)
    x = rng.standard_normal((2 * per_class, 1, pins)) * np.ones((1, samples, 1))
    taps = np.stack([x, np.where(label[:, None, None] == 0, x, -x)], axis=-1).reshape(2 * per_class, samples, -1)
    taps = taps + 0.1 * rng.standard_normal(taps.shape)
    return Dataset(taps, np.zeros(len(label)), label, None, "tactip", "none", "none", identity_names=("same", "mirror"))


def measure(train, test, kind, runs, seed):
    """(1-tap error, error at 0.9, mean taps at 0.9, BaselineReport) of one model kind; None if it cannot train."""
    from perception import VirtualEnvironment, compare_baselines, make_policy, monte_carlo, train_model
    from perception.errors import DatasetError

    try:
        model = train_model(train, kind=kind, n_locations=1)
    except DatasetError as error:   # e.g. a calibrated kind refusing taps it tells apart no better than chance
        print(f"  {kind} (seed {seed}) does not train: {error}")
        return None
    environment = VirtualEnvironment(model, test)
    report = compare_baselines(model, train, test, seed=seed, log_likelihood=environment.log_likelihood)
    result = monte_carlo(environment, make_policy("stationary", fixation_class=0), thresholds=[0.9], runs=runs,
                         seed=seed)
    return report.model_error, float(result.mean_identity_error[0]), float(result.mean_taps[0]), report


def main(argv=None) -> int:
    """Print the comparison table."""
    from tests.perception.labelled import labelled_taps

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--runs", type=int, default=2000)
    parser.add_argument("--unseen", type=float, default=0.1, help="probability that a pin is unseen for a tap")
    parser.add_argument("--test-per-class", type=int, default=400,
                        help="test taps per class (default 400: with the 30 of training, a 150-tap test set of 5 "
                             "classes moves the error by 0.0067 a tap, more than the 5 %% the bar asks for)")
    parser.add_argument("--kinds", nargs="+", default=list(KINDS), help="likelihood kinds (torch: slow, needs torch)")
    parser.add_argument("--cases", nargs="+", default=[*CASES, "xor"], choices=[*CASES, "xor"])
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    print(f"{'label':<9} {'model':<21} {'1 tap':>7} {'best bl':>8} {'ratio':>6} {'at 0.9':>7} {'taps':>5} "
          f"{'ratio':>6} {'worse':>6} {'well below':>10}  best baselines")
    for case in args.cases:
        table = {kind: [] for kind in args.kinds}
        for seed in range(args.seeds):
            if case == "xor":
                train, test = xor_pairs(seed), xor_pairs(seed + 100, per_class=args.test_per_class)
            else:
                options = dict(CASES[case], noise=1.0, unseen=args.unseen, structure_seed=seed)
                train = labelled_taps(seed=seed, **options)
                test = labelled_taps(seed=seed + 100, **{**options, "per_class": args.test_per_class})
            for kind in args.kinds:
                table[kind].append(measure(train, test, kind, args.runs, seed))
        for kind, rows in table.items():
            rows = [r for r in rows if r is not None]
            if not rows:
                continue
            one, held, taps = (np.array([r[k] for r in rows]) for k in range(3))
            best = np.array([r[3].best.error for r in rows])
            names = sorted({r[3].best.name for r in rows})
            ratio_one, ratio_held = one.mean() / best.mean(), held.mean() / best.mean()   # of the means over seeds
            worse = int((one > 1.05 * best + 1e-12).sum())
            below = int((held <= 0.75 * best + 1e-12).sum())
            print(f"{case:<9} {kind:<21} {one.mean():>7.3f} {best.mean():>8.3f} {ratio_one:>6.2f} "
                  f"{held.mean():>7.3f} {taps.mean():>5.2f} {ratio_held:>6.2f} {worse:>3}/{len(rows):<2} "
                  f"{below:>7}/{len(rows):<2}  {','.join(names)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
