"""Windowed pin centroids as tensor operations (torch): many frames' windows measured at once, on a GPU if any.

`BatchedWindowCentroids` is `pins._window.WindowCentroids.measure` for a batch: the windows of many
frames (of many videos) gathered from one (B, H, W) tensor and measured together, each window naming
its frame. The arithmetic is the NumPy path's, step for step (the local background plane through
the darkest runs along the window's sides, the threshold a fraction of the way up to the tip, the
plane tilted on a slope, the quarter-pixel disc masks, the moments), so the centroids agree with it
within 0.01 px (`tests/pins/test_accel.py`, on every synthetic preset, CPU torch).

torch is optional (the ``accel`` extra, pinned): it is imported when a `BatchedWindowCentroids` is made,
never by ``import pins``. Where no GPU is present, ``device="auto"`` runs on the CPU's torch, and the
NumPy path (`pins.PinTracker`) stays what replay uses: a tracker that steps many videos in lockstep
through this batch is not built yet.

Example
-------
>>> batched = BatchedWindowCentroids(WindowCentroids(5), device="cpu")          # doctest: +SKIP
>>> centres, measures = batched.measure(frames, frame_index, points, radius_px)  # doctest: +SKIP
"""

from __future__ import annotations

import numpy as np

from pins._window import _FLAT_RISE, _PHASES, _SIDE_RUN, WindowCentroids

__all__ = ["BatchedWindowCentroids", "pick_device"]


def pick_device(device: str = "auto"):
    """The torch device for ``device``: ``auto`` (a GPU if torch sees one, else the CPU), ``cuda``, ``cpu``.

    Raises
    ------
    ValueError
        ``cuda`` asked where torch sees no GPU, or an unknown name.
    """
    import torch

    if device == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    if device == "cuda" and not torch.cuda.is_available():
        raise ValueError("device 'cuda' asked, but torch sees no GPU here; use 'auto' or 'cpu'")
    if device not in ("cpu", "cuda") and not device.startswith("cuda:"):
        raise ValueError(f"unknown device {device!r}; choose from auto, cuda, cpu")
    return torch.device(device)


