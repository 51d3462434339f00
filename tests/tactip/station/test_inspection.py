"""Gap inspection: decisions, verdicts, what is stored, the depth range, and arm faults mid-inspection.

The decision logic runs against a virtual station that serves taps of a dataset of known structure
(no arm, no camera); the fault handling runs on the simulated station with a faulty simulated arm.
"""

from types import SimpleNamespace

import numpy as np
import pytest

from arm.errors import ArmFault
from perception import fit_model
from tactip.station.config import GapConfig, parse_station_config
from tactip.errors import TactipError
from tactip.station.inspection import inspect_gap, inspect_station, make_perceiver
from tactip.line.results import ResultsStore
from tactip.station.station import Station
from tests.perception.synthetic import gap_dataset
from tests.tactip.conftest import FaultyArm, sim_arm, small_station_table

# Depths 0..5 mm at 1 mm, widths 1, 2, 3 mm, legible at every depth.
GRID = dict(depths=6, widths=3, samples=10, dims=8, legible_from=0.0)


@pytest.fixture(scope="module")
def model():
    return fit_model(gap_dataset(seed=1, taps_per_class=5, **GRID), n_locations=6)


@pytest.fixture(scope="module")
def test_taps():
    return gap_dataset(seed=2, taps_per_class=10, **GRID)


class VirtualStation:
    """Taps drawn from ``dataset`` at the collected depth nearest the commanded one, of the gap's true width.

    ``shown_depth`` (mm) serves taps of that depth whatever the command: a sensor that misleads the
    perceiver about where it is. ``interrupt_at`` raises KeyboardInterrupt at that tap (1-based).
    """

    def __init__(self, config, dataset, *, shown_depth=None, interrupt_at=None, seed=0):
        self.config, self.dataset = config, dataset
        self.shown_depth, self.interrupt_at = shown_depth, interrupt_at
        self.rng = np.random.default_rng(seed)
        self.depths = []

    def tap(self, gap, depth, **_):
        Station.check_depth(self, depth)                     # the real station's refusal
        if len(self.depths) + 1 == self.interrupt_at:
            raise KeyboardInterrupt
        self.depths.append(depth)
        collected = np.unique(self.dataset.location)
        shown = depth if self.shown_depth is None else self.shown_depth
        nearest = collected[np.abs(collected - shown).argmin()]
        index = np.flatnonzero((self.dataset.location == nearest) & (self.dataset.identity == gap.true_width))
        return SimpleNamespace(features=self.dataset.taps[self.rng.choice(index)])


def virtual_config(tmp_path, **perception):
    table = small_station_table(tmp_path, protocol={"depth_max": 5.0, "depth_step": 1.0}, perception=perception)
    return parse_station_config(table, base_dir=tmp_path)


def inspect(config, model, test_taps, gap, *, start_depth=2.0, policy="active", seed=0, **station):
    store = ResultsStore(":memory:")
    station = VirtualStation(config, test_taps, seed=seed, **station)
    perceiver = make_perceiver(config, model, policy=policy, seed=seed)
    outcome = inspect_gap(station, perceiver, gap, store, start_depth=start_depth, policy=policy, log=lambda _: None)
    return outcome, store, station


def test_max_taps_without_crossing_is_undecided(tmp_path, model, test_taps):
    config = virtual_config(tmp_path, decision_threshold=1.0, max_taps=4)
    gap = GapConfig("g", 0.0, 0.0, nominal_width=2.0, tolerance=0.25, true_width=2.0)
    outcome, store, station = inspect(config, model, test_taps, gap)
    assert (outcome.taps, outcome.decided, outcome.passed, outcome.verdict) == (4, False, None, "UNDECIDED")
    assert len(station.depths) == 4
    row, = store.inspections()
    assert (row.status, row.decided, row.passed, row.taps) == ("done", False, None, 4)
    assert row.estimated_width == outcome.estimated_width


@pytest.mark.parametrize("true_width, nominal, tolerance, passed", [
    (3.0, 3.0, 0.25, True),
    (3.0, 2.5, 0.5, True),              # at the edge of the tolerance
    (3.0, 1.0, 0.5, False),
    (1.0, 1.5, 0.25, False),
])
def test_a_decided_width_is_judged_against_the_tolerance(tmp_path, model, test_taps, true_width, nominal, tolerance,
                                                         passed):
    config = virtual_config(tmp_path, decision_threshold=0.99, max_taps=20)
    gap = GapConfig("g", 0.0, 0.0, nominal_width=nominal, tolerance=tolerance, true_width=true_width)
    outcome, store, _ = inspect(config, model, test_taps, gap)
    assert outcome.decided and outcome.belief > 0.99 and outcome.taps < 20
    assert outcome.estimated_width == true_width                    # the classifier is right here
    assert outcome.passed is passed and outcome.verdict == ("PASS" if passed else "FAIL")
    row, = store.inspections()
    assert (row.status, row.decided, row.passed, row.estimated_width) == ("done", True, passed, true_width)


