"""One recording -> its taps, through a sensor calibration: the unit of work of ``tactip dataset build``.

`recording_taps` is a plain function of (recording, calibration, options), so that a batch runner can
map it over recordings; it reads its inputs and writes nothing.

- A **video** (or a folder of frames) is replayed as ``tactip replay --calibration`` replays it
  (`tactip.replay.video.track_video`): the calibration's pins are placed on the recording's rest
  frame (`calibration.place_reference_pins`), tracked through it, the contacts found, and each
  contact's feature pins resampled into a ``(samples, 2 P)`` tap. A tap whose feature pins were
  fewer than half seen is left out (and counted); one with some unseen keeps NaN in their columns.
- An **image** is one tap: the displacement of the feature pins from a rest image (the pins placed on
  the rest image and matched to the image's blobs outwards from the unambiguous ones,
  `pins.match_by_propagation`: one large step, not a frame-to-frame track), ``dx`` then ``dy`` of the
  P pins, repeated over ``samples`` rows (1 by default: a still image has no time course).

The feature pins are the calibration's in every recording, so taps of different recordings line up.
"""

from __future__ import annotations

import math
import pathlib
from dataclasses import dataclass, field

import numpy as np

from tactip.errors import SourceError




__all__ = ["RecordingTaps", "recording_taps", "is_image", "rest_frame_of", "read_grey_image", "recording_errors"]


@dataclass
class RecordingTaps:
    """The usable taps of one recording.

    Attributes
    ----------
    taps : (n, samples, 2 P) ndarray of float32
        Feature pins' dx then dy, px; NaN in the columns of a pin unseen for the whole tap.
    pins_seen : (n,) ndarray of int
        Feature pins seen in each tap (of P).
    kinds : list of str
        ``press``, ``slide`` (videos) or ``image``, per tap.
    directions_deg : list of float
        A slide's direction (degrees from image x towards image y), NaN otherwise, per tap.
    contacts : int
        Contacts found (images: 1), the left-out ones included.
    left_out : int
        Contacts left out: fewer than half their feature pins seen, or a single frame.
    warnings : list of str
        What did not go as asked in this recording.
    """

    taps: np.ndarray
    pins_seen: np.ndarray
    kinds: list = field(default_factory=list)
    directions_deg: list = field(default_factory=list)
    contacts: int = 0
    left_out: int = 0
    warnings: list = field(default_factory=list)


def is_image(path) -> bool:
    """Whether a recording is a single image (by its suffix) rather than a video or a folder of frames."""
    from tactip.sources import IMAGE_SUFFIXES

    path = pathlib.Path(path)
    return path.suffix.lower() in IMAGE_SUFFIXES and not path.is_dir()


def read_grey_image(path) -> np.ndarray:
    """An image file as a grey uint8 array; `SourceError` when it is missing or unreadable."""
    import cv2

    path = pathlib.Path(path)
    if not path.is_file():
        raise SourceError(f"no such image: {path}")
    image = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
    if image is None:
        raise SourceError(f"cannot read the image {path} (not an image OpenCV can decode)")
    return image


def rest_frame_of(path, *, rest=None, rest_frame: int = 0) -> np.ndarray:
    """The rest frame of a recording (grey): an image's rest image, or a video's frame `rest_frame`.

    Raises
    ------
    SourceError
        The file is missing or unreadable, an image has no rest image, or the video is shorter.
    """
    if is_image(path):
        if rest is None:
            raise SourceError("an image needs a rest image: give --rest IMAGE or a 'rest' column")
        return read_grey_image(rest)
    from tactip.sources import open_source

    with open_source(path, grey=True) as source:
        if source.live:
            raise SourceError(f"{path} is a live source, not a recording")
        for frame in source:
            if frame.index == rest_frame:
                return frame.image
    raise SourceError(f"{path} has no frame {rest_frame} (it has fewer frames)")


