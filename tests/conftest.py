"""The whole suite's order: the test files that take longest start first under pytest-xdist.

`make test` runs the suite on every core with ``--dist loadfile`` (pyproject.toml's ``addopts``): each
file goes to one worker whole, so a module's fixture (a trained station, a reproduction) is built once,
and workers take the files in the order collected here (``--no-loadscope-reorder`` keeps it). A file of
minutes that started last would run alone at the end while the other cores idle, so `LONGEST_FIRST`
puts the longest files first, longest first; the rest follow in pytest's own order. The order is only
a schedule: every test runs, and a file missing from the list (or a name in it that no longer exists)
changes nothing but when it runs.

Under pytest-xdist the simulated station's collections tap in the worker's own process when the
workers already use every core (``TACTIP_SIM_WORKERS``, `_free_cpus_per_worker`): a pool of spawned
processes per collection would only import the package again (~2 s of CPU each) and compete with the
other workers. test_cli_station.py still collects with a pool, and checks it stores the same taps.
"""

import os


def _free_cpus_per_worker() -> int:
    """The CPUs (at most 4, the product's default) each of this session's pytest-xdist workers may use."""
    workers = int(os.environ.get("PYTEST_XDIST_WORKER_COUNT") or 1)
    return max(1, min((os.cpu_count() or 1) // workers, 4))


if os.environ.get("PYTEST_XDIST_WORKER"):
    os.environ.setdefault("TACTIP_SIM_WORKERS", str(_free_cpus_per_worker()))
    # The same for the threads of numpy's BLAS and of torch (OpenMP; `perception._ensemble_training.all_cores`
    # honours OMP_NUM_THREADS too): by default each worker starts one per core, so two workers on two cores
    # would run four threads, which spin while they wait for each other (CPU time without work); the few
    # tests that ask for more threads (the torch training's reproducibility on 2 and 4) have theirs sleep
    # while they wait (OMP_WAIT_POLICY). Set before numpy and torch are imported (they read them once);
    # subprocesses inherit them.
    for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_variable, str(_free_cpus_per_worker()))
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

#: Test files of about 15 CPU-s or more, longest first (CPU-s of one worker, self + children, measured per test on
#: a 2-core VM under make test's 2 workers, 2026-11-29 on main f84c508, less what suite4 took off; files not yet
#: measured there from 2026-11-29's earlier run). test_station_bar (its own station, no session fixture) and the
#: README's examples (which build the session's station and recordings first) start the two workers;
#: test_station_torch, which needs that station, queues behind test_station_bar, by when it is built.
#: test_cluster and test_reproduce share quick reproductions (the first to need one builds it): apart.
LONGEST_FIRST = (
    "tests/tactip/station/test_station_bar.py",         # 125
    "tests/tactip/test_readme_examples.py",             # 200, of which ~75 the session's fixtures
    "tests/tactip/station/test_station_torch.py",       # 70-170
    "tests/perception/test_learned.py",                 # 70-100
    "tests/pins/test_lattice.py",                       # 94
    "tests/pins/test_accel_detect.py",                  # 65
    "tests/tactip/reproduce/test_reproduce_002.py",     # 65
    "tests/tactip/test_cluster.py",                     # 41 (+ the quick 001 and 003 when it runs them first)
    "tests/tactip/line/test_dashboard_browser.py",      # 40-60
    "tests/pins/test_lattice_seeds.py",                 # 52
    "tests/tactip/reproduce/test_reproduce.py",         # 50 when it runs the quick reproductions
    "tests/calibration/test_training.py",               # 40
    "tests/tactip/cli/test_cli_missing_pins.py",        # 33
    "tests/perception/test_baselines.py",               # 33
    "tests/pins/test_flat_gel.py",                      # 32
    "tests/tactip/dataset/test_build.py",               # 31
    "tests/tactip/reproduce/test_reproduce_004.py",     # 28
    "tests/tactip/reproduce/test_acuity.py",            # 28
    "tests/tactip/cli/test_cli_station.py",             # 23
    "tests/pins/test_accel.py",                         # 22
    "tests/tactip/dataset/test_cli_dataset.py",         # 18
    "tests/tactip/cli/test_cli_detect_replay_agree.py",  # 16
)


def pytest_collection_modifyitems(config, items):
    """Put the items of the `LONGEST_FIRST` files first, in its order; the others keep theirs after them."""
    rank = {path: i for i, path in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))   # a stable sort
