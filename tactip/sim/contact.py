"""The contact the synthetic TacTip renders, a rendered frame with its ground truth, and a tap's profile in time."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Contact", "SyntheticFrame", "tap_profile"]


@dataclass(frozen=True)
class Contact:
    """State of the pad against the plate.

    Attributes
    ----------
    indentation_mm : float
        How far the plate presses into the pad apex, mm; ``<= 0`` means no contact.
    gap_width_mm : float
        Width of the straight gap in the plate, mm (0 = flat plate).
    gap_offset_mm : float
        Lateral position of the gap centre line from the pad axis, along image y, mm.
    gap_angle_deg : float
        Direction of the gap line in the plate, degrees (0: along image x).
    slide_x_mm, slide_y_mm : float
        How far the plate has dragged the skin under it sideways (sticking), along image x and y, mm of
        pad surface: the contact patch moves by all of it, the skin around it less (`tactip.sim._slide`).
        No effect without contact (``indentation_mm <= 0``).
    shear_x_mm, shear_y_mm : float
        The skin's residual shear, mm of pad surface: what earlier slides left in it, creeping back to
        rest (opt-in, `tactip.sim.sequence.schedule`'s ``residual``; 0 by default). It shifts the apex
        by all of it and the skin round it less (`tactip.sim._slide`), with or without contact; under
        a slide it adds to the drag.
    shear_decay_mm : float
        How far, mm of pad surface, the residual shear falls off from the apex, laid out apart from the plate's
        slide (opt-in, `tactip.sim.sequence.schedule`'s ``set_share``: the shape its slide left); 0: the shear
        adds to the plate's drag and falls off with it (`tactip.sim._slide`).
    slide_decay_mm : float
        How far, mm of pad surface, the drag falls off outside the contact patch (opt-in, a stiffer
        skin: `tactip.sim.sequence.schedule`'s ``min_area``); 0: the default rule (`tactip.sim._slide`).
    texture_mm, texture_period_mm : float
        A textured plate (opt-in; 0: a smooth one): under a slide, ridges ``texture_period_mm`` apart across
        the slide catch and release the skin in the contact patch, moving each pin there back and forth
        along the slide by up to ``texture_mm`` (mm of pad surface) by where it lies against the ridges
        (`tactip.sim._slide.textured_points`).
    """

    indentation_mm: float = 0.0
    gap_width_mm: float = 0.0
    gap_offset_mm: float = 0.0
    gap_angle_deg: float = 0.0
    slide_x_mm: float = 0.0
    slide_y_mm: float = 0.0
    shear_x_mm: float = 0.0
    shear_y_mm: float = 0.0
    slide_decay_mm: float = 0.0
    shear_decay_mm: float = 0.0
    texture_mm: float = 0.0
    texture_period_mm: float = 2.0

    def __post_init__(self):
        for name in ("indentation_mm", "gap_width_mm", "gap_offset_mm", "gap_angle_deg", "slide_x_mm", "slide_y_mm",
                     "shear_x_mm", "shear_y_mm", "slide_decay_mm", "shear_decay_mm", "texture_mm",
                     "texture_period_mm"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"{name} must be finite, got {getattr(self, name)!r}")
        if self.slide_decay_mm < 0 or self.shear_decay_mm < 0:
            raise ValueError(f"slide_decay_mm and shear_decay_mm must be >= 0, got {self.slide_decay_mm}, "
                             f"{self.shear_decay_mm}")
        if self.gap_width_mm < 0:
            raise ValueError(f"gap_width_mm must be >= 0, got {self.gap_width_mm}")
        if self.texture_period_mm <= 0:
            raise ValueError(f"texture_period_mm must be > 0, got {self.texture_period_mm}")
        if not 0 <= self.texture_mm <= self.texture_period_mm / (4 * math.pi):
            # the wobble's own strain along the slide stays within 50 %: the skin never folds over it
            raise ValueError(f"texture_mm must be in [0, texture_period_mm / 4 pi = "
                             f"{self.texture_period_mm / (4 * math.pi):.3g}], got {self.texture_mm}")


@dataclass(frozen=True, eq=False)
class SyntheticFrame:
    """One rendered frame and its ground truth.

    Attributes
    ----------
    image : (H, W) uint8 ndarray, or (H, W, 3) uint8 BGR when the renderer has ``colour=True``
    centres : (N, 2) float64 ndarray
        True pin-tip centres (x, y), px; pixel centres at integer coordinates (OpenCV convention).
    visible : (N,) bool ndarray
        Whether each pin's whole tip is drawn (False when hidden, cut or outside the image).
    timestamp_s : float
        Time within the sequence, s.
    contact : Contact
        The contact state that was rendered.
    partial : (N,) bool ndarray
        Pins drawn but partly hidden: cut by the black rim ring (casing lip) or by the image edge.
        A detector may find them or not; see "Scoring" in the module docstring. All False when not given.
    """

    image: np.ndarray
    centres: np.ndarray
    visible: np.ndarray
    timestamp_s: float
    contact: Contact
    partial: np.ndarray | None = field(default=None)

    def __post_init__(self):
        if self.partial is None:
            object.__setattr__(self, "partial", np.zeros(len(self.visible), bool))


def tap_profile(t_s, *, rise_s: float = 0.25, plateau_s: float = 0.25, release_s: float = 0.25):
    """Fraction of full indentation at time ``t_s`` into a tap (0 before and after).

    A raised-cosine rise over ``rise_s``, a plateau of ``plateau_s`` at 1, and a raised-cosine
    release over ``release_s`` (paper 002, IV-A: about 250 ms each). Smooth (C1) throughout.

    Parameters
    ----------
    t_s : float or ndarray
        Time since the start of the rise, s.
    rise_s, plateau_s, release_s : float
        Phase durations, s (rise and release > 0, plateau >= 0).

    Returns
    -------
    float or ndarray
        Fraction in [0, 1], same shape as ``t_s``.

    Examples
    --------
    >>> tap_profile([0.0, 0.125, 0.3, 0.625, 0.8])
    array([0. , 0.5, 1. , 0.5, 0. ])
    """
    if not rise_s > 0 or not release_s > 0:
        raise ValueError(f"rise_s and release_s must be > 0, got {rise_s}, {release_s}")
    if not plateau_s >= 0:
        raise ValueError(f"plateau_s must be >= 0, got {plateau_s}")
    t = np.asarray(t_s, dtype=float)
    rise = 0.5 * (1.0 - np.cos(np.pi * np.clip(t / rise_s, 0.0, 1.0)))
    t_release = t - rise_s - plateau_s
    release = 0.5 * (1.0 + np.cos(np.pi * np.clip(t_release / release_s, 0.0, 1.0)))
    fraction = np.where(t_release > 0, release, rise)
    return float(fraction) if fraction.ndim == 0 else fraction
