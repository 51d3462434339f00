"""A picture of the stored verdicts: estimated against nominal width, with the tolerance bands."""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

from tactip.line.results._store import InspectionRow, ResultsError

__all__ = ["plot_inspections"]


def plot_inspections(rows: Sequence[InspectionRow], path, *, inputs=()) -> None:
    """Estimated against nominal width of each finished inspection, with its tolerance band.

    Pass, fail and undecided verdicts get their own marker; aborted and running inspections are
    left out (they have no estimate). Written with matplotlib (Agg) to ``path`` (format from the
    suffix, e.g. ``.png``), atomically; ``path`` must not be one of ``inputs`` (the database).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    done = [r for r in rows if r.status == "done" and r.estimated_width is not None]
    if not done:
        raise ResultsError("no finished inspections to plot")
    nominal = np.array([r.nominal_width for r in done])
    estimate = np.array([r.estimated_width for r in done])
    tolerance = np.array([r.tolerance for r in done])
    fig, ax = plt.subplots(figsize=(6, 5), layout="constrained")
    low, high = min(nominal.min(), estimate.min()), max(nominal.max(), estimate.max())
    pad = 0.05 * (high - low or 1.0)
    ax.plot([low - pad, high + pad], [low - pad, high + pad], color="0.6", lw=1, zorder=0)
    ax.errorbar(nominal, nominal, yerr=tolerance, fmt="none", ecolor="0.8", elinewidth=6, zorder=1,
                label="nominal ± tolerance")
    for verdict, marker, colour in ((True, "o", "tab:green"), (False, "x", "tab:red"), (None, "s", "tab:orange")):
        chosen = np.array([r.passed is verdict for r in done])
        if chosen.any():
            label = {True: "pass", False: "fail", None: "undecided"}[verdict]
            ax.scatter(nominal[chosen], estimate[chosen], marker=marker, color=colour, zorder=2,
                       label=f"{label} ({int(chosen.sum())})")
    error = np.abs(estimate - nominal)
    ax.set_xlabel("nominal width (mm)")
    ax.set_ylabel("estimated width (mm)")
    ax.set_title(f"{len(done)} inspections: mean |estimate - nominal| {error.mean():.2f} mm, "
                 f"mean {np.mean([r.taps for r in done]):.1f} taps", fontsize=10)
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left")
    from tactip._output import atomic_output

    try:
        with atomic_output(path, inputs=inputs) as tmp:
            fig.savefig(tmp, dpi=120, format=Path(path).suffix.lstrip(".") or "png")
    finally:
        plt.close(fig)
