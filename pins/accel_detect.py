"""Adaptive-threshold pin detection of many frames at once: the image operations as tensors (torch, kornia).

`pins.detect` finds the pins of one frame in two stages: image operations over the whole disc (the
grey image zeroed outside it, a Gaussian blur, the neighbourhood means of the adaptive threshold),
then the blobs (connected components, the split of touching pins, the intensity-weighted centres).
`BatchedDetector` runs both on a batch of frames as tensor operations, on a GPU where there is one:
kornia's separable filter (`kornia.filters.filter2d_separable`) for the blur and the box sums, kornia's
label propagation (`kornia.contrib.connected_components`) for the components, scatter reductions for
their stats and weighted sums (`pins._accel_blobs`); the per-blob decisions (which may be touching
pins, which look like pins) run on the CPU on small arrays, with `pins.detect`'s own code.

The blur and the means equal OpenCV's bit for bit, so the positions equal the NumPy path's
(`tests/pins/test_accel_detect.py`: every synthetic preset, CPU torch; the bar is 0.01 px):

- OpenCV blurs uint8 images in fixed point: its kernel (`gaussian_kernel_fixed`) is in 1/256 steps,
  the row pass exact, the column pass rounded half up once, at 1/65536. The same integer sums are
  exact in float64 (at most 255 * 2^16), and the rounding is done on integers.
- The box sums of the means are integers, exact in float64; OpenCV scales them by 1/block^2 in float32
  (its vector lanes, 4 columns at a time) and in double for the last width % 4 columns: so here.
- The inverse coverage of the disc (a per-disc constant) is `pins.detect`'s own array.

The blob stage follows OpenCV's too: the label propagation is run until it converges (a fixed
number of iterations could leave a long blob in pieces), components are numbered as OpenCV numbers them,
and a frame where `pins.detect._split_touching` splits touching pins is detected on the CPU whole
(`labelling="cpu"` does so for every frame). torch and kornia are optional (the ``accel`` extra,
pinned): imported when a `BatchedDetector` is made, never by ``import pins``.

Example
-------
>>> detector = BatchedDetector(field.disc, frames[0].shape, field.params, device="auto")  # doctest: +SKIP
>>> pins_per_frame = detector.detect_pins(frames)                                          # doctest: +SKIP
"""

from __future__ import annotations

import math

import numpy as np

from .detect import Blobs, DetectionParams, _blobs, _blur_size_px, _inverse_coverage, _roi
from .disc import SensorDisc, as_grey

__all__ = ["BatchedDetector", "detect_pins_batched", "gaussian_kernel_fixed"]

# OpenCV's box filter scales its integer sums by a float32 factor in vector lanes of this many columns,
# and by a double one in the columns past the last whole lane.
_BOX_LANES = 4


def gaussian_kernel_fixed(sigma_px: float, size: int) -> np.ndarray:
    """OpenCV's fixed-point Gaussian kernel for uint8 images: integers in 1/256 steps that sum to 256.

    The kernel ``exp(-x^2 / (2 sigma^2))`` normalised to 1 (in double, summed as OpenCV sums it),
    then rounded to 1/256 with error diffusion from the outside in; the centre takes the rest.

    Parameters
    ----------
    sigma_px : float
        Standard deviation, px (> 0).
    size : int
        Odd kernel size, px.

    Returns
    -------
    kernel : (size,) ndarray of int64
        Weights in 1/256, symmetric, summing to 256.
    """
    if not sigma_px > 0 or size < 1 or size % 2 == 0:
        raise ValueError(f"need sigma_px > 0 and an odd size, got {sigma_px}, {size}")
    half = (size - 1) // 2
    scale = -0.125 / (sigma_px * sigma_px)  # exp(scale * x^2) with x in half pixels, as OpenCV writes it
    values = [math.exp(float(x * x) * scale) for x in range(1 - size, 0, 2)]
    total = 0.0
    for value in values:
        total += value
    inverse = 1.0 / (2.0 * total + 1.0)
    kernel = np.zeros(size, np.int64)
    error = 0.0
    for i, value in enumerate(values):
        adjusted = value * inverse * 256.0 + error
        kernel[i] = kernel[size - 1 - i] = int(np.rint(adjusted))
        error = adjusted - kernel[i]
    kernel[half] = 256 - 2 * int(kernel[:half].sum())
    return kernel


