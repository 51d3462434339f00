"""Validation of `SyntheticTacTip`'s constructor options, once at the public boundary.

Each check raises a ValueError naming the parameter. Kept apart from the renderer so that
`tactip.sim.synthetic` reads as the model and its drawing.
"""

from __future__ import annotations

import math

from tactip.sim import _pad

LAYOUTS = ("auto", "radial")
SKIN_TINTS = (None, "brown")
MAX_REFLECTIONS = 16
PIN_SPACING_FRACTION = 0.3  # default pin radius / pin spacing at the apex


#: Most pins of a synthetic TacTip: well beyond real ones (100-1000), short of what renders for minutes a frame.
MAX_SYNTHETIC_PINS = 5000

def _finite_nonnegative(**values) -> None:
    for name, value in values.items():
        if not (math.isfinite(value) and value >= 0):
            raise ValueError(f"{name} must be finite and >= 0, got {value!r}")


def check_options(*, pins, pad_diameter_mm, image_size, noise_sigma, blur_sigma, jpeg_quality, layout,
                  pad_fraction, pin_fraction, rim_polar_deg, ring_glare, membrane_level, pin_level,
                  surround_level, glare_gain, veil, skin_texture, pin_shadows, skin_tint, frame_rate,
                  reflections, reflection_level, glare_gradient, shimmer) -> None:
    """Raise a ValueError naming the first option of `SyntheticTacTip` out of its range.

    The parameters are the constructor's (see `SyntheticTacTip`); ``image_size`` as given.
    """
    if int(pins) != pins or not 7 <= pins <= MAX_SYNTHETIC_PINS:
        raise ValueError(f"pins must be an integer in 7..{MAX_SYNTHETIC_PINS}, got {pins!r}")
    if layout not in LAYOUTS:
        raise ValueError(f"layout must be one of {LAYOUTS}, got {layout!r}")
    if not 0.25 <= pad_fraction <= 0.9:
        raise ValueError(f"pad_fraction must be in 0.25..0.9, got {pad_fraction!r}")
    if not 0.1 <= pin_fraction <= 0.4:
        raise ValueError(f"pin_fraction must be in 0.1..0.4, got {pin_fraction!r}")
    if rim_polar_deg is not None and not 60.0 <= rim_polar_deg < _pad.CASING_POLAR_DEG:
        raise ValueError(f"rim_polar_deg must be None or in 60..{_pad.CASING_POLAR_DEG}, got {rim_polar_deg!r}")
    if int(ring_glare) != ring_glare or not 0 <= ring_glare <= 64:
        raise ValueError(f"ring_glare must be an integer in 0..64, got {ring_glare!r}")
    if ring_glare and rim_polar_deg is None:
        raise ValueError("ring_glare needs a rim ring: give rim_polar_deg")
    for name, value in (("membrane_level", membrane_level), ("pin_level", pin_level),
                        ("surround_level", surround_level)):
        if value is not None and not 0 <= value <= 255:
            raise ValueError(f"{name} must be None or in 0..255, got {value!r}")
    _finite_nonnegative(glare_gain=glare_gain, veil=veil, skin_texture=skin_texture, pin_shadows=pin_shadows)
    if skin_tint not in SKIN_TINTS:
        raise ValueError(f"skin_tint must be one of {SKIN_TINTS}, got {skin_tint!r}")
    if not (math.isfinite(frame_rate) and frame_rate > 0):
        raise ValueError(f"frame_rate must be > 0, got {frame_rate!r}")
    if layout == "radial":
        _pad.radial_rings(int(pins))  # raises ValueError naming pins
    if not pad_diameter_mm > 4 * _pad.STALK_MM:
        raise ValueError(f"pad_diameter_mm must be > {4 * _pad.STALK_MM}, got {pad_diameter_mm!r}")
    width, height = (int(v) for v in image_size)
    if width < 64 or height < 64:
        raise ValueError(f"image_size must be at least (64, 64), got {image_size!r}")
    if not noise_sigma >= 0:
        raise ValueError(f"noise_sigma must be >= 0, got {noise_sigma!r}")
    if not blur_sigma >= 0:
        raise ValueError(f"blur_sigma must be >= 0, got {blur_sigma!r}")
    if jpeg_quality is not None and not 1 <= jpeg_quality <= 100:
        raise ValueError(f"jpeg_quality must be in 1..100 or None, got {jpeg_quality!r}")
    if isinstance(reflections, bool) or int(reflections) != reflections or not 0 <= reflections <= MAX_REFLECTIONS:
        raise ValueError(f"reflections must be an integer in 0..{MAX_REFLECTIONS}, got {reflections!r}")
    if not (math.isfinite(reflection_level) and 0 <= reflection_level <= 255):
        raise ValueError(f"reflection_level must be in 0..255, got {reflection_level!r}")
    if not (math.isfinite(glare_gradient) and 0 <= glare_gradient <= 255):
        raise ValueError(f"glare_gradient must be in 0..255, got {glare_gradient!r}")
    _finite_nonnegative(shimmer=shimmer)


# Options whose defaults the repr leaves out (it names them only when changed), so a repr stays short.
REPR_DEFAULTS = {"layout": "auto", "pad_fraction": 0.87, "pin_fraction": PIN_SPACING_FRACTION, "rim_polar_deg": None,
                 "ring_glare": 0, "membrane_level": None, "pin_level": None, "surround_level": None,
                 "glare_gain": 1.0, "veil": 0.0, "skin_texture": 0.0, "pin_shadows": 0.0, "skin_tint": None,
                 "frame_rate": 20.0, "reflections": 0, "reflection_level": 50.0, "glare_gradient": 0.0,
                 "shimmer": 0.0}
