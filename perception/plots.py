"""Figures of the validation experiments (matplotlib, Agg backend, written to a file).

- `plot_speed_accuracy`: mean error against mean decision taps, one curve per policy (paper 002 Fig. 9);
- `plot_fixation_sweep`: best error within the tap budget against fixation location (paper 002 Fig. 10);
- `plot_lateral_sweep`: error ratio against lateral placement noise (paper 002 Fig. 11);
- `plot_reliability`: reliability diagrams of the identity belief after 1, 3 and 5 taps, one line per model.

Example
-------
>>> plot_speed_accuracy(compare_policies(env, policies), "curves.png")   # doctest: +SKIP
"""

from __future__ import annotations

import pathlib

__all__ = ["plot_speed_accuracy", "plot_fixation_sweep", "plot_lateral_sweep", "plot_reliability",
           "plot_accuracy_sweep"]

_COLOURS = {"active": "tab:blue", "random": "tab:green", "stationary": "tab:red"}


def _figure():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt, *plt.subplots(figsize=(6, 4), layout="constrained")


def _save(plt, fig, path) -> None:
    from _shared import atomic_path

    path = pathlib.Path(path)
    try:
        with atomic_path(path) as tmp:  # a full disk leaves the old figure, not half a new one
            fig.savefig(tmp, dpi=120, format=path.suffix.lstrip(".") or "png")
    finally:
        plt.close(fig)


def plot_speed_accuracy(results, path, *, units: str = "mm") -> None:
    """Mean identity error (location error for a location task) against mean decision taps.

    Parameters
    ----------
    results : mapping of policy name -> MonteCarloResult
    path : str or os.PathLike
        Image file to write (format from the suffix, e.g. ``.png``).
    units : str
        Unit of the error axis.
    """
    plt, fig, ax = _figure()
    for name, result in results.items():
        single = result.identity_error_map.shape[-1] == 1
        error = result.mean_location_error if single else result.mean_identity_error
        ax.plot(result.mean_taps, error, "o-", ms=3, label=name, color=_COLOURS.get(name))
    ax.set_xlabel("mean decision time (taps)")
    ax.set_ylabel(f"mean {'location' if single else 'identity'} error ({units})")
    ax.set_title(f"Speed-accuracy ({next(iter(results.values())).runs} runs per threshold)")
    ax.grid(alpha=0.3)
    ax.legend()
    _save(plt, fig, path)


def plot_fixation_sweep(sweep, path, *, units: str = "mm") -> None:
    """Best error within the tap budget against fixation location, best marked.

    Parameters
    ----------
    sweep : FixationSweep
    path : str or os.PathLike
    units : str
        Unit of both axes.
    """
    plt, fig, ax = _figure()
    ax.plot(sweep.fixations, sweep.errors, "o-", color="tab:blue")
    ax.axvline(sweep.best_fixation, color="tab:red", ls="--",
               label=f"best {sweep.best_fixation:g} {units} (threshold {sweep.best_threshold:g})")
    ax.set_xlabel(f"fixation location ({units})")
    ax.set_ylabel(f"mean error within {sweep.tap_budget:g} taps ({units})")
    ax.grid(alpha=0.3)
    ax.legend()
    _save(plt, fig, path)


def plot_lateral_sweep(sweep, path) -> None:
    """Error relative to the smallest lateral noise against the noise magnitude sigma.

    Parameters
    ----------
    sweep : LateralSweep
    path : str or os.PathLike
    """
    plt, fig, ax = _figure()
    ax.plot(sweep.sigmas, sweep.ratio, "o-", color="tab:blue")
    ax.set_xlabel("lateral placement noise sigma (mm)")
    ax.set_ylabel("error ratio e(sigma) / e(0)")
    ax.grid(alpha=0.3)
    _save(plt, fig, path)


def plot_reliability(traces, path, *, taps=(1, 3, 5), bins: int = 10) -> None:
    """Accuracy against belief after each number of taps; the diagonal is a calibrated belief.

    Parameters
    ----------
    traces : mapping of model name -> BeliefTrace
    path : str or os.PathLike
    taps : sequence of int
        One panel per number of taps (those beyond a trace's length are skipped).
    bins : int
        Equal belief bins over [0, 1].
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    taps = [t for t in taps if all(t <= trace.max_taps for trace in traces.values())]
    fig, axes = plt.subplots(1, len(taps), figsize=(4 * len(taps), 4.3), layout="constrained", squeeze=False)
    for ax, t in zip(axes[0], taps):
        ax.plot([0, 1], [0, 1], color="grey", ls="--", lw=1, label="calibrated")
        for name, trace in traces.items():
            confidence, accuracy, counts = trace.reliability(t, bins=bins)
            full = counts > 0
            line, = ax.plot(confidence[full], accuracy[full], "-", lw=1,
                            label=f"{name} (ECE {trace.calibration_error(t, bins=bins):.3f})")
            # marker area: the bin's share of runs, so that a bin of a few runs does not look like a verdict
            ax.scatter(confidence[full], accuracy[full], s=4 + 200 * counts[full] / counts.sum(),
                       color=line.get_color(), alpha=0.8, zorder=3)
        ax.set_xlim(0, 1)
        ax.set_ylim(0, 1)
        ax.set_xlabel("belief in the decided class")
        ax.set_ylabel("fraction right")
        ax.set_title(f"after {t} tap{'s' if t > 1 else ''}")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    fig.suptitle("above the diagonal: underconfident, below: overconfident; marker area: share of runs",
                 fontsize=8)
    _save(plt, fig, path)


def plot_accuracy_sweep(sweep, path, *, units: str = "mm") -> None:
    """Mean taps to reach the target accuracy against fixation location, best marked.

    Parameters
    ----------
    sweep : AccuracySweep
    path : str or os.PathLike
    units : str
        Unit of the fixation axis.
    """
    plt, fig, ax = _figure()
    ax.plot(sweep.fixations, sweep.taps, "o-", color="tab:blue")
    if sweep.best is not None:
        ax.axvline(sweep.fixations[sweep.best], color="tab:red", ls="--",
                   label=f"best {sweep.fixations[sweep.best]:g} {units} (threshold {sweep.thresholds[sweep.best]:g})")
        ax.legend()
    ax.set_xlabel(f"fixation location ({units})")
    ax.set_ylabel(f"mean taps to {100 * sweep.target:g} % within {sweep.tolerance:g}")
    ax.grid(alpha=0.3)
    _save(plt, fig, path)
