"""Candidate detection parameters of the pin-field search, for `pins.lattice.find_pin_field`.

Each candidate parameter set (`_candidates`: blocks and offsets scaled to a pitch) is run once:
blobs detected (`pins.detect`) and judged against the lattice (`pins._judge`), a `_Run`; the runs
are run two at a time (`_evaluate_all`), voted on (`_consensus`: the pins at least half of the good
runs keep, and each run's distance to their consensus), and the winner's parameters are narrowed
for later frames (`_final_params`). `pins.lattice` says how the search uses them (steps 1-2, 5, 6).
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import cv2
import numpy as np
from scipy.spatial import cKDTree

from ._judge import _KEPT, _MIN_PINS, _judge_lattice, _sharpness
from ._noise import binned_noise_sigma, noise_sigma
from .detect import Blobs, DetectionParams, _blur_size_px, _detect
from .disc import SensorDisc

_FIELD_MARGIN = 0.5
# Area range of the final parameters around the kept pins' median area.
_AREA_RANGE = (0.25, 2.5)
# Candidate sets: a pin matches within this many pitches; 'the same pins' within this fraction.
_MATCH = 0.3
_SAME_PINS = 0.005
_VOTER = 0.97
# At least this many sets vote: those keeping the next most pins join a lone voter when they keep at least
# `_JOIN` of its pins (`_consensus`).
_MIN_VOTERS = 2
_JOIN = 0.9
# No candidate offset below this many standard deviations of the blurred camera noise (`_noise_floored`).
_NOISE_OFFSET = 2.0


@dataclass(frozen=True)
class _Run:
    """One candidate parameter set: its blobs, the lattice verdict on each, and their pitch, px."""

    params: DetectionParams
    blobs: Blobs
    reason: np.ndarray
    pitch: float

    @property
    def kept(self) -> np.ndarray:
        return self.reason == _KEPT

    @property
    def strength(self) -> float:
        """Summed contrast x area of the kept blobs: the strongest lattice is the pins'."""
        kept = self.kept
        return float(np.sum(self.blobs.contrasts[kept] * self.blobs.areas[kept]))


# OpenCV and NumPy release the GIL in the detection, so two candidate sets run at once on two cores.
_WORKERS = 2


class _SharedCache(dict):
    """The filtered images of one grey image and disc shared by the candidate sets of a search (the
    `cache` of `pins.detect._detect` and `pins._judge._sharpness`), safe to share between threads.

    Each entry is a pure function of the image, the disc and its key (blur, polarity, block), computed
    whole before it is stored; a dict's lookups and stores are atomic under the GIL, and every array
    is made read-only as it is stored, so no thread sees one half written or changed after. Two
    threads that miss the same key both compute it, to the same bits (the second store is a no-op).
    """

    def __setitem__(self, key, value):
        for array in value if isinstance(value, tuple) else (value,):
            if isinstance(array, np.ndarray):
                array.setflags(write=False)
        super().__setitem__(key, value)


def _evaluate_all(grey: np.ndarray, disc: SensorDisc, candidates: list, cache: _SharedCache) -> list:
    """`_evaluate` for each candidate parameter set, on `_WORKERS` threads sharing `cache`."""
    if not isinstance(cache, _SharedCache):
        raise TypeError("the candidate sets' threads share their filtered images only in a _SharedCache")
    with ThreadPoolExecutor(_WORKERS) as pool:
        return list(pool.map(lambda params: _evaluate(grey, disc, params, cache), candidates))


def _evaluate(grey: np.ndarray, disc: SensorDisc, params: DetectionParams, cache: dict) -> _Run:
    """Detect with one candidate parameter set and judge the blobs."""
    blobs = _detect(grey, disc, params, cache)
    reason, pitch = _judge_lattice(blobs, _sharpness(grey, blobs, params, cache, disc))
    return _Run(params, blobs, reason, pitch)


