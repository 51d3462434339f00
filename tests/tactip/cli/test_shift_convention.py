"""The model carries its front end's belief-shift convention and `tactip validate` uses it (issue 10)."""

import json

import numpy as np
import pytest

from perception import Dataset, fit_model, save_dataset
from tactip.cli import main
from tests.perception.synthetic import gap_dataset


def test_models_carry_their_front_ends_shift_convention():
    taps = gap_dataset(depths=3, widths=2, taps_per_class=2)
    assert fit_model(taps, n_locations=3).shift_mode == "edge"                       # TacTip: paper 002
    taxel = Dataset(taps.taps, taps.location, taps.identity, None, "taxel")
    assert fit_model(taxel, n_locations=3).shift_mode == "uniform"                   # taxels: paper 000 eq. 8


@pytest.fixture(scope="module")
def taxel_files(tmp_path_factory):
    from tactip.taxel import TaxelSimulator, simulate_taxel_dataset, sweep_locations

    root = tmp_path_factory.mktemp("taxel")
    simulator = TaxelSimulator("fingertip", seed=0)
    where = sweep_locations(simulator.sensor, 600)
    save_dataset(root / "train.h5", simulate_taxel_dataset(simulator, where, seed=(0, 2), collection="train"))
    save_dataset(root / "test.h5", simulate_taxel_dataset(simulator, where, seed=(0, 3), collection="test"))
    assert main(["train", str(root / "train.h5"), "--out", str(root / "model.h5"), "--locations", "60"]) == 0
    return root


def _validate(root, *extra):
    out = root / f"rows{len(extra)}{'-'.join(extra)}.json"
    assert main(["validate", str(root / "model.h5"), str(root / "test.h5"), "--policy", "active", "--fixation", "15",
                 "--runs", "1500", "--thresholds", "0.5", "--json", str(out), "--quiet", *extra]) == 0
    return json.loads(out.read_text())[0]


def test_validate_defaults_to_the_uniform_fill_on_a_taxel_model(taxel_files):
    default, uniform, edge = (_validate(taxel_files), _validate(taxel_files, "--shift", "uniform"),
                              _validate(taxel_files, "--shift", "edge"))
    assert default == uniform
    # paper 000's fill keeps active localisation sharp where the edge copy does not (issue 10: 0.064 vs 4.29 mm)
    assert default["mean_location_error"] < 0.5 * edge["mean_location_error"]
    assert np.isfinite(default["mean_taps"])
