"""A replay's recorders: the HDF5 file and the annotated video, written from its `PinTrack`.

The layout of the file is in `tactip.replay.video`'s docstring.
"""

from __future__ import annotations

import dataclasses
import json

import cv2
import numpy as np

from _shared import hdf5_in_memory
from pins import feature_dim_names

from tactip import __version__
from tactip.pipeline import PinTrack
from tactip.replay.decisions import write_decisions
from tactip.sources import open_source

__all__ = ["ARROW_SCALE", "FORMAT", "write_annotated", "write_hdf5"]

FORMAT = "tactip-replay/2"
# Displacement arrows in the annotated video are drawn this many times their length.
ARROW_SCALE = 3.0
_BAR_X = np.array([24, 0], dtype=np.int32)
_BAR_Y = np.array([0, 24], dtype=np.int32)


def write_hdf5(path, track: PinTrack, analysis: dict, settings: dict, decisions=None) -> None:
    """The replay file (see the module docstring for its layout)."""
    tracker = track.tracker
    settings = dict(settings)
    frame_size, frame_rate = settings.pop("frame_size"), settings.pop("frame_rate")
    frames, pins = track.lost.shape
    # Positions are sub-pixel floats with sensor noise: gzip saves a third of their size for about
    # 10 % of the decoding time, so they are stored plain; the masks shrink to almost nothing.
    packed = dict(compression="gzip", compression_opts=1)
    with hdf5_in_memory(path) as h5:  # a full disk is an OSError, not a crash inside HDF5
        h5.create_dataset("positions", data=track.positions.astype(np.float32))
        h5.create_dataset("displacements", data=track.displacements.astype(np.float32))
        for name in ("lost", "retired"):
            h5.create_dataset(name, data=getattr(track, name), chunks=(min(64, max(frames, 1)), pins) if frames else None,
                              **(packed if frames else {}))
        h5.create_dataset("lost_count", data=track.lost.sum(axis=1, dtype=np.int32))
        h5.create_dataset("retired_count", data=track.retired.sum(axis=1, dtype=np.int32))
        h5.create_dataset("blank", data=track.blank)
        h5.create_dataset("tracked", data=track.tracked)
        h5.create_dataset("timestamps", data=track.timestamps_s)
        h5.create_dataset("rest_positions", data=track.rest_positions)
        selected = h5.create_dataset("selected_pins", data=np.asarray(analysis["selected"], dtype=np.int64))
        selection = analysis["selection"]
        if selection is not None:
            selected.attrs.update({"requested": selection.requested, "min_separation_mm": selection.min_separation_mm,
                                   "separation_mm": selection.separation_mm, "warning": selection.warning})
        bounds = analysis["bounds"]
        h5.create_dataset("tap_bounds", data=np.asarray(bounds, dtype=np.int64).reshape(-1, 2))
        kinds = analysis.get("kinds", [])
        h5.create_dataset("tap_kinds", data=np.array([k.kind for k in kinds], dtype="S5"))
        directions = h5.create_dataset("tap_directions_deg", data=np.array([k.direction_deg for k in kinds], float))
        directions.attrs["units"] = "degrees from image x towards image y; NaN for a press"
        rests = h5.create_dataset("tap_rest_frames", data=np.asarray(
            analysis.get("rest_frames", [settings["rest_frame"]] * len(bounds)), dtype=np.int64).reshape(-1))
        rests.attrs["meaning"] = ("the frame each tap's features are measured from: the rest frame, or the skin's "
                                  "own rest before the tap when the feature pins rest off the rest frame's")
        if track.features is not None and len(track.contacts):
            dataset = h5.create_dataset("taps", data=track.features.astype(np.float32))
            dataset.attrs["feature_names"] = json.dumps(feature_dim_names(len(analysis["selected"])))
            dataset.attrs["layout"] = "columns 0..P-1 dx, P..2P-1 dy of the selected pins, px"
            h5.create_dataset("tap_valid", data=track.valid)
            seen = h5.create_dataset("tap_pins_seen", data=np.asarray(track.pins_seen, dtype=np.int32))
            seen.attrs["of"] = len(analysis["selected"])
        disc = track.disc
        scale = analysis["scale"]
        scale_info = {"mm_per_px": float(analysis["mm_per_px"]), "source": "calibration"} if scale is None else {
            "mm_per_px": scale.mm_per_px, "pitch_px": scale.pitch_px, "pitch_mm": scale.pitch_mm,
            "source": scale.source, "sensor": scale.sensor}
        h5.attrs.update({
            "format": FORMAT,
            "software_version": __version__,
            "frame_size": np.asarray(frame_size, dtype=np.int64),
            "frame_rate": float(frame_rate or np.nan),
            "disc": json.dumps({"cx": disc.cx, "cy": disc.cy, "radius_px": disc.radius_px}),
            "detection_params": json.dumps(track.detection.to_dict()),
            "tracking_params": json.dumps({"lk": dataclasses.asdict(tracker.lk), "refine": tracker.refine,
                                           "gate_fraction": tracker.gate_fraction,
                                           "neighbours": tracker.neighbours}),
            "sensor": json.dumps({"kind": "tactip", "pins": int(track.rest_positions.shape[0]),
                                  "pad_diameter_mm": settings["pad_diameter_mm"]}),
            "scale": json.dumps(scale_info, default=float),
            "pins_detected": int(track.pins_detected),
            "blank_frames": np.flatnonzero(track.blank).astype(np.int64),
            "warnings": json.dumps(analysis["warnings"]),
            "tap_thresholds_px": np.asarray(analysis["tap_thresholds_px"], dtype=np.float64),
            **settings,
        })
        if decisions is not None:
            write_decisions(h5, decisions)


