"""The tap primitive: approach height, stroke down to the tap depth, dwell, stroke back up.

As in the gap-inspection protocol (Lepora & Ward-Cherrier, III-A.2): the fingertip starts above the part,
moves straight down onto it, comes back up, and the next tap follows at a new depth or position. A tap
at ``(x, y)`` with depth ``d`` (positive = below the surface reference ``z = 0`` of the work frame) is
planned as straight segments, every one of which is checked against the safety limits before the first
one moves:

1. ``"approach"`` - vertically to the approach height (slowly if starting below it, in case the pad is
   still in contact), only if not already there;
2. ``"travel"``   - horizontally at the approach height to above ``(x, y)``, only if not already there;
3. ``"press"``    - down to ``z = -d`` at the tap speed (the ``"contact"`` callback fires just before);
4. dwell ``dwell_s`` at the bottom;
5. ``"release"``  - back up to the approach height (the ``"release"`` callback fires just after).

Example
-------
>>> from arm.pose import Pose
>>> [s.name for s in plan_tap(Pose(0, 0, 20, 180, 0, 0), 10.0, 0.0, depth_mm=2.0, motion=TapMotion())]
['approach', 'travel', 'press', 'release']
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .pose import Pose

__all__ = ["TapMotion", "Segment", "plan_tap"]

# Positions closer than this are "already there" (well under the 0.01 mm repeatability of an arm).
_SAME_PLACE_MM = 1e-3


@dataclass(frozen=True)
class TapMotion:
    """How a tap moves. Defaults suit a soft silicone fingertip.

    Parameters
    ----------
    approach_height_mm : float
        Height of the pad apex above the surface reference before and after the stroke, mm (> 0).
    speed_mm_s : float
        Speed of the strokes down and up, mm/s (> 0).
    acceleration_mm_s2 : float
        Acceleration of every segment of the tap, mm/s^2 (> 0).
    dwell_s : float
        Time spent at the bottom of the stroke, s (>= 0).
    travel_speed_mm_s : float
        Speed of the horizontal move at the approach height, mm/s (> 0).
    """

    approach_height_mm: float = 5.0
    speed_mm_s: float = 10.0
    acceleration_mm_s2: float = 100.0
    dwell_s: float = 0.5
    travel_speed_mm_s: float = 30.0

    def __post_init__(self):
        for name in ("approach_height_mm", "speed_mm_s", "acceleration_mm_s2", "travel_speed_mm_s"):
            value = float(getattr(self, name))
            if not (math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a finite number > 0, got {value}")
            object.__setattr__(self, name, value)
        dwell = float(self.dwell_s)
        if not (math.isfinite(dwell) and dwell >= 0):
            raise ValueError(f"dwell_s must be a finite number >= 0, got {dwell}")
        object.__setattr__(self, "dwell_s", dwell)


@dataclass(frozen=True)
class Segment:
    """One straight move of a plan: the target pose (work frame), speed (mm/s) and acceleration (mm/s^2)."""

    name: str
    target: Pose
    speed_mm_s: float
    acceleration_mm_s2: float


def plan_tap(start: Pose, x: float, y: float, *, depth_mm: float, motion: TapMotion) -> list[Segment]:
    """The straight segments of one tap, keeping the orientation of ``start``.

    Parameters
    ----------
    start : Pose
        Current TCP pose in the work frame.
    x, y : float
        Tap point in the work frame, mm.
    depth_mm : float
        Depth of the bottom of the stroke below the surface reference, mm (positive = into the part).
    motion : TapMotion
        Heights, speeds, acceleration and dwell.

    Returns
    -------
    list of Segment
        ``approach`` and ``travel`` only when needed, then always ``press`` and ``release``.
    """
    for name, value in (("x", x), ("y", y), ("depth_mm", depth_mm)):
        if not math.isfinite(float(value)):
            raise ValueError(f"{name} must be finite, got {value}")
    approach_z = motion.approach_height_mm
    accel = motion.acceleration_mm_s2
    segments = []
    here = start
    if abs(here.z - approach_z) > _SAME_PLACE_MM:
        # Coming up from below the approach height the pad may still touch the part: go up slowly.
        speed = motion.speed_mm_s if here.z < approach_z else motion.travel_speed_mm_s
        here = here.moved_to(here.x, here.y, approach_z)
        segments.append(Segment("approach", here, speed, accel))
    above = here.moved_to(x, y, approach_z)
    if here.distance_to(above) > _SAME_PLACE_MM:
        segments.append(Segment("travel", above, motion.travel_speed_mm_s, accel))
    segments.append(Segment("press", above.moved_to(x, y, -depth_mm), motion.speed_mm_s, accel))
    segments.append(Segment("release", above, motion.speed_mm_s, accel))
    return segments
