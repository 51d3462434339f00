"""Paper 002's Figs 9-11 on the simulated station: gap width error against taps, fixation depth and lateral noise.

Fig. 9 from the rows of `tactip.reproduce.p002` (``policy, threshold, width_error_mm, mean_taps``): one
curve per policy, the paper's errors after 8-12 taps as segments over 8-12 taps, and the variant (active at
the fixation the station chose on its training taps) dashed beside active. Fig. 10 marks the fixation the
sweep gives Fig. 9 (lowest error within 12 mean taps) and the station's own. It is a fit: the
skin's sag (``MEMBRANE_RHO_MM`` 8 -> 1 mm) was tuned so that the station reproduces it, and its title
says so. Figs 10 (``fixation_mm, tap_budget, width_error_mm``) and 11 (``policy, sigma_mm,
width_error_mm, ratio``) come from their own runs (`tactip.reproduce.figure_runs`).
"""

from __future__ import annotations

import numpy as np

from perception.choices import POLICIES

from tactip.reproduce.figures import COLOURS, PAPER_STYLE, legend, new_figure, values
from tactip.reproduce.p002 import PAPER_FIXATION_MM

__all__ = ["NAMES", "PAPER_FIXATION_MM", "PAPER_LATERAL_RATIO", "figures"]

#: The figures this module may draw (`make_figures` keys).
NAMES = ("fig9", "fig10", "fig11")

#: Paper 002 Fig. 11 (text): error ratio e(sigma) / e(0) "within 25 %" at sigma <= 0.5 mm, "doubling" at 2 mm.
PAPER_LATERAL_RATIO = {0.5: 1.25, 2.0: 2.0}


def _fig9(report):
    from tactip.reproduce.p002 import PAPER_ERROR_MM, STATION_FIXATION

    fig, (ax,) = new_figure(title="paper 002 Fig. 9 (a FIT: MEMBRANE_RHO_MM 8 -> 1 mm tuned on it): "
                                  "gap width error against decision time", width_in=7.0)
    for policy in POLICIES:
        mine = sorted((r for r in report.rows if r["policy"] == policy), key=lambda r: r["mean_taps"])
        if not mine:
            continue
        ax.plot(values(mine, "mean_taps"), values(mine, "width_error_mm"), ".-", ms=3, color=COLOURS[policy],
                label=f"{policy} (simulated)")
        ax.plot([8, 12], [PAPER_ERROR_MM[policy]] * 2, color=COLOURS[policy], ls=":", lw=3, alpha=0.7,
                label=f"{policy} (paper, 8-12 taps)")
    variant = sorted((r for r in report.rows if r["policy"] == STATION_FIXATION), key=lambda r: r["mean_taps"])
    if variant:
        ax.plot(values(variant, "mean_taps"), values(variant, "width_error_mm"), "--", lw=1, color=COLOURS["active"],
                label=f"variant: {STATION_FIXATION} (simulated)")
    ax.set_xlabel("mean decision time (taps)")
    ax.set_ylabel("mean gap width error (mm)")
    legend(ax)
    return fig


def _fixations(report) -> dict:
    """Fixation (mm) of each active row kind of the report: the Fig. 10 sweep's and the station's own."""
    return {r["policy"]: r["fixation_mm"] for r in report.rows if r.get("fixation_mm") is not None}


def _fig10(rows, report):
    from tactip.reproduce.p002 import STATION_FIXATION

    fig, (ax,) = new_figure(title="paper 002 Fig. 10: active perception, width error against fixation depth",
                            width_in=7.0)
    budgets = sorted({r["tap_budget"] for r in rows})
    for k, budget in enumerate(budgets):
        mine = sorted((r for r in rows if r["tap_budget"] == budget), key=lambda r: r["fixation_mm"])
        grey = str(0.75 - 0.6 * k / max(len(budgets) - 1, 1))
        ax.plot(values(mine, "fixation_mm"), values(mine, "width_error_mm"), "o-", ms=3, color=grey,
                label=f"within {budget:g} mean taps (simulated)")
    ax.axvline(PAPER_FIXATION_MM, color="tab:red", ls="--", label=f"paper's best fixation {PAPER_FIXATION_MM:g} mm")
    chosen = _fixations(report)
    if "active" in chosen:
        ax.axvline(chosen["active"], color=COLOURS["active"], ls="-", lw=1,
                   label=f"simulated best within 12 mean taps, Fig. 9's fixation: {chosen['active']:g} mm")
    if STATION_FIXATION in chosen:
        ax.axvline(chosen[STATION_FIXATION], color=COLOURS["active"], ls=":", lw=1.5,
                   label=f"variant: the station's, from training taps: {chosen[STATION_FIXATION]:g} mm")
    ax.set_xlabel("fixation depth (mm)")
    ax.set_ylabel("mean gap width error (mm)")
    legend(ax)
    return fig


def _fig11(rows):
    fig, axes = new_figure(2, title="paper 002 Fig. 11: width error against lateral placement noise (A: the "
                                    "paper's ratio to the noise-free error, B: the errors themselves)")
    for ax, key in zip(axes, ("ratio", "width_error_mm")):
        for policy in POLICIES:
            mine = sorted((r for r in rows if r["policy"] == policy), key=lambda r: r["sigma_mm"])
            if not mine:
                continue
            label = f"{policy} (simulated)"
            if key == "ratio" and not np.isfinite(values(mine, key)).any():
                # A noise-free error of 0 mm (the policy judged every gap right) has no ratio: say so
                # here rather than leave the policy out of A without a word (B draws its errors).
                label = f"{policy}: no ratio, its noise-free error is 0 mm (B)"
            ax.plot(values(mine, "sigma_mm"), values(mine, key), "o-", color=COLOURS[policy], label=label)
        ax.set_xlabel("lateral noise sigma: offsets uniform over [-sigma, sigma] (mm)")
    axes[0].plot(list(PAPER_LATERAL_RATIO), list(PAPER_LATERAL_RATIO.values()), "s", mfc="none", ms=8,
                 label="paper (text): <= 1.25 at 0.5 mm, 2 at 2 mm", **PAPER_STYLE)
    axes[0].axhline(1.0, color="0.6", lw=1)
    axes[0].set_ylabel("error ratio e(sigma) / e(0)")
    axes[1].set_ylabel("mean gap width error at 10 mean taps (mm)")
    for ax in axes:
        legend(ax)
    return fig


def figures(report, extra: dict) -> dict:
    """Fig. 9, and Figs 10 and 11 when their runs' rows are given."""
    out = {"fig9": _fig9(report)}
    if extra.get("fig10"):
        out["fig10"] = _fig10(extra["fig10"], report)
    if extra.get("fig11"):
        out["fig11"] = _fig11(extra["fig11"])
    return out
