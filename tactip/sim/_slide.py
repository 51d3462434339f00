"""Lateral slide of the skin under a sticking plate (the model is argued in `tactip.sim`, "Slides").

The plate, pressed in by ``d`` mm, is dragged sideways by ``S = (slide_x_mm, slide_y_mm)`` and the
skin sticks to it: the material in the contact patch (radius ``a = sqrt(R d)``) moves by the whole of
``S``; outside it the shift falls smoothly (raised cosine) to zero over ``L = max(SLIDE_DECAY_MM, 2 |S|)``
of pad surface, but never past the pad's clamped base (arc ``pi R / 2``). The shift is laid out in
unrolled pad coordinates (arc length from the apex and azimuth, those of the pin lattice), so it is a
shift along the pad surface. The map ``q -> q + S f(|q|)`` has
Jacobian determinant ``1 + |S| f'(|q|) cos(angle)`` >= ``1 - pi |S| / 2 L`` >= ``1 - pi / 4``: it never
folds, so pins never cross. Where the base cuts the fall-off short, the longest slide is the one that
keeps that determinant >= `MIN_JACOBIAN` (`max_slide_mm`); a longer one is refused. The contact
mechanics then act at the material's new place.

Residual shear (opt-in, ``Contact.shear_x_mm``, ``shear_y_mm``): a real elastomer does not spring back
at once when the plate lifts; what a slide leaves in the skin creeps back to rest over tens of frames
(paper 000 waits 1 s between contacts "to ensure transients decayed"). It is laid out as a slide is,
from the apex when nothing touches, and adds to the plate's drag under contact.

With ``Contact.shear_decay_mm`` > 0 (the schedule's slower relaxation, ``set_share``) the residual shear keeps
the shape the slide that left it had (falling off over that length from the apex), laid out apart from any
plate pressing on it now: a press on a sheared skin does not drag it further.

Stiffer skin (opt-in, ``Contact.slide_decay_mm``): by default the skin ahead of a slide may be squeezed
to ``1 - pi / 4`` (21 %) of its area along the slide, or to `MIN_JACOBIAN` where the base cuts the
fall-off short: neighbouring tips then merge. A skin of 1-2 mm of elastomer over gel wrinkles long
before a surface strain of -80 %; a fixed fall-off per stroke (`decay_for_area_mm`, the schedule's
``min_area``) keeps the squeeze to a given share of the area.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

SLIDE_DECAY_MM = 6.0  # shortest fall-off of the slide outside the contact patch, mm of pad surface (2+ pitches)
DECAY_PER_SLIDE = 2.0  # the fall-off is at least this x the slide: the map's Jacobian stays >= 1 - pi / 4
MIN_JACOBIAN = 0.05  # a slide may compress the skin round the patch to this share of its area, no further


def _decay_mm(indentation_mm: float, slide_mm: float, radius_mm: float, given_mm: float = 0.0) -> float:
    """Fall-off length of the slide outside the patch, mm (`given_mm` when > 0, ``Contact.slide_decay_mm``):
    it ends at the latest at the clamped base."""
    room = np.pi * radius_mm / 2 - np.sqrt(radius_mm * indentation_mm)
    return min(given_mm if given_mm > 0 else max(SLIDE_DECAY_MM, DECAY_PER_SLIDE * slide_mm), room)


def decay_for_area_mm(slide_mm: float, min_area: float) -> float:
    """The fall-off, mm, that keeps a slide of `slide_mm` from squeezing the skin below `min_area` of its area.

    The map's Jacobian is at least ``1 - pi S / (2 L)`` (a pad's base may cut ``L`` shorter).

    >>> round(decay_for_area_mm(9.0, 0.5), 2)
    28.27
    """
    return max(SLIDE_DECAY_MM, np.pi * slide_mm / (2.0 * (1.0 - min_area)))


def max_slide_mm(indentation_mm: float, radius_mm: float) -> float:
    """The longest slide the model renders without folding at this indentation, mm of pad surface.

    Parameters
    ----------
    indentation_mm : float
        Depth of the press, mm (> 0).
    radius_mm : float
        Pad radius R, mm.

    Examples
    --------
    >>> round(max_slide_mm(2.0, 20.0), 1)
    15.2
    """
    room = np.pi * radius_mm / 2 - np.sqrt(radius_mm * indentation_mm)
    # 1 - pi S / (2 L) >= MIN_JACOBIAN with L = min(max(decay, 2 S), room)
    return float(max(2 * room * (1 - MIN_JACOBIAN) / np.pi, 0.0))


def _drag_mm(contact, radius_mm: float) -> tuple[float, float]:
    """How far the skin at the apex is shifted, (x, y) mm: the plate's slide under contact plus the residual shear.

    Where the two together would fold the skin (`max_slide_mm`), the residual shear is cut to what still fits
    (the skin slips under the plate rather than fold); a slide alone past it is refused (`slide_fraction`)."""
    touching = contact.indentation_mm > 0
    px, py = (contact.slide_x_mm, contact.slide_y_mm) if touching else (0.0, 0.0)
    sx, sy = px + contact.shear_x_mm, py + contact.shear_y_mm
    most = max_slide_mm(max(contact.indentation_mm, 0.0), radius_mm)
    if (contact.shear_x_mm or contact.shear_y_mm) and np.hypot(sx, sy) > most and np.hypot(px, py) < most:
        # the largest share k of the shear s with |p + k s| = most:
        # k = (-p.s + sqrt((p.s)^2 - |s|^2 (|p|^2 - most^2))) / |s|^2
        ps, ss = px * contact.shear_x_mm + py * contact.shear_y_mm, contact.shear_x_mm ** 2 + contact.shear_y_mm ** 2
        k = (-ps + np.sqrt(ps * ps - ss * (px * px + py * py - most * most))) / ss * (1.0 - 1e-9)
        sx, sy = px + k * contact.shear_x_mm, py + k * contact.shear_y_mm
    return sx, sy


def slide_fraction(arc_mm, contact, radius_mm: float):
    """Share of the slide each material point takes, by its rest arc length from the apex: 1 in the patch.

    Parameters
    ----------
    arc_mm : ndarray
        Arc length of the points from the apex along the pad surface at rest, mm.
    contact : Contact
    radius_mm : float
        Pad radius R, mm.

    Returns
    -------
    ndarray shaped like ``arc_mm``, in [0, 1] (zeros when nothing shifts the skin: no slide under
    contact, no residual shear ``shear_x_mm``, ``shear_y_mm``).
    """
    d, slide = contact.indentation_mm, np.hypot(*_drag_mm(contact, radius_mm))
    if slide == 0:
        return np.zeros(np.shape(arc_mm))
    d = max(d, 0.0)  # a residual shear alone falls off from the apex
    patch = np.sqrt(radius_mm * d)  # Hertz contact radius a
    if slide > max_slide_mm(d, radius_mm) + 1e-9:
        raise ValueError(f"slide_x_mm, slide_y_mm: a slide of {slide:.3g} mm folds the skin of a {2 * radius_mm:g} mm "
                         f"pad at {d:g} mm indentation; at most {max_slide_mm(d, radius_mm):.3g} mm")
    decay = _decay_mm(d, slide, radius_mm, contact.slide_decay_mm)
    t = np.clip((np.asarray(arc_mm) - patch) / decay, 0.0, 1.0)
    return 0.5 * (1.0 + np.cos(np.pi * t))


def textured_points(qx, qy, share, contact):
    """Unrolled pad positions (qx, qy), mm, moved by a textured plate's ridges under a slide.

    Ridges ``texture_period_mm`` apart across the slide direction ``u`` catch and release the skin the
    plate drags: a point moves along ``u`` by ``texture_mm * share * sin(2 pi (q.u + |S|) / period)``,
    where ``share`` is its part of the slide ``S`` (1 in the contact patch, `slide_fraction`) and
    ``|S|`` how far the plate has gone, so each pin wobbles back and forth as ridges pass under it, and
    neighbours a part of a period apart along ``u`` move differently. Nothing moves without a slide
    under contact (a residual shear alone is not textured).

    Parameters
    ----------
    qx, qy : ndarray
        Unrolled positions after the slide, mm.
    share : ndarray
        Each point's share of the slide, in [0, 1].
    contact : Contact
        With ``texture_mm`` > 0 and ``texture_period_mm``.

    Returns
    -------
    qx, qy : ndarray
    """
    slide = np.hypot(contact.slide_x_mm, contact.slide_y_mm)
    if contact.indentation_mm <= 0 or slide == 0:
        return qx, qy
    ux, uy = contact.slide_x_mm / slide, contact.slide_y_mm / slide
    wobble = contact.texture_mm * share * np.sin(2 * np.pi * (qx * ux + qy * uy + slide) / contact.texture_period_mm)
    return qx + wobble * ux, qy + wobble * uy


def slid_points(x, y, contact, radius_mm: float):
    """Lateral positions (x, y), mm, of membrane points at rest (x, y) after the plate's slide.

    Parameters
    ----------
    x, y : ndarray
        Lateral positions at rest, mm, on the sphere of radius ``radius_mm``.
    contact : Contact
    radius_mm : float

    Returns
    -------
    x, y : ndarray
        The same points shifted along the pad surface (the inputs themselves when nothing slides).
    """
    sx, sy = _drag_mm(contact, radius_mm)
    if sx == 0 and sy == 0:
        return x, y
    r = np.hypot(x, y)
    arc = radius_mm * np.arcsin(np.clip(r / radius_mm, 0.0, 1.0))
    scale = np.divide(arc, r, out=np.ones_like(r), where=r > 0)
    if contact.shear_decay_mm > 0 and (contact.shear_x_mm or contact.shear_y_mm):
        # the shear keeps the shape its slide left (falling off over shear_decay_mm from the apex), whatever
        # presses on it now; the plate's slide, if any, is laid out on its own
        plate = replace(contact, shear_x_mm=0.0, shear_y_mm=0.0, shear_decay_mm=0.0)
        px, py = _drag_mm(plate, radius_mm)
        share = slide_fraction(arc, plate, radius_mm)
        kept = 0.5 * (1.0 + np.cos(np.pi * np.clip(arc / contact.shear_decay_mm, 0.0, 1.0)))
        qx, qy = x * scale + px * share + (sx - px) * kept, y * scale + py * share + (sy - py) * kept
    else:
        share = slide_fraction(arc, contact, radius_mm)
        qx, qy = x * scale + sx * share, y * scale + sy * share
    if contact.texture_mm > 0:
        qx, qy = textured_points(qx, qy, share, contact)
    arc = np.hypot(qx, qy)
    lateral = radius_mm * np.sin(np.clip(arc / radius_mm, 0.0, np.pi / 2))
    back = np.divide(lateral, arc, out=np.ones_like(arc), where=arc > 0)
    return qx * back, qy * back