def _strongest(grey: np.ndarray, disc: SensorDisc, candidates: list, cache: _SharedCache) -> _Run:
    """The run of greatest `_Run.strength` among `candidates` (the first of equals), as
    ``max(_evaluate_all(...), key=strength)`` gives it, judging only the runs that could be it.

    A run's strength sums the contrast x area of the blobs it keeps, so it is at most its blobs' total:
    detected on `_WORKERS` threads, the sets are judged in descending totals, and one whose total is
    below the strongest run judged so far is not judged (`pins.lattice`'s coarse pass: 44 % of its
    judgements left on 10 presets x 3 seeds). The margin covers the sums' rounding.
    """
    if not isinstance(cache, _SharedCache):
        raise TypeError("the candidate sets' threads share their filtered images only in a _SharedCache")
    with ThreadPoolExecutor(_WORKERS) as pool:
        detected = list(pool.map(lambda params: _detect(grey, disc, params, cache), candidates))
        # The judgements on a candidate thread too, as `_evaluate_all` runs them (one after another: each
        # decides whether the next is needed).
        return pool.submit(_judge_strongest, grey, disc, candidates, detected, cache).result()


def _judge_strongest(grey: np.ndarray, disc: SensorDisc, candidates: list, detected: list, cache: dict) -> _Run:
    """`_strongest`'s judgements: the `detected` blobs of each candidate set judged in descending totals of
    contrast x area, until the next total is below the strongest run's kept strength."""
    totals = [float(np.sum(np.maximum(blobs.contrasts * blobs.areas, 0.0))) for blobs in detected]
    best: _Run | None = None
    best_at = -1
    for at in sorted(range(len(candidates)), key=lambda i: -totals[i]):
        if best is not None and totals[at] < best.strength * (1.0 - 1e-9):
            break
        blobs = detected[at]
        reason, pitch = _judge_lattice(blobs, _sharpness(grey, blobs, candidates[at], cache, disc))
        run = _Run(candidates[at], blobs, reason, pitch)
        if best is None or run.strength > best.strength or (run.strength == best.strength and at < best_at):
            best, best_at = run, at
    return best


def _keeps_more(grey: np.ndarray, disc: SensorDisc, params: DetectionParams, cache: dict, count: int) -> bool:
    """Whether `params` keeps more than `count` lattice pins in `disc`: ``_evaluate(...).kept.sum() > count``,
    judged only when it detects more than `count` blobs (the lattice keeps some of its blobs, never more).

    `pins.lattice`'s polarity probes: the other polarity's second probe (at sqrt(3) of the pitch) detects a
    fraction of the field's count on every preset (radial-led-120: 31-34 blobs for 120 pins), and the
    judgement costs ten times the detection.
    """
    blobs = _detect(grey, disc, params, cache)
    if len(blobs.centres) <= count:
        return False
    reason, _ = _judge_lattice(blobs, _sharpness(grey, blobs, params, cache, disc))
    return int(np.count_nonzero(reason == _KEPT)) > count


