"""Unattended gap inspection by active Bayesian perception (paper 002, Algorithm).

For each gap: move over it at the start depth, tap, extract the tap's features, update the joint
(depth, width) beliefs, move in depth as the policy asks (every move safety-checked by the arm),
until the width marginal crosses the decision threshold or ``max_taps`` is reached (the result is
then *undecided*). The width is judged against the gap's nominal width and tolerance; every tap
and every verdict is written to the results database as it happens.

The perceiver knows nothing of the start depth (paper 002: "no information about the initial contact
depth"); the station starts at ``[perception] start_depth``, or, when it is not set, at a protocol depth
drawn at random (seeded), as in the paper's evaluation.

An arm fault mid-inspection stops the arm (the station's context manager), records the inspection
as aborted with the reason, and propagates, so the command exits non-zero; stored rows stay.
Ctrl-C and SIGTERM abort the same way (reasons "interrupted (Ctrl-C)", "terminated (SIGTERM)"); a
write error of the results database (disk full) is reported as such, the rows already stored stay.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from tactip.station.config import GapConfig, StationConfig
from tactip.errors import TactipError
from tactip.line.results import ResultsError, ResultsStoreBase, open_results
from tactip.station.heartbeat import Heartbeat

__all__ = ["InspectionOutcome", "inspect_gap", "inspect_station", "load_station_model", "make_perceiver"]


@dataclass(frozen=True)
class InspectionOutcome:
    """The verdict on one gap.

    Attributes
    ----------
    gap : GapConfig
    estimated_width : float
        MAP width, mm.
    estimated_depth : float
        MAP depth class centre at the last tap, mm.
    belief : float
        Posterior of the estimated width, 0-1.
    taps : int
    decided : bool
        The belief crossed the decision threshold (False: stopped at ``max_taps``).
    passed : bool or None
        Decided and within tolerance; None when undecided.
    duration_s : float
    inspection_id : int
        Row id in the results database.
    depths : tuple of float
        Protocol depth of every tap, mm.
    """

    gap: GapConfig
    estimated_width: float
    estimated_depth: float
    belief: float
    taps: int
    decided: bool
    passed: bool | None
    duration_s: float
    inspection_id: int
    depths: tuple[float, ...]

    @property
    def verdict(self) -> str:
        """PASS, FAIL or UNDECIDED."""
        return {True: "PASS", False: "FAIL", None: "UNDECIDED"}[self.passed]


def load_station_model(config: StationConfig, calibration):
    """The station's model, checked against its sensor calibration and protocol."""
    from calibration import check_model_fits
    from perception import ModelError, load_model

    path = config.perception.model
    if path is None:
        raise TactipError("no [perception] model in the configuration")
    if not path.exists():
        raise ModelError(f"no model at {path}: collect taps and run 'tactip train' (or 'tactip inspect --sim')")
    model = load_model(path)
    check_model_fits(model, calibration, samples=config.protocol.samples, source=str(path))
    if model.KIND != config.perception.likelihood:  # the key would otherwise say one thing while another runs
        raise ModelError(f"{path} is a {model.KIND} model but [perception] likelihood = "
                         f"\"{config.perception.likelihood}\": set likelihood = \"{model.KIND}\", or train the "
                         f"model again with that kind")
    return model


def make_perceiver(config: StationConfig, model, *, policy: str | None = None, seed: int | None = None):
    """A `perception.Perceiver` with the station's (or the model's recommended) settings."""
    from perception import Perceiver, make_policy

    p = config.perception
    name = policy or p.policy
    # fixation_class(None) is the model's recommended fixation (tactip validate --sweep-fixation).
    threshold = p.decision_threshold
    if threshold is None:
        threshold = model.recommended.get("decision_threshold", 0.9)
    return Perceiver(model, make_policy(name, fixation_class=model.fixation_class(p.fixation_depth)),
                     decision_threshold=threshold, max_taps=p.max_taps, rng=seed)


def inspect_gap(station, perceiver, gap: GapConfig, store: ResultsStoreBase, *, start_depth: float, policy: str,
                seed: int | None = None, log: Callable[[str], None] = print) -> InspectionOutcome:
    """Inspect one gap (see the module docstring); returns the outcome, stored in ``store``.

    ``seed`` makes a simulated inspection reproducible (each tap's camera noise and placement).
    """
    from calibration import tap_seed

    config = station.config
    protocol = config.protocol
    inspection = store.start_inspection(gap.name, nominal_width=gap.nominal_width, tolerance=gap.tolerance,
                                        policy=policy, decision_threshold=perceiver.decision_threshold,
                                        station=config.name, model=str(config.perception.model))
    started = time.monotonic()
    perceiver.reset()
    depth = float(start_depth)
    depths = []
    try:
        while True:
            result = station.tap(gap, depth, seed=None if seed is None else tap_seed(seed, len(depths)))
            depths.append(depth)
            step = perceiver.observe(result.features)
            store.record_tap(inspection, tap=step.taps, depth_mm=depth, location_estimate=step.location_estimate,
                             identity_estimate=step.identity_estimate, belief=step.belief,
                             what_belief=step.what_belief, where_belief=step.where_belief)
            log(f"  {gap.name} tap {step.taps:>2}  depth {depth:4.2f} mm  width {step.identity_estimate:4.2f} mm "
                f"(belief {step.belief:.3f})  depth est. {step.location_estimate:4.2f} mm")
            if step.decided:
                break
            target = float(np.clip(depth + step.move, protocol.depth_min, protocol.depth_max))
            perceiver.moved(target - depth)
            depth = target
    except BaseException as exc:
        from tactip._signals import interruption_reason

        try:
            store.abort_inspection(inspection, interruption_reason(exc))
        except (OSError, ResultsError):  # e.g. the disk is full: the first error is the one to report
            pass
        raise
    decided = bool(step.decided and not step.forced)
    passed = store.finish_inspection(inspection, estimated_width=step.identity_estimate,
                                     estimated_depth=step.location_estimate, belief=step.belief, taps=step.taps,
                                     decided=decided)
    return InspectionOutcome(gap, float(step.identity_estimate), float(step.location_estimate), float(step.belief),
                             int(step.taps), decided, passed, time.monotonic() - started, inspection, tuple(depths))


