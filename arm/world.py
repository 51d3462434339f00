"""The simulated world the simulated arm taps on: a flat plate with straight gaps of known widths.

Conventions (work frame, mm): z is up and the plate surface is the plane ``z = surface_z_mm``. The TCP is
the apex of the fingertip pad, so the pad's *indentation* is ``surface_z_mm - tcp.z`` (positive = pressed
into the plate, ``<= 0`` = no contact). A gap is a straight slot of ``width_mm`` centred on ``(x_mm, y_mm)``
whose long axis points at ``angle_deg`` counter-clockwise from the work frame's +y axis; at ``angle_deg=0``
the gap runs along y and the lateral offset is measured along +x. The offset is signed: positive when the
pad axis lies on the +x side of the gap's centre line (rotated with the gap).

Placement noise models where the arm really puts the pad: each call of `PlateWorld.contact` (one per tap)
draws a lateral error ``N(0, placement_noise_mm)`` on x and y from the world's seeded generator.

Example
-------
>>> world = PlateWorld(gaps=[Gap("g1", 30.0, 0.0, 1.25)])
>>> c = world.contact(Pose(30.4, 0.0, -2.0))
>>> c.gap_name, c.gap_width_mm, round(c.gap_offset_mm, 3), c.indentation_mm
('g1', 1.25, 0.4, 2.0)
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from .pose import Pose

__all__ = ["Gap", "PlateWorld", "WorldContact"]


@dataclass(frozen=True)
class Gap:
    """A straight gap in the plate.

    Parameters
    ----------
    name : str
        Label of the gap (e.g. ``"g07"``).
    x_mm, y_mm : float
        Centre of the gap in the work frame, mm.
    width_mm : float
        Gap width, mm (> 0).
    angle_deg : float
        Direction of the gap's long axis, counter-clockwise from the work frame's +y axis, degrees.
    length_mm : float
        Length of the gap along its axis, mm; the nearest gap is chosen by distance to this segment.
    """

    name: str
    x_mm: float
    y_mm: float
    width_mm: float
    angle_deg: float = 0.0
    length_mm: float = 25.0

    def __post_init__(self):
        for key in ("x_mm", "y_mm", "width_mm", "angle_deg", "length_mm"):
            value = float(getattr(self, key))
            if not math.isfinite(value):
                raise ValueError(f"gap {self.name!r}: {key} must be finite, got {value}")
            object.__setattr__(self, key, value)
        if self.width_mm <= 0:
            raise ValueError(f"gap {self.name!r}: width_mm must be > 0, got {self.width_mm}")
        if self.length_mm <= 0:
            raise ValueError(f"gap {self.name!r}: length_mm must be > 0, got {self.length_mm}")


@dataclass(frozen=True)
class WorldContact:
    """What the pad meets at one pose.

    Attributes
    ----------
    indentation_mm : float
        How far the pad apex is below the plate surface, mm; ``<= 0`` means no contact.
    gap_width_mm : float
        Width of the nearest gap, mm (0.0 on a plate without gaps).
    gap_offset_mm : float
        Signed lateral offset of the pad axis from the nearest gap's centre line, mm (NaN without gaps).
    gap_name : str or None
        Name of the nearest gap (None without gaps).
    placement_error_mm : (2,) tuple of float
        The lateral placement error (x, y) drawn for this contact, mm.
    """

    indentation_mm: float
    gap_width_mm: float
    gap_offset_mm: float
    gap_name: str | None
    placement_error_mm: tuple[float, float] = (0.0, 0.0)

    @property
    def in_contact(self) -> bool:
        """Whether the pad touches the plate."""
        return self.indentation_mm > 0


@dataclass
class PlateWorld:
    """A flat plate with gaps, in the work frame.

    Parameters
    ----------
    gaps : sequence of Gap
        The gaps cut into the plate (names must be unique).
    surface_z_mm : float
        Height of the plate surface in the work frame, mm.
    placement_noise_mm : float
        Standard deviation of the lateral placement error drawn per contact, mm (>= 0).
    seed : int or None
        Seed of the generator that draws placement errors.
    """

    gaps: Sequence[Gap] = ()
    surface_z_mm: float = 0.0
    placement_noise_mm: float = 0.0
    seed: int | None = None
    _rng: np.random.Generator = field(init=False, repr=False)

    def __post_init__(self):
        self.gaps = tuple(self.gaps)
        names = [gap.name for gap in self.gaps]
        if len(set(names)) != len(names):
            raise ValueError(f"gap names must be unique, got {names}")
        if not (math.isfinite(self.placement_noise_mm) and self.placement_noise_mm >= 0):
            raise ValueError(f"placement_noise_mm must be >= 0, got {self.placement_noise_mm}")
        if not math.isfinite(self.surface_z_mm):
            raise ValueError(f"surface_z_mm must be finite, got {self.surface_z_mm}")
        self._rng = np.random.default_rng(self.seed)
        angles = np.radians([gap.angle_deg for gap in self.gaps])
        # Unit vectors along each gap's axis (from +y, counter-clockwise) and across it (+x at angle 0).
        self._axis = np.stack([-np.sin(angles), np.cos(angles)], axis=1).reshape(-1, 2)
        self._normal = np.stack([np.cos(angles), np.sin(angles)], axis=1).reshape(-1, 2)
        self._centres = np.array([[gap.x_mm, gap.y_mm] for gap in self.gaps]).reshape(-1, 2)
        self._half_lengths = np.array([gap.length_mm / 2 for gap in self.gaps])

    def reseed(self, seed: int | None) -> None:
        """Restart the placement-error generator from ``seed`` (per-tap reproducible placement)."""
        self._rng = np.random.default_rng(seed)

    def gap(self, name: str) -> Gap:
        """The gap called ``name`` (KeyError naming the known gaps otherwise)."""
        for gap in self.gaps:
            if gap.name == name:
                return gap
        raise KeyError(f"no gap {name!r}; the plate has {[g.name for g in self.gaps]}")

    def contact(self, tcp_pose: Pose) -> WorldContact:
        """The contact of the pad at ``tcp_pose`` (work frame), with a fresh placement error.

        Parameters
        ----------
        tcp_pose : Pose
            Commanded pose of the pad apex in the work frame (mm, deg).

        Returns
        -------
        WorldContact
            Indentation and the nearest gap's width and lateral offset at the pad's true position.
        """
        error = self._rng.normal(0.0, self.placement_noise_mm, size=2) if self.placement_noise_mm > 0 else np.zeros(2)
        indentation = self.surface_z_mm - tcp_pose.z
        if not self.gaps:
            return WorldContact(indentation, 0.0, math.nan, None, tuple(error.tolist()))
        relative = np.array([tcp_pose.x, tcp_pose.y]) + error - self._centres      # (G, 2)
        along = np.einsum("gi,gi->g", relative, self._axis)
        across = np.einsum("gi,gi->g", relative, self._normal)
        beyond_end = np.maximum(np.abs(along) - self._half_lengths, 0.0)
        nearest = int(np.argmin(np.hypot(across, beyond_end)))
        gap = self.gaps[nearest]
        return WorldContact(indentation, gap.width_mm, float(across[nearest]), gap.name, tuple(error.tolist()))
