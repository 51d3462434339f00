"""tactip.cluster: sweeps and reproductions on Dask give what a run here gives, seed for seed.

The cluster is Dask's LocalCluster with its workers as threads of the test process: in process for
the Python API, and on TCP bound to 127.0.0.1 (no dashboard) where the CLI needs an address.
"""

import json

import numpy as np
import pytest
from distributed import LocalCluster

from perception import VirtualEnvironment, fit_model, fixation_sweep, load_model, save_dataset
from tactip.cli import main
from tactip.cluster import LOOPBACK_ONLY, cluster_map, open_client
from tactip.errors import TactipError
from tactip.reproduce import reproduce
from tests.perception.synthetic import gap_dataset
from tests.perception.test_experiments import assert_same

GRID = dict(depths=6, widths=4, samples=10, dims=8, legible_from=0.5)


@pytest.fixture(scope="module")
def client():
    with open_client(workers=2, processes=False) as c:
        yield c


@pytest.fixture(scope="module")
def address():
    """``tcp://127.0.0.1:PORT`` of a local cluster of two worker threads."""
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False, protocol="tcp://", host="127.0.0.1",
                      **LOOPBACK_ONLY) as cluster:
        yield cluster.scheduler_address


class Bar:
    """A progress factory that records its total and ticks."""

    made: list = []

    def __init__(self, total):
        self.total, self.ticks, self.closed = total, 0, False
        Bar.made.append(self)

    def update(self, n):
        self.ticks += n

    def close(self):
        self.closed = True


def _slow_square(x):
    import time

    time.sleep(0.05 * (3 - x))  # the first items finish last
    return x * x


def _fails_on_two(x):
    if x == 2:
        raise ValueError("two is bad")
    return x


def test_cluster_map_keeps_order_counts_progress_and_raises_errors(client):
    Bar.made.clear()
    assert cluster_map(client, progress=Bar)(_slow_square, [0, 1, 2, 3]) == [0, 1, 4, 9]
    assert [(b.total, b.ticks, b.closed) for b in Bar.made] == [(4, 4, True)]
    with pytest.raises(ValueError, match="two is bad"):
        cluster_map(client)(_fails_on_two, [0, 1, 2, 3])
    assert cluster_map(client)(_slow_square, []) == []


def test_open_client_refusals():
    with pytest.raises(ValueError, match="workers"):
        with open_client("tcp://127.0.0.1:1", workers=2):
            pass
    with pytest.raises(ValueError, match="positive integer"):
        with open_client(workers=0):
            pass


def test_an_unreachable_scheduler_is_one_clear_error(monkeypatch):
    import tactip.cluster

    monkeypatch.setattr(tactip.cluster, "CONNECT_TIMEOUT_S", 0.5)
    with pytest.raises(TactipError, match="cannot reach the Dask scheduler at tcp://127.0.0.1:9"):
        with open_client("tcp://127.0.0.1:9"):
            pass


def test_a_scheduler_without_workers_is_one_clear_error(monkeypatch):
    import tactip.cluster

    monkeypatch.setattr(tactip.cluster, "CONNECT_TIMEOUT_S", 0.5)
    with LocalCluster(n_workers=0, processes=False, protocol="tcp://", host="127.0.0.1", **LOOPBACK_ONLY) as cluster:
        with pytest.raises(TactipError, match="has no workers .*dask worker tcp://127.0.0.1"):
            with open_client(cluster.scheduler_address):
                pass


def test_fixation_sweep_on_the_cluster_equals_a_run_here(client):
    model = fit_model(gap_dataset(seed=1, taps_per_class=4, **GRID), n_locations=6)
    env = VirtualEnvironment(model, gap_dataset(seed=2, taps_per_class=10, **GRID))
    options = dict(thresholds=[0.5, 0.9, 0.99], runs=400, seed=7)
    here = fixation_sweep(env, **options)
    there = fixation_sweep(env, map_fn=cluster_map(client), **options)
    assert_same(there, here)
    assert here.best_fixation >= 4.0  # not a vacuous equality: the sweep found the legible depths


