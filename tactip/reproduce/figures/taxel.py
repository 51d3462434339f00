"""Paper 000's Figs 7, 8B, 10 and 11 on the simulated fingertip, from the rows of `tactip.reproduce.taxel_runs`.

- Fig. 7 (``policy, run, tap, location_mm, decided``): example trajectories, passive (A) and active (B);
- Fig. 8B (``threshold, taps, runs``): decision-time histograms, one line per threshold;
- Fig. 10 (``threshold, location_mm, error_mm, decision_taps``): passive error (A) and decision time (B)
  against the sensor location, grey by threshold (darker: higher);
- Fig. 11 (``policy, classes, threshold, error_mm, mean_taps``): mean error (A) and decision time (B)
  against the threshold, and error against decision time (C), passive red and active green (as the
  paper), shaded by class count; the paper's passive ~4.5 mm and Table II beside.
"""

from __future__ import annotations

from tactip.reproduce.figures import PAPER_STYLE, legend, new_figure, values
from tactip.reproduce.taxel_runs import MAX_TAPS

__all__ = ["fig7", "fig8b", "fig10", "fig11", "taxel_figures", "PAPER_FIG10_BEST_MM"]

#: Paper 000 Fig. 10 (text): the lowest passive errors, near the middle of the range, mm.
PAPER_FIG10_BEST_MM = 0.2
#: Paper 000 Fig. 11's colours: passive red, active green.
_MAPS = {"passive": "Reds", "active": "Greens"}


def _grey(k: int, n: int) -> str:
    """Light to dark grey over ``n`` thresholds (the paper's grey scale)."""
    return str(round(0.8 - 0.8 * k / max(n - 1, 1), 3))


def _shade(policy: str, k: int, n: int):
    from matplotlib import colormaps

    return colormaps[_MAPS.get(policy, "Greys")](0.45 + 0.5 * k / max(n - 1, 1))


def fig7(rows):
    """Fig. 7: each run's location at every tap until its decision (a marker at the decision)."""
    fig, axes = new_figure(2, title="paper 000 Fig. 7: example trajectories of the simulated fingertip (A passive: "
                                    "the sensor stays; B active: it moves to the 15 mm fixation point; dots: "
                                    f"decisions, runs still undecided are decided at the cap of {MAX_TAPS} taps)")
    for ax, policy in zip(axes, ("passive", "active")):
        mine = [r for r in rows if r["policy"] == policy]
        for run in sorted({r["run"] for r in mine}):
            trace = sorted((r for r in mine if r["run"] == run), key=lambda r: r["tap"])
            ax.plot(values(trace, "tap"), values(trace, "location_mm"), "-", lw=0.6, alpha=0.5,
                    color="tab:red" if policy == "passive" else "tab:green", label=f"_run{run}")
            ax.plot([trace[-1]["tap"]], [trace[-1]["location_mm"]], "k.", ms=3, label="_decision")
        ax.set_title(f"({'AB'[policy == 'active']}) {policy}, {len({r['run'] for r in mine})} runs", fontsize=9)
        ax.set_xlabel("tap")
        ax.set_ylabel("sensor location (mm)")
    return fig


def fig8b(rows):
    """Fig. 8B: how many runs decided after each number of taps, one line per threshold."""
    fig, (ax,) = new_figure(title="paper 000 Fig. 8B: decision-time histograms, passive perception, 30 classes "
                                  "(paper: the peak moves to longer times as the threshold rises). The spike at "
                                  f"{MAX_TAPS} taps: runs still undecided at the cap, most at the ends of the range "
                                  "where the simulated rod gives no signal", width_in=7.0)
    thresholds = sorted({r["threshold"] for r in rows})
    for k, t in enumerate(thresholds):
        mine = sorted((r for r in rows if r["threshold"] == t), key=lambda r: r["taps"])
        ax.step(values(mine, "taps"), values(mine, "runs"), where="mid", color=_grey(k, len(thresholds)),
                label=f"threshold {t:g}")
    ax.set_xscale("log")
    ax.set_xlabel("decision time (taps)")
    ax.set_ylabel("runs")
    legend(ax)
    return fig


