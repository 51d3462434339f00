"""`ReplayResult`: what a replay found, and the summary it prints (the arrays are in its HDF5 file)."""

from __future__ import annotations

import pathlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pins import DetectionParams, PadScale, PinSelection, SensorDisc

__all__ = ["ReplayResult"]


@dataclass(frozen=True)
class ReplayResult:
    """What a replay found (the arrays are in the HDF5 file).

    Attributes
    ----------
    out_path, annotate_path : pathlib.Path, pathlib.Path or None
    video : str
    frames, pins : int
        Frames read; pins tracked.
    frame_rate : float or None
    lost_per_frame, retired_per_frame : (frames,) ndarray of int
        Pins lost (retired included) and retired in each frame (all pins before the rest frame
        and in blank frames).
    blank_frames : list of int
        Frames with nothing trackable (all pins lost), after the rest frame.
    rest_frame : int
    tap_bounds : list of (start, stop)
    contact_kinds : list of pins.ContactKind
        Press or slide, and a slide's direction, per contact.
    invalid_taps : list of int
        Taps whose features are NaN (fewer than half the selected pins seen in the tap).
    selected_pins : (P,) ndarray of int
    selection : pins.PinSelection or None
        How the feature pins were chosen (None with a calibration, or when selection failed).
    mm_per_px : float
    scale : pins.PadScale or None
        How the scale was derived (None with a calibration).
    disc : SensorDisc
    detection : DetectionParams
    pins_detected : int
        Pins found in the rest frame.
    pin_field : str
        The rest frame's pin field: pins kept, pitch, blobs rejected and why (`pins.PinField.summary`).
    expected_pins : int or None
    warnings : list of str
        What did not go as asked (also in the file).
    decisions : tactip.replay.decisions.ReplayDecisions or None
        The decision, when a model was given.
    pins_seen : list of int
        Selected pins seen in each tap (a pin unseen for a whole tap has NaN features there).
    """

    out_path: pathlib.Path
    annotate_path: pathlib.Path | None
    video: str
    frames: int
    pins: int
    frame_rate: float | None
    lost_per_frame: np.ndarray
    retired_per_frame: np.ndarray
    blank_frames: list
    rest_frame: int
    tap_bounds: list
    invalid_taps: list
    selected_pins: np.ndarray
    selection: PinSelection | None
    mm_per_px: float
    scale: PadScale | None
    disc: SensorDisc
    detection: DetectionParams
    pins_detected: int
    pin_field: str = ""
    expected_pins: int | None = None
    warnings: list = field(default_factory=list)
    decisions: Any = None
    contact_kinds: list = field(default_factory=list)
    pins_seen: list = field(default_factory=list)

    @property
    def lost_pin_frames(self) -> int:
        """Pin-frames flagged lost after the rest frame (blank frames included)."""
        return int(self.lost_per_frame[self.rest_frame:].sum())

    def summary(self) -> str:
        """A few readable lines: frames, pins, scale, lost and retired pins, taps, warnings, files."""
        rate = f" at {self.frame_rate:g} fps" if self.frame_rate else ""
        kinds = self.contact_kinds or [None] * len(self.tap_bounds)
        taps = ", ".join(f"{a}-{b - 1}" + _kind(k) for (a, b), k in zip(self.tap_bounds, kinds)) or "none"
        detected = f"rest frame {self.rest_frame}: {self.pin_field or f'{self.pins_detected} pins'}"
        if self.expected_pins and "expected" not in self.pin_field:
            off = self.pins_detected - self.expected_pins
            detected += f", {self.expected_pins} expected ({off:+d}, {off / self.expected_pins:+.1%})"
        scale = self.scale.describe() if self.scale is not None else f"{self.mm_per_px:.4f} mm/px (calibration)"
        lines = [
            f"Replayed {self.video}: {self.frames} frames{rate}",
            f"Pins: {self.pins} tracked ({detected}); "
            + ("sensing region: the whole frame (no disc)" if getattr(self.disc, "whole_frame", False)
               else f"disc radius {self.disc.radius_px:.1f} px"),
            f"Scale: {scale}",
            self._losses(),
            f"Taps: {len(self.tap_bounds)} (frames {taps}); features of "
            + (self.selection.describe() if self.selection is not None else f"{len(self.selected_pins)} pins"),
        ]
        if self.pins_seen:
            lines[-1] += f"; pins seen {min(self.pins_seen)}/{len(self.selected_pins)} in the poorest tap"
            if min(self.pins_seen) < max(self.pins_seen):  # which contacts missed pins, and how many
                lines[-1] += f" (per tap: {' '.join(map(str, self.pins_seen))})"
        lines += [f"Warning: {w}" for w in self.warnings]
        if self.invalid_taps:
            lines.append(f"Warning: taps {self.invalid_taps} have fewer than half the selected pins seen (features NaN)")
        if self.decisions is not None:
            lines += self.decisions.lines()
        written = [str(self.out_path)] + ([str(self.annotate_path)] if self.annotate_path else [])
        lines.append("Wrote " + " and ".join(written))
        return "\n".join(lines)

    def _losses(self) -> str:
        """Lost and retired pins per tracked frame (blank frames apart), and the blank frames."""
        tracked = np.arange(self.frames) >= self.rest_frame
        tracked[self.blank_frames] = False
        lost, retired = self.lost_per_frame[tracked], self.retired_per_frame[tracked]
        if lost.size == 0:
            text = "Lost pins: no tracked frame"
        else:
            worst = np.flatnonzero(tracked)[np.argsort(-lost, kind="stable")[:3]]
            worst = [int(f) for f in worst if self.lost_per_frame[f] > 0]
            text = (f"Lost pins per frame (retired included): median {np.median(lost):g}, max {lost.max()} of {self.pins}"
                    + (f" (frames {', '.join(map(str, worst))})" if worst else "")
                    + f"; retired: median {np.median(retired):g}, max {retired.max()}")
        if self.blank_frames:
            shown = ", ".join(map(str, self.blank_frames[:10])) + (" ..." if len(self.blank_frames) > 10 else "")
            text += f"; {len(self.blank_frames)} blank frame(s) (nothing trackable, pins NaN): {shown}"
        return text


def _kind(kind) -> str:
    """" press" or " slide 45 deg" for the summary's list of contacts ("" when unknown)."""
    if kind is None:
        return ""
    return f" {kind.kind}" + (f" {kind.direction_deg:.0f} deg" if kind.kind == "slide" else "")
