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
    _cpus = str(_free_cpus_per_worker())
    os.environ.setdefault("TACTIP_SIM_WORKERS", _cpus)
    # The same for the threads of numpy's BLAS and of torch (OpenMP; `perception._ensemble_training.all_cores`
    # honours OMP_NUM_THREADS too): by default each worker starts one per core, so two workers on two cores
    # would run four threads, which spin while they wait for each other (CPU time without work); the few
    # tests that ask for more threads (the torch training's reproducibility on 2 and 4) have theirs sleep
    # while they wait (OMP_WAIT_POLICY). Set before numpy and torch are imported (they read them once);
    # subprocesses inherit them.
    for _variable in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_variable, _cpus)
    os.environ.setdefault("OMP_WAIT_POLICY", "PASSIVE")

#: Test files of about 20 s or more, longest first (seconds of one worker, setup + call + teardown, from pytest's
#: --durations under 2 xdist workers on the 2-core VM, 2026-11-29 on branch suite6; the machine was shared (load
#: 6-8), so every figure is about 2.4x its CPU-s; /work/scratch/s15/suite6/after.txt). test_station_bar (its own
#: station, no session fixture) and the README's examples (which build the session's station and recordings
#: first) start the two workers; test_station_torch, which needs that station, queues behind test_station_bar, by
#: when it is built (before suite6 its 323 was the torch station's preparation 238 and the session's ECE
#: collection 81: now 35 and 24). test_cluster (under 20 s now) and test_reproduce share quick reproductions (the
#: first to need one builds it): apart. test_dashboard_browser was skipped there (no Chromium): 45 is suite5's.
LONGEST_FIRST = (
    "tests/tactip/station/test_station_bar.py",         # 72 (one test)
    "tests/tactip/test_readme_examples.py",             # 205, with the session's station and recordings
    "tests/tactip/station/test_station_torch.py",       # 63
    "tests/pins/test_lattice.py",                       # 89
    "tests/perception/test_learned.py",                 # 77
    "tests/tactip/test_faults_data.py",                 # 74 (subprocesses)
    "tests/tactip/test_one_scale.py",                   # 71
    "tests/tactip/reproduce/test_reproduce_002.py",     # 65 (one test)
    "tests/pins/test_lattice_seeds.py",                 # 60
    "tests/tactip/reproduce/test_reproduce.py",         # 52 (the quick reproductions it runs first)
    "tests/pins/test_track_identity.py",                # 50
    "tests/pins/test_accel_detect.py",                  # 50
    "tests/tactip/test_faults_input.py",                # 49
    "tests/tactip/line/test_dashboard_browser.py",      # 45 (suite5)
    "tests/tactip/cli/test_cli_station.py",             # 43
    "tests/tactip/dataset/test_build.py",               # 42
    "tests/pins/test_flat_gel.py",                      # 30
    "tests/tactip/replay/test_batch.py",                # 27
    "tests/pins/test_track.py",                         # 26
    "tests/tactip/line/test_results_postgres.py",       # 25
    "tests/tactip/replay/test_replay.py",               # 24
    "tests/tactip/reproduce/test_figure_samples.py",    # 23
    "tests/tactip/replay/test_replay_contacts.py",      # 22
    "tests/tactip/dataset/test_cli_dataset.py",         # 22
    "tests/perception/test_baselines.py",               # 22
)


def pytest_collection_modifyitems(config, items):
    """Put the items of the `LONGEST_FIRST` files first, in its order; the others keep theirs after them."""
    rank = {path: i for i, path in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))   # a stable sort
