"""Paper 001's Figs 4-7B: rod shape and position errors, null decisions and reaction times, per deadline.

One curve per deadline (black: fixed perception, no deadline) from the rows of `tactip.reproduce.p001`
(``deadline, threshold, shape_error_mm, position_error_mm, reaction_taps, null_fraction``); the
paper's numbers (Fig. 4 comparisons) dotted. Figs 7A (reaction-time histograms) and 8 (per-class maps)
from the samples the reproduction keeps (``Report.samples``, `tactip.reproduce.figures.samples`).
"""

from __future__ import annotations

from tactip.reproduce.figures import legend, new_figure, paper_lines, values

__all__ = ["NAMES", "figures"]

#: The figures this module may draw (`make_figures` keys).
NAMES = ("fig4", "fig5", "fig6", "fig7a", "fig7b", "fig8")

_DEADLINE_COLOURS = ("tab:orange", "tab:blue", "tab:green", "tab:purple", "tab:brown")


def _curves(rows):
    """Deadline -> its rows sorted by threshold (None, fixed perception, first)."""
    deadlines = sorted({r["deadline"] for r in rows}, key=lambda d: (d is not None, d or 0))
    return {d: sorted((r for r in rows if r["deadline"] == d), key=lambda r: r["threshold"]) for d in deadlines}


def _threshold_axis(ax, rows) -> None:
    """Thresholds up to 0.99999 (the paper's range) on a logit axis, where 0.9, 0.99 ... are evenly spaced."""
    thresholds = [r["threshold"] for r in rows]
    if thresholds and 0 < min(thresholds) and max(thresholds) < 1 and max(thresholds) > 0.95:
        ax.set_xscale("logit")
        ticks = sorted(set(thresholds))
        ax.set_xticks(ticks, [f"{t:g}" for t in ticks], fontsize=7, rotation=45)
        ax.minorticks_off()
    ax.set_xlabel("belief threshold")


def _style(deadline, k: int) -> dict:
    if deadline is None:
        return dict(color="black", label="fixed (no deadline)")
    return dict(color=_DEADLINE_COLOURS[k % len(_DEADLINE_COLOURS)], label=f"deadline {deadline} taps")


def _errors(report, x: str, name: str, title: str):
    fig, axes = new_figure(2, title=title)
    for ax, (error, what) in zip(axes, (("shape_error_mm", "shape"), ("position_error_mm", "position"))):
        for k, (deadline, mine) in enumerate(_curves(report.rows).items()):
            ax.plot(values(mine, x), values(mine, error), "o-", ms=3, **_style(deadline, k))
        if x == "threshold":
            paper_lines(ax, report.comparisons, prefix="Fig. 4", contains=what, at_theta=True)
        if x == "threshold":
            _threshold_axis(ax, report.rows)
        else:
            ax.set_xlabel("mean reaction time (taps)")
        ax.set_ylabel(f"mean {what} error (mm)")
        ax.set_title(f"({'AB'[what == 'position']}) {what}", fontsize=9)
        legend(ax)
    return fig


def _against_threshold(report, key: str, label: str, title: str):
    fig, (ax,) = new_figure(title=title)
    for k, (deadline, mine) in enumerate(_curves(report.rows).items()):
        ax.plot(values(mine, "threshold"), values(mine, key), "o-", ms=3, **_style(deadline, k))
    _threshold_axis(ax, report.rows)
    ax.set_ylabel(label)
    legend(ax)
    return fig


def figures(report, extra: dict) -> dict:
    """Figs 4, 5, 6 and 7B, and Figs 7A and 8 when the report holds their samples (``Report.samples``)."""
    from tactip.reproduce.figures.samples import fig7a_001, fig8_001

    samples = getattr(report, "samples", {}) or {}
    out = {"fig4": _errors(report, "threshold", "fig4", "paper 001 Fig. 4: decision errors against belief threshold"),
            "fig5": _errors(report, "reaction_taps", "fig5",
                            "paper 001 Fig. 5: decision errors against mean reaction time"),
            "fig6": _against_threshold(report, "null_fraction", "proportion of null decisions (moves)",
                                       "paper 001 Fig. 6: move requests against belief threshold"),
            "fig7b": _against_threshold(report, "reaction_taps", "mean reaction time (taps)",
                                        "paper 001 Fig. 7B: reaction time against belief threshold")}
    if samples.get("fig7a"):
        out["fig7a"] = fig7a_001(samples["fig7a"])
    if samples.get("fig8"):
        out["fig8"] = fig8_001(samples["fig8"])
    return {name: out[name] for name in NAMES if name in out}
