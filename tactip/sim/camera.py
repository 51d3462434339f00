"""The synthetic TacTip as the simulated station's camera (`tactip.station.camera.Camera`).

It renders each tap from the simulated arm's true contact (indentation, gap width, lateral offset) on
the tap's own timeline: the stroke down from the approach height at the tap speed, the dwell, the
stroke back up, at the camera's frame rate.
"""

from __future__ import annotations

import math

import numpy as np

from tactip.errors import TactipError
from tactip.sim.contact import Contact
from tactip.sim.gel import SyntheticGel
from tactip.sim.presets import GEL_PRESETS, PRESETS
from tactip.sim.synthetic import SyntheticTacTip

__all__ = ["SimulatedCamera"]


class SimulatedCamera:
    """The synthetic TacTip filming the simulated arm's taps (see the module docstring).

    Parameters
    ----------
    pins : int
        Pin preset (127, 331 or 532).
    frame_rate : float
        Camera frames/s.
    tap_speed_mm_s, dwell_s, approach_height_mm : float
        The arm's tap motion (``[arm.tap]``): they set the tap's timeline.
    noise_sigma : float
        Camera noise, grey levels.
    seed : int
        Seed of the sensor (pin layout and noise).
    preset : str
        A flat gel's preset (`tactip.sim.GEL_PRESETS`, e.g. "gelsight-mini") to film instead of a
        TacTip of ``pins`` pins, or a TacTip's (`tactip.sim.PRESETS`, e.g. "radial-led-120": its own
        pins, layout and look, ``noise_sigma`` as given); "" or any other name: the TacTip of ``pins``
        pins. A gap in the plate is not modelled on a flat gel: its frames show the press only.
    """

    def __init__(self, *, pins: int = 331, frame_rate: float = 20.0, tap_speed_mm_s: float = 20.0,
                 dwell_s: float = 0.25, approach_height_mm: float = 5.0, noise_sigma: float = 4.0, seed: int = 0,
                 preset: str = ""):
        if preset in GEL_PRESETS:
            self.sensor = SyntheticGel.from_preset(preset, seed=seed)
        elif preset in PRESETS:  # the named TacTip (its layout, pad and look), with the station's noise
            self.sensor = SyntheticTacTip.from_preset(preset, noise_sigma=noise_sigma, seed=seed)
        else:
            self.sensor = SyntheticTacTip(pins=pins, noise_sigma=noise_sigma, seed=seed)
        self.frame_rate = float(frame_rate)
        self.tap_speed_mm_s = float(tap_speed_mm_s)
        self.dwell_s = float(dwell_s)
        self.approach_height_mm = float(approach_height_mm)
        self._event = None

    def rest_frames(self, n: int) -> list[np.ndarray]:
        """``n`` frames off contact."""
        return [self.sensor.render(timestamp_s=k / self.frame_rate).image for k in range(n)]

    def begin_tap(self, event, *, seed: int | None = None) -> None:
        """The arm starts its stroke down; ``event.contact`` is the simulated world's contact."""
        if seed is not None:
            self.sensor.reseed_noise(seed)
        self._event = event

    def end_tap(self, event) -> tuple[list[np.ndarray], list[float]]:
        """The arm is back up: render the tap's frames on its timeline. Returns (frames, times in s)."""
        contact = (self._event or event).contact
        if contact is None:
            raise TactipError("the simulated camera needs the simulated arm (no world contact in the tap event)")
        speed = self.tap_speed_mm_s
        indentation = max(float(contact.indentation_mm), 0.0)
        offset = 0.0 if not math.isfinite(contact.gap_offset_mm) else float(contact.gap_offset_mm)
        # From the approach height down to the surface (z = 0), the pressed stroke, dwell, back up.
        free_s = max(self.approach_height_mm / speed, 1.0 / self.frame_rate)
        press_s = max(indentation / speed, 1.0 / self.frame_rate)
        frames, times = [], []
        for f in self.sensor.tap(Contact(indentation_mm=indentation, gap_width_mm=float(contact.gap_width_mm),
                                         gap_offset_mm=offset),
                                 frame_rate=self.frame_rate, rise_s=press_s, plateau_s=self.dwell_s,
                                 release_s=press_s, rest_before_s=free_s, rest_after_s=free_s):
            frames.append(f.image)
            times.append(f.timestamp_s)
        self._event = None
        return frames, times

    def close(self) -> None:
        """Nothing to release."""
