"""Named synthetic sensors: `SyntheticTacTip` options that draw TacTips of other generations and makes
(described in `tactip.sim`, "Presets")."""

from __future__ import annotations

from types import MappingProxyType

__all__ = ["GEL_PRESETS", "PRESETS", "preset_names", "build_preset"]

#: Named sensors: constructor options of `SyntheticTacTip` for each (see the module docstring, "Presets").
PRESETS = MappingProxyType({
    "tactip-331": MappingProxyType({"pins": 331}),
    "tactip-127": MappingProxyType({"pins": 127}),
    "tactip-532": MappingProxyType({"pins": 532}),
    "dark-331": MappingProxyType({"pins": 331, "dark_pins": True}),
    "rim-ring-331": MappingProxyType({"pins": 331, "glare": False, "rim_polar_deg": 77.0, "ring_glare": 18}),
    "brown-127": MappingProxyType({"pins": 127, "colour": True, "skin_tint": "brown", "membrane_level": 70.0,
                                   "pin_level": 140.0, "skin_texture": 12.0, "pin_shadows": 22.0}),
    "radial-120": MappingProxyType({"pins": 120, "layout": "radial", "pad_fraction": 1 / 3, "pin_fraction": 0.25,
                                    "surround_level": 245.0, "glare_gain": 1.6, "veil": 40.0, "noise_sigma": 5.0,
                                    "frame_rate": 120.0}),
    "radial-led-120": MappingProxyType({"pins": 120, "layout": "radial", "pad_fraction": 1 / 3, "pin_fraction": 0.25,
                                        "surround_level": 245.0, "glare_gain": 1.6, "veil": 40.0, "noise_sigma": 5.0,
                                        "frame_rate": 120.0, "membrane_level": 100.0, "pin_level": 180.0,
                                        "reflections": 4, "reflection_level": 50.0, "glare_gradient": 25.0,
                                        "shimmer": 1.0}),
    "white-dark-331": MappingProxyType({"pins": 331, "surround_level": 30.0}),
    "small-pad-100": MappingProxyType({"pins": 100, "image_size": (320, 240), "pad_fraction": 0.25,
                                       "pin_fraction": 0.22, "surround_level": 235.0}),
    "dense-1000": MappingProxyType({"pins": 1000, "image_size": (1280, 720), "pad_fraction": 0.9}),
})


def preset_names() -> tuple[str, ...]:
    """Names of the synthetic TacTip presets, in `PRESETS` order.

    Examples
    --------
    >>> preset_names()[:3]
    ('tactip-331', 'tactip-127', 'tactip-532')
    """
    return tuple(PRESETS)


#: Named flat gels: constructor options of `tactip.sim.gel.SyntheticGel` (see `tactip.sim`, "Flat gels").
GEL_PRESETS = MappingProxyType({
    "gelsight-mini": MappingProxyType({"grid": (8, 10), "pitch_mm": 1.8, "image_size": (320, 240),
                                       "frame_rate": 25.0}),
})


def build_preset(cls, table, what: str, name: str, overrides: dict):
    """``cls(**table[name], **overrides)`` with its ``preset`` name set; `ValueError` naming the choices
    (``what``: e.g. "synthetic TacTip") when ``name`` is not in ``table``."""
    if name not in table:
        raise ValueError(f"unknown {what} preset {name!r}; choose from {', '.join(table)}")
    sensor = cls(**{**table[name], **overrides})
    sensor.preset = name
    return sensor