class BatchedDetector:
    """`pins.detect_blobs` on many frames of one sensor at once, the image operations as tensors.

    Parameters
    ----------
    disc : SensorDisc
        The sensor disc (the same in every frame: one camera, one sensor).
    frame_shape : tuple of int
        (height, width) of the frames, px.
    params : DetectionParams, optional
        Detection parameters (default ``DetectionParams()``).
    device : str
        ``auto`` (default: a GPU if torch sees one, else the CPU), ``cuda`` or ``cpu``.
    labelling : {"auto", "tensor", "cpu"}
        Where the blob stage runs: ``tensor``: the components, their stats and weighted sums on the
        device (`pins._accel_blobs`), the per-blob decisions on the CPU; ``cpu``: each frame's blobs on
        the CPU with `pins.detect`'s code; ``auto`` (default): ``tensor`` on a GPU, ``cpu`` on the CPU
        (where the label propagation's many poolings cost more than OpenCV's labelling). The same blobs.
    """

    def __init__(self, disc: SensorDisc, frame_shape: tuple[int, int], params: DetectionParams | None = None, *,
                 device: str = "auto", labelling: str = "auto") -> None:
        import kornia
        import torch

        from .accel import pick_device

        if labelling not in ("auto", "tensor", "cpu"):
            raise ValueError(f"unknown labelling {labelling!r}; choose from auto, tensor, cpu")
        self.torch, self.kornia = torch, kornia
        self.disc, self.params = disc, params or DetectionParams()
        self.frame_shape = (int(frame_shape[0]), int(frame_shape[1]))
        self.device = pick_device(device)
        self.labelling = labelling if labelling != "auto" else "cpu" if self.device.type == "cpu" else "tensor"
        on = dict(device=self.device)
        self.x0, self.y0, mask = _roi(disc, self.frame_shape)
        height, width = mask.shape
        self._mask = torch.as_tensor(mask.astype(bool), **on)
        block = self.params.block_size_px
        self._inverse = torch.tensor(_inverse_coverage(disc, self.frame_shape, block), **on)  # a copy: read-only array
        self._box = torch.ones((1, block), dtype=torch.float64, **on)
        tail = torch.arange(width, **on) >= width - width % _BOX_LANES
        self._tail = tail[None, :]
        self._blur = None
        if self.params.blur_sigma_px > 0:
            size = _blur_size_px(self.params.blur_sigma_px)
            kernel = gaussian_kernel_fixed(self.params.blur_sigma_px, size)
            self._blur = torch.as_tensor(kernel[None, :], dtype=torch.float64, **on)
            # OpenCV's border, reflect 101, gathered once (torch's reflect padding needs a box wider than the kernel).
            self._rows, self._cols = (torch.as_tensor(_reflect_101(n, size // 2), **on) for n in (height, width))

    def __repr__(self) -> str:
        return (f"BatchedDetector(disc={self.disc!r}, frame_shape={self.frame_shape}, params={self.params!r}, "
                f"device={str(self.device)!r}, labelling={self.labelling!r})")

    def filtered(self, frames):
        """The image operations of a batch: the disc's image, its blur and its neighbourhood means.

        Parameters
        ----------
        frames : (B, H, W) uint8 ndarray or tensor, or a sequence of (H, W) or (H, W, 3) uint8 frames
            Grey (or BGR) frames of `frame_shape`.

        Returns
        -------
        image, smooth : (B, h, w) uint8 tensors
            The disc's box of each frame, zero outside the disc (inverted for dark pins), and its blur.
        mean : (B, h, w) float32 tensor
            The neighbourhood means of the adaptive threshold, grey levels.
        """
        torch = self.torch
        frames = self._as_batch(frames)
        height, width = self._mask.shape
        image = frames[:, self.y0:self.y0 + height, self.x0:self.x0 + width]
        if self.params.dark_pins:
            image = 255 - image
        image = torch.where(self._mask, image, torch.zeros((), dtype=torch.uint8, device=self.device))
        # Convolutions in float64: the integer sums are exact (no TF32, no rounding of large sums).
        grey = image[:, None].to(torch.float64)
        if self._blur is None:
            smooth = image
        else:
            # OpenCV's fixed point: a row pass in 1/256, a column pass in 1/65536, rounded half up once.
            padded = grey[:, :, self._rows][:, :, :, self._cols]
            sums = self.kornia.filters.filter2d_separable(padded, self._blur, self._blur, padding="valid")
            smooth = ((torch.round(sums).to(torch.int64) + 32768) >> 16).to(torch.uint8)[:, 0]
            grey = smooth[:, None].to(torch.float64)
        sums = torch.round(self.kornia.filters.filter2d_separable(grey, self._box, self._box,
                                                                  border_type="constant"))[:, 0]
        area = float(self._box.shape[1] ** 2)
        lanes = sums.to(torch.float32) * torch.tensor(1.0 / area, dtype=torch.float32)
        mean = torch.where(self._tail, (sums * (1.0 / area)).to(torch.float32), lanes) * self._inverse
        return image, smooth, mean

    def detect_blobs(self, frames) -> list[Blobs]:
        """The blobs of every frame of a batch, as `pins.detect_blobs` finds them one frame at a time.

        Parameters
        ----------
        frames
            As `filtered`.

        Returns
        -------
        blobs : list of Blobs
            One per frame, in order.
        """
        tensors = self.filtered(frames)
        if self.labelling == "tensor":
            from ._accel_blobs import blobs_on_device

            return blobs_on_device(self.torch, self.kornia, *tensors, self.disc, self.params, self.x0, self.y0)
        image, smooth, mean = (t.cpu().numpy() for t in tensors)
        return [_blobs(image[k], smooth[k], mean[k], self.disc, self.params, self.x0, self.y0)
                for k in range(len(image))]

    def detect_pins(self, frames) -> list[np.ndarray]:
        """The pin centres of every frame of a batch: a list of (N, 2) ndarrays of (x, y), px (`pins.detect_pins`)."""
        return [blobs.centres for blobs in self.detect_blobs(frames)]

    def _as_batch(self, frames):
        """Frames as one (B, H, W) uint8 tensor on the device (BGR converted to grey on the CPU, as OpenCV does)."""
        torch = self.torch
        if not isinstance(frames, torch.Tensor):
            if not (isinstance(frames, np.ndarray) and frames.ndim == 3):
                frames = np.stack([as_grey(np.asarray(frame)) for frame in frames]) if len(frames) else \
                    np.empty((0, *self.frame_shape), np.uint8)
            frames = torch.as_tensor(np.ascontiguousarray(frames))
        if frames.dim() != 3 or frames.dtype != torch.uint8 or tuple(frames.shape[1:]) != self.frame_shape:
            raise ValueError(f"frames must be (B, {self.frame_shape[0]}, {self.frame_shape[1]}) uint8, got "
                             f"{tuple(frames.shape)} {frames.dtype}")
        return frames.to(self.device)


def _reflect_101(n: int, pad: int) -> np.ndarray:
    """Indices of [0, n) padded by `pad` on each side with OpenCV's default border (reflect 101: ``gfedcb|abcdefgh|gfedcba``)."""
    import cv2

    return np.array([cv2.borderInterpolate(p, n, cv2.BORDER_REFLECT_101) for p in range(-pad, n + pad)], np.int64)


def detect_pins_batched(frames, *, params: DetectionParams | None = None, disc: SensorDisc | None = None,
                        device: str = "auto", together: int = 32, progress=None) -> list[np.ndarray]:
    """`pins.detect_pins` on many frames of one sensor, `together` frames per tensor batch.

    Parameters
    ----------
    frames : sequence of (H, W) or (H, W, 3) ndarray of uint8
        Grey or BGR frames of one size (an iterable of them is read `together` at a time).
    params : DetectionParams, optional
        Detection parameters (default ``DetectionParams()``).
    disc : SensorDisc, optional
        The sensor disc; found in the first frame when not given (`pins.find_sensor_disc`).
    device : str
        ``auto`` (a GPU if torch sees one, else the CPU), ``cuda`` or ``cpu``.
    together : int
        Frames per batch (>= 1).
    progress : callable, optional
        Called with the number of frames of each finished batch (a tqdm bar's ``update``).

    Returns
    -------
    pins : list of (N, 2) ndarray of float64
        Each frame's pins (x, y), px, sorted by y then x: what `pins.detect_pins` gives.

    Examples
    --------
    >>> from pins import detect_pins
    >>> from tactip.sim import Contact, SyntheticTacTip
    >>> sensor = SyntheticTacTip(pins=331, seed=0)
    >>> frames = [sensor.render(Contact(depth_mm, 2.0)).image for depth_mm in (0.0, 4.0)]
    >>> found = detect_pins_batched(frames, device="cpu", together=2)
    >>> all(np.array_equal(pins, detect_pins(frame)) for pins, frame in zip(found, frames))
    True
    """
    from .disc import find_sensor_disc

    if int(together) != together or together < 1:
        raise ValueError(f"together must be a positive integer, got {together}")
    params = params or DetectionParams()
    detector, batch, found = None, [], []

    def flush() -> None:
        found.extend(detector.detect_pins(batch))
        if progress is not None:
            progress(len(batch))
        batch.clear()

    for frame in frames:
        grey = as_grey(np.asarray(frame))
        if detector is None:
            disc = disc or find_sensor_disc(grey, dark_pins=params.dark_pins)
            detector = BatchedDetector(disc, grey.shape, params, device=device)
        batch.append(grey)
        if len(batch) == together:
            flush()
    if batch:
        flush()
    return found
