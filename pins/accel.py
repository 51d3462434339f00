"""Windowed pin centroids as tensor operations (torch): many frames' windows measured at once, on a GPU if any.

- `BatchedWindowCentroids`: `pins._window.WindowCentroids.measure` for a batch: the windows of many
  frames (of many videos) gathered from one buffer of frames and measured together, each window
  naming its frame; each window may have its own settings (threshold fraction, above-mean rule,
  least contrast: each video's tracker has its own).
- `WindowBatcher`: many trackers, each on its own thread (one per video), stepping in lockstep: every
  `measure` a tracker's refiner makes waits until every tracker has made its own, and all are
  measured in one batch (`PinTracker.windows` takes the proxy `WindowBatcher.wrap` gives).

The arithmetic is the NumPy path's, step for step (the local background plane through the darkest
runs along the window's sides, the threshold a fraction of the way up to the tip, the plane tilted on
a slope, the quarter-pixel disc masks, the moments in float32 over whole grey levels), so the
centroids equal it (`tests/pins/test_accel.py`: every synthetic preset, CPU torch; bar 0.01 px).

torch is optional (the ``accel`` extra, pinned): it is imported when one of these is made, never by
``import pins``; without a GPU the NumPy path stays what replay uses (``device="auto"``).

Example
-------
>>> batched = BatchedWindowCentroids(WindowCentroids(5), device="cpu")          # doctest: +SKIP
>>> centres, measures = batched.measure(frames, frame_index, points, radius_px)  # doctest: +SKIP
"""

from __future__ import annotations

import contextlib
import threading

import numpy as np

from pins._window import _FLAT_RISE, _PHASES, _SIDE_RUN, WindowCentroids

__all__ = ["BatchedWindowCentroids", "WindowBatcher", "pick_device"]


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
        The window side and masks (copied to the device once), and the default settings.
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
        side = 2 * windows.half_px + 1
        offsets = torch.arange(side, **on)
        self._rows, self._cols = offsets.repeat_interleave(side), offsets.repeat(side)   # (P,): y, x in a window

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
        frames = torch.as_tensor(frames, device=self.device)
        if frames.dim() != 3 or frames.dtype != torch.uint8:
            raise ValueError(f"frames must be (B, H, W) uint8, got {tuple(frames.shape)} {frames.dtype}")
        frame_index = np.asarray(frame_index)
        if frame_index.shape != (len(np.asarray(points)),):
            raise ValueError(f"frame_index must be ({len(np.asarray(points))},), got {frame_index.shape}")
        _, height, width = frames.shape
        n = len(frame_index)
        w = self.windows
        settings = (np.full(n, w.threshold_fraction), np.full(n, w.above_mean), np.full(n, w.least_contrast))
        return self.measure_flat(frames.reshape(-1), frame_index * (height * width), np.full(n, width),
                                 np.full(n, height), points, radius_px, *settings)

    def measure_flat(self, buffer, start, width, height, points, radius_px, threshold_fraction, above_mean,
                     least_contrast) -> tuple[np.ndarray, np.ndarray]:
        """`measure` with each window's frame given by where it starts in one flat buffer of frames.

        Parameters
        ----------
        buffer : (M,) tensor of uint8
            Frames of any sizes, each flattened row by row, end to end (on the device).
        start, width, height : (N,) int arrays
            The first pixel of each window's frame in `buffer`, and that frame's size, px.
        points, radius_px
            As `measure`.
        threshold_fraction, above_mean, least_contrast : (N,) arrays
            Each window's settings (`WindowCentroids`'s attributes of the same names).

        Returns
        -------
        centres, measures
            As `measure`.
        """
        torch = self.torch
        on = dict(device=self.device)
        half, side = self.windows.half_px, 2 * self.windows.half_px + 1
        points_np = np.asarray(points, dtype=np.float64)
        if points_np.ndim != 2 or points_np.shape[1] != 2:
            raise ValueError(f"points must be (N, 2), got {points_np.shape}")
        n = len(points_np)
        if n == 0:
            return np.empty((0, 2)), np.empty((3, 0))

        def column(values, dtype):
            return torch.as_tensor(np.asarray(values), dtype=dtype, **on)

        start, width, height = (column(v, torch.long) for v in (start, width, height))
        fraction, above, least = (column(threshold_fraction, torch.float64), column(above_mean, torch.bool),
                                  column(least_contrast, torch.float64))
        point = torch.as_tensor(points_np, **on)
        anchor = torch.round(point)  # half to even, as np.rint
        corner = anchor.long() - half
        fits = ((corner[:, 0] >= 0) & (corner[:, 0] <= width - side) & (corner[:, 1] >= 0)
                & (corner[:, 1] <= height - side))
        corner = corner * fits[:, None]
        # All windows at once: one gather from the buffer (each window's pixels row by row).
        first = start + corner[:, 1] * width + corner[:, 0]
        patches = buffer[first[:, None] + self._rows[None, :] * width[:, None] + self._cols[None, :]]  # (N, P)
        top = patches[:, self._top].to(torch.float64).sum(dim=1) / len(self._top)
        runs = patches[:, self._sides].to(torch.int32).reshape(n, 4, -1, _SIDE_RUN).sum(dim=3)
        plane = runs.amin(dim=2).to(torch.float64) @ self._side_plane                       # (N, 3)
        background, rise = plane[:, 0], plane[:, 1:]
        contrast = top - background
        shrink = _FLAT_RISE * contrast / torch.sqrt((rise * rise).sum(dim=1))            # inf, NaN as NumPy's
        sloped = torch.nonzero((shrink < 1.0) & (contrast > least)).flatten()
        positive = torch.clamp(contrast, min=0.0)
        lift = fraction * positive
        mean = patches.to(torch.float64).sum(dim=1) / patches.shape[1]
        lift = torch.where(above, torch.minimum(torch.maximum(lift, mean - background), positive), lift)
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
        widest = float(len(self.windows._radii))
        phase = torch.round((point - anchor) * _PHASES)
        radius = torch.round(column(np.asarray(radius_px, dtype=np.float64), torch.float64) * _PHASES)
        radius = torch.where(torch.isnan(radius), torch.full_like(radius, widest), radius.clamp(1.0, widest))
        phases = self.windows._n_phases
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
        return centres.cpu().numpy(), torch.stack([area, contrast, compactness]).cpu().numpy()


