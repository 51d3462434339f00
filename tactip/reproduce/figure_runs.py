"""The small experiments that only figures need: 000 Figs 7, 8B, 10, 11; 002 Figs 10-11; 003 Fig. 5; 004 Figs 6-8.

Each returns JSON-ready rows, drawn by `tactip.reproduce.figures` and saved beside the PNGs:

- 002 Fig. 10: not here. `tactip.reproduce.p002.run` sweeps every fixation depth itself (it gives Fig. 9
  its fixation, as the paper's: `p002.fixation_from_sweep`, rows by `p002.sweep_rows`), so
  `run_with_figure_runs` takes those rows from the report's samples;
- 002 Fig. 11 (`lateral_rows`): a test collection per lateral noise sigma (offsets uniform over
  [-sigma, sigma] mm, ``[protocol] lateral_jitter_mm``) tapped on the same simulated station, the model
  trained without noise; each policy's width error at 10 mean taps (as Fig. 9, at Fig. 9's fixation)
  over the error at sigma 0;
- 000 Figs 7, 8B, 10 and 11 on the simulated fingertip (`tactip.reproduce.taxel_runs`);
- 003 Fig. 5 over a sweep of test depth offsets (`fig5_sweep_rows`);
- 004 Fig. 6, the traced contours of passive, active and adaptive perception at thresholds 0.2 and 0.9
  (`tactip.reproduce.figure_samples.traced_contour_samples`);
- 004 Figs 7 and 8 (`beta_sweep_rows`): contour following by active, adaptive (eq. 7 as printed) and
  the angle-only variant over a sweep of belief thresholds (the paper's beta); the adaptive runs'
  learned shift error at every decision is Fig. 8.

``quick`` keeps each to seconds or a minute (002's Fig. 11 taps new collections: the slowest; its
figure runs share the station the reproduction prepared); every run is seeded from ``seed``, as the
reproduction it accompanies.
"""

from __future__ import annotations

import functools
import tempfile
from pathlib import Path

import numpy as np

from _shared import map_pieces

__all__ = ["beta_sweep_rows", "fig5_sweep_rows", "lateral_rows", "run_with_figure_runs"]

#: Lateral noise sigmas of 002 Fig. 11, mm (quick: two of them).
SIGMAS_MM = (0.25, 0.5, 1.0, 2.0)
QUICK_SIGMAS_MM = (0.5, 2.0)
#: Methods and belief thresholds of the 004 sweep (the paper: 0 to 1 in steps of 0.05).
SWEEP_METHODS = ("active", "adaptive", "adaptive_angle_only")
SWEEP_THRESHOLDS = tuple(np.round(np.arange(0.1, 0.95, 0.1), 2))
QUICK_SWEEP_THRESHOLDS = (0.1, 0.3, 0.5, 0.7, 0.9)
#: Paper 003 Fig. 5: test depth offsets, mm (the paper: up to +-0.6 mm and beyond, to chance).
FIG5_OFFSETS_MM = tuple(np.round(np.arange(-1.0, 0.81, 0.1), 2))
QUICK_FIG5_OFFSETS_MM = (-0.6, -0.4, -0.2, 0.0, 0.2, 0.4, 0.6)
#: Thresholds whose learning curves make 004 Fig. 8.
FIG8_THRESHOLDS = (0.5, 0.9)


def _policy_error(environment, fixation: int, runs: int, seed: int) -> dict:
    """Each policy's width error at the compared mean taps (002 Fig. 9's measure) on one test collection."""
    from perception.choices import POLICIES
    from tactip.reproduce.p002 import COMPARED_AT_TAPS, _at_taps, _policy_runs

    return {name: _at_taps(_policy_runs(name, environment, fixation, runs, seed), COMPARED_AT_TAPS)
            for name in POLICIES}


