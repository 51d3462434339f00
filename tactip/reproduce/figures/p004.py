"""Paper 004's Figs 6-8: contour following with passive, active and adaptive perception.

From the rows of `tactip.reproduce.p004` (``method, threshold, angle_error_deg, position_error_mm,
taps_per_decision, closed_contour``): Fig. 6 as the fraction of runs that close the contour, Fig. 7 (angle error, position error, taps per decision
against the belief threshold, one curve per method). With the runs of `tactip.reproduce.figure_runs`:
Fig. 6's traced contours (``fig6_traced``: ``method, threshold, run, decision, x_mm, y_mm``, drawn by
`tactip.reproduce.figures.samples`), Fig. 7 over a dense threshold sweep (``fig7_sweep``) and Fig. 8, the learned shift's error against the
decision (``method, threshold, decision, delta_error_classes``). ``adaptive`` is eq. 7 as printed;
``adaptive_angle_only`` is a variant and ``adaptive_shift0`` a control, named so in the legends.
"""

from __future__ import annotations

import numpy as np

from tactip.reproduce.figures import COLOURS, legend, new_figure, paper_lines, values

__all__ = ["NAMES", "figures"]

#: The figures this module may draw (`make_figures` keys).
NAMES = ("fig6", "fig6_traced", "fig7", "fig7_sweep", "fig8")

_LABELS = {"passive": "passive", "active": "active", "adaptive": "adaptive (eq. 7 as printed)",
           "adaptive_angle_only": "adaptive, angle-only (a variant)", "adaptive_shift0": "adaptive, Delta = 0 (control)"}
_PANELS = (("angle_error_deg", "mean angle error (deg)", "Fig. 7A"),
           ("position_error_mm", "mean position error (mm)", "Fig. 7B"),
           ("taps_per_decision", "mean taps per decision", "Fig. 7C"))


def _methods(rows):
    return [m for m in _LABELS if any(r["method"] == m for r in rows)] + \
        sorted({r["method"] for r in rows} - set(_LABELS))


def _fig7(rows, comparisons, title: str):
    fig, axes = new_figure(3, title=title, width_in=4.6, height_in=4.4)
    for ax, (key, label, prefix) in zip(axes, _PANELS):
        for method in _methods(rows):
            mine = sorted((r for r in rows if r["method"] == method), key=lambda r: r["threshold"])
            ax.plot(values(mine, "threshold"), values(mine, key), "o-", ms=3, color=COLOURS.get(method),
                    label=_LABELS.get(method, method))
        paper_lines(ax, comparisons, prefix=prefix, at_theta=True)
        ax.set_xlabel("belief threshold")
        ax.set_ylabel(label)
        ax.set_title(prefix, fontsize=9)
        papers = [(h, t) for h, t in zip(*ax.get_legend_handles_labels()) if t.startswith("paper:")]
        if papers:                                              # the paper's numbers: on their own panel
            ax.legend(*zip(*papers), fontsize=6)
    methods = [(h, t) for h, t in zip(*axes[0].get_legend_handles_labels()) if not t.startswith("paper:")]
    fig.legend(*zip(*methods), loc="outside lower center", ncol=len(methods), fontsize=7)
    return fig


def _fig6(rows):
    fig, (ax,) = new_figure(title="paper 004 Fig. 6: runs that trace the whole contour", width_in=7.0)
    thresholds = sorted({r["threshold"] for r in rows})
    methods = _methods(rows)
    width = 0.8 / len(methods)
    for k, method in enumerate(methods):
        by = {r["threshold"]: r["closed_contour"] for r in rows if r["method"] == method}
        ax.bar(np.arange(len(thresholds)) + (k - (len(methods) - 1) / 2) * width,
               [np.nan if by.get(t) is None else by[t] for t in thresholds], width, color=COLOURS.get(method),
               label=_LABELS.get(method, method))
    ax.set_xticks(np.arange(len(thresholds)), [f"{t:g}" for t in thresholds])
    ax.set_xlabel("belief threshold")
    ax.set_ylabel("fraction of runs closing the contour")
    ax.set_ylim(0, 1.05)
    legend(ax)
    return fig


def _fig8(rows):
    fig, (ax,) = new_figure(title="paper 004 Fig. 8: the learned shift Delta, error against decision", width_in=7.0)
    for k, key in enumerate(sorted({(r["method"], r["threshold"]) for r in rows})):
        mine = sorted((r for r in rows if (r["method"], r["threshold"]) == key), key=lambda r: r["decision"])
        ax.plot(values(mine, "decision"), values(mine, "delta_error_classes"), "-",
                color=COLOURS.get(key[0]), alpha=0.5 + 0.5 * (k % 2),
                label=f"{_LABELS.get(key[0], key[0])}, threshold {key[1]:g}")
    ax.set_xlabel("decision")
    ax.set_ylabel("mean |Delta - true turn| (angle classes)")
    legend(ax)
    return fig


def figures(report, extra: dict) -> dict:
    """Figs 6 and 7, and with the runs' rows the threshold sweep of Fig. 7 and Fig. 8."""
    out = {"fig6": _fig6(report.rows),
           "fig7": _fig7(report.rows, report.comparisons, "paper 004 Fig. 7: contour following, errors and taps "
                                                          "against belief threshold")}
    if extra.get("fig6_traced"):
        from tactip.reproduce.figures.samples import fig6_traced_004

        out["fig6_traced"] = fig6_traced_004(extra["fig6_traced"])
    if extra.get("fig7_sweep"):
        out["fig7_sweep"] = _fig7(extra["fig7_sweep"], report.comparisons,
                                  "paper 004 Fig. 7 (threshold sweep): active and adaptive perception")
    if extra.get("fig8"):
        out["fig8"] = _fig8(extra["fig8"])
    return {name: out[name] for name in NAMES if name in out}
