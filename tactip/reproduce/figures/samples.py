"""The figures drawn from samples rather than rows: distributions, per-class maps and traced contours.

- 001 Fig. 7A (`fig7a_001`): reaction-time histograms of fixed perception at two thresholds;
- 001 Fig. 8 (`fig8_001`): shape error, position error and reaction time per test class (threshold 0.9);
- 003 Fig. 5 over offsets (`fig5_sweep_003`), Fig. 6A (`fig6a_003`: texture error per depth and
  texture, the mean of the seeds' maps) and Fig. 7 as the paper draws it (`fig7_hist_003`: how often
  each texture error was made, per policy);
- 004 Fig. 6 (`fig6_traced_004`): the contours traced by the first runs, passive / active / adaptive at
  thresholds 0.2 and 0.9.

The samples come from `tactip.reproduce.figure_samples` (`Report.samples`) or, for the figure runs,
from their JSON rows. Every drawn value can be read back from the figure's artists: lines carry the
histograms and curves, images the maps (``ax.images[0].get_array()``), bar containers the bars.
"""

from __future__ import annotations

import numpy as np

from tactip.reproduce.figures import COLOURS, PAPER_STYLE, legend, new_figure, values

__all__ = ["fig7a_001", "fig8_001", "fig5_sweep_003", "fig6a_003", "fig7_hist_003", "fig6_traced_004"]

#: Paper 001 Fig. 8: the ranges of its maps (shape error mm, position error mm, reaction taps).
_PAPER_FIG8_RANGES = {"shape_error_mm": 4.0, "position_error_mm": 2.0, "reaction_taps": 20.0}


def _map(fig, ax, data, *, x, y, vmax: float, label: str):
    """A (len(y), len(x)) map as an image with a colour bar (light: small, dark: large, as the paper)."""
    from matplotlib import colormaps

    data = np.asarray(data, float)
    if np.isnan(data).any():
        ax.set_title(ax.get_title() + "\n(pink: no run started in that class)", fontsize=8)
    image = ax.imshow(data, origin="lower", aspect="auto", cmap=colormaps["Greys"].with_extremes(bad="pink"), vmin=0.0,
                      vmax=max(vmax, float(np.nanmax(data)) if np.isfinite(data).any() else vmax),
                      extent=(x[0] - 0.5 * _step(x), x[-1] + 0.5 * _step(x), y[0] - 0.5 * _step(y), y[-1] + 0.5 * _step(y)))
    fig.colorbar(image, ax=ax, label=label, shrink=0.85)
    return image


def _step(centres) -> float:
    return float(np.diff(centres).mean()) if len(centres) > 1 else 1.0


def fig7a_001(samples: dict):
    """001 Fig. 7A: ``{thresholds, taps}`` -> one histogram line per threshold (runs per reaction time)."""
    fig, (ax,) = new_figure(title="paper 001 Fig. 7A: reaction-time histograms of fixed perception (no deadline; "
                                  "the paper: thresholds 0.9 and 0.999, skewed to long times)", width_in=7.0)
    for k, (threshold, taps) in enumerate(zip(samples["thresholds"], samples["taps"])):
        counts = np.bincount(np.asarray(taps, np.intp))
        ax.step(np.arange(len(counts)), counts, where="mid", color=("0.55", "0.0")[k % 2],
                label=f"threshold {threshold:g} (mean {np.mean(taps):.1f} taps, {len(taps)} runs)")
    longest = max(int(np.max(taps)) for taps in samples["taps"])
    cut = float(max(np.percentile(np.concatenate([np.asarray(t, float) for t in samples["taps"]]), 99), 10))
    ax.set_xlim(0, cut)
    ax.set_xlabel(f"reaction time (taps; cut at the 99th percentile, the longest: {longest} taps)")
    ax.set_ylabel("runs")
    legend(ax)
    return fig


def fig8_001(samples: dict):
    """001 Fig. 8: shape error, position error and reaction time per test class (rod x position)."""
    fig, axes = new_figure(3, title=f"paper 001 Fig. 8: errors and reaction times per test class, fixed perception, "
                                    f"threshold {samples['threshold']:g} (light: small, dark: large)",
                           width_in=4.4, height_in=3.8)
    for ax, (key, label, panel) in zip(axes, (("shape_error_mm", "mean shape error (mm)", "A"),
                                              ("position_error_mm", "mean position error (mm)", "B"),
                                              ("reaction_taps", "mean reaction time (taps)", "C"))):
        ax.set_title(f"({panel}) paper's range 0-{_PAPER_FIG8_RANGES[key]:g}", fontsize=9)
        _map(fig, ax, np.asarray(samples[key], float).T, x=samples["positions_mm"], y=samples["shapes_mm"],
             vmax=_PAPER_FIG8_RANGES[key], label=label)
        ax.set_xlabel("position (mm)")
        ax.set_ylabel("rod diameter (mm)")
        ax.grid(False)
    return fig


