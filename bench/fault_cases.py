"""Issues 9 and 22: the fault cases the suite tries, and which it handles (one line per case with --run).

Three counts, each from the test suite itself (nothing here is typed in by hand but the map below):

1. the issue's own cases (one line per case of its "Why" and "Outcome"), each mapped to the tests
   that try it; a case is handled when every one of its tests passes (a skip is not handled);
2. the pytest items of the two fault files (each parametrised id is one item);
3. the values the two in-process sweeps try inside their items: every numeric flag x
   (nan, inf, -inf, '', a word), and every key of the sample stations x the wrong values of its type.

    python bench/fault_cases.py          # collect only: cases tried, items, sweep values
    python bench/fault_cases.py --run    # also run the two fault files (and the mapped tests elsewhere)
    python bench/fault_cases.py --run -n 2   # the same on two workers
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


_B = "tests/tactip/test_bad_inputs.py::"
_S = "tests/test_special_outputs.py::"
_O = "tests/tactip/cli/test_cli_overwrite.py::"
_J = "tests/tactip/cli/test_cli_json.py::"
# Issue 22's cases (group, case, tests). A test named without its parameters stands for all of them.
ISSUE22_CASES = [
    ("special output", "results export --out /dev/null: a device written into, never replaced",
     [f"{_S}test_a_character_device_is_written_into_and_a_block_device_refused"]),
    ("special output", "--out /dev/stdout > file: the link written through, the file filled",
     [f"{_S}test_a_link_to_standard_output_is_written_through_not_replaced"]),
    ("special output", "--out FIFO and validate --json /dev/stdout | wc: no hang",
     [f"{_S}test_a_fifo_with_a_reader_receives_the_output_and_stays_a_fifo",
      f"{_S}test_a_fifo_nobody_reads_is_refused_at_once_and_the_result_kept", f"{_J}test_json_into_a_fifo_is_streamed"]),
    ("our files", "results export --out model.h5, --json --out calibration.h5, train --out calibration.h5 / "
                  "station.toml, validate --json model.h5: refused without --overwrite",
     [f"{_O}test_the_issue_cases_are_refused_without_overwrite_and_leave_the_file",
      f"{_O}test_each_kind_of_project_file_is_recognised_by_its_content"]),
    ("our files", "--overwrite replaces; a foreign file, a new path, a stream written as before",
     [f"{_O}test_with_overwrite_the_file_is_replaced",
      f"{_O}test_a_foreign_file_a_new_path_and_a_stream_are_written_as_before",
      f"{_O}test_every_command_that_writes_a_file_has_overwrite_and_the_common_flags"]),
    ("our files", "a foreign SQLite refused before anything is added to it",
     ["tests/tactip/line/test_results.py::test_a_foreign_database_with_tables_named_as_ours_is_refused_unchanged"]),
    ("ignored input", "train --epsilon 1e308", [f"{_B}test_an_epsilon_that_drowns_the_counts_is_refused"]),
    ("ignored input", "a model with taps_per_class = -3", [f"{_B}test_a_model_with_negative_tap_counts_is_refused"]),
    ("ignored input", "[sensor] source = 7 or '/etc/passwd' on the simulated arm",
     [f"{_B}test_a_source_the_simulated_arm_would_ignore_is_refused"]),
    ("ignored input", "--data-dir without --sim", [f"{_B}test_data_dir_without_sim_is_refused_not_ignored"]),
    ("ignored input", "replay --decision-threshold without --model",
     [f"{_B}test_a_decision_threshold_without_a_model_is_refused_not_ignored"]),
    ("ignored input", "likelihood = 'histogram' over a Gaussian model file",
     [f"{_B}test_a_model_of_another_kind_than_the_station_names_is_refused"]),
    ("ignored input", "record synthetic:2000000, record synthetic:0",
     [f"{_B}test_a_synthetic_source_out_of_range_is_refused_before_recording"]),
    ("ignored input", "detect --expected-pins 1e30", [f"{_B}test_an_expected_pin_count_beyond_any_pad_is_refused_not_warned_about"]),
    ("traceback", "a PNG claiming 60000 x 60000 px (detect, replay)",
     [f"{_B}test_an_image_claiming_more_pixels_than_the_decoder_takes_is_named"]),
    ("traceback", "a symlink loop as an output", [f"{_B}test_a_symlink_loop_as_an_output_is_one_line"]),
    ("cheap first", "inspect --sim --gap g99 refused before training",
     [f"{_B}test_an_unknown_gap_is_refused_before_the_simulated_station_prepares"]),
    ("cheap first", "the --sim station in one place whatever the folder",
     [f"{_B}test_the_simulated_station_lives_in_one_place_whatever_the_folder"]),
    ("scripting", "inspect --json and --fail-on fail|undecided set the exit status",
     [f"{_J}test_inspect_json_is_alone_on_stdout_and_matches_the_stored_verdicts",
      f"{_J}test_inspect_fail_on_sets_the_exit_status_from_the_verdicts",
      f"{_J}test_the_exit_status_of_each_verdict_and_fail_on",
      f"{_J}test_inspect_json_to_a_file_keeps_the_human_lines_on_stdout"]),
    ("scripting", "--json [FILE|-] the same in detect, results list/export, validate, reproduce, arm status",
     [f"{_J}test_results_list_and_export_json_to_stdout_or_a_file",
      f"{_J}test_detect_json_to_stdout_alone_or_to_a_file_beside_the_summary",
      f"{_J}test_validate_json_to_stdout_is_alone_there", f"{_J}test_arm_status_json",
      f"{_J}test_reproduce_json_to_stdout"]),
    ("scripting", "-q / -v on every command", [f"{_J}test_quiet_and_verbose_on_every_command_and_before_it"]),
    ("scripting", "Ctrl-C exits 130",
     ["tests/tactip/cli/test_cli_station.py::test_a_killed_collection_resumes_to_the_uninterrupted_dataset[SIGINT]"]),
    ("scripting", "progress off a terminal: plain lines, at most one per few seconds",
     ["tests/test_progress.py::test_off_a_terminal_a_bar_writes_whole_lines_only_at_its_start_and_end",
      "tests/test_progress.py::test_off_a_terminal_the_interval_is_a_few_seconds_and_a_bar_left_off_still_ends_with_a_line"]),
    ("scripting", "every README example runs as written (output folders created)",
     ["tests/tactip/test_readme_examples.py::test_a_readme_example_runs_as_written",
      "tests/tactip/test_readme_examples.py::test_the_readme_has_examples_of_every_command"]),
    ("clock", "frame counts of the live camera and recorder from fake clocks",
     ["tests/tactip/station/test_live_camera.py::test_a_tap_is_the_rest_frame_then_every_frame_until_release",
      "tests/tactip/replay/test_record.py::test_a_live_camera_is_recorded_for_the_time_asked"]),
]


def _matching(node: str, items) -> list[str]:
    """The collected items ``node`` names: itself, or every parametrised item of a test named without them."""
    return [n for n in items if n == node or n.startswith(node + "[")]


# The two sweeps: each item tries several values (counted by `sweep_values`).
_SWEEPS = "::test_every_"


class _Recorder:
    """A pytest plugin noting each item collected and each outcome."""

    def __init__(self):
        self.items: list[str] = []
        self.outcome: dict[str, str] = {}

    def pytest_collection_finish(self, session):
        self.items = [item.nodeid for item in session.items]

    def pytest_xdist_node_collection_finished(self, node, ids):    # with -n: the workers collect
        self.items = sorted(set(self.items) | set(ids))

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
    parser.add_argument("-n", "--workers", type=int, default=0, help="pytest-xdist workers (default: none)")
    args = parser.parse_args()
    import pytest

    mapped = sorted({node for _, _, nodes in ISSUE_CASES + ISSUE22_CASES for node in nodes})
    elsewhere = [n for n in mapped if not n.startswith(FILES)]
    recorder = _Recorder()
    argv = ["-q", "-p", "no:cacheprovider", *FILES, *elsewhere]
    if args.workers:
        argv += ["-n", str(args.workers)]
    pytest.main(argv + ([] if args.run else ["--collect-only"]), plugins=[recorder])
    missing = [n for n in mapped if not _matching(n, recorder.items)]
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
    in_files = [n for n in recorder.items if n.startswith(FILES)]
    passed = sum(results.get(n) == "passed" for n in in_files)
    skipped = sum(results.get(n) == "skipped" for n in in_files)
    for issue, cases in (("9", ISSUE_CASES), ("22", ISSUE22_CASES)):
        print(f"\nissue {issue}'s cases, one line each:")
        handled = 0
        for group, case, nodes in cases:
            items = [n for node in nodes for n in _matching(node, recorder.items)]
            # A README example skipped for want of hardware (its reason in the test) does not count against it.
            bad = {n: results.get(n) for n in items if results.get(n) != "passed"
                   and not (results.get(n) == "skipped" and "readme_example" in n)}
            handled += not bad
            print(f"  {'handled' if not bad else 'NOT HANDLED'}  [{group}] {case}"
                  + ("" if not bad else f"  ({', '.join(f'{n.split(chr(58))[-1]}: {o}' for n, o in bad.items())})"))
        print(f"issue {issue}'s cases handled: {handled} of {len(cases)}")
    print(f"pytest items passed: {passed} of {len(in_files)} ({skipped} skipped)")


if __name__ == "__main__":
    main()
