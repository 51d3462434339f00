"""The reproduced figures as PNGs: each paper's measured curves beside the paper's numbers.

`make_figures` draws one paper's figures from the rows its reproduction produced (`Report.rows`,
the JSON rows) and, where a figure needs its own small experiment (002 Figs 10-11, 004 Figs 7
sweep and 8; `tactip.reproduce.figure_runs`), from that experiment's rows. The paper's values are
drawn on the same axes (dotted, grey or hollow markers), from the numbers the reproduction holds
for comparison (`Report.comparisons`) or, for whole tables, from the paper's text (000 Tables II
and III). A figure a world was tuned against says "FIT" in its title (002 Fig. 9, and any figure a
comparison marks with ``fit``). `save_figures` writes them (Agg backend, no display), each atomically.

One module per paper draws its figures (``tactip.reproduce.figures.p000`` ... ``p004``); every
function returns a `matplotlib.figure.Figure` whose lines carry the plotted rows, so that a test can
compare the drawn data with the JSON rows.

Example
-------
>>> report = reproduce("003", quick=True)                                  # doctest: +SKIP
>>> save_figures(make_figures(report), "out/reproduce/003", paper="003")   # doctest: +SKIP
[PosixPath('out/reproduce/003/003_fig5.png'), ...]
"""

from __future__ import annotations

import importlib
import math
import pathlib

__all__ = ["make_figures", "save_figures", "figure_names", "figure_path", "figure_label", "mark_fits", "new_figure",
           "paper_lines", "values", "legend"]

#: Dots per inch of the saved PNGs (a 10 x 4 in figure is 1000 x 400 px).
DPI = 100
#: Colours of the conditions, the same in every paper.
COLOURS = {"passive": "tab:red", "stationary": "tab:red", "active": "tab:blue", "random": "tab:green",
           "adaptive": "tab:green", "adaptive_angle_only": "tab:olive", "adaptive_shift0": "tab:grey",
           "fingertip": "tab:blue", "skin": "tab:purple"}
#: How the paper's values are drawn.
PAPER_STYLE = dict(color="0.35", ls=":", lw=1.5)


def make_figures(report, extra: dict | None = None) -> dict:
    """Draw a reproduction's figures.

    Parameters
    ----------
    report : tactip.reproduce.Report
        A paper's reproduction (its ``paper``, ``rows`` and ``comparisons`` are drawn).
    extra : dict of str -> list of dict, optional
        Rows of the small experiments only figures need (`tactip.reproduce.figure_runs.run_with_figure_runs`),
        by figure name; the figures they feed are drawn only when given.

    Returns
    -------
    dict of str -> matplotlib.figure.Figure
        Figure name (``"fig9"``, ``"table2"`` ...) -> the figure, in the paper's order.
    """
    module = importlib.import_module(f"tactip.reproduce.figures.p{report.paper}")
    figures = module.figures(report, extra or {})
    mark_fits(figures, report.comparisons)
    return figures


def figure_label(name: str) -> str:
    """The paper's name of figure ``name``: ``"fig7b"`` -> ``"Fig. 7B"``, ``"table3"`` -> ``"Table III"``."""
    import re

    if name.startswith("table"):
        return "Table " + {"1": "I", "2": "II", "3": "III", "4": "IV"}[name[5:]]
    number = re.match(r"fig(\d+)([a-z]?)", name)
    return f"Fig. {number.group(1)}{number.group(2).upper()}"


def mark_fits(figures: dict, comparisons) -> None:
    """Say "FIT" in the title of every figure a comparison marks as tuned on (``Comparison.fit``): the world
    reproduces it by construction, so it is not a prediction."""
    for name, fig in figures.items():
        label = figure_label(name)
        fitted = [c for c in comparisons if getattr(c, "fit", False) and
                  (c.figure == label or c.figure.startswith((label + " ", label + ":")))]
        title = fig._suptitle.get_text() if fig._suptitle is not None else ""
        if fitted and "FIT" not in title:
            fig.suptitle(title + "\n(a FIT: the simulated world was tuned on this figure)", fontsize=10)


