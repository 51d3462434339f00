"""Reproduce a paper's experiment on the simulated sensor and print its figures beside the paper's.

PAPER is 000 (tactile hyperacuity: Table II on the simulated fingertip), 001 (rod shape and
position with a 'boredom' deadline), 002 (the inspection station: gap width by active, random and
stationary perception, Fig. 9), 003 (texture under depth uncertainty, passive / weakly / strongly
active) or 004 (edge angle and position, contour following, adaptive prior). Each simulated world was
tuned against one figure of its paper (the report says which: a fit, not a prediction); the other
figures are predictions. --quick runs the same
experiment with fewer runs and conditions (seconds to a minute); the full run takes minutes.
With --scheduler tcp://HOST:PORT the conditions (003: the simulator seeds; 001: the deadlines; 004:
the methods and thresholds; 000: the class counts) run on that Dask cluster: the same figures, seed
for seed, as a run here.

Each reproduced figure is saved as a PNG, the paper's numbers drawn on the same axes, in
--figures DIR (default: beside the --json FILE; out/reproduce/PAPER/ without one or when the JSON
goes to a stream), named PAPER_FIGURE.png (e.g. 002_fig9.png); --no-figures skips them. A figure a
world was tuned on says "FIT" in its title. Figures per paper (PNG names; [R]: only with --figure-runs):
  000: table2, table3 (error against class count); [R] fig7 (example trajectories), fig8b (decision-time
       histograms), fig10 (passive error and time against location), fig11 (error and time against
       threshold, passive and active, per class count) on the simulated fingertip
  001: fig4, fig5, fig6, fig7a (reaction-time histograms), fig7b, fig8 (errors and times per test class)
  002: fig9 (a fit); [R] fig10 (fixation depth), fig11 (lateral noise: the station is prepared again and
       a noisy test collection tapped per sigma, a few minutes even with --quick)
  003: fig5, fig6a (error per texture and depth), fig6b, fig7 (mean errors), fig7_hist (error
       frequencies, as the paper's bars); [R] fig5_sweep (a sweep of test depth offsets)
  004: fig6 (runs closing the contour), fig7; [R] fig6_traced (the traced contours), fig7_sweep (a
       threshold sweep), fig8 (the learned shift)
The rows of the --figure-runs are saved as PAPER_figure_runs.json beside the PNGs. Figures and JSON reports are rewritten by a new
run (a file tactip wrote otherwise, such as a model, is never replaced without --overwrite).

Examples:
  tactip reproduce 001 --json results/001.json           (figures in results/: 001_fig4.png ...)
  tactip reproduce 002 --quick --figure-runs --figures out/figs
  tactip reproduce 004 --quick --json > out/004.json
  tactip reproduce 003 --scheduler tcp://10.0.0.5:8786
"""

from __future__ import annotations

import argparse
from pathlib import Path

from tactip.cli._types import add_json_argument, seed

