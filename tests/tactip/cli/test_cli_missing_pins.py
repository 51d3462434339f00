"""`tactip validate` on taps missing feature pins: each contact misses 5 of its 40 pins (issue 20, outcome 4).

The same model classifies the complete test taps and the same taps with 5 random pins of each unseen
(both their dx and dy dimensions NaN); the decisions stay as accurate, within 2 points on average over
seeds, for the papers' histogram model, the station's Gaussian model and the torch ensemble (it scores a
tap missing values on their conditional mean; torch is in the test extra, so this runs in CI). Training taps may miss pins too.
"""

import json

import numpy as np
import pytest

from perception import Dataset, save_dataset
from tactip.cli import main
from tests.perception.synthetic import gap_dataset

PINS, LOST = 40, 5
GRID = dict(depths=4, widths=4, samples=6, dims=2 * PINS, legible_from=0.3, noise=0.05)
SEEDS = (0, 1, 2)
# The torch networks train at most 30 epochs (`tactip train --epochs`; the default 100 takes about twice the
# CPU). On seeds 0-2 either way every drop is 0.0 (complete and missing taps 1.00), the one-tap drop
# -0.021..0.012 (default -0.002..0.003) and the one-tap accuracy on missing taps 0.68-0.72 (default 0.71-0.74;
# the bar 0.5); seeds 3-6 at 30 epochs: drops 0.0, one-tap drops -0.010..0.015, one-tap accuracy 0.68-0.72.
EPOCHS = {"torch": ["--epochs", "30"]}


def lose_pins(dataset, seed):
    """The dataset with LOST random pins of each tap unseen for the whole tap."""
    rng = np.random.default_rng(seed)
    taps = dataset.taps.copy()
    for tap in taps:
        k = rng.choice(PINS, LOST, replace=False)
        tap[:, np.concatenate([k, k + PINS])] = np.nan
    return Dataset(taps, dataset.location, dataset.identity, None, "tactip")


def accuracy(folder, model, test, seed, *extra):
    """Fraction of right identities of the active policy at threshold 0.9, through the command line."""
    out = folder / "validate.json"
    assert main(["validate", str(model), str(test), "--policy", "active", "--thresholds", "0.9", "--runs", "2000",
                 "--seed", str(seed), "--json", str(out), "--quiet", *extra]) == 0
    return json.loads(out.read_text())[0]["accuracy"]


@pytest.mark.parametrize("kind", ["histogram", "gaussian", "torch"])
def test_taps_missing_5_of_40_pins_are_classified_as_well_as_complete_ones(tmp_path, kind, capsys):
    drops, single = [], []
    for seed in SEEDS:
        train = gap_dataset(seed=10 + seed, taps_per_class=8, structure_seed=seed, **GRID)
        test = gap_dataset(seed=100 + seed, taps_per_class=10, structure_seed=seed, **GRID)
        save_dataset(tmp_path / "complete.h5", test)
        save_dataset(tmp_path / "missing.h5", lose_pins(test, seed))
        save_dataset(tmp_path / "train.h5", lose_pins(train, seed + 50))   # training taps miss pins as well
        assert main(["train", str(tmp_path / "train.h5"), "--out", str(tmp_path / "model.h5"), "--locations", "4",
                     "--model", kind, "--overwrite", *EPOCHS.get(kind, [])]) == 0   # the last seed's model is replaced
        complete = accuracy(tmp_path, tmp_path / "model.h5", tmp_path / "complete.h5", seed)
        missing = accuracy(tmp_path, tmp_path / "model.h5", tmp_path / "missing.h5", seed)
        drops.append(complete - missing)
        assert complete > 0.9
        # One tap per decision: the evidence of a single tap, not saturated by repeated taps.
        one = [accuracy(tmp_path, tmp_path / "model.h5", tmp_path / f"{name}.h5", seed, "--max-taps", "1")
               for name in ("complete", "missing")]
        single.append(one[0] - one[1])
        assert one[1] > 2.0 / GRID["widths"]                # far above chance: the missing dims are not garbage
    capsys.readouterr()
    assert np.mean(drops) <= 0.02, drops                  # the bar: within 2 points on average over seeds
    if kind != "torch":  # the network's conditional-mean plug-in spreads wider per seed (-2.5 to +4.5 points seen)
        assert max(drops) <= 0.04, drops
    assert np.mean(single) <= 0.05, single


def test_train_says_which_class_never_saw_a_pin(tmp_path, capsys):
    train = gap_dataset(seed=1, taps_per_class=4, **GRID)
    taps = train.taps.copy()
    rows = np.flatnonzero((train.location == 0) & (train.identity == 1))
    taps[rows[:, None], :, [7, 47]] = np.nan                                      # pin 7 never seen in one class
    save_dataset(tmp_path / "train.h5", Dataset(taps, train.location, train.identity, None, "tactip"))
    assert main(["train", str(tmp_path / "train.h5"), "--out", str(tmp_path / "m.h5"), "--locations", "4"]) == 0
    out = capsys.readouterr().out
    assert "(4 with missing dims)" in out
    assert "warning: 2 class and dimension pair(s) have no observed value in the training taps (e.g. dim07 at" in out