def inspect_station(config: StationConfig, *, policy: str | None = None, seed: int | None = None,
                    gaps: Sequence[str] | None = None, start_depth: float | None = None,
                    log: Callable[[str], None] = print, station=None) -> list[InspectionOutcome]:
    """Inspect the configured gaps (or those named in ``gaps``); returns the outcomes in order.

    Parameters
    ----------
    config : StationConfig
    policy : {"active", "stationary", "random"}, optional
        Overrides ``[perception] policy``.
    seed : int, optional
        Seed of the random start depths, the random policy and (simulated station) each tap's
        camera noise and placement: the same seed repeats the same inspection.
    gaps : sequence of str, optional
        Names of the gaps to inspect (default all).
    start_depth : float, optional
        Start every inspection at this protocol depth (mm); default ``[perception] start_depth``,
        else a random protocol depth (seeded).
    station : Station, optional
        An open station to use (tests); opened from ``config`` otherwise.
    """
    from tactip.station.procedures import load_station_calibration
    from tactip.station.station import Station

    calibration = load_station_calibration(config)
    model = load_station_model(config, calibration)
    name = policy or config.perception.policy
    perceiver = make_perceiver(config, model, policy=name, seed=seed)
    targets = [config.gap(g) for g in gaps] if gaps else list(config.gaps)
    rng = np.random.default_rng(seed)
    depths = np.asarray(config.protocol.depths)
    fixation = perceiver.policy
    missing = [key for key, own in (("decision_threshold", config.perception.decision_threshold),
                                    ("fixation_location", config.perception.fixation_depth))
               if own is None and key not in model.recommended]
    if missing:
        log(f"warning: the model {config.perception.model} has no recommended {' or '.join(missing)} and "
            f"[perception] sets none: using the defaults (threshold {perceiver.decision_threshold:g}, the middle "
            f"depth class); run 'tactip validate --sweep-fixation' to choose them")
    log(f"inspecting {len(targets)} gap(s) on {config.name}: policy {name}"
        f"{'' if name != 'active' else f' (fixation {model.location_centres[fixation.fixation_class]:g} mm)'}, "
        f"decision threshold {perceiver.decision_threshold:g}, at most {perceiver.max_taps} taps")
    outcomes = []
    with (station if station is not None else Station(config, calibration=calibration)) as open_station:
        store = open_results(config.results)
        model_name = str(config.perception.model)
        state = "stopped"
        heartbeat = Heartbeat(lambda: open_results(config.results), config.name)
        try:
            store.update_station(config.name, state="ready", model=model_name, **station_status(open_station))
            heartbeat.start()  # after the status row it stamps exists
            stale = store.close_stale_inspections(config.name)
            if stale:
                log(f"closed {len(stale)} inspection(s) left 'running' by a process that ended without closing "
                    f"them (ids {', '.join(map(str, stale))}) as aborted")
            for gap in targets:
                start = start_depth if start_depth is not None else config.perception.start_depth
                start = float(rng.choice(depths)) if start is None else float(start)
                gap_seed = None if seed is None else int(rng.integers(2**62))
                store.update_station(config.name, state="inspecting", model=model_name,
                                     **station_status(open_station))
                outcome = inspect_gap(open_station, perceiver, gap, store, start_depth=start, policy=name,
                                      seed=gap_seed, log=log)
                log(f"{gap.name}: width {outcome.estimated_width:.2f} mm (nominal {gap.nominal_width:.2f} "
                    f"+- {gap.tolerance:.2f}), belief {outcome.belief:.3f}, {outcome.taps} taps, "
                    f"{outcome.duration_s:.1f} s -> {outcome.verdict}")
                outcomes.append(outcome)
        except BaseException as exc:
            from tactip._signals import interruption_reason

            state = f"stopped: {interruption_reason(exc)}"
            raise
        finally:
            heartbeat.stop()
            try:  # the station's last word; never in the way of the error being reported
                store.update_station(config.name, state=state, model=model_name, **station_status(open_station))
            except (OSError, ResultsError):
                pass
            store.close()
    return outcomes


def station_status(station) -> dict:
    """The arm and camera of an open station as the results store's station row holds them.

    Returns
    -------
    dict
        ``arm``: ``"BACKEND: ready"`` or ``"BACKEND: PROBLEM"`` (as the controller reports it);
        ``frame_rate``: the camera's frame rate, frames/s (None when unknown).
    """
    backend = station.config.arm.backend
    try:
        state = station.arm.state()
        arm = f"{backend}: ready" if state.ready else f"{backend}: {state.problem}"
    except Exception as exc:  # a controller that does not answer is a status too
        arm = f"{backend}: no state ({' '.join(str(exc).split()) or type(exc).__name__})"
    rate = getattr(station.camera, "frame_rate", None)
    return dict(arm=arm, frame_rate=None if rate is None else float(rate))