def test_every_tap_is_stored_with_its_beliefs(tmp_path, model, test_taps):
    config = virtual_config(tmp_path, decision_threshold=0.999, max_taps=20)
    gap = GapConfig("g", 0.0, 0.0, nominal_width=1.0, tolerance=0.25, true_width=1.0)
    outcome, store, station = inspect(config, model, test_taps, gap, start_depth=0.0)
    taps = store.taps(outcome.inspection_id)
    assert outcome.taps == len(taps) == len(station.depths) > 1
    assert [t["tap"] for t in taps] == list(range(1, outcome.taps + 1))
    assert [t["depth_mm"] for t in taps] == list(outcome.depths) == station.depths
    for t in taps:
        assert len(t["what_belief"]) == 3 and len(t["where_belief"]) == 6
        assert sum(t["what_belief"]) == pytest.approx(1, abs=1e-5)
        assert sum(t["where_belief"]) == pytest.approx(1, abs=1e-5)
        assert t["belief"] == pytest.approx(max(t["what_belief"]), abs=1e-6)
        assert t["identity_estimate"] == model.identities[int(np.argmax(t["what_belief"]))]
    assert taps[-1]["belief"] == pytest.approx(outcome.belief)
    assert taps[-1]["identity_estimate"] == outcome.estimated_width
    assert taps[0]["belief"] < taps[-1]["belief"]                    # evidence accumulates


@pytest.mark.parametrize("policy", ["active", "random"])
@pytest.mark.parametrize("start_depth, shown_depth", [(0.0, None), (5.0, None), (5.0, 0.0), (0.0, 5.0)])
def test_moves_keep_the_commanded_depth_in_the_protocol_range(tmp_path, model, test_taps, policy, start_depth,
                                                              shown_depth):
    # shown_depth: the sensor misleads the perceiver about its depth, so it asks for moves beyond the
    # range (from the deep end it believes it is at the shallow end, and the other way round)
    config = virtual_config(tmp_path, decision_threshold=1.0, max_taps=25)
    gap = GapConfig("g", 0.0, 0.0, nominal_width=2.0, tolerance=0.25, true_width=2.0)
    outcome, _, station = inspect(config, model, test_taps, gap, start_depth=start_depth, policy=policy,
                                  shown_depth=shown_depth)
    assert outcome.taps == 25
    assert min(station.depths) >= 0.0 and max(station.depths) <= 5.0
    if shown_depth is None:
        assert len(set(station.depths)) > 1                          # it did move
    else:
        assert set(station.depths) == {start_depth}                  # every move was clipped to the edge


def test_the_active_policy_goes_to_the_fixation_depth(tmp_path, model, test_taps):
    config = virtual_config(tmp_path, decision_threshold=1.0, max_taps=6, fixation_depth=4.0)
    gap = GapConfig("g", 0.0, 0.0, nominal_width=2.0, tolerance=0.25, true_width=2.0)
    outcome, _, _ = inspect(config, model, test_taps, gap, start_depth=0.0)
    assert outcome.depths[0] == 0.0
    assert outcome.depths[-1] == pytest.approx(model.location_centres[model.fixation_class(4.0)], abs=0.5)


def test_ctrl_c_or_an_error_aborts_the_inspection_with_the_reason_keeping_its_taps(tmp_path, model, test_taps):
    config = virtual_config(tmp_path, decision_threshold=1.0, max_taps=10)
    store = ResultsStore(tmp_path / "results.sqlite")
    station = VirtualStation(config, test_taps, interrupt_at=3)
    gap = GapConfig("g", 0.0, 0.0, nominal_width=2.0, tolerance=0.25, true_width=2.0)
    with pytest.raises(KeyboardInterrupt):
        inspect_gap(station, make_perceiver(config, model), gap, store, start_depth=1.0, policy="active",
                    log=lambda _: None)
    row, = store.inspections()
    assert (row.status, row.reason, row.taps, row.passed) == ("aborted", "interrupted (Ctrl-C)", 2, None)
    assert len(store.taps(row.id)) == 2 and row.finished_at is not None
    station = VirtualStation(config, test_taps)
    with pytest.raises(TactipError):
        inspect_gap(station, make_perceiver(config, model), gap, store, start_depth=7.0, policy="active",
                    log=lambda _: None)
    row = store.inspections()[-1]
    assert row.status == "aborted" and row.reason.startswith("TactipError: depth 7 mm is outside the protocol range")
    assert row.taps == 0 and store.taps(row.id) == []