def fig5_sweep_003(rows, comparisons, chance_classes: float):
    """003 Fig. 5 over a sweep of offsets: ``{offset_mm, texture_error_classes}`` rows, the paper's points beside."""
    import re

    fig, (ax,) = new_figure(title="paper 003 Fig. 5 (offset sweep): texture error of a one-depth model against "
                                  "the test depth offset", width_in=7.0)
    mine = sorted(rows, key=lambda r: r["offset_mm"])
    ax.plot(values(mine, "offset_mm"), values(mine, "texture_error_classes"), "o-", color=COLOURS["passive"],
            label="passive (simulated)")
    paper = sorted((float(m.group(1)), c.paper) for c in comparisons if c.figure.startswith("Fig. 5") and
                   c.paper is not None for m in [re.search(r"offset ([-0-9.]+) mm", c.figure)] if m)
    if paper:
        ax.plot(*zip(*paper), "s", mfc="none", ms=8, label="paper (text)", **PAPER_STYLE)
    ax.axhline(chance_classes, color="0.6", lw=1, label=f"chance beyond +-0.6 mm (paper: {chance_classes:g} classes)")
    ax.set_xlabel("test depth offset from training (mm)")
    ax.set_ylabel("mean texture error (classes)")
    legend(ax)
    return fig


def fig6a_003(maps: list[dict]):
    """003 Fig. 6A: passive texture error per (depth, texture) class, the mean of the seeds' maps."""
    seeds = [m.get("seed") for m in maps]
    fig, (ax,) = new_figure(title=f"paper 003 Fig. 6A: passive texture error per texture and depth (mean of "
                                  f"{len(maps)} seed{'s' * (len(maps) > 1)}: {', '.join(map(str, seeds))})",
                            width_in=7.0)
    import warnings

    with warnings.catch_warnings():                 # a class no run started in on any seed stays NaN (blank)
        warnings.simplefilter("ignore", RuntimeWarning)
        mean = np.nanmean(np.stack([np.asarray(m["texture_error_classes"], float) for m in maps]), axis=0)  # (L, I)
    _map(fig, ax, mean.T, x=maps[0]["depths_mm"], y=maps[0]["textures"], vmax=3.0,
         label="mean texture error (classes)")
    ax.set_xlabel("depth (mm)")
    ax.set_ylabel("texture class")
    ax.grid(False)
    return fig


def fig7_hist_003(counts: dict, names: dict, paper: dict):
    """003 Fig. 7 as the paper draws it: the frequency of each texture error (classes), one panel per policy.

    Parameters
    ----------
    counts : dict of float -> (I,) array
        Move threshold -> runs per texture error 0 .. I - 1.
    names : dict of float -> str
        Move threshold -> panel name.
    paper : dict of float -> float or None
        Move threshold -> the paper's mean error (classes).
    """
    moves = [m for m in names if m in counts]
    fig, axes = new_figure(len(moves), title="paper 003 Fig. 7: frequency of each texture error over random starting "
                                             "depths (simulated; every seed's runs)", width_in=3.8, height_in=3.6)
    for ax, move in zip(axes, moves):
        n = np.asarray(counts[move], float)
        frequency = n / n.sum()
        mean = float((np.arange(len(n)) * frequency).sum())
        ax.bar(np.arange(len(n)), frequency, color="tab:blue", label=f"simulated: mean {mean:.2f}")
        ax.set_title(f"{'ABC'[moves.index(move)]}: {names[move]}", fontsize=9)
        if paper.get(move) is not None:
            ax.axvline(paper[move], label=f"paper: mean {paper[move]:g}", **PAPER_STYLE)
        ax.set_xlabel("texture error (classes)")
        ax.set_ylabel("frequency")
        ax.set_ylim(0, 1)
        legend(ax)
    return fig


def fig6_traced_004(rows, *, radius_mm: float = 30.0, trace_mm: float = 2.0):
    """004 Fig. 6: the traced contours, one panel per (method, threshold), the plate's circle beside.

    A run closes the contour only if every traced point lies within ``trace_mm`` of the plate
    (`tactip.reproduce.contour.follow_contour`); each panel says how many of the runs shown do not.
    """
    conditions = list(dict.fromkeys((r["method"], r["threshold"]) for r in rows))
    fig, axes = new_figure(len(conditions), rows=2 if len(conditions) > 3 else 1, width_in=3.4, height_in=3.6,
                           title="paper 004 Fig. 6: contours traced by the first runs (points: the edge each "
                                 "decision perceives; grey: the plate; a closed contour keeps every point within "
                                 f"{trace_mm:g} mm of it)")
    circle = np.linspace(0, 2 * np.pi, 181)
    for ax, (method, threshold) in zip(axes, conditions):
        mine = [r for r in rows if (r["method"], r["threshold"]) == (method, threshold)]
        ax.plot(radius_mm * np.cos(circle), radius_mm * np.sin(circle), color="0.7", lw=2, label="_plate")
        for run in sorted({r["run"] for r in mine}):
            trace = sorted((r for r in mine if r["run"] == run), key=lambda r: r["decision"])
            ax.plot(values(trace, "x_mm"), values(trace, "y_mm"), "o-", ms=3, lw=0.6, alpha=0.8,
                    color=COLOURS.get(method), label=f"_run{run}")
        shown = sorted({r["run"] for r in mine})
        off = sum(any(abs(np.hypot(r["x_mm"], r["y_mm"]) - radius_mm) > trace_mm for r in mine if r["run"] == run)
                  for run in shown)
        ax.set_title(f"{method}, threshold {threshold:g}: {mine[0]['closed_contour']:.0%} of all runs close;\n"
                     f"{off} of the {len(shown)} shown trace a point > {trace_mm:g} mm off the plate", fontsize=8)
        ax.set_aspect("equal")
        limit = 1.6 * radius_mm
        ax.set_xlim(-limit, limit)
        ax.set_ylim(-limit, limit)
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
    return fig
