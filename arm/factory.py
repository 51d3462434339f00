"""Pick the arm backend named by the configuration.

Example
-------
>>> from arm.config import ArmConfig
>>> arm = make_arm(ArmConfig("sim", (-10, -10, -8), (100, 40, 30), max_tap_depth_mm=6.0))
>>> type(arm).__name__
'SimArm'
"""

from __future__ import annotations

from .base import BaseArm
from .config import BACKENDS, ArmConfig
from .errors import ArmConfigError

__all__ = ["make_arm"]


def make_arm(config: ArmConfig, **options) -> BaseArm:
    """A new, not yet connected arm for ``config.backend``.

    Parameters
    ----------
    config : ArmConfig
    **options
        Passed to the backend's constructor (`arm.sim.SimArm` or `arm.ur.UrArm`).

    Raises
    ------
    ArmConfigError
        Unknown backend.
    """
    if config.backend == "sim":
        from .sim import SimArm

        return SimArm(config, **options)
    if config.backend == "ur":
        from .ur import UrArm

        return UrArm(config, **options)
    raise ArmConfigError(f"unknown arm backend {config.backend!r}; choose from {', '.join(BACKENDS)}")