class WindowBatcher:
    """Trackers on their own threads, their windows measured together: each waits for the others' windows.

    Each thread tracking a video joins with ``with batcher.member():`` for as long as it tracks, and
    gives its tracker the proxy of ``batcher.wrap(tracker.windows)``. A `measure` of a member waits
    until every member has asked for one (or left); the last to ask measures them all in one batch
    (one per window side) and each gets its own windows back, exactly as measured alone.

    Parameters
    ----------
    device : str
        ``auto`` (a GPU if present, else the CPU), ``cuda`` or ``cpu``.

    Attributes
    ----------
    batches : list of int
        How many members' requests each batch measured (for benches and tests).
    """

    def __init__(self, *, device: str = "auto") -> None:
        self.device = pick_device(device)
        self._engines: dict[int, BatchedWindowCentroids] = {}
        self._condition = threading.Condition()
        self._members = 0
        self._pending: list[dict] = []
        self.batches: list[int] = []

    def __repr__(self) -> str:
        return f"WindowBatcher(device={str(self.device)!r}, members={self._members})"

    @contextlib.contextmanager
    def member(self):
        """This thread's membership: its measures wait for the other members' (leaving releases them)."""
        with self._condition:
            self._members += 1
        try:
            yield self
        finally:
            with self._condition:
                self._members -= 1
                self._run_if_complete()

    def wrap(self, windows: WindowCentroids) -> _BatchedWindows:
        """A stand-in for ``windows`` whose measures go through this batcher (settings stay its own)."""
        return _BatchedWindows(windows, self)

    def measure(self, windows: WindowCentroids, image: np.ndarray, points, radius_px):
        """``windows.measure(image, points, radius_px)``, measured with the other members' windows."""
        request = dict(windows=windows, image=np.ascontiguousarray(image, dtype=np.uint8),
                       points=np.asarray(points, dtype=np.float64), radius=np.asarray(radius_px, dtype=np.float64))
        with self._condition:
            self._pending.append(request)
            self._run_if_complete()
            while "result" not in request:
                self._condition.wait()
        if isinstance(request["result"], BaseException):
            raise request["result"]
        return request["result"]

    def _run_if_complete(self) -> None:
        """With the lock held: measure the pending windows once every member has asked (then wake them)."""
        if not self._pending or len(self._pending) < self._members:
            return
        pending, self._pending = self._pending, []
        self.batches.append(len(pending))
        for half_px in sorted({r["windows"].half_px for r in pending}):
            group = [r for r in pending if r["windows"].half_px == half_px]
            try:
                results = self._measure_group(half_px, group)
            except Exception as exc:  # noqa: BLE001 - every waiting member gets the error
                results = [exc] * len(group)
            for request, result in zip(group, results):
                request["result"] = result
        self._condition.notify_all()

    def _measure_group(self, half_px: int, group: list[dict]) -> list:
        """One batch of requests whose windows have the same side."""
        torch = __import__("torch")
        engine = self._engines.get(half_px)
        if engine is None:
            engine = self._engines[half_px] = BatchedWindowCentroids(WindowCentroids(half_px), device=str(self.device))
        sizes = [r["image"].size for r in group]
        starts = np.cumsum([0, *sizes[:-1]])
        buffer = torch.as_tensor(np.concatenate([r["image"].ravel() for r in group]), device=self.device)
        counts = [len(r["points"]) for r in group]

        def each(values):
            return np.concatenate([np.full(c, v) for c, v in zip(counts, values)])

        centres, measures = engine.measure_flat(
            buffer, each(starts), each([r["image"].shape[1] for r in group]), each([r["image"].shape[0] for r in group]),
            np.concatenate([r["points"].reshape(-1, 2) for r in group]), np.concatenate([r["radius"] for r in group]),
            each([r["windows"].threshold_fraction for r in group]), each([r["windows"].above_mean for r in group]),
            each([r["windows"].least_contrast for r in group]))
        edges = np.cumsum([0, *counts])
        return [(centres[a:b].copy(), measures[:, a:b].copy()) for a, b in zip(edges[:-1], edges[1:])]


class _BatchedWindows:
    """A `WindowCentroids` whose `measure` (and call) go through a `WindowBatcher`; its settings are the wrapped one's."""

    def __init__(self, windows: WindowCentroids, batcher: WindowBatcher) -> None:
        object.__setattr__(self, "_windows", windows)
        object.__setattr__(self, "_batcher", batcher)

    def __getattr__(self, name):
        return getattr(self._windows, name)

    def __setattr__(self, name, value) -> None:
        setattr(self._windows, name, value)

    def __repr__(self) -> str:
        return f"batched {self._windows!r}"

    def measure(self, image, points, radius_px):
        """As `WindowCentroids.measure`, measured in a batch with the other trackers' windows."""
        if len(points) == 0:
            return self._windows.measure(image, points, radius_px)
        return self._batcher.measure(self._windows, image, points, radius_px)

    def __call__(self, image, points, radius_px):
        """As `WindowCentroids.__call__`."""
        centres, measures = self.measure(image, points, radius_px)
        return centres, measures[0], measures[1], measures[2]