def write_annotated(video, path, track: PinTrack, bounds, selected, *, frame_size, frame_rate,
                    decisions=None) -> None:
    """The video again, with pins, displacement arrows (x ARROW_SCALE), the tap state and the
    running decision (each tap's width estimate and belief) drawn on."""
    width, height = frame_size
    rate = frame_rate or 20.0
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"mp4v"), rate, (width, height), True)
    if not writer.isOpened():
        raise OSError(f"cannot write the annotated video {str(path)!r} (no MPEG-4 encoder?)")
    tap_of_frame = np.full(len(track.timestamps_s), -1)
    for k, (start, stop) in enumerate(bounds):
        tap_of_frame[start:stop] = k
    rest = track.rest_positions
    is_selected = np.zeros(len(rest), dtype=bool)
    is_selected[selected] = True
    shift = 4  # sub-pixel drawing: coordinates in 1/16 px (the crosses' half-bars are 24/16 = 1.5 px)
    try:
        with open_source(video) as source:
            for frame, positions, displacement, tap in zip(source, track.positions, track.displacements,
                                                           tap_of_frame):
                image = frame.image if frame.image.ndim == 3 else cv2.cvtColor(frame.image, cv2.COLOR_GRAY2BGR)
                seen = np.isfinite(positions[:, 0])
                # Arrows from the rest position to rest + ARROW_SCALE x displacement; a cross on the pin.
                tail = np.rint(rest * 16).astype(np.int32)
                # Lost pins (NaN) are drawn at rest, then masked out: no NaN reaches the integer cast.
                tip = np.rint((rest + ARROW_SCALE * np.nan_to_num(displacement)) * 16).astype(np.int32)
                base = np.rint(np.where(np.isfinite(positions), positions, rest) * 16).astype(np.int32)
                for mask, colour in ((seen & ~is_selected, (0, 200, 0)), (seen & is_selected, (0, 0, 255))):
                    centre = base[mask]
                    # One polyline call per colour: arrow shafts and the two bars of each cross.
                    lines = np.concatenate([np.stack([tail[mask], tip[mask]], axis=1),
                                            np.stack([centre - _BAR_X, centre + _BAR_X], axis=1),
                                            np.stack([centre - _BAR_Y, centre + _BAR_Y], axis=1)])
                    cv2.polylines(image, list(lines), False, colour, 1, cv2.LINE_AA, shift)
                state = f"tap {tap + 1}" if tap >= 0 else "rest"
                text = f"frame {frame.index}  {frame.timestamp_s:6.2f} s  {state}  lost {int((~seen).sum())}"
                cv2.putText(image, text, (10, height - 12), cv2.FONT_HERSHEY_SIMPLEX, 0.55, (0, 255, 255), 1,
                            cv2.LINE_AA)
                if decisions is not None and tap >= 0:
                    cv2.putText(image, _decision_text(decisions, tap), (10, 22), cv2.FONT_HERSHEY_SIMPLEX, 0.55,
                                (0, 255, 255), 1, cv2.LINE_AA)
                writer.write(image)
    finally:
        writer.release()


def _decision_text(decisions, tap: int) -> str:
    """The running decision shown on the frames of tap ``tap``."""
    if decisions.used[tap]:
        mark = "  DECIDED" if tap == decisions.decided_at_tap else ""
        return (f"width {decisions.identity_estimate[tap]:g} {decisions.identity_unit}  "
                f"belief {decisions.belief[tap]:.3f}{mark}")
    if 0 <= decisions.decided_at_tap < tap:
        return f"decided {decisions.identity:g} {decisions.identity_unit} at tap {decisions.decided_at_tap + 1}"
    return "tap not used (pins lost)"
