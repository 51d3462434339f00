"""Decisions for a replayed video: the station's calibration and model applied to recorded taps.

`tactip.replay.video.replay_video` uses this module when it is given a sensor calibration and a model:

- `calibration.place_reference_pins` (called by the replay) places the calibrated reference pins on
  the rest frame, as the station's `tactip.station.station.OpticalFrontEnd` does for every tap, so pin
  identities and the feature subset are the calibration's;
- `check_model` refuses a model that does not fit the replay's taps (one-line `ModelError`);
- `decide_taps` runs a passive `perception.Perceiver` (stationary policy: a recording cannot move
  the sensor) over the valid taps in order, stopping at the decision as the station would.

The result (`ReplayDecisions`) is written as the ``decisions`` group of the replay's HDF5 file.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ReplayDecisions", "check_model", "decide_taps", "write_decisions"]

DEFAULT_THRESHOLD = 0.9


@dataclass(frozen=True)
class ReplayDecisions:
    """The running decision over the taps of a video (NaN where a tap did not enter the belief).

    Attributes
    ----------
    location_estimate, identity_estimate, belief : (taps,) ndarray of float64
        After each tap: MAP location (e.g. depth, mm), MAP identity (e.g. gap width, mm) and the
        largest identity belief. NaN for invalid taps (skipped) and taps after the decision.
    what_belief : (taps, identities) ndarray of float64
        The identity marginal after each tap (NaN rows likewise).
    used : (taps,) ndarray of bool
        Taps that entered the belief.
    identities : (identities,) ndarray of float64
        The model's identity classes, identity units.
    identity, final_belief : float
        The decision (or the last MAP identity when never decided) and its belief; NaN without valid taps.
    decided : bool
        The belief crossed `decision_threshold`.
    decided_at_tap : int
        Index of the tap that made the decision, -1 if never.
    decision_threshold : float
    model_path : str
    location_unit, identity_unit : str
    """

    location_estimate: np.ndarray
    identity_estimate: np.ndarray
    belief: np.ndarray
    what_belief: np.ndarray
    used: np.ndarray
    identities: np.ndarray
    identity: float
    final_belief: float
    decided: bool
    decided_at_tap: int
    decision_threshold: float
    model_path: str
    location_unit: str
    identity_unit: str

    def lines(self) -> list[str]:
        """Readable lines: one per tap that entered the belief, then the decision."""
        unit = self.identity_unit
        lines = [f"  tap {k + 1}: {self.identity_estimate[k]:g} {unit} (belief {self.belief[k]:.3f}; "
                 f"location {self.location_estimate[k]:g} {self.location_unit})" for k in np.flatnonzero(self.used)]
        if self.decided:
            lines.append(f"Decision: {self.identity:g} {unit} (belief {self.final_belief:.3f} > "
                         f"{self.decision_threshold:g}) at tap {self.decided_at_tap + 1}")
        elif np.isfinite(self.identity):
            lines.append(f"Undecided: best {self.identity:g} {unit} (belief {self.final_belief:.3f} <= "
                         f"{self.decision_threshold:g}) after {int(self.used.sum())} taps")
        else:
            lines.append("Undecided: no valid taps")
        return lines


def check_model(model, calibration, *, n_samples: int, path: str = "the model") -> None:
    """Refuse a model that does not fit the taps of this calibration (`calibration.check_model_fits`)."""
    from calibration import check_model_fits

    check_model_fits(model, calibration, samples=n_samples, source=path, maker="the replay")


def decide_taps(taps: np.ndarray, valid: np.ndarray, model, *, decision_threshold: float | None = None,
                model_path: str = "") -> ReplayDecisions:
    """Run a passive perceiver over the valid taps in order, until it decides.

    Parameters
    ----------
    taps : (taps, samples, dims) ndarray
        Feature arrays of the video's taps.
    valid : (taps,) ndarray of bool
        Taps whose features are usable; the others are skipped.
    model : perception.HistogramModel
    decision_threshold : float in [0, 1], optional
        theta_dec; default the model's recommended one, else 0.9.
    model_path : str
        Recorded with the result.

    Returns
    -------
    ReplayDecisions
    """
    from perception import Perceiver, StationaryPolicy

    if decision_threshold is None:
        decision_threshold = model.recommended.get("decision_threshold", DEFAULT_THRESHOLD)
    n_taps = len(valid)
    perceiver = Perceiver(model, StationaryPolicy(), decision_threshold=float(decision_threshold),
                          max_taps=max(n_taps, 1))
    location, identity, belief = (np.full(n_taps, np.nan) for _ in range(3))
    what = np.full((n_taps, model.n_identities), np.nan)
    used = np.zeros(n_taps, dtype=bool)
    decided_at, step = -1, None
    for k in np.flatnonzero(valid):
        step = perceiver.observe(taps[k])
        perceiver.moved(0.0)
        used[k] = True
        location[k], identity[k], belief[k] = step.location_estimate, step.identity_estimate, step.belief
        what[k] = step.what_belief
        if step.decided and not step.forced:
            decided_at = int(k)
        if step.decided:  # the station stops here (forced: the last tap)
            break
    return ReplayDecisions(location_estimate=location, identity_estimate=identity, belief=belief, what_belief=what,
                           used=used, identities=np.asarray(model.identities, dtype=np.float64),
                           identity=np.nan if step is None else step.identity_estimate,
                           final_belief=np.nan if step is None else step.belief, decided=decided_at >= 0,
                           decided_at_tap=decided_at, decision_threshold=float(decision_threshold),
                           model_path=str(model_path), location_unit=model.location_unit,
                           identity_unit=model.identity_unit)


def write_decisions(h5, decisions: ReplayDecisions) -> None:
    """Write ``decisions`` as the ``decisions`` group of an open HDF5 file (see the module docstring)."""
    group = h5.create_group("decisions")
    for name in ("location_estimate", "identity_estimate", "belief", "what_belief", "used", "identities"):
        group.create_dataset(name, data=getattr(decisions, name))
    group.attrs.update({
        "identity_estimate": decisions.identity, "belief": decisions.final_belief, "decided": decisions.decided,
        "decided_at_tap": decisions.decided_at_tap, "decision_threshold": decisions.decision_threshold,
        "model": decisions.model_path, "location_unit": decisions.location_unit,
        "identity_unit": decisions.identity_unit, "policy": "stationary",
    })