class BatchedWindowCentroids:
    """`WindowCentroids.measure` on the windows of many frames at once, as torch tensors.

    Parameters
    ----------
    windows : WindowCentroids
        The configuration (half side, threshold fraction, above-mean rule, least contrast) and its
        masks, copied to the device once.
    device : str
        ``auto`` (default: a GPU if present, else the CPU), ``cuda`` or ``cpu``.
    """

    def __init__(self, windows: WindowCentroids, *, device: str = "auto") -> None:
        import torch

        self.torch = torch
        self.windows = windows
        self.device = pick_device(device)
        on = dict(device=self.device)
        self._moments = torch.as_tensor(windows._moments, dtype=torch.float32, **on)      # (P, 4)
        self._masks = torch.as_tensor(windows._masks, dtype=torch.uint8, **on)            # (masks, P)
        self._top = torch.as_tensor(windows._top, dtype=torch.long, **on)                 # (5,)
        self._sides = torch.as_tensor(windows._sides, dtype=torch.long, **on)             # (4 x runs x run,)
        self._side_plane = torch.as_tensor(windows._side_plane, dtype=torch.float64, **on)  # (4, 3)
        self._plane = torch.as_tensor(windows._plane, dtype=torch.float32, **on)          # (3, P)

    def __repr__(self) -> str:
        return f"BatchedWindowCentroids({self.windows!r}, device={str(self.device)!r})"

    def measure(self, frames, frame_index, points, radius_px) -> tuple[np.ndarray, np.ndarray]:
        """Centroids of the bright tips around ``points``, each in its own frame of ``frames``.

        Parameters
        ----------
        frames : (B, H, W) ndarray or tensor of uint8
            Grey frames, bright pins on a dark membrane (many videos' frames, stacked).
        frame_index : (N,) int array
            The frame of each window, in [0, B).
        points : (N, 2) ndarray
            Finite guesses (x, y), px.
        radius_px : (N,) ndarray
            Radius of each window's mask, px (clipped to the masks'; NaN: the widest).

        Returns
        -------
        centres : (N, 2) ndarray of float64
            (x, y), px; NaN where the window is empty or does not fit in its frame.
        measures : (3, N) ndarray of float64
            Area, contrast and compactness (`WindowCentroids.__call__` says what each is).

        Raises
        ------
        ValueError
            Shapes that do not match (expected and actual named).
        """
        torch = self.torch
        w = self.windows
        half, side = w.half_px, 2 * w.half_px + 1
        on = dict(device=self.device)
        frames = torch.as_tensor(frames, **on)
        points_np = np.asarray(points, dtype=np.float64)
        if frames.dim() != 3 or frames.dtype != torch.uint8:
            raise ValueError(f"frames must be (B, H, W) uint8, got {tuple(frames.shape)} {frames.dtype}")
        if points_np.ndim != 2 or points_np.shape[1] != 2:
            raise ValueError(f"points must be (N, 2), got {points_np.shape}")
        n = len(points_np)
        if n == 0:
            return np.empty((0, 2)), np.empty((3, 0))
        batch, height, width = frames.shape
        index = torch.as_tensor(np.asarray(frame_index), dtype=torch.long, **on)
        if index.shape != (n,):
            raise ValueError(f"frame_index must be ({n},), got {tuple(index.shape)}")
        point = torch.as_tensor(points_np, dtype=torch.float64, **on)
        anchor = torch.round(point)  # half to even, as np.rint
        corner = anchor.long() - half
        fits = ((corner[:, 0] >= 0) & (corner[:, 0] <= width - side) & (corner[:, 1] >= 0)
                & (corner[:, 1] <= height - side))
        corner = corner * fits[:, None]
        # All windows at once: a (B, H - side + 1, W - side + 1, side, side) sliding view, indexed.
        frames = frames.contiguous()
        view = frames.as_strided((batch, height - side + 1, width - side + 1, side, side),
                                 (height * width, width, 1, width, 1))
        patches = view[index, corner[:, 1], corner[:, 0]].reshape(n, -1)                   # (N, P) uint8 copy
        top = patches[:, self._top].to(torch.float64).sum(dim=1) / len(w._top)
        runs = patches[:, self._sides].to(torch.int32).reshape(n, 4, -1, _SIDE_RUN).sum(dim=3)
        plane = runs.amin(dim=2).to(torch.float64) @ self._side_plane                       # (N, 3)
        background, rise = plane[:, 0], plane[:, 1:]
        contrast = top - background
        shrink = _FLAT_RISE * contrast / torch.sqrt((rise * rise).sum(dim=1))            # inf, NaN as NumPy's
        sloped = torch.nonzero((shrink < 1.0) & (contrast > w.least_contrast)).flatten()
        positive = torch.clamp(contrast, min=0.0)
        lift = w.threshold_fraction * positive
        if w.above_mean:
            mean = patches.to(torch.float64).sum(dim=1) / patches.shape[1]
            lift = torch.minimum(torch.maximum(lift, mean - background), positive)
        level = background + lift
        if sloped.numel():
            coefficients = torch.empty((sloped.numel(), 3), dtype=torch.float32, **on)
            coefficients[:, 0] = level[sloped].to(torch.float32)
            scale = (1.0 - torch.clamp(shrink[sloped], min=0.0)) / half
            coefficients[:, 1:] = (rise[sloped] * scale[:, None]).to(torch.float32)
            tilted = torch.clamp(patches[sloped].to(torch.float32) - torch.round(coefficients @ self._plane), min=0.0)
        threshold = torch.round(level).to(torch.uint8)[:, None]
        patches = torch.maximum(patches, threshold) - threshold
        # The mask of each guess's quarter-pixel phase and radius, as `WindowCentroids.measure` picks it.
        phase = torch.round((point - anchor) * _PHASES)
        radius = torch.round(torch.as_tensor(np.asarray(radius_px, dtype=np.float64), **on) * _PHASES)
        radius = torch.clamp(radius, min=1.0)
        radius = torch.where(torch.isnan(radius), torch.full_like(radius, float(len(w._radii))),
                             torch.clamp(radius, max=float(len(w._radii))))
        phases = w._n_phases
        mask = (radius * phases + phase[:, 1]) * phases + phase[:, 0] + (_PHASES // 2) * (phases + 1) - phases * phases
        masks = self._masks[mask.long()]
        weights = (patches * masks).to(torch.float32)
        if sloped.numel():
            weights[sloped] = tilted * masks[sloped].to(torch.float32)
        moments = (weights @ self._moments).to(torch.float64)                               # (N, 4)
        mass = moments[:, 0]
        offset = moments[:, 1:3] / mass[:, None]
        area = mass / (top - level)
        spread = moments[:, 3] / mass - (offset * offset).sum(dim=1)
        compactness = area / (2 * np.pi * spread)
        centres = anchor + offset
        centres[~fits | (mass <= 0)] = float("nan")
        measures = torch.stack([area, contrast, compactness])
        return centres.cpu().numpy(), measures.cpu().numpy()
