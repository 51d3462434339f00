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

#: Test files of about 15 CPU-s or more, longest first (CPU-s of one worker, self + children, measured per test on
#: the 2-core VM under make test's 2 workers, 2026-11-29 on branch suite5 = main b811570 with one BLAS/OpenMP thread
#: per worker; load 4-8, so somewhat inflated; /work/scratch/s14/suite5-durations.txt). test_station_bar (its own
#: station, no session fixture) and the README's examples (which build the session's station and recordings first)
#: start the two workers; test_station_torch, which needs that station, queues behind test_station_bar, by when it
#: is built (its 166: the torch station's preparation ~126, the session's ECE collection ~39 when it builds it).
#: test_cluster and test_reproduce share quick reproductions (the first to need one builds it): apart. Simulated
#: with these per-test figures (xdist's loadfile rule: a worker gets its next file when <= 2 of its tests are
#: pending), the two workers end within 1 % of each other (662 and 665 CPU-s).
LONGEST_FIRST = (
    "tests/tactip/station/test_station_bar.py",         # 100 (one test)
    "tests/tactip/test_readme_examples.py",             # 141, of which 43 its first example with the session's fixtures
    "tests/tactip/station/test_station_torch.py",       # 166
    "tests/pins/test_lattice.py",                       # 76
    "tests/tactip/test_faults_data.py",                 # 59 (subprocesses)
    "tests/perception/test_learned.py",                 # 48
    "tests/tactip/reproduce/test_reproduce_002.py",     # 47 (one test)
    "tests/tactip/line/test_dashboard_browser.py",      # 45
    "tests/tactip/test_one_scale.py",                   # 44
    "tests/pins/test_lattice_seeds.py",                 # 38
    "tests/tactip/cli/test_cli_station.py",             # 31
    "tests/pins/test_accel_detect.py",                  # 29
    "tests/tactip/test_cluster.py",                     # 27 (+ the quick 001 and 003 when it runs them first)
    "tests/tactip/test_faults_input.py",                # 27
    "tests/tactip/dataset/test_build.py",               # 26
    "tests/pins/test_flat_gel.py",                      # 22
    "tests/tactip/replay/test_batch.py",                # 21
    "tests/tactip/replay/test_replay_contacts.py",      # 17
    "tests/pins/test_track_identity.py",                # 17
    "tests/tactip/reproduce/test_reproduce.py",         # 16 (more when it runs the quick reproductions first)
    "tests/tactip/reproduce/test_figure_samples.py",    # 14
    "tests/tactip/replay/test_replay.py",               # 13
)


def pytest_collection_modifyitems(config, items):
    """Put the items of the `LONGEST_FIRST` files first, in its order; the others keep theirs after them."""
    rank = {path: i for i, path in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))   # a stable sort
