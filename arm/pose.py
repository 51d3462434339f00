"""Rigid poses in mm and degrees, and their conversion to Universal Robots poses (m, rotation vector in rad).

A `Pose` is a position ``(x, y, z)`` in mm and an orientation given as extrinsic ``xyz`` Euler angles
``(roll, pitch, yaw)`` in degrees (rotate about the fixed x axis by roll, then fixed y by pitch, then fixed z
by yaw), the convention of `scipy.spatial.transform.Rotation.from_euler("xyz", ..., degrees=True)`.
Poses compose like homogeneous transforms: ``a @ b`` is "b expressed in a's frame, seen from a's parent".

Example
-------
>>> work_frame = Pose(400.0, -100.0, 150.0, 180.0, 0.0, 0.0)   # work frame in the robot base frame
>>> target = Pose(10.0, 0.0, 5.0)                               # a point of the work frame
>>> base = work_frame @ target                                  # the same point in the base frame
>>> round(base.z, 6)
145.0
"""

from __future__ import annotations

import functools
import math
import struct
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

__all__ = ["Pose", "pose_to_ur", "pose_from_ur"]

_EULER = "xyz"


@dataclass(frozen=True)
class Pose:
    """A rigid pose: position in mm, orientation as extrinsic xyz Euler angles in degrees.

    Parameters
    ----------
    x, y, z : float
        Position in mm.
    roll, pitch, yaw : float
        Rotation about the fixed x, then y, then z axis, in degrees.
    """

    x: float
    y: float
    z: float
    roll: float = 0.0
    pitch: float = 0.0
    yaw: float = 0.0

    def __post_init__(self):
        for name in ("x", "y", "z", "roll", "pitch", "yaw"):
            value = float(getattr(self, name))
            if not math.isfinite(value):
                raise ValueError(f"pose {name} must be finite, got {value}")
            object.__setattr__(self, name, value)

    @classmethod
    def from_array(cls, values) -> Pose:
        """A pose from 3 numbers ``(x, y, z)`` in mm or 6 numbers ``(x, y, z, roll, pitch, yaw)`` (mm, deg)."""
        array = np.asarray(values, dtype=float).ravel()
        if array.shape not in ((3,), (6,)):
            raise ValueError(f"a pose needs 3 or 6 numbers, got {array.size}")
        return cls(*array.tolist())

    @classmethod
    def from_matrix(cls, matrix) -> Pose:
        """A pose from a (4, 4) homogeneous transform whose translation is in mm."""
        matrix = np.asarray(matrix, dtype=float)
        if matrix.shape != (4, 4):
            raise ValueError(f"a homogeneous transform is (4, 4), got {matrix.shape}")
        angles = Rotation.from_matrix(matrix[:3, :3]).as_euler(_EULER, degrees=True)
        return cls(*matrix[:3, 3].tolist(), *angles.tolist())

    @property
    def position(self) -> np.ndarray:
        """(3,) ndarray: the position in mm."""
        return np.array([self.x, self.y, self.z])

    @property
    def rotation(self) -> Rotation:
        """The orientation as a `scipy.spatial.transform.Rotation`."""
        return Rotation.from_euler(_EULER, [self.roll, self.pitch, self.yaw], degrees=True)

    def as_matrix(self) -> np.ndarray:
        """(4, 4) ndarray: the homogeneous transform, translation in mm."""
        matrix = np.eye(4)
        matrix[:3, :3] = self.rotation.as_matrix()
        matrix[:3, 3] = self.position
        return matrix

    def __matmul__(self, other: Pose) -> Pose:
        """Compose: ``self @ other`` maps other's frame through self (``T_self · T_other``)."""
        if not isinstance(other, Pose):
            return NotImplemented
        key = struct.pack("12d", self.x, self.y, self.z, self.roll, self.pitch, self.yaw,
                          other.x, other.y, other.z, other.roll, other.pitch, other.yaw)
        return _compose(key, self, other)

    def inverse(self) -> Pose:
        """The inverse transform."""
        inverse_rotation = self.rotation.inv()
        position = -inverse_rotation.apply(self.position)
        return Pose(*position.tolist(), *inverse_rotation.as_euler(_EULER, degrees=True).tolist())

    def moved_to(self, x: float, y: float, z: float) -> Pose:
        """The same orientation at another position (mm)."""
        return Pose(x, y, z, self.roll, self.pitch, self.yaw)

    def translated(self, dx: float = 0.0, dy: float = 0.0, dz: float = 0.0) -> Pose:
        """The same orientation, the position shifted by ``(dx, dy, dz)`` mm along the parent frame's axes."""
        return Pose(self.x + dx, self.y + dy, self.z + dz, self.roll, self.pitch, self.yaw)

    def distance_to(self, other: Pose) -> float:
        """Euclidean distance between the two positions, in mm."""
        return float(np.linalg.norm(self.position - other.position))

    def is_close(self, other: Pose, *, position_mm: float = 1e-6, angle_deg: float = 1e-6) -> bool:
        """Whether two poses agree within a position (mm) and an orientation (deg) tolerance."""
        angle = np.degrees((self.rotation.inv() * other.rotation).magnitude())
        return self.distance_to(other) <= position_mm and angle <= angle_deg


@functools.lru_cache(maxsize=512)
def _compose(key: bytes, first: Pose, second: Pose) -> Pose:
    """``first @ second`` (poses are immutable: a station's moves compose the same few poses again and
    again, so the products are kept, keyed on their twelve numbers' bytes: -0.0 is not 0.0)."""
    return Pose.from_matrix(first.as_matrix() @ second.as_matrix())


def pose_to_ur(pose: Pose) -> list[float]:
    """A pose as Universal Robots expects it: ``[x, y, z, rx, ry, rz]`` in m and a rotation vector in rad."""
    return [*(pose.position / 1000.0).tolist(), *pose.rotation.as_rotvec().tolist()]


def pose_from_ur(values) -> Pose:
    """A pose from a Universal Robots ``[x, y, z, rx, ry, rz]`` (m, rotation vector in rad)."""
    array = np.asarray(values, dtype=float).ravel()
    if array.shape != (6,):
        raise ValueError(f"a UR pose has 6 numbers, got {array.size}")
    angles = Rotation.from_rotvec(array[3:]).as_euler(_EULER, degrees=True)
    return Pose(*(array[:3] * 1000.0).tolist(), *angles.tolist())