def _consensus(runs: list, pitch: float) -> tuple[np.ndarray, np.ndarray]:
    """Per run: kept pins the voters agree on minus the others; median distance to the consensus, px.

    Runs keeping fewer than `_VOTER` times the most pins kept neither vote nor win (-inf), unless fewer
    than `_MIN_VOTERS` would vote: then the runs keeping the next most pins vote as well (ties included)
    when they keep at least `_JOIN` of the most.
    The voters agree on a pin that at least half of them keep (both, when two vote). A lone voter agreed
    with itself: on a noisy webcam's frame the lowest offset keeps the pins and a few noise blobs, more
    than 97 % of any other set's pins, and its noise blobs were pins (bench_user_chain radial-led-120 seed
    0: 122 pins, 3 of them noise blobs on the LED reflections: the next kept 0.95 of its pins; brown-127
    seed 9: 0.97). Where the next keeps less than `_JOIN` of them the extras are pins only the best set
    finds (radial-led-120 filmed at 320x240, 1 px tips: 0.85-0.89), and it votes alone as before. It votes
    alone too when its offset is higher than that of every set that would join it: its extras passed a
    stricter threshold, so they are no noise blobs of a low one, but faint pins that the lower offsets
    merge with the membrane round them (bench_user_chain radial-led-120 seed 28: offset 15 keeps 110 pins,
    offset 5 keeps 102, and with both voting the lower won and one pin was lost for good).

    A kept pin is matched in another run by its nearest kept pin within `_MATCH` pitches; the
    consensus position of a pin is the mean of its matches.
    """
    kept = [run.blobs.centres[run.kept] for run in runs]
    # Only runs that keep nearly as many pins as the best one vote (on a small pad most candidate
    # sets lose pins, and pins that only the good ones find must not look like outliers).
    counts = np.array([len(c) for c in kept])
    voters = counts >= _VOTER * counts.max()
    if voters.sum() < _MIN_VOTERS and np.count_nonzero(counts) >= _MIN_VOTERS:
        # One set's own blobs are no agreement: those keeping the next most pins vote with it, unless they
        # keep a tenth fewer (then its extra blobs are the faint pins only it finds: 1 px tips at 320x240),
        # or unless every one of them thresholds lower than it (then its extras passed a stricter
        # threshold than theirs: no noise a low offset lets through).
        runner_up = np.sort(counts)[-_MIN_VOTERS]
        joining = np.flatnonzero((counts >= runner_up) & ~voters)
        lone_offset = runs[int(np.argmax(counts))].params.offset
        stricter = all(lone_offset > runs[r].params.offset for r in joining)
        if runner_up >= _JOIN * counts.max() and not stricter:
            voters = counts >= runner_up
    gate = _MATCH * pitch if np.isfinite(pitch) else 1.0
    membership = np.full(len(runs), -np.inf)
    deviation = np.full(len(runs), np.inf)
    voting = [r for r in range(len(runs)) if voters[r] and len(kept[r])]
    if not voting:
        return membership, deviation
    # Every voter's kept centres matched in every voter's at once: the nearest centres of all of
    # them (one k-d tree), nearest first, so that a voter's first among them is its nearest.
    bounds = np.cumsum([0] + [len(kept[r]) for r in voting])
    every = np.concatenate([kept[r] for r in voting])
    voter_of = np.append(np.repeat(np.arange(len(voting)), np.diff(bounds)), -1)  # -1: no neighbour
    tree = cKDTree(every)
    reach = min(len(voting) + 2, len(every))
    distance, index = tree.query(every, k=reach, distance_upper_bound=gate)
    distance, index = distance.reshape(len(every), reach), index.reshape(len(every), reach)
    rows = np.arange(len(every))
    matched = np.full((len(voting) + 1, len(every)), -1)  # the extra row takes "no neighbour"
    for column in range(reach - 1, -1, -1):  # nearest last: it stays
        matched[voter_of[index[:, column]], rows] = index[:, column]
    crowded = np.flatnonzero(np.isfinite(distance[:, -1]))  # all of them within the gate: maybe more
    if crowded.size:
        for s, r in enumerate(voting):  # asked of each voter, as one at a time
            found, nearest = cKDTree(kept[r]).query(every[crowded], distance_upper_bound=gate)
            matched[s, crowded] = np.where(np.isfinite(found), bounds[s] + np.minimum(nearest, len(kept[r]) - 1), -1)
    matched = matched[:-1]
    support = (matched >= 0).sum(axis=0)
    # At least half: a strict majority of four voters would let the two least complete veto the
    # pins only the two most complete find. Two voters must both keep a pin (one run's own blobs
    # are no agreement).
    agreed = (2 * support >= voters.sum()) & (support >= min(2, voters.sum()))
    # The mean of each centre's matches (the row past the end of `every` is zeros: no match).
    with np.errstate(invalid="ignore"):  # centres no voter matched: averaged, never used
        consensus = np.append(every, [[0.0, 0.0]], axis=0)[matched].sum(axis=0) / support[:, None]
    for s, r in enumerate(voting):
        mine = slice(bounds[s], bounds[s + 1])
        membership[r] = agreed[mine].sum() - (~agreed[mine]).sum()
        if agreed[mine].any():
            offset = kept[r][agreed[mine]] - consensus[mine][agreed[mine]]
            deviation[r] = float(np.median(np.hypot(*offset.T)))
    return membership, deviation


