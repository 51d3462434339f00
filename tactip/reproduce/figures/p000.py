"""Paper 000's Tables II (fingertip) and III (skin) as plots: mean location error against class count.

Reads either row layout of `tactip.reproduce.p000`: one row per (sensor, classes, policy) with
``error_mm`` (issue 25), or one row per class count with ``passive_error_mm`` and ``active_error_mm``
(the fingertip only). The paper's tables are drawn beside, from its text. With the rows of
`tactip.reproduce.taxel_runs` (``--figure-runs``), Figs 7, 8B, 10 and 11 of the simulated fingertip
(`tactip.reproduce.figures.taxel`).
"""

from __future__ import annotations

from tactip.reproduce.figures import COLOURS, PAPER_STYLE, legend, new_figure
from tactip.reproduce.p000 import PAPER_PASSIVE_MM, PAPER_TABLE2, PAPER_TABLE3

__all__ = ["NAMES", "PAPER_TABLES", "figures", "table_rows"]

#: The figures this module may draw (`make_figures` keys).
NAMES = ("table2", "table3", "fig7", "fig8b", "fig10", "fig11")

#: Paper 000 Tables II (fingertip, 30 mm, 2 taps) and III (skin, 50 mm, 4 taps): classes -> mean error (mm),
#: the numbers `tactip.reproduce.p000` compares with.
PAPER_TABLES = {
    sensor: {"table": table, "range_mm": range_mm, "taps": taps, "active": active,
             "passive": {c: PAPER_PASSIVE_MM[sensor] for c in active}}
    for sensor, table, range_mm, taps, active in (("fingertip", "table2", 30.0, 2, PAPER_TABLE2),
                                                   ("skin", "table3", 50.0, 4, PAPER_TABLE3))}


def table_rows(rows) -> list[dict]:
    """The rows as ``{sensor, classes, policy, error_mm}``, whatever their layout."""
    out = []
    for r in rows:
        if "policy" in r:
            out.append({"sensor": r.get("sensor", "fingertip"), "classes": r["classes"], "policy": r["policy"],
                        "error_mm": r["error_mm"]})
        else:
            out += [{"sensor": "fingertip", "classes": r["classes"], "policy": policy,
                     "error_mm": r[f"{policy}_error_mm"]} for policy in ("passive", "active")]
    return out


def _table(rows, sensor: str):
    paper = PAPER_TABLES[sensor]
    name = "Table II" if sensor == "fingertip" else "Table III"
    fig, (ax,) = new_figure(title=f"paper 000 {name} ({sensor}): mean location error against class count "
                                  f"(paper: {paper['taps']} mean taps)", width_in=7.0)
    for policy in ("passive", "active"):
        mine = sorted((r for r in rows if r["sensor"] == sensor and r["policy"] == policy), key=lambda r: r["classes"])
        if mine:
            ax.plot([r["classes"] for r in mine], [r["error_mm"] for r in mine], "o-", color=COLOURS[policy],
                    label=f"{policy} (simulated)")
        ref = paper[policy]
        ax.plot(list(ref), list(ref.values()), "s", mfc="none", ms=7, label=f"{policy} (paper)",
                **{**PAPER_STYLE, "color": COLOURS[policy]})
    classes = sorted(set(paper["active"]) | {r["classes"] for r in rows if r["sensor"] == sensor})
    ax.plot(classes, [paper["range_mm"] / c for c in classes], color="0.6", lw=1, label="class width")
    ax.set_xscale("log")
    ax.set_xticks(classes, [str(c) for c in classes], fontsize=8)
    ax.minorticks_off()
    ax.set_yscale("symlog", linthresh=0.01)
    highest = max([r["error_mm"] for r in rows if r["sensor"] == sensor and r["error_mm"] is not None] +
                  list(paper["passive"].values()))
    ax.set_ylim(0, 1.6 * highest)
    ax.set_xlabel("location classes")
    ax.set_ylabel("mean location error (mm)")
    legend(ax)
    return fig


def figures(report, extra: dict) -> dict:
    """Table II, Table III when the rows hold the skin, and Figs 7, 8B, 10 and 11 when their runs' rows are given
    (`tactip.reproduce.taxel_runs`, drawn by `tactip.reproduce.figures.taxel`)."""
    from tactip.reproduce.figures.taxel import taxel_figures

    rows = table_rows(report.rows)
    out = {PAPER_TABLES[s]["table"]: _table(rows, s) for s in ("fingertip", "skin")
           if any(r["sensor"] == s for r in rows)}
    return {**out, **taxel_figures(extra)}