def figure_names(paper: str) -> tuple[str, ...]:
    """Every figure `make_figures` may draw for ``paper`` (``NAMES`` of its module), in the paper's order."""
    return importlib.import_module(f"tactip.reproduce.figures.p{paper}").NAMES


def figure_path(folder, paper: str, name: str) -> pathlib.Path:
    """Where figure ``name`` of ``paper`` is saved: ``folder/PAPER_NAME.png`` (e.g. ``002_fig9.png``)."""
    return pathlib.Path(folder) / f"{paper}_{name}.png"


def save_figures(figures: dict, folder, *, paper: str) -> list[pathlib.Path]:
    """Write each figure as a PNG in ``folder`` (created), atomically: a failure leaves no half-written file.

    Parameters
    ----------
    figures : dict of str -> matplotlib.figure.Figure
        From `make_figures`.
    folder : str or os.PathLike
    paper : str
        Prefix of the file names (`figure_path`).

    Returns
    -------
    list of pathlib.Path
        The files written, in the order of ``figures``.
    """
    from _shared import atomic_path

    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    written = []
    for name, fig in figures.items():
        path = figure_path(folder, paper, name)
        with atomic_path(path) as tmp:
            fig.savefig(tmp, dpi=DPI, format="png", metadata={"Software": f"tactip reproduce {paper}"})
        written.append(path)
    return written


def new_figure(panels: int = 1, *, title: str, width_in: float = 5.0, height_in: float = 4.0, rows: int = 1):
    """A figure of ``panels`` axes side by side, in ``rows`` rows (Agg canvas: no display, no pyplot state).

    ``width_in`` and ``height_in`` are one panel's size, inches.

    Returns
    -------
    fig : matplotlib.figure.Figure
    axes : list of matplotlib.axes.Axes
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    columns = -(-panels // rows)
    fig = Figure(figsize=(width_in * columns, height_in * rows), layout="constrained")
    FigureCanvasAgg(fig)
    axes = [fig.add_subplot(rows, columns, k + 1) for k in range(panels)]
    import textwrap

    fig.suptitle(textwrap.fill(title, int(11 * width_in * columns)), fontsize=10)
    for ax in axes:
        ax.grid(alpha=0.3)
    return fig, axes


def values(rows, key: str) -> list[float]:
    """``row[key]`` of each row as floats, None (a NaN in strict JSON) as NaN; a missing key raises KeyError."""
    return [math.nan if r[key] is None else float(r[key]) for r in rows]


def paper_lines(ax, comparisons, *, prefix: str, contains: str = "", at_theta: bool = False) -> list:
    """Draw the paper's numbers of the comparisons whose figure starts with ``prefix`` (and contains
    ``contains``) on ``ax``: a dotted horizontal line each or, with ``at_theta``, a hollow marker at the
    threshold the comparison names ("theta 0.5"; a line when it names none).

    Returns
    -------
    list of Comparison
        The comparisons drawn (those with a paper number).
    """
    import re

    drawn = [c for c in comparisons if c.figure.startswith(prefix) and contains in c.figure and c.paper is not None]
    for c in drawn:
        label = f"paper: {c.figure} = {c.paper:g} {c.unit}".rstrip()
        theta = re.search(r"theta ([0-9.eE+-]+)", c.figure) if at_theta else None
        if theta is None:
            ax.axhline(c.paper, label=label, **PAPER_STYLE)
        else:
            ax.plot([float(theta.group(1).rstrip("."))], [c.paper], "o", mfc="none", mec="0.2", ms=9, mew=1.5,
                    label=label)
    return drawn


def legend(ax, **options) -> None:
    """A small legend, when the axes have labelled artists."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=7, **options)
