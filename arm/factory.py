"""Pick the arm backend named by the configuration.

Example
-------
>>> from arm.config import ArmConfig
>>> arm = make_arm(ArmConfig("sim", (-10, -10, -8), (100, 40, 30), max_tap_depth_mm=6.0))
>>> type(arm).__name__
'SimArm'
"""

from __future__ import annotations

from typing import Sequence

from .base import BaseArm
from .config import BACKENDS, ArmConfig
from .errors import ArmConfigError
from .world import Gap

__all__ = ["make_arm"]


def make_arm(config: ArmConfig, *, default_gaps: Sequence[Gap] = (), **options) -> BaseArm:
    """A new, not yet connected arm for ``config.backend``.

    Parameters
    ----------
    config : ArmConfig
    default_gaps : sequence of Gap
        ``sim`` only: the simulated plate's gaps when ``[arm.sim]`` lists none
        (`arm.config.SimSettings.make_world`); ignored when ``world`` is passed.
    **options
        Passed to the backend's constructor (`arm.sim.SimArm` or `arm.ur.UrArm`).

    Raises
    ------
    ArmConfigError
        Unknown backend.
    """
    if config.backend == "sim":
        from .sim import SimArm

        if options.get("world") is None:
            options["world"] = config.sim.make_world(default_gaps)
        return SimArm(config, **options)
    if config.backend == "ur":
        from .ur import UrArm

        return UrArm(config, **options)
    raise ArmConfigError(f"unknown arm backend {config.backend!r}; choose from {', '.join(BACKENDS)}")