# -- the simulated station ----------------------------------------------------------------------

def sim_config(sim_station, tmp_path, **perception):
    """The shared station's calibration and model, results in ``tmp_path``; 3 undecided taps per gap."""
    perception = {"decision_threshold": 1.0, "max_taps": 3, **perception}
    table = small_station_table(sim_station.root, station={"results": str(tmp_path / "results.sqlite")},
                                perception=perception)
    return parse_station_config(table, base_dir=tmp_path)


@pytest.mark.parametrize("fault, reason", [
    ("protective", "ArmFault: protective stop during the move to"),
    ("emergency", "ArmFault: refusing to move: the controller reports an emergency stop"),
    ("program", "ArmFault: refusing to move: the control program is not running"),
])
def test_an_arm_fault_aborts_the_inspection_and_keeps_what_was_stored(sim_station, tmp_path, fault, reason):
    config = sim_config(sim_station, tmp_path)
    quiet = dict(start_depth=4.0, log=lambda _: None)
    first, = inspect_station(config, gaps=["g02"], **quiet)
    # fault on the 5th tap: the second gap's second tap, as the pad starts down
    arm = sim_arm(config, FaultyArm, fault_tap=5, fault=fault)
    station = Station(config, calibration=sim_station.calibration, arm=arm)
    with pytest.raises(ArmFault) as info:
        inspect_station(config, gaps=["g06", "g10"], station=station, **quiet)
    assert reason.split(": ", 1)[1] in str(info.value)
    with ResultsStore(config.results) as store:
        rows = store.inspections()
        assert [(r.gap, r.status, r.taps) for r in rows] == [("g02", "done", 3), ("g06", "done", 3),
                                                             ("g10", "aborted", 1)]
        assert rows[0].id == first.inspection_id and rows[2].reason.startswith(reason)
        assert rows[2].passed is None and rows[2].finished_at is not None
        assert [len(store.taps(r.id)) for r in rows] == [3, 3, 1]
    # the station stopped and released the arm; the fault stays until an operator clears it
    assert not arm.connected
    arm.connect()
    state = arm.state()
    assert not state.ready and (state.protective_stop, state.emergency_stop, state.program_running) == {
        "protective": (True, False, True), "emergency": (False, True, False), "program": (False, False, False)}[fault]
    if fault == "protective":
        # stopped half-way down the press: between the approach height and the bottom of the tap
        bottom = config.arm.work_frame.inverse() @ arm.commands[-1].target_base
        assert bottom.z < arm.pose().z < config.arm.tap.approach_height_mm
    with pytest.raises(ArmFault, match="refusing to move"):
        arm.tap(config.gap("g10").x, 0.0, depth_mm=1.0)
    arm.disconnect()


def test_the_same_seed_repeats_the_simulated_inspection(sim_station, tmp_path):
    config = sim_config(sim_station, tmp_path, policy="random")
    runs = [inspect_station(config, gaps=["g10", "g14"], seed=4, log=lambda _: None) for _ in range(2)]
    for a, b in zip(*runs):
        assert a.depths == b.depths and a.depths[0] in config.protocol.depths
        assert (a.estimated_width, a.belief, a.taps) == (b.estimated_width, b.belief, b.taps)
    other = inspect_station(config, gaps=["g10", "g14"], seed=5, log=lambda _: None)
    assert [o.depths for o in other] != [o.depths for o in runs[0]]


def test_the_configured_start_depth_is_where_every_inspection_starts(sim_station, tmp_path):
    config = sim_config(sim_station, tmp_path, start_depth=1.5, max_taps=1)
    outcomes = inspect_station(config, gaps=["g10", "g14"], seed=3, log=lambda _: None)
    assert [o.depths[0] for o in outcomes] == [1.5, 1.5]
    # An explicit start depth (tactip inspect --start-depth) wins over the configuration.
    outcome, = inspect_station(config, gaps=["g10"], start_depth=4.0, log=lambda _: None)
    assert outcome.depths[0] == 4.0