# 000 on the cluster: its mapped pieces, the class counts of `acuity_table`, on small collections (below); the
# quick reproduction itself on Dask would be a second run of ~35 CPU-s of the same code. 003 on the cluster:
# through the CLI below (the same checks: its rows and its comparisons), not a second time.
@pytest.mark.parametrize("paper", ["001"])
def test_reproduce_on_the_cluster_equals_a_run_here(client, paper, quick_reproduction):
    # here: the session's `tactip reproduce PAPER --quick` (seed 0), whose rows test_reproduce.py checks
    here_rows, _, here_comparisons = quick_reproduction(paper)
    there = reproduce(paper, quick=True, seed=0, map_fn=cluster_map(client))
    assert json.loads(json.dumps(there.json_rows())) == here_rows and len(here_rows) >= 2   # as the CLI writes them
    # measured is NaN where no run decides (001's deadline at 0.99): equal as NaN
    np.testing.assert_equal([[c.figure, float(c.measured)] for c in there.comparisons], here_comparisons)


def test_acuity_table_on_the_cluster_equals_a_run_here(client):
    """Paper 000's pieces (`tactip.reproduce.p000` maps the class counts of `acuity_table`) on Dask: the same
    rows, seed for seed, and the cluster ran them (a map that ignored it would give the same rows)."""
    from tactip.reproduce.acuity import acuity_table
    from tactip.taxel import TaxelSimulator, simulate_taxel_dataset, sweep_locations

    simulator = TaxelSimulator("fingertip", seed=0)
    where = sweep_locations(simulator.sensor, 600)
    train = simulate_taxel_dataset(simulator, where, seed=(0, 2), collection="train")
    test = simulate_taxel_dataset(simulator, where, seed=(0, 3), collection="test")
    mapped = []

    def on_the_cluster(function, pieces):
        mapped.append(list(pieces))
        return cluster_map(client)(function, pieces)

    options = dict(class_counts=(10, 30, 60), fixation_mm=15.0, tap_budget=2.0, runs=300, seed=1)
    here = acuity_table(train, test, **options)
    there = acuity_table(train, test, map_fn=on_the_cluster, **options)
    assert mapped == [[10, 30, 60]] and there == here
    assert here[0].active_error_mm < here[0].passive_error_mm      # not a vacuous equality: active localises


def test_cli_sweep_fixation_and_reproduce_with_scheduler(address, tmp_path, capsys, quick_reproduction, monkeypatch):
    save_dataset(tmp_path / "train.h5", gap_dataset(seed=1, taps_per_class=4, **GRID))
    save_dataset(tmp_path / "test.h5", gap_dataset(seed=2, taps_per_class=10, **GRID))
    assert main(["train", str(tmp_path / "train.h5"), "--out", str(tmp_path / "here.h5"), "--locations", "6"]) == 0
    (tmp_path / "there.h5").write_bytes((tmp_path / "here.h5").read_bytes())
    sweep = ["--sweep-fixation", "--runs", "400", "--thresholds", "0.5,0.9,0.99", "--seed", "5", "--quiet"]
    for name, extra in (("here", []), ("there", ["--scheduler", address])):
        assert main(["validate", str(tmp_path / f"{name}.h5"), str(tmp_path / "test.h5"), *sweep, "--json",
                     str(tmp_path / f"{name}.json"), *extra]) == 0
    capsys.readouterr()
    assert json.loads((tmp_path / "there.json").read_text()) == json.loads((tmp_path / "here.json").read_text())
    assert load_model(tmp_path / "there.h5").recommended == load_model(tmp_path / "here.h5").recommended
    import tactip.reproduce

    # the same command without --scheduler, run once per session (before the patch: it may run it now)
    here_rows, _, here_comparisons = quick_reproduction("003")
    real, reports = tactip.reproduce.reproduce, []

    def keeping_the_report(*args, **kwargs):
        reports.append(real(*args, **kwargs))
        return reports[-1]

    monkeypatch.setattr(tactip.reproduce, "reproduce", keeping_the_report)     # the CLI calls it, as it is
    assert main(["reproduce", "003", "--quick", "--quiet", "--json", str(tmp_path / "p003-there.json"), "--scheduler",
                 address]) == 0
    # the same rows and comparisons as there (NaN as NaN)
    assert json.loads((tmp_path / "p003-there.json").read_text()) == here_rows and len(here_rows) >= 2
    np.testing.assert_equal([[c.figure, float(c.measured)] for c in reports[0].comparisons], here_comparisons)
    assert len(reports) == 1
    assert main(["validate", str(tmp_path / "here.h5"), str(tmp_path / "test.h5"), "--scheduler", address]) == 1
    assert "--scheduler runs a sweep" in capsys.readouterr().err