def fig10(rows):
    """Fig. 10: passive error and decision time against the sensor location, one curve per threshold."""
    thresholds = sorted({r["threshold"] for r in rows})
    locations = sorted({r["location_mm"] for r in rows})
    exact = [x for x in locations if all(r["error_mm"] == 0 for r in rows if r["location_mm"] == x and r["threshold"] > 0)]
    fig, axes = new_figure(2, title="paper 000 Fig. 10: passive perception against sensor location (30 classes; "
                                    f"darker: higher threshold; runs capped at {MAX_TAPS} taps). The simulated "
                                    f"fingertip is cleaner than the paper's: {len(exact)} of {len(locations)} "
                                    "locations decide with 0 mm error at every threshold > 0")
    for ax, key, label in zip(axes, ("error_mm", "decision_taps"), ("mean location error (mm)",
                                                                    "mean decision time (taps)")):
        for k, t in enumerate(thresholds):
            mine = sorted((r for r in rows if r["threshold"] == t), key=lambda r: r["location_mm"])
            ax.plot(values(mine, "location_mm"), values(mine, key), "-", color=_grey(k, len(thresholds)),
                    label=f"threshold {t:g}")
        ax.set_xlabel("sensor location (mm)")
        ax.set_ylabel(label)
    axes[0].axhline(PAPER_FIG10_BEST_MM, label=f"paper: lowest errors <= {PAPER_FIG10_BEST_MM:g} mm near 15 mm",
                    **PAPER_STYLE)
    legend(axes[0], ncol=2)
    return fig


def fig11(rows):
    """Fig. 11: mean error and decision time against threshold, and error against decision time."""
    from tactip.reproduce.p000 import PAPER_PASSIVE_MM, PAPER_TABLE2

    fig, axes = new_figure(3, title="paper 000 Fig. 11: fingertip, passive (red) and active (green, fixation 15 mm), "
                                    f"darker: more location classes; runs capped at {MAX_TAPS} taps",
                           width_in=4.6, height_in=4.2)
    classes = sorted({r["classes"] for r in rows})
    for policy in ("passive", "active"):
        for k, n in enumerate(classes):
            mine = sorted((r for r in rows if r["policy"] == policy and r["classes"] == n), key=lambda r: r["threshold"])
            if not mine:
                continue
            style = dict(color=_shade(policy, k, len(classes)), label=f"{policy}, {n} classes")
            axes[0].plot(values(mine, "threshold"), values(mine, "error_mm"), "o-", ms=3, **style)
            axes[1].plot(values(mine, "threshold"), values(mine, "mean_taps"), "o-", ms=3, **style)
            axes[2].plot(values(mine, "mean_taps"), values(mine, "error_mm"), "o-", ms=3, **style)
    for ax in (axes[0], axes[2]):
        ax.axhline(PAPER_PASSIVE_MM["fingertip"], label=f"paper: passive ~{PAPER_PASSIVE_MM['fingertip']:g} mm",
                   **PAPER_STYLE)
        ax.set_yscale("symlog", linthresh=0.05)
    shown = [n for n in classes if n in PAPER_TABLE2]
    axes[2].plot([2.0] * len(shown), [PAPER_TABLE2[n] for n in shown], "s", mfc="none", mec="0.2", ms=7,
                 label="paper: active at 2 taps (Table II)")
    for ax, (x, y) in zip(axes, (("belief threshold", "mean location error (mm)"),
                                 ("belief threshold", "mean decision time (taps)"),
                                 ("mean decision time (taps)", "mean location error (mm)"))):
        ax.set_xlabel(x)
        ax.set_ylabel(y)
        ax.set_title("ABC"[axes.index(ax)], fontsize=9)
    axes[2].set_xscale("log")
    legend(axes[2])
    return fig


def taxel_figures(extra: dict) -> dict:
    """The figures whose rows ``extra`` holds (``fig7``, ``fig8b``, ``fig10``, ``fig11``), in the paper's order."""
    draw = {"fig7": fig7, "fig8b": fig8b, "fig10": fig10, "fig11": fig11}
    return {name: function(extra[name]) for name, function in draw.items() if extra.get(name)}