HELP = "run a paper's experiment (000-004) on the simulator, figures beside the paper's"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Fill the parser of ``tactip reproduce``."""
    parser.add_argument("paper", choices=("000", "001", "002", "003", "004"), metavar="PAPER",
                        help="paper number: 000, 001, 002, 003 or 004")
    add_json_argument(parser, "the rows of the paper's figures")
    parser.add_argument("--quick", action="store_true", help="fewer runs and conditions (for a quick look and tests)")
    parser.add_argument("--seed", type=seed, default=0, help="seed of the simulated sensor and runs, >= 0 (default 0)")
    figures = parser.add_mutually_exclusive_group()
    figures.add_argument("--figures", type=figure_folder, metavar="DIR",
                         help="folder of the figures' PNGs (default: beside the --json FILE, else "
                              "out/reproduce/PAPER)")
    figures.add_argument("--no-figures", action="store_true", help="no PNG figures")
    parser.add_argument("--figure-runs", action="store_true",
                        help="also run the experiments only figures need (000 Figs 7, 8B, 10, 11; 002 Figs 10-11; "
                             "003 Fig. 5 sweep; 004 Figs 6 traced, 7 sweep and 8)")
    parser.add_argument("--scheduler", metavar="tcp://HOST:PORT",
                        help="run the conditions on this Dask cluster (dask scheduler; dask worker on each machine)")


def figure_folder(text: str) -> Path:
    """An argparse type: a folder for the figures (created when missing); refused when it is a file."""
    if not text.strip():
        raise argparse.ArgumentTypeError("must name a folder, got ''")
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise argparse.ArgumentTypeError(f"{text!r} is a file, not a folder")
    return path


def _figures_folder(args: argparse.Namespace) -> Path | None:
    """Where the PNGs go: --figures, else beside the --json FILE, else out/reproduce/PAPER; None: no figures."""
    if args.no_figures:
        return None
    if args.figures is not None:
        return args.figures
    if args.json is not None and not _streamed(args.json):
        return Path(args.json).parent
    return Path("out") / "reproduce" / args.paper


def _streamed(path) -> bool:
    """Whether the JSON goes to a stream (``-``, ``/dev/null``, a FIFO ...): no folder to put figures beside."""
    from _shared import stream_target

    try:
        return str(path) == "-" or stream_target(path)
    except OSError:                     # a block device or a socket: the JSON writer reports it
        return True


def _check_figures_folder(folder: Path | None) -> None:
    """Before the work: the folder can be made and written (its nearest existing parent is a writable folder)."""
    import os

    from tactip.errors import TactipError

    if folder is None:
        return
    existing = next((p for p in (folder, *folder.parents) if p.exists()), Path("."))
    if not existing.is_dir():
        raise TactipError(f"figures folder {str(folder)!r}: {str(existing)!r} is a file")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise TactipError(f"figures folder {str(folder)!r}: {str(existing)!r} cannot be written")


def run(args: argparse.Namespace) -> int:
    """Run the reproduction, print the report, write the JSON rows and the figures."""
    import contextlib
    import functools

    from _shared.progress import progress_bar
    from tactip._output import write_json
    from tactip.reproduce import reproduce
    from tactip.reproduce.figure_runs import run_with_figure_runs

    folder = _figures_folder(args)
    _check_figures_folder(folder)
    if folder is not None:                  # before the work, as for every output of the CLI
        _refuse_replacing_figures(folder, args.paper, overwrite=args.overwrite)

    # --quiet: no progress at all (None also keeps the station's collection bars of 002 and its figure runs off)
    progress = None if args.quiet else functools.partial(progress_bar, desc=f"paper {args.paper}",
                                                          unit="condition", leave=False)
    with contextlib.ExitStack() as stack:
        map_fn = None
        if args.scheduler is not None:
            from tactip.cluster import cluster_map, open_client

            map_fn = cluster_map(stack.enter_context(open_client(args.scheduler)), progress=progress)
        if args.figure_runs:
            report, extra = run_with_figure_runs(args.paper, quick=args.quick, seed=args.seed, progress=progress,
                                                 map_fn=map_fn)
        else:
            report, extra = reproduce(args.paper, quick=args.quick, seed=args.seed, progress=progress,
                                      map_fn=map_fn), {}
    print(report.text())
    if args.figure_runs and not extra:
        print(f"  note: --figure-runs: every figure of paper {args.paper} comes from its rows; no runs of its own")
    if args.json is not None:
        write_json(args.json, report.json_rows())
        if str(args.json) != "-":
            print(f"wrote {len(report.rows)} rows to {args.json}")
    if folder is not None:
        _save_figures(report, extra, folder)
    return 0


def _refuse_replacing_figures(folder: Path, paper: str, *, overwrite: bool) -> None:
    """No figure file may replace a file tactip wrote (a model ...) unless --overwrite (`tactip._output`)."""
    from tactip._output import refuse_replacing_project_files
    from tactip.reproduce.figures import figure_names, figure_path

    refuse_replacing_project_files([figure_path(folder, paper, name) for name in figure_names(paper)] +
                                   [folder / f"{paper}_figure_runs.json"], overwrite=overwrite)


def _save_figures(report, extra: dict, folder: Path) -> None:
    """The PNGs (and the rows of the figure runs) in ``folder``."""
    from tactip._output import write_json
    from tactip.reproduce.figures import make_figures, save_figures

    figures = make_figures(report, extra)
    runs_json = folder / f"{report.paper}_figure_runs.json"
    written = save_figures(figures, folder, paper=report.paper)
    if extra:
        write_json(runs_json, extra)
    names = ", ".join(p.name for p in written)
    print(f"wrote {len(written)} figures to {folder}: {names}" + (f" (figure runs: {runs_json.name})" if extra else ""))