def lateral_rows(config, model, test, *, sigmas_mm, runs: int, seed: int, progress: bool = False,
                 log=lambda line: None, fixation: int | None = None) -> list[dict]:
    """002 Fig. 11: ``{policy, sigma_mm, width_error_mm, ratio}``, sigma 0 first (ratio 1).

    Parameters
    ----------
    config : tactip.station.config.StationConfig
        The simulated station the model was prepared on; a test collection per sigma is tapped on it,
        under ``data_dir/lateral-SIGMA`` (reused when there).
    model : perception model
        Trained without lateral noise.
    test : perception.Dataset
        The noise-free test collection (sigma 0).
    sigmas_mm : sequence of float
    runs, seed : int
    progress : bool
        Progress bars of the collections.
    log : callable
        Where the collections' lines go.
    fixation : int, optional
        The active policy's location class (Fig. 9's: the Fig. 10 sweep's best); default the model's own.
    """
    import dataclasses

    from perception import VirtualEnvironment, load_dataset
    from tactip.station.procedures import collect_station

    fixation = model.fixation_class() if fixation is None else int(fixation)
    rows = []
    base = None
    for sigma in (0.0, *sigmas_mm):
        if sigma == 0:
            collection = test
        else:
            noisy = dataclasses.replace(config, protocol=dataclasses.replace(config.protocol,
                                                                             lateral_jitter_mm=float(sigma)))
            paths = collect_station(noisy, config.data_dir / f"lateral-{sigma:g}", progress=progress, log=log,
                                    sets=("test",))
            collection = load_dataset(paths["test"])
        errors = _policy_error(VirtualEnvironment(model, collection), fixation, runs, seed)
        base = base or errors
        rows += [{"policy": name, "sigma_mm": float(sigma), "width_error_mm": error,
                  "ratio": error / base[name] if base[name] > 0 else float("nan")} for name, error in errors.items()]
    return rows


def _sweep_run(condition, *, env, options: dict, seed: int):
    """One (method, threshold) of the 004 sweep (module level: it travels to a worker)."""
    from tactip.reproduce.contour import follow_contour
    from tactip.reproduce.p004 import METHODS

    method, threshold = condition
    return follow_contour(env, threshold=threshold, seed=seed + 1, **options, **METHODS[method])


def beta_sweep_rows(env, *, thresholds, runs: int, decisions: int, max_taps: int, seed: int, progress=None,
                    map_fn=None) -> tuple[list[dict], list[dict]]:
    """004 Figs 7 and 8: contour following over a sweep of belief thresholds.

    Parameters
    ----------
    env : perception.VirtualEnvironment
        The edge world of `tactip.reproduce.p004`.
    thresholds : sequence of float
    runs, decisions, max_taps : int
        As `tactip.reproduce.contour.follow_contour`.
    seed : int
    progress, map_fn : callable, optional
        As `_shared.map_pieces`, over the (method, threshold) conditions.

    Returns
    -------
    sweep : list of dict
        ``{method, threshold, angle_error_deg, position_error_mm, taps_per_decision, closed_contour}``.
    learning : list of dict
        ``{method, threshold, decision, delta_error_classes}`` of the adaptive methods at the thresholds
        of `FIG8_THRESHOLDS` in the sweep (NaN as None; decision 0 has no prediction yet).
    """
    conditions = [(m, float(t)) for t in thresholds for m in SWEEP_METHODS]
    options = dict(runs=runs, decisions=decisions, max_taps=max_taps)
    results = map_pieces(functools.partial(_sweep_run, env=env, options=options, seed=seed), conditions,
                         map_fn=map_fn, progress=progress)
    sweep, learning = [], []
    for (method, threshold), r in zip(conditions, results):
        sweep.append({"method": method, "threshold": threshold, "angle_error_deg": r.angle_error_deg,
                      "position_error_mm": r.position_error_mm, "taps_per_decision": r.taps_per_decision,
                      "closed_contour": r.closed_contour})
        if method != "active" and any(np.isclose(threshold, FIG8_THRESHOLDS)):
            learning += [{"method": method, "threshold": threshold, "decision": d,
                          "delta_error_classes": None if np.isnan(e) else float(e)}
                         for d, e in enumerate(r.delta_error_by_decision)]
    return sweep, learning


def _p004_rows(*, quick: bool, seed: int, progress=None, map_fn=None) -> dict:
    from tactip.reproduce.figure_samples import traced_contour_samples
    from tactip.reproduce.report import environment
    from tactip.reproduce.stimuli import make_stimulus

    env = environment(make_stimulus("edge"), seed=seed, taps_per_identity=90, n_locations=18)
    options = dict(runs=12, decisions=40, max_taps=25) if quick else dict(runs=50, decisions=45, max_taps=50)
    sweep, learning = beta_sweep_rows(env, thresholds=QUICK_SWEEP_THRESHOLDS if quick else SWEEP_THRESHOLDS,
                                      seed=seed, progress=progress, map_fn=map_fn, **options)
    # Fig. 6: the paper's runs go about 40 decisions round its plate; the traces of 3 runs per condition
    traced = traced_contour_samples(env, traces=3, seed=seed, **options)
    return {"fig6_traced": traced, "fig7_sweep": sweep, "fig8": learning}


