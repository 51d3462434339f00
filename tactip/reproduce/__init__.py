"""Papers 000-004 reproduced on the simulators: each experiment's figures beside the paper's.

`reproduce` runs one paper's experiment and returns a `Report`: JSON-ready rows (one per
condition of the paper's figure) and comparisons of measured figures with the paper's numbers.
Each simulated world was tuned only against one of the paper's figures (000: Table II; 001:
fixed-position errors, Fig. 4 black; 002: Fig. 9, the skin's sag over a gap; 003: Figs 5-6,
passive; 004: passive and active single decisions); `tactip.reproduce.fits.FITS` lists every tuned
parameter beside its figure, and the report marks those figures as fits. Every other figure is a
prediction. ``quick=True`` runs the same experiment with fewer runs and conditions (tests).

- 000 (`tactip.reproduce.p000`): localisation acuity against class count, passive and active (Tables II, III);
- 001 (`tactip.reproduce.p001`): rods, joint decisions, 'boredom' deadline with random relocation;
- 002 (`tactip.reproduce.p002`): the inspection station, active / random / stationary perception (Fig. 9);
- 003 (`tactip.reproduce.p003`): textures under depth uncertainty, passive / weakly / strongly active;
- 004 (`tactip.reproduce.p004`): edge angle and position, contour following, adaptive prior.
"""

from __future__ import annotations

import importlib

from tactip.reproduce.report import Comparison, Report

__all__ = ["PAPERS", "Comparison", "Report", "reproduce"]

#: Papers `reproduce` knows, with the module of each.
PAPERS = {"000": "tactip.reproduce.p000", "001": "tactip.reproduce.p001", "002": "tactip.reproduce.p002",
          "003": "tactip.reproduce.p003", "004": "tactip.reproduce.p004"}


def reproduce(paper: str, *, quick: bool = False, seed: int = 0, progress=None, map_fn=None) -> Report:
    """Run paper ``paper``'s experiment on the simulator.

    Parameters
    ----------
    paper : {"000", "001", "002", "003", "004"}
    quick : bool
        Fewer runs and conditions (a few seconds to a minute), for tests.
    seed : int
        Seed of the simulated sensor, its collections and the Monte Carlo.
    progress : callable, optional
        Wraps an iterable of conditions (e.g. ``tqdm``).
    map_fn : callable, optional
        Runs the conditions (001: deadlines, 003: simulator seeds, 004: methods and thresholds, 000:
        class counts): ``map_fn(function, conditions)``, results in order (e.g. on a Dask cluster,
        `tactip.cluster.cluster_map`); the same report as run here (default), seed for seed.

    Returns
    -------
    Report

    Raises
    ------
    ValueError
        An unknown paper; the message lists the choices.
    """
    from tactip.reproduce.fits import mark_fits

    if paper not in PAPERS:
        raise ValueError(f"unknown paper {paper!r}; choose from {', '.join(PAPERS)}")
    report = importlib.import_module(PAPERS[paper]).run(quick=quick, seed=seed, progress=progress, map_fn=map_fn)
    return mark_fits(report)