def _candidates(pitches: np.ndarray, start: DetectionParams, blocks, offsets):
    """Permissive parameter sets scaled to each pitch (px)."""
    for pitch in pitches:
        blur = float(np.clip(0.07 * pitch, 0.6, 2.5))
        loose = dict(blur_sigma_px=round(blur, 2), min_area_px=2, max_area_px=max(int(1.2 * pitch**2), 8),
                     min_fill=0.3, max_aspect=4.0, split_radius_px=round(min(0.12 * pitch, 20.0), 2))
        for block in blocks:
            size = max(2 * int(round(block * pitch / 2.0)) + 1, 3)
            for offset in offsets:
                yield start.replace(block_size_px=size, offset=offset, **loose)


def _noise_floored(candidates, grey: np.ndarray) -> list:
    """`candidates` with each offset raised to `_NOISE_OFFSET` standard deviations of the camera's noise
    (`pins._noise.noise_sigma`) after the candidate's blur, where it is below that.

    The offsets (5-25 grey levels) were set on frames with noise sigma 2-5. A noisier camera (sigma
    10: a cheap webcam in dim light) at offset 5 thresholds a pixel of bare membrane above its
    neighbourhood's mean one time in six: a lattice of noise blobs at about the pins' pitch, kept by
    more candidate sets than the pins are, won the vote (radial-led-120, sigma 10: 126-141 pins found
    of 120, 74-78 of them true). The noise is the larger of `noise_sigma` and `pins._noise.binned_noise_sigma`:
    through JPEG (a webcam's MJPG) the first reads 2-10 x low while the noise a blur of 0.6-2.5 px leaves
    survives (radial-led-120, sigma 8, JPEG 75: offset 5 kept 122-149 pins of 120, scale up to +67 %).
    """
    sigma = max(noise_sigma(grey), binned_noise_sigma(grey))
    floored = []
    for params in candidates:
        blurred = sigma * _blur_gain(params.blur_sigma_px)
        floored.append(params.replace(offset=round(max(params.offset, _NOISE_OFFSET * blurred), 1)))
    return floored


def _blur_gain(sigma_px: float) -> float:
    """The factor by which `pins.detect`'s Gaussian blur of `sigma_px` scales white noise's standard deviation."""
    if sigma_px <= 0:
        return 1.0
    kernel = cv2.getGaussianKernel(_blur_size_px(sigma_px), sigma_px)[:, 0]
    return float(np.sum(kernel ** 2))


def _distinct(candidates: list) -> list:
    """`candidates` without repeats, in order."""
    return list(dict.fromkeys(candidates))


def _final_params(run: _Run, centres: np.ndarray, disc: SensorDisc, pitch: float, reach_px: float) -> DetectionParams:
    """Parameters for later frames: `run`'s, with the area range of its kept blobs and a rim margin
    that leaves out the membrane beyond `centres` (the pins, px) and whatever lies beyond `reach_px`
    from the disc centre (a rim ring)."""
    kept = run.kept
    if kept.sum() < _MIN_PINS or len(centres) < _MIN_PINS or not np.isfinite(pitch):
        return run.params
    median_area = float(np.median(run.blobs.areas[kept]))
    radius = np.sqrt(median_area / np.pi)
    params = run.params.replace(min_area_px=max(int(_AREA_RANGE[0] * median_area), 1),
                                max_area_px=max(int(np.ceil(_AREA_RANGE[1] * median_area)), 2),
                                min_fill=0.4, max_aspect=3.0, split_radius_px=round(float(min(0.4 * radius, 20.0)), 2))
    reach = float(np.max(np.hypot(centres[:, 0] - disc.cx, centres[:, 1] - disc.cy)))
    margin = disc.radius_px - min(reach + _FIELD_MARGIN * pitch, reach_px)
    return params.replace(rim_margin_px=round(float(max(params.rim_margin_px, margin)), 2))
