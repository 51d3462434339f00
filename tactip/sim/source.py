"""The synthetic TacTip as a frame source: a scripted sequence of taps with ground truth."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tactip.errors import SourceError
from tactip.sim.contact import Contact, SyntheticFrame, tap_profile
from tactip.sim.gel import SyntheticGel
from tactip.sim.presets import GEL_PRESETS
from tactip.sim.synthetic import SyntheticTacTip
from tactip.sources.base import FrameSourceBase

__all__ = ["SyntheticSource", "DEFAULT_TAPS"]

# Three taps over a 2 mm gap at increasing depth, as in samples/synthetic_tap.mp4.
DEFAULT_TAPS = (Contact(2.0, 2.0), Contact(3.5, 2.0), Contact(5.0, 2.0))


class SyntheticSource(FrameSourceBase):
    """Frames of a `SyntheticTacTip` tapping a scripted sequence of contacts.

    The stream is ``rest_s`` of rest, then for each tap its rise, plateau and release followed by
    ``rest_s`` of rest, sampled at ``frame_rate``. After each `read`, `truth` holds the rendered
    `SyntheticFrame` (true pin centres, visibility, contact).

    Parameters
    ----------
    sensor : SyntheticTacTip or None
        The renderer; None builds one from ``preset`` or ``pins``, and ``seed`` (other renderer options
        via ``sensor``).
    taps : sequence of Contact
        Contact at the deepest point of each tap.
    pins : int
        Pin count when ``sensor`` is None.
    frame_rate : float or None
        Frames per second; None: the sensor's own (20, or e.g. 120 for the "radial-120" preset).
    rise_s, plateau_s, release_s : float
        Phases of every tap, s (paper 002, IV-A: about 250 ms each).
    rest_s : float
        Rest before the first tap and after each tap, s.
    grey : bool
        Accepted for a uniform interface (frames are grey unless the sensor renders colour).
    seed : int
        Seed when ``sensor`` is None.
    preset : str or None
        A `tactip.sim.synthetic.PRESETS` name (e.g. "rim-ring-331") or a flat gel's (`GEL_PRESETS`,
        "gelsight-mini") when ``sensor`` is None; it wins over ``pins``.

    Examples
    --------
    >>> with SyntheticSource(pins=127, taps=[Contact(4.0, 2.0)]) as source:
    ...     frames = list(source)
    >>> len(frames), frames[0].image.shape
    (36, (480, 640))
    """

    def __init__(self, sensor: SyntheticTacTip | None = None, *, taps: Sequence[Contact] = DEFAULT_TAPS,
                 pins: int = 331, frame_rate: float | None = None, rise_s: float = 0.25, plateau_s: float = 0.25,
                 release_s: float = 0.25, rest_s: float = 0.5, grey: bool = False, seed: int = 0,
                 preset: str | None = None):
        super().__init__(grey=grey)
        if sensor is None and preset is not None:
            try:
                maker = SyntheticGel if preset in GEL_PRESETS else SyntheticTacTip  # a flat gel, or a TacTip
                sensor = maker.from_preset(preset, seed=seed)
            except ValueError as exc:
                raise SourceError(str(exc)) from None
        self.sensor = sensor if sensor is not None else SyntheticTacTip(pins=pins, seed=seed)
        frame_rate = self.sensor.frame_rate if frame_rate is None else frame_rate
        if not frame_rate > 0:
            raise SourceError(f"frame_rate must be > 0, got {frame_rate!r}")
        if not rest_s >= 0:
            raise SourceError(f"rest_s must be >= 0, got {rest_s!r}")
        try:
            tap_profile(0.0, rise_s=rise_s, plateau_s=plateau_s, release_s=release_s)
        except ValueError as exc:
            raise SourceError(str(exc)) from None
        self.name = f"synthetic:{self.sensor.preset or self.sensor.n_pins}"
        self.taps = tuple(taps)
        self.frame_rate = float(frame_rate)
        self.frame_size = tuple(self.sensor.image_size)
        self._phases = (rise_s, plateau_s, release_s)
        period = rise_s + plateau_s + release_s + rest_s
        self.tap_starts_s = rest_s + period * np.arange(len(self.taps))
        self.duration_s = rest_s + period * len(self.taps)
        self.frame_count = int(np.floor(self.duration_s * self.frame_rate + 1e-9)) + 1
        self.truth: SyntheticFrame | None = None

    def contact_at(self, t_s: float) -> Contact:
        """The scripted contact at time ``t_s`` of the stream."""
        rise_s, plateau_s, release_s = self._phases
        for start, tap in zip(self.tap_starts_s, self.taps):
            if start <= t_s <= start + rise_s + plateau_s + release_s:
                fraction = tap_profile(t_s - start, rise_s=rise_s, plateau_s=plateau_s, release_s=release_s)
                return Contact(tap.indentation_mm * fraction, tap.gap_width_mm, tap.gap_offset_mm,
                               tap.gap_angle_deg)
        return Contact()

    def _read(self):
        if self._index >= self.frame_count:
            return None
        t = self._index / self.frame_rate
        self.truth = self.sensor.render(self.contact_at(t), timestamp_s=t)
        return self.truth.image, t

    def _seek(self, index: int) -> None:
        """Jump in the script; the ground truth of every frame is unchanged (the noise is not replayed)."""
