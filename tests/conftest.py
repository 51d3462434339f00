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

#: Test files of a worker-minute or more, longest first (seconds of one worker, ``--durations=0`` on a
#: 2-core VM, 2026-11-28; the station and reproduction files prepare simulated stations).
LONGEST_FIRST = (
    "tests/tactip/station/test_station_bar.py",
    "tests/tactip/test_readme_examples.py",
    "tests/tactip/reproduce/test_reproduce_002.py",
    "tests/tactip/station/test_station_torch.py",
    "tests/tactip/test_cluster.py",
    "tests/tactip/reproduce/test_reproduce.py",
    "tests/tactip/reproduce/test_reproduce_004.py",
    "tests/tactip/line/test_dashboard_browser.py",
    "tests/tactip/reproduce/test_acuity.py",
    "tests/calibration/test_sensor.py",
    "tests/tactip/cli/test_cli_json.py",
    "tests/tactip/cli/test_cli_missing_pins.py",
)


def pytest_collection_modifyitems(config, items):
    """Put the items of the `LONGEST_FIRST` files first, in its order; the others keep theirs after them."""
    rank = {path: i for i, path in enumerate(LONGEST_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::")[0], len(rank)))   # a stable sort
