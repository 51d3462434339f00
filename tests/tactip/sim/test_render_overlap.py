"""Overlapping pin tips (a skin squeezed ahead of a slide, issue 20 outcome 8): a real skin shows one tip
occluding the other, never the sum of their light. Ground truth: a lone tip's render."""

import numpy as np
import pytest

from tactip.sim import Contact, SyntheticTacTip
from tactip.sim import _render

SIZE = (64, 48)  # (width, height), px


def _paint(centres, levels, under=25.0, radius_px=5.0):
    """Tips of ``radius_px`` at ``centres`` (x, y) px with grey ``levels`` on a flat scene of ``under`` grey."""
    scene = np.full(SIZE[0] * SIZE[1], under, dtype=np.float32)
    centres = np.asarray(centres, dtype=float)
    shape = np.broadcast_to(radius_px ** 2 * np.eye(2), (len(centres), 2, 2))
    _render.paint_pins(scene, SIZE, centres, shape, np.asarray(levels, dtype=float))
    return scene.reshape(SIZE[1], SIZE[0])


@pytest.mark.parametrize("under, level", [(25.0, 215.0), (200.0, 40.0)])  # bright tips on dark, dark on bright
@pytest.mark.parametrize("gap_px", [0.0, 2.5, 6.0])
def test_two_overlapping_tips_render_no_brighter_or_darker_than_one(under, level, gap_px):
    a, b = (20.3, 24.1), (20.3 + gap_px, 24.6)
    both = _paint([a, b], [level, level], under)
    lone_a, lone_b = _paint([a], [level], under), _paint([b], [level], under)
    sign = 1.0 if level > under else -1.0  # (dark tips: the same with grey levels negated)
    both, lone_a, lone_b, level = sign * both, sign * lone_a, sign * lone_b, sign * level
    # Where both tips cover the whole pixel, it shows the nearer tip: the brighter of the two lone renders
    # (dark tips: the darker). The sum gave 2 * 215 - 25 = 405 grey there.
    yy, xx = np.mgrid[:SIZE[1], :SIZE[0]]
    inside = (np.hypot(xx - a[0], yy - a[1]) < 4.0) & (np.hypot(xx - b[0], yy - b[1]) < 4.0)  # radius 5, 1 px edge
    assert inside.sum() >= 5
    assert np.allclose(both[inside], np.maximum(lone_a, lone_b)[inside], atol=1e-3)
    # Along the edges (a tip partly covering a pixel the other covers too) the tips' shares of the pixel
    # overlap by an unknown part: at least the brighter tip, at most the sum, never beyond a tip's own paint
    # (its apex level, domed to 0.85 of it at the edge: for dark tips the edge is the extreme).
    assert (both >= np.maximum(lone_a, lone_b) - 1e-3).all()
    assert (both <= lone_a + lone_b - sign * under + 1e-3).all()
    assert both.max() <= max(level, 0.85 * level) + 1e-3


def test_tips_apart_or_touching_only_along_their_edges_add_as_before():
    # Two tips whose anti-aliased edges share pixels (coverages summing to at most 1) blend there: the
    # pixel between them is covered by both halves, as bright as a tip, not darker (a max would dim it).
    centres = [(20.0, 24.0), (30.0, 24.0)]  # 10 px apart, radius 5: edges touch at x = 25
    both = _paint(centres, [215.0, 215.0])
    assert both[24, 25] > 0.8 * 215.0
    # Pins apart: exactly the sum of the lone renders' changes.
    far = _paint([(15.0, 24.0), (45.0, 24.0)], [215.0, 215.0])
    lone = _paint([(15.0, 24.0)], [215.0]) + _paint([(45.0, 24.0)], [215.0]) - 25.0
    assert np.array_equal(far, lone)


@pytest.mark.parametrize("name", ["tactip-331", "dark-331"])
def test_a_slide_squeezing_tips_together_shows_no_seam(name):
    # Ahead of a 3-pitch slide the model skin squeezes tips into each other; no pixel of the pad may be
    # brighter than the brightest tip (darker than the darkest, for dark tips) can be drawn. (Dark tips
    # of 240 - 150 grey: at the default 215 the darkest are clipped to 0 already at rest.)
    s = SyntheticTacTip.from_preset(name, seed=0, noise_sigma=0.0, glare=False, gradient=False, pin_level=150.0)
    rest = s.render().image.astype(float)
    slid = s.render(Contact(indentation_mm=1.0, slide_x_mm=3 * s.pin_spacing_mm)).image.astype(float)
    cx, cy, r = s.disc
    yy, xx = np.mgrid[:rest.shape[0], :rest.shape[1]]
    pad = np.hypot(xx - cx, yy - cy) < 0.9 * r
    if s.dark_pins:
        assert slid[pad].min() >= rest[pad].min() - 1
    else:
        assert slid[pad].max() <= rest[pad].max() + 1
