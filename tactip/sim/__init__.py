"""The simulated TacTip: a renderer with exact ground truth, and the frame source built on it.

Nothing here imports the rest of `tactip`, so `pins`' tests and doctests can draw frames from it.

- `tactip.sim.synthetic`: `SyntheticTacTip` renders the pin array under a `Contact`, with the true
  centre of every pin tip (`SyntheticFrame`); its presets name sensors of other generations.
- `tactip.sim.source`: `SyntheticSource`, a frame source of rendered taps (``synthetic:`` specs).
- `tactip.sim._pad`, `tactip.sim._render`: the pad's geometry and contact mechanics, and the painting.
"""

from tactip.sim.synthetic import PRESETS, Contact, SyntheticFrame, SyntheticTacTip, preset_names, tap_profile

__all__ = ["Contact", "PRESETS", "SyntheticFrame", "SyntheticTacTip", "preset_names", "tap_profile"]
