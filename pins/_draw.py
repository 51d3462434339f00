"""`draw_pin_field`: a picture of what `pins.find_pin_field` kept and rejected, and why."""

from __future__ import annotations

import cv2
import numpy as np

from .disc import as_grey

__all__ = ["draw_pin_field", "COLOURS"]


# `draw_pin_field` enlarges frames to this shorter side, px, and scales its marks to it.
_LEGIBLE_PX = 480

#: Colours (B, G, R) of `draw_pin_field`: kept pins, then each rejection reason.
COLOURS = {"kept": (0, 200, 0), "outside field": (255, 80, 255), "off lattice": (0, 160, 255),
           "size": (255, 160, 0), "contrast": (0, 0, 255)}


def draw_pin_field(frame: np.ndarray, field, *, legend: bool = True) -> np.ndarray:
    """A colour picture of what `find_pin_field` kept and rejected, and why.

    Kept pins are green circles; rejected blobs are crosses coloured by reason (`COLOURS`); the
    pin field's circle (`PinField.field_disc`) is a thin yellow circle; a legend with the counts
    sits top left. Frames whose shorter side is under 480 px are enlarged by a whole factor (pixels
    repeated) so that the marks and the legend can be read.

    Parameters
    ----------
    frame : (H, W) or (H, W, 3) ndarray of uint8
        The frame the field was found in.
    field : pins.PinField
    legend : bool
        Draw the legend.

    Returns
    -------
    picture : (k H, k W, 3) ndarray of uint8
        BGR; k = 1 for frames of 480 px or more (shorter side), else ceil(480 / shorter side).
    """
    grey = as_grey(frame)
    image = np.asarray(frame)
    picture = image.copy() if image.ndim == 3 and image.shape[2] == 3 else cv2.cvtColor(grey, cv2.COLOR_GRAY2BGR)
    zoom = max(int(np.ceil(_LEGIBLE_PX / min(grey.shape))), 1)
    if zoom > 1:
        picture = cv2.resize(picture, None, fx=zoom, fy=zoom, interpolation=cv2.INTER_NEAREST)
    scale = max(min(picture.shape[:2]) / _LEGIBLE_PX, 1.0)
    thick = max(int(round(scale)), 1)
    pitch = field.pitch_px if np.isfinite(field.pitch_px) else 10.0
    radius = max(0.3 * pitch * zoom, 2.0)

    def at(x: float, y: float) -> tuple[int, int]:
        # Pixel centres sit at integers in the frame and in the enlarged picture; 4 fractional bits.
        return int(round(((x + 0.5) * zoom - 0.5) * 16)), int(round(((y + 0.5) * zoom - 0.5) * 16))

    d = field.field_disc
    cv2.circle(picture, at(d.cx, d.cy), int(round(d.radius_px * zoom * 16)), (0, 230, 230), thick, cv2.LINE_AA, 4)
    for x, y in field.centres:
        cv2.circle(picture, at(x, y), int(round(radius * 16)), COLOURS["kept"], thick, cv2.LINE_AA, 4)
    half = radius / zoom
    for (x, y), reason in zip(field.rejected, field.rejected_reason):
        colour = COLOURS[str(reason)]
        cv2.line(picture, at(x - half, y - half), at(x + half, y + half), colour, thick, cv2.LINE_AA, 4)
        cv2.line(picture, at(x - half, y + half), at(x + half, y - half), colour, thick, cv2.LINE_AA, 4)
    if legend:
        counts = field.rejected_counts()
        lines = [("kept", f"kept {field.count}")] + [(r, f"{r} {n}") for r, n in counts.items()]
        step = int(round(18 * scale))
        cv2.rectangle(picture, (0, 0), (int(round(150 * scale)), step * len(lines) + step // 2), (0, 0, 0), -1)
        for i, (key, text) in enumerate(lines):
            cv2.putText(picture, text, (int(round(6 * scale)), step * (i + 1)), cv2.FONT_HERSHEY_SIMPLEX, 0.45 * scale,
                        COLOURS[key], thick, cv2.LINE_AA)
    return picture
