"""The pin field `pins.find_pin_field` returns (`pins.lattice`): the pins of a frame that form the pin
lattice, the blobs rejected beside them and why, the detection parameters for later frames, the
sensor disc and the pitch."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ._judge import REJECTION_REASONS
from .detect import DetectionParams
from .disc import SensorDisc

__all__ = ["PinField"]


@dataclass(frozen=True)
class PinField:
    """The pins of a frame that form the pin lattice, and the blobs rejected beside them.

    Attributes
    ----------
    centres : (N, 2) ndarray of float64
        Kept pins (x, y), px, sorted by y then x; (0, 2) when there are none.
    params : DetectionParams
        Detection parameters for later frames of this sensor (`pins.detect_pins` with
        ``disc=field.disc``): the kept pins' blur, threshold and area range, and a rim margin that
        leaves out the membrane beyond the pin field (a rim ring and its glare).
    disc : SensorDisc
        The sensor disc, px (the pins were searched inside it, or inside a black rim ring's inner
        edge when there is one); ``disc.whole_frame`` when the sensing region is the whole frame.
    pitch_px : float
        The pin pitch, px, of the kept pins near the field's centre (their first shell's median distance
        on a hexagonal lattice or spokes, else their nearest neighbours')
        (`pins.central_spacing_px`, the pitch the scale `pins.pad_scale` divides by; nan with fewer
        than two).
    rejected : (M, 2) ndarray of float64
        Centres of the candidate blobs rejected, px.
    rejected_reason : (M,) ndarray of str
        Why each was rejected: one of `REJECTION_REASONS` ("outside field": beyond the lattice, such
        as glare round the rim or pins a rim ring cuts, or cut by the frame's edge too deeply to measure; "off lattice": too close to a stronger pin,
        such as a speck or a light patch of skin between pins, or at no lattice site and unlike its
        neighbours; "size": much smaller or larger than its neighbours; "contrast": much fainter
        than its neighbours, or with a much softer edge).
    expected_pins : int or None
        The pin count given, if any.
    count_error : int or None
        Pins kept minus `expected_pins` (None without a count).
    warnings : tuple of str
        What in the frame may have hidden pins, for a person (`pins._exposure`): a pad saturated off
        the tips (lower the exposure), pins faint against the camera noise or too small (raise the
        exposure, film the pad larger); empty when the frame shows its pins well.
    """

    centres: np.ndarray
    params: DetectionParams
    disc: SensorDisc
    pitch_px: float
    rejected: np.ndarray
    rejected_reason: np.ndarray
    expected_pins: int | None = None
    count_error: int | None = None
    warnings: tuple[str, ...] = ()

    @property
    def count(self) -> int:
        """Number of pins kept."""
        return int(len(self.centres))

    @property
    def field_disc(self) -> SensorDisc:
        """The pin field's circle: `disc` less the rim margin of `params`, px."""
        return SensorDisc(self.disc.cx, self.disc.cy, max(self.disc.radius_px - self.params.rim_margin_px, 0.0))

    def rejected_counts(self) -> dict[str, int]:
        """How many blobs were rejected for each reason (every reason listed, zeros included)."""
        return {reason: int(np.count_nonzero(self.rejected_reason == reason)) for reason in REJECTION_REASONS}

    def summary(self, *, pitch: bool = True) -> str:
        """One line for a person: pins kept, pitch (unless `pitch` is False: a summary that prints the
        scale prints the pitch there), blobs rejected by reason, the count check."""
        rejected = ", ".join(f"{n} {reason}" for reason, n in self.rejected_counts().items() if n)
        pitch = f", pitch {self.pitch_px:.1f} px" if pitch and np.isfinite(self.pitch_px) else ""
        line = f"{self.count} pins{pitch}; rejected {len(self.rejected)}"
        line += f" ({rejected})" if rejected else ""
        if self.expected_pins is not None:
            error = self.count_error
            off = "exact" if error == 0 else f"{error:+d} ({error / self.expected_pins:+.1%})"
            line += f"; expected {self.expected_pins}: {off}"
        return line
