"""Issue 9's numbers: the fault cases the suite tries, and how many it handles.

Three counts, each from the test suite itself (nothing here is typed in by hand but the map below):

1. the issue's own cases (one line per case of its "Why" and "Outcome"), each mapped to the tests
   that try it; a case is handled when every one of its tests passes (a skip is not handled);
2. the pytest items of the two fault files (each parametrised id is one item);
3. the values the two in-process sweeps try inside their items: every numeric flag x
   (nan, inf, -inf, '', a word), and every key of the sample stations x the wrong values of its type.

    python bench/fault_cases.py          # collect only: cases tried, items, sweep values
    python bench/fault_cases.py --run    # also run the two fault files (and the mapped tests elsewhere)
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
FILES = ("tests/tactip/test_faults_input.py", "tests/tactip/test_faults_data.py")

_D = "tests/tactip/test_faults_data.py::"
_I = "tests/tactip/test_faults_input.py::"


def _cli(case: str) -> str:
    return f"{_I}test_bad_input_is_refused_by_the_real_cli[{case}]"


def _in(case: str) -> str:
    return f"{_I}test_bad_input_is_refused_in_process[{case}]"


_SETTINGS = f"{_D}test_a_model_with_bad_recommended_settings_is_refused"
# (group, the issue's case, the tests that try it)
ISSUE_CASES = [
    ("over input", "train train.h5 --out train.h5", [f"{_D}test_train_refuses_to_write_the_model_over_its_dataset"]),
    ("over input", "results export --db r.sqlite --csv --out r.sqlite",
     [f"{_D}test_results_export_and_plot_refuse_to_write_over_the_database"]),
    ("over input", "replay v.mp4 --out o.h5 --annotate v.mp4",
     [f"{_D}test_replay_refuses_outputs_over_the_video_or_each_other"]),
    ("disk full", "collect: write errors, segfault, zero taps, rerun 'success', zero taps trained",
     [f"{_D}test_collect_on_a_full_disk_keeps_only_complete_taps_and_resumes",
      f"{_D}test_a_partly_written_tap_is_never_read"]),
    ("disk full", "replay: segfault, hidden .part", [f"{_D}test_replay_on_a_full_disk_reports_it_and_leaves_nothing"]),
    ("disk full", "inspect: stored aborted with the wrong reason",
     [f"{_D}test_inspect_on_a_full_disk_reports_it_and_keeps_the_stored_rows"]),
    ("disk full", "results export truncates the old output",
     [f"{_D}test_results_export_on_a_full_disk_keeps_the_old_file"]),
    ("interrupted", "first inspect --sim interrupted in the fixation sweep",
     [f"{_D}test_an_interrupted_preparation_leaves_no_half_prepared_model",
      f"{_D}test_a_half_prepared_model_is_prepared_again_or_warned_about"]),
    ("tap budget", "--tap-budget 0", [_cli("tap budget 0")]),
    ("tap budget", "--tap-budget nan", [_cli("tap budget nan")]),
    ("tap budget", "--tap-budget too tight", [_cli("tap budget too tight")]),
    ("tap budget", "stored settings never checked on load",
     [f"{_SETTINGS}[decision_threshold-0.0-inspect-words0-True]",
      f"{_SETTINGS}[decision_threshold-nan-validate-words1-False]",
      f"{_SETTINGS}[decision_threshold-1.5-replay-words2-False]",
      f"{_SETTINGS}[fixation_location-40.0-inspect-words3-False]"]),
    ("traceback", "--expected-pins 1..5",
     [f"{_I}test_warned_cases_of_the_issue_run_to_the_end_through_the_real_cli", _in("replay --expected-pins 1..5"),
      *(f"tests/tactip/cli/test_cli_detect.py::test_a_count_far_off_is_a_one_line_warning[{n}]" for n in (1, 2, 5))]),
    ("traceback", "one black frame in a video", [f"{_I}test_warned_cases_of_the_issue_run_to_the_end_through_the_real_cli"]),
    ("traceback", "record --seconds inf", [_cli("record --seconds inf")]),
    ("traceback", "taps stored as bytes", [f"{_D}test_taps_stored_as_bytes_are_refused_naming_the_dataset"]),
    ("traceback", "huge --locations", [_cli("simulate huge --locations"), _cli("train huge --locations"),
                                       _in("simulate locations x taps")]),
    ("traceback", "huge --bins", [_cli("train huge --bins")]),
    ("traceback", "huge --runs", [_cli("validate huge --runs")]),
    ("traceback", "negative --seed", [_cli("validate negative --seed"), _in("simulate negative --seed")]),
    ("traceback", "negative --sweep-lateral", [_cli("validate negative --sweep-lateral")]),
    ("traceback", "--plot x.xyz", [_cli("validate --plot x.xyz"), _in("results plot --out x.xyz")]),
    ("traceback", "binary TOML", [_cli("binary TOML")]),
    ("traceback", "Latin-1 TOML", [_cli("Latin-1 TOML")]),
    ("traceback", "data_dir = 5", [_cli("data_dir = 5")]),
    ("traceback", "results = 5", [_cli("results = 5")]),
    ("traceback", "negative [sim] seed", [_cli("negative [sim] seed")]),
    ("traceback", "results at another SQLite database (tables added)",
     [f"{_D}test_results_refuse_another_sqlite_database_unchanged"]),
    ("traceback", "calibrate with pins = 5", [_cli("calibrate pins = 5")]),
    ("nonsense", "train --epsilon inf; validate and replay accept the NaN model",
     [f"{_D}test_a_model_with_nan_likelihoods_is_refused_and_train_refuses_inf_epsilon"]),
    ("nonsense", "validate --fixation 100", [_cli("validate --fixation 100")]),
    ("nonsense", "validate --fixation nan", [_cli("validate --fixation nan")]),
    ("nonsense", "replay --mm-per-px inf", [_cli("replay --mm-per-px inf")]),
    ("nonsense", "a rest frame taken during a tap", [f"{_I}test_warned_cases_of_the_issue_run_to_the_end_through_the_real_cli"]),
    ("nonsense", "collect resumed with another protocol seed",
     [f"{_D}test_a_resumed_collection_with_another_protocol_is_refused[protocol-change0-seed-True]"]),
    ("nonsense", "results --limit -1", [f"{_D}test_results_list_refuses_a_limit_below_one"]),
    ("hang", "dwell = 100000", [_cli("dwell = 100000")]),
    ("hang", "depth_step = 1e-7", [_cli("depth_step = 1e-7")]),
    ("hang", "collect --workers 500", [_cli("collect --workers 500")]),
    ("misleading", "read-only data folder", [f"{_D}test_a_read_only_data_folder_is_reported_as_permission_denied"]),
    ("misleading", "unreadable video said 'corrupt'", [f"{_I}test_an_unreadable_video_says_permission_denied"]),
    ("misleading", "every BrokenPipeError taken for 'piped into head'",
     [f"{_D}test_only_a_broken_stdout_is_the_quiet_broken_pipe"]),
    ("misleading", "SIGTERM during inspect leaves a row running",
     [f"{_D}test_sigterm_or_a_hang_up_during_inspect_stores_the_inspection_as_aborted[15-Stopped (terminated)]"]),
    ("outcome", "stale running rows closed on the next start",
     [f"{_D}test_stale_running_rows_are_closed_but_live_ones_are_not"]),
    ("outcome", "atomic writes (temporary, fsync, rename; killed writers' temporaries)",
     ["tests/test_files.py::test_a_failed_write_keeps_the_old_file_and_leaves_no_temporary",
      f"{_D}test_temporaries_of_killed_writers_are_removed_by_the_next_write"]),
    ("outcome", "write errors named, earlier data intact (read-only output folder)",
     [f"{_D}test_an_output_in_a_read_only_folder_is_refused_before_any_work"]),
]


# The two sweeps: each item tries several values (counted by `sweep_values`).
_SWEEPS = "::test_every_"


class _Recorder:
    """A pytest plugin noting each item collected and each outcome."""

    def __init__(self):
        self.items: list[str] = []
        self.outcome: dict[str, str] = {}

    def pytest_collection_finish(self, session):
        self.items = [item.nodeid for item in session.items]

    def pytest_runtest_logreport(self, report):
        if report.failed:                                        # in setup, call or teardown
            self.outcome[report.nodeid] = "failed"
        elif report.skipped and self.outcome.get(report.nodeid) != "failed":
            self.outcome[report.nodeid] = "skipped"
        elif report.when == "call":
            self.outcome.setdefault(report.nodeid, "passed")


def sweep_values() -> tuple[int, int]:
    """(numeric flags x values, station keys x wrong values) tried inside the two sweep tests."""
    sys.path.insert(0, str(ROOT))
    from tests.tactip import test_faults_input as t

    flags = len(t.NUMERIC_FLAGS) * len(t.NOT_A_NUMBER)
    keys = sum(len(t.wrong_values(path, value)) for _, path, value in t.SAMPLE_KEYS)
    return flags, keys


def main() -> None:
    """Print the counts."""
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--run", action="store_true", help="run the tests and count the cases handled")
    args = parser.parse_args()
    import pytest

    mapped = sorted({node for _, _, nodes in ISSUE_CASES for node in nodes})
    elsewhere = [n for n in mapped if not n.startswith(FILES)]
    recorder = _Recorder()
    argv = ["-q", "-p", "no:cacheprovider", *FILES, *elsewhere]
    pytest.main(argv + ([] if args.run else ["--collect-only"]), plugins=[recorder])
    missing = [n for n in mapped if n not in recorder.items]
    if missing:
        sys.exit(f"mapped tests not collected (renamed?): {missing}")
    items = {f: sum(1 for n in recorder.items if n.startswith(f)) for f in FILES}
    flags, keys = sweep_values()
    sweeps = sum(1 for n in recorder.items if n.startswith(FILES) and _SWEEPS in n)
    print(f"\nissue 9's cases mapped to tests: {len(ISSUE_CASES)} (tests: {len(mapped)})")
    print("pytest items: " + ", ".join(f"{Path(f).name} {n}" for f, n in items.items()) + f", total {sum(items.values())}"
          f" ({sweeps} of them sweep items)")
    print(f"values tried inside the {sweeps} sweep items: {flags} (numeric flags x 5) + {keys} (station keys x wrong "
          f"values)")
    print(f"fault cases tried: {sum(items.values()) - sweeps + flags + keys} (items other than sweep items + sweep "
          f"values)")
    if not args.run:
        return
    results = recorder.outcome
    handled = [c for _, c, nodes in ISSUE_CASES if all(results.get(n) == "passed" for n in nodes)]
    not_handled = [(c, {n: results.get(n) for n in nodes if results.get(n) != "passed"})
                   for _, c, nodes in ISSUE_CASES if c not in handled]
    in_files = [n for n in recorder.items if n.startswith(FILES)]
    passed = sum(results.get(n) == "passed" for n in in_files)
    skipped = sum(results.get(n) == "skipped" for n in in_files)
    print(f"issue 9's cases handled: {len(handled)} of {len(ISSUE_CASES)}")
    for case, why in not_handled:
        print(f"  not handled: {case}: {why}")
    print(f"pytest items passed: {passed} of {len(in_files)} ({skipped} skipped)")


if __name__ == "__main__":
    main()