def fig5_sweep_rows(train, test, *, offsets_mm, runs: int, seed: int) -> list[dict]:
    """003 Fig. 5 over a sweep of offsets: a model of one depth class (2.0-2.2 mm), tested deeper or shallower.

    Parameters
    ----------
    train, test : perception.Dataset
        The texture sessions of `tactip.reproduce.p003`.
    offsets_mm : sequence of float
        Test depth minus training depth, mm (the test taps must reach 2.0 + offset .. 2.2 + offset mm).
    runs, seed : int

    Returns
    -------
    list of dict
        ``{offset_mm, texture_error_classes, mean_taps}``, in the order of ``offsets_mm``.
    """
    from tactip.reproduce.p003 import _single_depth

    rows = []
    for offset in offsets_mm:
        result = _single_depth(train, test, float(offset), runs, seed)
        rows.append({"offset_mm": float(offset), "texture_error_classes": float(result.mean_identity_error[0]),
                     "mean_taps": float(result.mean_taps[0])})
    return rows


def _p003_rows(*, quick: bool, seed: int) -> dict:
    from tactip.reproduce.report import collections
    from tactip.reproduce.stimuli import make_stimulus

    train, test = collections(make_stimulus("textures"), seed=seed, taps_per_identity=150)
    return {"fig5_sweep": fig5_sweep_rows(train, test, offsets_mm=QUICK_FIG5_OFFSETS_MM if quick else FIG5_OFFSETS_MM,
                                          runs=600 if quick else 2000, seed=seed + 1)}


def _p002_rows(root: Path, report, *, quick: bool, seed: int, progress=None, log=lambda line: None) -> dict:
    """002 Figs 10 and 11 on the station `p002.run` prepared under ``root``: Fig. 10 is the report's own sweep
    (``report.samples["fig10"]``, not run again), Fig. 11 fixates where Fig. 9's active rows do."""
    from perception import load_dataset, load_model
    from tactip.reproduce.p002 import _station_table
    from tactip.station.config import parse_station_config

    config = parse_station_config(_station_table(root, quick=quick, seed=seed), base_dir=root)
    model = load_model(config.perception.model)
    test = load_dataset(root / "datasets" / "test.h5")
    fixation_mm, = {r["fixation_mm"] for r in report.rows if r["policy"] == "active"}
    return {"fig10": report.samples["fig10"],
            "fig11": lateral_rows(config, model, test, sigmas_mm=QUICK_SIGMAS_MM if quick else SIGMAS_MM,
                                  runs=300 if quick else 2000, seed=seed + 1, progress=progress is not None, log=log,
                                  fixation=int(model.location_class(fixation_mm)))}


def run_with_figure_runs(paper: str, *, quick: bool = False, seed: int = 0, progress=None, map_fn=None):
    """A paper's reproduction and the runs its figures need beyond it.

    Parameters
    ----------
    paper : {"000", "001", "002", "003", "004"}
    quick, seed, progress, map_fn
        As `tactip.reproduce.reproduce`.

    Returns
    -------
    report : tactip.reproduce.Report
    extra : dict of str -> list of dict
        Figure name -> JSON-ready rows (NaN as None; empty for papers whose figures all come from the
        report's rows).
    """
    from tactip.reproduce import reproduce

    extra = {}
    if paper == "002":
        # The station prepared once, in one folder, for the reproduction and its figure runs (preparing
        # it is most of the work: calibration, two collections, the model). `reproduce` would prepare it
        # in a folder of its own and remove it, so paper 002 is run here as `reproduce` runs it.
        from tactip.reproduce import p002
        from tactip.reproduce.fits import mark_fits

        with tempfile.TemporaryDirectory(prefix="tactip-002-figures-") as folder:
            report = mark_fits(p002.run(quick=quick, seed=seed, progress=progress, map_fn=map_fn,
                                        data_dir=Path(folder)))
            extra = _p002_rows(Path(folder), report, quick=quick, seed=seed, progress=progress)
        return report, {name: _json_ready(rows) for name, rows in extra.items()}
    report = reproduce(paper, quick=quick, seed=seed, progress=progress, map_fn=map_fn)
    if paper == "004":
        extra = _p004_rows(quick=quick, seed=seed, progress=progress, map_fn=map_fn)
    elif paper == "003":
        extra = _p003_rows(quick=quick, seed=seed)
    elif paper == "000":
        from tactip.reproduce.taxel_runs import taxel_figure_rows

        extra = taxel_figure_rows(quick=quick, seed=seed, progress=progress)
    return report, {name: _json_ready(rows) for name, rows in extra.items()}


def _json_ready(rows: list[dict]) -> list[dict]:
    """NaN as None and numpy scalars as Python numbers (strict JSON)."""
    def clean(v):
        if isinstance(v, (float, np.floating)):
            return None if np.isnan(v) else float(v)
        return int(v) if isinstance(v, np.integer) else v
    return [{k: clean(v) for k, v in row.items()} for row in rows]
