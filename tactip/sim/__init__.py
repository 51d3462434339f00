"""The simulated TacTip: a renderer with exact ground truth, and the frame source built on it.

Nothing here imports the rest of `tactip`, so `pins`' tests and doctests can draw frames from it.

- `tactip.sim.synthetic`: `SyntheticTacTip` renders the pin array under a `Contact`, with the true
  centre of every pin tip (`SyntheticFrame`); its presets name sensors of other generations.
- `tactip.sim.sequence`: `SyntheticTacTip.sequence`, ``slides`` and ``taps``: presses and slides with
  short rests between them, and their ground truth (`ContactEvent`: frame bounds, kind, direction, depth).
- `tactip.sim.source`: `SyntheticSource`, a frame source of rendered taps (``synthetic:`` specs).
- `tactip.sim.gel`, `tactip.sim._gel`: `SyntheticGel`, a flat gel with a grid of dark markers filling the
  frame (GelSight-Mini-like; "Flat gels" below), with the same ground truth and sequences.
- `tactip.sim._pad`, `tactip.sim._slide`, `tactip.sim._render`, `tactip.sim._scene`: the pad's geometry
  and contact mechanics, the skin's slide under a sticking plate, the painting, and the light inside the pad.

Model and its assumptions
-------------------------
Geometry (mm; helpers in `tactip.sim._pad`). The pad is a hemisphere of radius ``R`` (default 20 mm)
centred on the origin, apex at ``z = R``. The camera is a pinhole on the axis at ``z = -h``,
``h = 2 R``, looking up; image x runs along pad X, image y along pad Y, principal point at the image
centre. The focal length makes the dark membrane disc, whose edge is where the casing hides the
membrane (polar angle 86 degrees), 0.435 x the image height in radius (209 px at 640x480), so a bright
surround shows on every side.

Pins. Their bases sit on the membrane on a lattice laid out in pad-surface coordinates (arc length
``s = R theta`` from the apex, azimuth ``phi``), out to ``theta = 80`` degrees. A hexagonal number of
pins (127, 331 = 1 + 3K(K+1)) fills K hexagonal rings of 6k pins; any other count (532) uses K
concentric circles, K the smallest ring count whose hexagonal number reaches N, circle k getting a
share of the N - 1 outer pins proportional to k (largest remainder), odd circles rotated half a step.
Bases jitter by 2 % of the spacing (seeded). Each pin is a stalk of length ``L = 1.5 mm`` along the
membrane's inward normal, ending in a flat white disc facing along the stalk. The disc is sized to
0.3 x the pin spacing in the image at the apex (6, 5.7 and 4.4 px for 127, 331 and 532 pins), which
keeps neighbours at least 2.6 radii apart at rest. Its image is the exact affine image of a circle: an
ellipse centred on the projected tip, foreshortened (radially narrower) towards the rim. The drawn
blob is point-symmetric about that centre, so its intensity-weighted centroid is the ground truth
(within 0.03 px after 8-bit rounding).

Contact (`tactip.sim._pad.membrane_displacement`). A rigid flat plate, normal to the pad axis, presses
the apex in by ``d`` mm. The pad is an elastic, incompressible half-space in Hertz contact: contact
radius ``a = sqrt(R d)``; displacement towards the camera ``u_z = d - r^2 / 2R`` inside the patch
(which is then flat to parabolic order) and ``(d / pi) [(2 - r^2/a^2) asin(a/r) + sqrt(r^2/a^2 - 1)]``
outside, continuous in value and slope. (Geometric overlap alone would give ``a = sqrt(2 R d)``; in
Hertz contact the surrounding gel sinks too, taking half the approach, and gives the smooth decay
outside the patch.) The incompressible gel flows outward under the plate and drags the skin with it:
``u_r = 0.5 u_z r / R``. The pad is clamped to the casing at its base, so both displacements are
multiplied by ``1 - (r / R)^6``: zero at the rim, within 2 % of the half-space field where the plate
touches (r < R / 2 up to d = 5 mm). A straight gap (width ``w``, centre line ``gap_offset`` from the axis along
image y, direction ``gap_angle``) leaves the skin over it unsupported: like a tensioned membrane over
a slot under pressure it bulges into the gap by ``w^2 / (8 rho)`` (``rho = 1 mm``, the ratio of skin
tension to contact pressure: a thin skin on a very soft gel carries little tension, so a slot a few mm
wide is almost unsupported in the middle of the contact), spread across the line with a Gaussian of width ``w/4 + 0.5 mm`` (the
skin's bending length smooths the slot's edges), weighted by the pressure ``(1 - r^2/a^2)^1.5`` in the
patch, and softly capped by the local indentation (the skin cannot rise above its rest shape).
Each tip moves with its base plus the lever: ``L`` times the change of the membrane normal, the slope
being averaged over +-1.5 mm (the stalk's base and the skin's thickness). Flattening tilts stalks
outward and brings the patch nearer the camera, so pins spread from the contact: the peak tip motion
is about 10.5 px at d = 4 mm and 14 px at d = 5 mm. The gap's imprint is subtle and grows with ``w``:
at d = 4 mm the fields for w = 1 and w = 2 mm differ by at most about 1 px, for w = 1 and 3 mm by
about 2.7 px and for w = 1 and 5 mm by about 6 px, on the pins right over the gap (331 pins); the 40
feature pins 4 mm apart see at most about 2.4 px between 0.25 and 5 mm, and 0.15 px between adjacent
widths 0.25 mm apart, against about 1 px for 0.25 mm more depth. (With ``rho = 8 mm`` adjacent widths
differed by 0.02 px and no classifier could tell them apart.) Neighbouring tips stay separated (at least 1.8 px between the
ellipses' edges) up to d = 5 mm on every preset; beyond about 6 mm the densest pad's tips begin
to touch at the contact edge. A tap follows `tap_profile`: raised-cosine rise, plateau and release,
250 ms each by default (paper 002, IV-A).

Slides (`tactip.sim._slide`). ``Contact.slide_x_mm``, ``slide_y_mm``: the plate, pressed in, is
dragged sideways and the skin sticks to it. The material in the contact patch (arc length from the
apex ``<= a``) moves by the whole slide ``S`` along the pad surface; outside it the shift falls as a
raised cosine to zero over ``L = max(6 mm, 2 |S|)`` (at most to the clamped base), so the map never
folds (Jacobian >= 1 - pi/4; a slide too long for the pad, beyond `_slide.max_slide_mm`, about 15 mm at
2 mm on a 40 mm pad, is refused). The indentation then acts where the material now is: the patch stays
centred on the apex, the skin slides through it. Slides move pins several pitches sideways, not outward
as a tap does: 3 pitches of ``radial-led-120`` (9.6 mm, 25 px) move the central pins 3.0-3.5 pitches in
the image (the pressed patch is nearer the camera). No contact, no slide. A sequence
(`tactip.sim.sequence`) is made of whole-frame phases: rest, then per stroke a raised-cosine press, a
hold or a raised-cosine slide, a raised-cosine lift that releases depth and slide together (the pad
springs back), and a rest of at least one frame; its ``events`` are exactly the runs of frames in contact.

Appearance (`tactip.sim._render`). Bright casing around the disc (about 200 grey, vignetted); a dark
membrane (about 25) with a radial illumination gradient towards the LED ring; six LED glare spots on
the rim; white pin tips (about 215, +-5 % per pin, lit like the membrane, slightly domed) with an
anti-aliased 1 px edge ramp; where a squeezed skin brings tips over each other, a pixel shows the
brighter tip (the darker for dark tips), never the sum of their light; sensor noise of ``noise_sigma``
grey levels (near-Gaussian, a sum of four uniform bytes, fresh every frame and deterministic given the
seed); optional optical blur and JPEG compression (as from an MJPG webcam). ``dark_pins`` inverts the
scene for dark-marker sensors.
Rendering is vectorised over pins: about 2-5 ms per 640x480 frame.

What makes real TacTips hard for the front end, as options
----------------------------------------------------------
Real recordings differ from the clean default in ways that each fooled detection or tracking; each is
an option (all off by default, so the default frames are unchanged byte for byte) and a preset below.

- Layout ``layout="radial"``: home-built TacTips place pins with a rotary jig, on rings crossed by
  straight spokes, the same count on every ring, so the spacing along a ring grows with its radius
  while the ring spacing stays one pitch; a lattice-consistency test tuned to hexagons sees a pitch
  that varies across the pad. ``pins = rings x spokes (+ 1 centre pin)``, spokes / rings near 2.4
  (120 = 1 + 7 x 17); the innermost ring sits at ``spokes / 2 pi`` pitches so its pins are a pitch
  apart, leaving an empty zone round the centre pin.
- Pad size ``pad_fraction``: the dark disc's diameter over the image height (default 0.87). The
  camera's focal length follows from it (the casing edge at 86 degrees lands on the disc edge), so
  a small pad is a wide-angle view of the same pad: everything, pins included, shrinks with it. A pin
  is never smaller than 1 px in radius, so on the smallest pads (``small-pad-100``: 60 px across at
  320x240, pitch 3.7-4.4 px) ``pin_fraction`` must drop to keep neighbouring tips apart. The six LED
  glare spots scale with a pad whose size is given (at the default they keep their historical size).
- Black rim ring ``rim_polar_deg``, ``ring_glare``: on many TacTips the casing lip in front of the
  membrane's edge is matt or glossy black plastic. It is drawn as an opaque ring (level 8) from the
  disc edge in to where the pin tips at polar angle ``rim_polar_deg`` are seen, with a 1 px
  anti-aliased inner edge; it is composited over the pins, so the outermost pins are cut by it (on a
  hexagonal pad a circular lip cuts the hexagon's corners first). An LED ring facing the lip reflects
  in it as ``ring_glare`` bright blobs: one to three elongated Gaussian lobes each, one to a few pins
  in size (main lobe sigma 0.6-1.8 pin radii along the ring, 0.4-0.8 across), 110-230 grey,
  irregular in shape and brightness, at evenly spaced azimuths with jitter. Their light stays on the
  ring: they lie outside the pin field, and their true centres are ``ring_glare_centres``.
- Low-contrast coloured skin ``membrane_level``, ``pin_level``, ``skin_texture``, ``pin_shadows``,
  ``skin_tint``: a pigmented (brown) skin reflects far more than black rubber, so the pins stand only
  40-70 grey levels above it. The skin carries texture: a static low-frequency mottling (pigment and
  thickness, standard deviation 0.6 x ``skin_texture`` over five pitches), soft highlights between
  the pins (about one per pin, 0.6-1.1 pin radii, 1.5-3.5 x ``skin_texture`` grey, where the skin
  bulges between stalks) and small specks (two per pin, 0.5-0.9 px, dust and bubbles, 60 % dark).
  Highlights and specks are material points of the skin: they move with it under contact. Lit by
  LEDs all round the pad, each stalk casts several faint shadows that together shade a soft ring of
  skin round its tip (``pin_shadows`` deep at 1.4 pin radii, Gaussian 0.35 pin radii across), so the
  skin between pins breaks into blob-like light patches at the lattice's interstices, ringed by dark.
  Texture stays 3 sigma clear of the tips at rest and the shadow rings are centred on the tips, so a
  tip's weighted centroid is still its true centre. In colour frames ``skin_tint="brown"`` colours each
  pixel by its grey level, from brown skin (B, G, R gains 0.6, 0.95, 1.3) to cream paint on the pins,
  each gain triple normalised so that the BT.601 grey of the colour frame is the grey scene.
- Bright surround and strong glare ``surround_level``, ``glare_gain``, ``veil``: a small pad in a very
  bright surround (an open, white-lit casing near saturation) with LED glare made stronger, and a
  veil of scattered light that brightens the disc edge (grey levels ``veil`` at the edge, fading
  inward over a tenth of the radius). Pins near the edge lose contrast.
- LED reflections inside the pad ``reflections``, ``reflection_level``, ``glare_gradient``, ``shimmer``
  (`tactip.sim._scene`): on the home-built radial TacTip the LEDs reflect in the clear window as soft
  bright blobs inside the pad, and their glare brightens one side of it. ``reflections`` blobs
  (flat-topped, ``2^-(r/rho)^4``, half-maximum radius ``rho`` 0.75-1.5 apex pin spacings, so 1.5-3
  spacings across) at seeded positions 0.2-0.7 of the disc radius from its centre, each adding
  ``reflection_level`` (+-15 %) grey at its centre; ``glare_gradient`` grey levels added on the bright
  side of the disc, falling linearly to 0 on the other (a seeded direction). They are fixed in the
  IMAGE, not on the membrane: they are light paths between the LEDs, the window and the lens, which do
  not move when the skin behind them is pressed or dragged, so pins slide under and out of them. A pin
  under this light gains only 0.7 of it (its white paint sits near the knee of the camera's response),
  so it stands out less: on ``radial-led-120`` pins on a reflection stand on about 160 grey with a
  contrast of about 35, the others on about 115 with about 50, as measured on the real pads (issue 20).
  They stay ``visible`` pins; their true centres are unchanged (the tip is drawn point-symmetric; on a
  reflection's flank the anti-aliased edge blends with a background sloping by several grey levels per
  px, which pulls a background-subtracted centroid by up to about 0.2 px). The centres and radii are
  ``reflection_centres`` and ``reflection_radii_px``. ``shimmer`` makes a still pad's frames differ by
  more than sensor noise: every frame each reflection's peak varies with standard deviation ``shimmer``
  grey (the gradient half that), and the reflections jitter by ``0.05 x shimmer`` px (at most 0.25 px);
  a pin on a reflection then varies by 0.7 x that. The shimmer has its own random stream
  (`SyntheticTacTip.reseed_noise` restarts it with the noise), so the noise stays what it was.
- Pin count 100-1000: any count works (``dense-1000``: 1000 pins at 1280x720, 5 px tips about 16 px
  apart); rendering stays vectorised: about 3x the default 331-pin frame for 1000 pins at 1280x720
  (15-20 ms), 4x for a textured colour frame at 640x480 (20-30 ms; ``bench/bench_render.py``).

Flat gels (`tactip.sim.gel`, `tactip.sim._gel`)
----------------------------------------------
The other large family of optical tactile sensors films a flat gel carrying a grid of dark markers
(GelSight Mini: 320x240 at 25 frames/s, about 8 x 10 dots). `SyntheticGel` draws one: no pad, no
disc, no casing; the gel fills the frame and the whole frame is the sensing area (its ``disc`` is
the circle about the frame's centre through its corners, which detection's whole-frame region is too).

- Geometry: markers on a square grid of pitch ``pitch_mm`` (1.8 mm), the frame showing ``grid``
  (rows, columns) pitches at most along each side (30 px at 320x240 for 8 x 10); the grid goes on
  one row and column beyond every edge, offset from the frame's centre by a seeded phase of up to
  0.2 pitch (so the outermost markers are whole, cut by the frame's edge or out of view, depending on
  the seed), each marker jittered by 1 % of the pitch. Markers are round (the gel is seen square on,
  at a fixed scale ``mm_per_px``), of radius ``marker_fraction`` x the pitch (4.2 px), drawn with
  the TacTip's anti-aliased 1 px edge ramp, so a marker's darkness-weighted centroid against the gel
  drawn without it is its true centre (within 0.05 px, gradient and shading included).
- Press (`_gel.outward_flow_mm`): the indenter at the frame's centre makes a patch of radius
  ``a = sqrt(2.5 d)`` mm (3.5 mm at d = 5 mm) and squeezes the gel outward round it:
  ``u_r = 0.1 d (r / a) exp((1 - r^2 / a^2) / 2)``, zero at the centre, 0.1 d (8 px at 5 mm) at the
  patch edge, fading beyond (the markers 9 mm away move under 1.5 px). The map never folds.
- Shear (`_gel.slide_share`): ``Contact.slide_x_mm``, ``slide_y_mm`` drag the patch by the whole
  slide and the gel round it by a raised cosine falling to zero over ``max(6 mm, 4 |S|)``: markers
  stay at least 0.6 pitch apart (Jacobian >= 1 - pi / 8); the press then acts where the patch now is.
  A gap in the plate (``gap_width_mm``) is not modelled on a flat gel.
- Light (`_gel.gel_light`, `_gel.shading`): BGR frames, each channel lit from one side (B from the
  left, G from the top, R from the right): ``gel_level`` (150) at the centre, ``+- gradient / 2``
  (80) across, ``vignette`` (30) grey lost in the corners; markers reflect ``marker_reflectance``
  (0.3) of the light on them (about 45 grey). The pressed gel is shaded as GelSight's photometric
  image: each channel gains ``shading`` (25) grey levels per unit slope of the dent facing its light
  (a Gaussian dome of depth d, sigma 0.6 a, moving with the slide); image-fixed, it slopes the
  background under the markers near the contact. At ``shading=40`` the steepest flanks (d = 3 mm)
  pull two markers' detected centroids by 0.5-0.7 px (detection RMSE 0.08-0.10 px over all markers).
- Noise ``noise_sigma`` (3), optional blur and JPEG, 25 frames/s.

Ground truth: ``visible`` markers are whole in the frame (ramp included, a px clear of the edge),
``partial`` ones are cut by the frame's edge, the others are out of view. Sequences (``slides``,
``taps``, ``sequence``) and `SyntheticTacTip.tap` work as for the TacTip. Preset (`GEL_PRESETS`):
``gelsight-mini``: 8 x 10 markers 1.8 mm apart at 320x240, 25 frames/s (120 markers on the gel, about
80 whole in view). ``SyntheticGel.from_preset`` builds it; the TacTip's `PRESETS` leave it out, so
the tests parametrised over them are the TacTip's.

Ground truth and scoring
------------------------
``SyntheticFrame.centres`` holds every pin's true tip centre. ``visible`` marks pins whose whole tip
(ellipse plus its 1 px edge ramp) is drawn, clear of the image edge and a pixel clear of the rim
ring's inner edge; ``partial`` marks pins drawn but cut by the rim ring or the image edge; the others
(hidden by ``render(hidden=...)``, wholly behind the ring, facing away) are not drawn. Scoring
convention for detection and tracking: a detector must find the ``visible`` pins (recall is over
them); a ``partial`` pin may be found or not (a detection matched to one counts neither for nor
against); any other detection (glare, texture, shadow, rim) is a false positive. The
intensity-weighted centroid of a visible pin over its ellipse, above a constant local background,
is its true centre to about 0.03 px on noise-free renders (0.05 px on the 1 px tips of the smallest
pad and with skin texture under contact), whatever the options.

Presets
-------
`PRESETS` names the sensors that tests, benches and ``open_source("synthetic:NAME")`` use;
`SyntheticTacTip.from_preset` builds one with any option overridden:

- ``tactip-331``, ``tactip-127``, ``tactip-532``: the default renderer (exactly) with 331, 127, 532 pins.
- ``dark-331``: dark markers on a light membrane.
- ``rim-ring-331``: a black rim ring cutting the outer pins (12 partial at rest, seed 0) with 18 LED
  glare blobs on it; no glare on the membrane's rim.
- ``brown-127``: colour frames of a brown skin, pins about 60 grey above it (median; 33-78), texture 12
  and shadows 22 grey.
- ``radial-120``: 120 small pins (2 px) on 7 rings x 17 spokes plus a centre pin, the pad a third of the
  frame height in a near-saturated surround (245) with strong glare and a veil, noise 5, 120 frames/s.
- ``radial-led-120``: the real home-built pad of issue 20: ``radial-120`` with a grey membrane (100)
  and pins (180), four LED reflections (50 grey) inside the pad, a glare gradient (25 grey) and shimmer 1.
  Detection finds 117-120 of the 120 pins and no reflection (seeds 0-11, rest and a 5 mm tap), and
  all 233 pins on the reflections: 21 of the 23 it misses are outermost-ring tips under the veil (-8
  to 16 grey above the membrane round them, noise 5), two are second-ring pins under the tap. On the
  real recordings the pins on the reflections were rejected.
- ``white-dark-331``: white pins on a dark membrane in a dark (matt black, 30 grey) casing, the six LED
  glare spots on the rim: no bright surround frames the disc. Today ``tactip detect`` refuses it ("no sensor
  disc ... not a disc"), while ``tactip replay`` falls back to dark markers, finds a false disc and tracks
  about 100 spurious pins (the dark gaps between the white pins), as on a real recording (issue 20).
- ``small-pad-100``: 100 pins, the pad a quarter of the frame height, 320x240, bright surround (1 px tips).
- ``dense-1000``: 1000 pins at 1280x720, the pad 0.9 of the frame height.
"""

from tactip.sim.contact import Contact, SyntheticFrame, tap_profile
from tactip.sim.presets import GEL_PRESETS, PRESETS, preset_names
from tactip.sim.sequence import ContactEvent, ContactSequence, Stroke
from tactip.sim.synthetic import SyntheticTacTip
from tactip.sim.gel import SyntheticGel

__all__ = ["Contact", "ContactEvent", "ContactSequence", "GEL_PRESETS", "PRESETS", "Stroke", "SyntheticFrame",
           "SyntheticGel", "SyntheticTacTip", "preset_names", "tap_profile"]
