"""Paper 003's Figs 5, 6B and 7: texture error under depth uncertainty, passive and active.

Fig. 7 from the rows of `tactip.reproduce.p003` (``seed, move_threshold, texture_error_classes``): one
bar per move threshold (the mean over the seeds, each seed a dot), the paper's errors as hollow bars.
Figs 5 and 6B from the report's comparisons (measured beside the paper's, at the depths compared).
From the report's samples (``Report.samples``): Fig. 6A (texture error per depth and texture) and Fig. 7
as the paper draws it, error frequencies (``fig7_hist``); with ``--figure-runs``, Fig. 5 over a sweep of
offsets (``fig5_sweep``). Drawn by `tactip.reproduce.figures.samples`.
"""

from __future__ import annotations

import re

import numpy as np

from tactip.reproduce.figures import legend, new_figure, values

__all__ = ["NAMES", "PAPER_CHANCE_CLASSES", "figures"]

#: The figures this module may draw (`make_figures` keys).
NAMES = ("fig5", "fig5_sweep", "fig6a", "fig6b", "fig7", "fig7_hist")

#: Move threshold -> name, in the order of Fig. 7 (1.5 stands for the paper's ">1", never moves).
_POLICIES = {1.5: "passive (>1)", 0.999: "weakly active (0.999)", 0.05: "strongly active (0.05)"}
#: Paper 003 Fig. 5 (text): texture error at chance, reached beyond +-0.6 mm of offset, classes.
PAPER_CHANCE_CLASSES = 3.2
_PAPER_FIG7 = {"passive": 1.5, "weakly active": 0.999, "strongly active": 0.05}


def _fig5(report):
    fig, (ax,) = new_figure(title="paper 003 Fig. 5: texture error at one depth class against test depth offset")
    found = [(float(m.group(1)), c) for c in report.comparisons if c.figure.startswith("Fig. 5")
             for m in [re.search(r"offset ([-0-9.]+) mm", c.figure)] if m]
    found.sort(key=lambda t: t[0])
    ax.plot([o for o, _ in found], [c.measured for _, c in found], "o-", color="tab:red", label="passive (simulated)")
    paper = [(o, c.paper) for o, c in found if c.paper is not None]
    ax.plot([o for o, _ in paper], [p for _, p in paper], "s:", mfc="none", color="0.35", label="paper")
    ax.axhline(PAPER_CHANCE_CLASSES, color="0.6", lw=1, label=f"chance (paper: {PAPER_CHANCE_CLASSES:g} classes)")
    ax.set_xlabel("test depth offset from training (mm)")
    ax.set_ylabel("mean texture error (classes)")
    legend(ax)
    return fig


def _bars(ax, labels, measured, paper):
    x = np.arange(len(labels))
    ax.bar(x - 0.2, measured, 0.4, color="tab:blue", label="simulated")
    ax.bar(x + 0.2, [np.nan if p is None else p for p in paper], 0.4, fill=False, hatch="//", edgecolor="0.35",
           label="paper")
    ax.set_xticks(x, labels, fontsize=8)


def _fig6b(report):
    fig, (ax,) = new_figure(title="paper 003 Fig. 6B: passive texture error by depth range")
    found = [c for c in report.comparisons if c.figure.startswith("Fig. 6B")]
    _bars(ax, [c.figure.split(",")[1].split(":")[0].strip() for c in found], [c.measured for c in found],
          [c.paper for c in found])
    ax.set_ylabel("mean texture error (classes)")
    legend(ax)
    return fig


def _fig7(report):
    fig, (ax,) = new_figure(title="paper 003 Fig. 7: mean texture error, passive and active (bars: mean over "
                                  "seeds, dots: seeds; the paper's panels show the error frequencies)", width_in=6.0)
    moves = [m for m in _POLICIES if any(r["move_threshold"] == m for r in report.rows)]
    per_seed = [values([r for r in report.rows if r["move_threshold"] == m], "texture_error_classes") for m in moves]
    paper = {}
    for c in report.comparisons:
        for name, move in _PAPER_FIG7.items():
            if c.figure.startswith(f"Fig. 7 {name}:"):
                paper[move] = c.paper
    _bars(ax, [_POLICIES[m] for m in moves], [np.mean(e) for e in per_seed], [paper.get(m) for m in moves])
    for k, errors in enumerate(per_seed):
        ax.plot(np.full(len(errors), k - 0.2), errors, "k.", ms=4)
    ax.set_ylabel("mean texture error (classes)")
    legend(ax)
    return fig


def figures(report, extra: dict) -> dict:
    """Figs 5, 6B and 7; Figs 6A and 7 as histograms from the report's samples; Fig. 5 over offsets from its runs."""
    from tactip.reproduce.figures.samples import fig5_sweep_003, fig6a_003, fig7_hist_003

    samples = getattr(report, "samples", {}) or {}
    out = {"fig5": _fig5(report), "fig6b": _fig6b(report), "fig7": _fig7(report)}
    if extra.get("fig5_sweep"):
        out["fig5_sweep"] = fig5_sweep_003(extra["fig5_sweep"], report.comparisons, PAPER_CHANCE_CLASSES)
    if samples.get("fig6a"):
        out["fig6a"] = fig6a_003(samples["fig6a"])
    if samples.get("fig7_hist"):
        paper = {move: next((c.paper for c in report.comparisons if c.figure.startswith(f"Fig. 7 {name}:")), None)
                 for name, move in _PAPER_FIG7.items()}
        out["fig7_hist"] = fig7_hist_003(samples["fig7_hist"], _POLICIES, paper)
    return {name: out[name] for name in NAMES if name in out}