def recording_taps(path, calibration, *, rest=None, n_samples: int = 40, image_samples: int = 1,
                   rest_frame: int = 0, progress: bool = False, image_pins=None) -> RecordingTaps:
    """The taps of one recording, made with a sensor calibration.

    Parameters
    ----------
    path : str or path
        A video file, a folder of frames, or an image file.
    calibration : calibration.SensorCalibration
        Its detection, reference pins, feature pins and frame size are used.
    rest : str or path, optional
        An image's rest image (required for an image; ignored for a video).
    n_samples : int
        Samples per tap of a video (the contact resampled in time).
    image_samples : int
        Rows of an image's tap (its one displacement repeated).
    rest_frame : int
        A video's rest frame (off contact).
    progress : bool
        Show a tqdm bar in frames (videos).
    image_pins : (M, 2) ndarray, optional
        An image's pins (x, y), px, already detected with the calibration's detection and disc (many
        images at once: `pins.accel_detect`); detected here when not given.

    Returns
    -------
    RecordingTaps

    Raises
    ------
    SourceError
        Missing or unreadable file, no rest image, or no usable contact.
    CalibrationError
        Frames of another size than the calibration's.
    PinsError
        No sensor in the rest frame.
    """
    if is_image(path):
        return _image_taps(path, rest, calibration, samples=int(image_samples), image_pins=image_pins)
    from tactip.replay.video import track_video

    track, analysis, _, _ = track_video(path, calibration=calibration, n_samples=int(n_samples),
                                        rest_frame=int(rest_frame), progress=progress)
    warnings = [w for w in analysis["warnings"] if not w.startswith("no taps found")]
    contacts = len(track.contacts)
    if contacts == 0:
        raise SourceError("no contact found in the recording (the pins never moved from the rest frame)")
    valid = np.asarray(track.valid, dtype=bool)
    if not valid.any():
        raise SourceError(f"none of its {contacts} contacts saw half the feature pins "
                          f"({int(np.max(track.pins_seen))} of {calibration.n_selected} at most)")
    kinds = analysis.get("kinds", [])
    left_out = contacts - int(valid.sum())
    if left_out:
        warnings.append(f"{left_out} of {contacts} contacts left out (fewer than half the feature pins seen, or a "
                        f"single frame)")
    return RecordingTaps(taps=np.asarray(track.features[valid], dtype=np.float32),
                         pins_seen=np.asarray(track.pins_seen[valid], dtype=np.int64),
                         kinds=[kinds[k].kind if k < len(kinds) else "contact" for k in np.flatnonzero(valid)],
                         directions_deg=[_direction(kinds[k]) if k < len(kinds) else math.nan
                                         for k in np.flatnonzero(valid)],
                         contacts=contacts, left_out=left_out, warnings=warnings)


def _direction(kind) -> float:
    value = getattr(kind, "direction_deg", None)
    return math.nan if value is None else float(value)


def _image_taps(path, rest, calibration, *, samples: int, image_pins=None) -> RecordingTaps:
    """One tap: the feature pins' displacement from the rest image to the image.

    The two images are one large step apart (a deep press moves rim pins by most of a pitch), so the
    pins are not tracked frame to frame: the calibration's pins are placed on the rest image's blobs,
    and matched to the image's blobs outwards from the unambiguous ones (`pins.match_by_propagation`).
    """
    from pins import detect_pins, match_by_propagation, median_spacing_px

    from calibration import CalibrationError, place_reference_pins
    from tactip.pipeline import MIN_SEEN_FRACTION

    if rest is None:
        raise SourceError("an image needs a rest image: give --rest IMAGE or a 'rest' column")
    before, after = read_grey_image(rest), read_grey_image(path)
    for name, image in (("rest image", before), ("image", after)):
        if (image.shape[1], image.shape[0]) != tuple(calibration.frame_size):
            width, height = calibration.frame_size
            raise CalibrationError(f"the {name} is {image.shape[1]}x{image.shape[0]} px, the calibration's frames "
                                   f"{width}x{height} px")
    at_rest = place_reference_pins(calibration, before)
    blobs = (detect_pins(after, params=calibration.detection, disc=calibration.disc) if image_pins is None
             else np.asarray(image_pins, dtype=np.float64).reshape(-1, 2))
    found = match_by_propagation(at_rest, blobs, spacing_px=median_spacing_px(at_rest))
    chosen = np.asarray(calibration.selected_pins, dtype=np.intp)
    moved = (found - at_rest)[chosen]  # (P, 2) px, NaN where unmatched
    seen = np.isfinite(moved).all(axis=1)
    needed = math.ceil(MIN_SEEN_FRACTION * len(chosen))
    if seen.sum() < needed:
        raise SourceError(f"only {int(seen.sum())} of {len(chosen)} feature pins were found in the image; a tap "
                          f"needs {needed}")
    tap = np.tile(np.concatenate([moved[:, 0], moved[:, 1]])[None, :], (samples, 1)).astype(np.float32)
    return RecordingTaps(taps=tap[None], pins_seen=np.array([int(seen.sum())]), kinds=["image"],
                         directions_deg=[math.nan], contacts=1)


def recording_errors() -> tuple:
    """The errors a recording may raise that leave it out (and not the build)."""
    from pins import PinsError

    from calibration import CalibrationError
    from tactip.errors import TactipError

    return (TactipError, PinsError, CalibrationError, OSError, ValueError)
