"""The blob stage of batched detection on the tensors' device: components, their stats and weighted centres.

`pins.accel_detect.BatchedDetector` with ``labelling="tensor"``: `pins.detect._blobs` for a whole batch,
step for step, with the per-pixel work on the device and the per-blob decisions on small arrays on the CPU:

1. threshold, and 8-connected components by kornia's label propagation (`kornia.contrib.connected_components`:
   3x3 max pooling of pixel ids), stepped until a step changes nothing (`_components`);
2. each component's area and bounding box (scatter reductions), and its OpenCV label: OpenCV's
   labelling (Grana's 2x2 blocks) numbers components by their first 2x2 block in raster order. The
   numbering matters: the one-pixel growth gives a background pixel between two components to the
   higher label, as OpenCV's dilation of the labels does;
3. the components that may be touching pins (`pins.detect._odd_shaped`, per frame): where a frame has
   some, `pins.detect._split_touching` tries them on the CPU, and a frame where it splits one is
   detected there whole (`pins.detect._blobs`); it rarely splits;
4. the one-pixel growth (3x3 max pooling of the labels), each blob's background (the neighbourhood
   mean at its box's middle) and the weighted sums by label (``index_add``), in float64;
5. the filters and centres of `pins.detect._kept`, per frame.

The weighted sums are float64 sums in another order than NumPy's (a GPU's ``index_add`` has none):
each weight is a grey level less a float32 mean (a multiple of the mean's float32 step, 2^-23 of a
grey level or coarser for means of one grey level and more), so a blob's sums (< 2^28) are exact and the
centres equal the NumPy path's; on a darker background they may differ in the last bits (~1e-12 px).
"""

from __future__ import annotations

import numpy as np

from .detect import Blobs, DetectionParams, _blobs, _kept, _odd_shaped, _split_touching
from .disc import SensorDisc


def blobs_on_device(torch, kornia, image, smooth, mean, disc: SensorDisc, params: DetectionParams, x0: int,
                    y0: int) -> list[Blobs]:
    """`pins.detect._blobs` of every frame of a batch of `BatchedDetector.filtered` tensors (B, h, w)."""
    batch, height, width = image.shape
    if batch == 0:
        return []
    device = image.device
    plane = height * width
    foreground = smooth.to(torch.float32) > mean + torch.tensor(params.offset, dtype=torch.float32)
    labels = _components(torch, kornia, foreground)                           # (B, h, w) int64, unique in the batch
    flat = torch.nonzero(foreground.reshape(-1)).squeeze(1)
    keys, component = torch.unique(labels.reshape(-1)[flat], return_inverse=True)
    count = len(keys)
    frame_of = torch.div(keys - 1, plane, rounding_mode="floor")
    pixel = flat % plane
    y, x = torch.div(pixel, width, rounding_mode="floor"), pixel % width

    def reduce(values, how, fill):
        out = torch.full((count,), fill, dtype=torch.int64, device=device)
        return out.scatter_reduce(0, component, values, how, include_self=True)

    big = np.iinfo(np.int64).max
    left, right, top, bottom = reduce(x, "amin", big), reduce(x, "amax", -1), reduce(y, "amin", big), reduce(y, "amax", -1)
    area = torch.bincount(component, minlength=count)
    blocks = (height + 1) // 2 * ((width + 1) // 2)
    first_block = reduce(torch.div(y, 2, rounding_mode="floor") * ((width + 1) // 2)
                         + torch.div(x, 2, rounding_mode="floor"), "amin", big)
    # OpenCV's order: by frame, then by first 2x2 block; each component's label within its frame (1, 2, ...).
    order = torch.argsort(frame_of * blocks + first_block)
    rank = torch.empty_like(order)
    rank[order] = torch.arange(count, device=device)
    per_frame = torch.bincount(frame_of, minlength=batch)
    frame_start = torch.cumsum(per_frame, 0) - per_frame
    local = rank - frame_start[frame_of] + 1                                    # by component: 1..n in its frame
    label_map = torch.zeros(batch * plane, dtype=torch.float32 if count < 2 ** 24 else torch.float64, device=device)
    label_map[flat] = local[component].to(label_map.dtype)
    label_map = label_map.reshape(batch, 1, height, width)
    grown = torch.nn.functional.max_pool2d(label_map, 3, stride=1, padding=1).reshape(-1)
    grown_flat = torch.nonzero(grown > 0).squeeze(1)
    grown_frame = torch.div(grown_flat, plane, rounding_mode="floor")
    grown_rank = frame_start[grown_frame] + grown[grown_flat].to(torch.int64) - 1   # index in OpenCV order
    # Stats in OpenCV order (rank), on the CPU: small arrays.
    stats = torch.stack([left, top, right - left + 1, bottom - top + 1, area])[:, order]
    left, top, box_w, box_h, area = stats.cpu().numpy()
    middle_x, middle_y = left + box_w // 2, top + box_h // 2
    starts = frame_start.cpu().numpy()
    counts = per_frame.cpu().numpy()
    # Step 3: frames whose odd-shaped components the CPU splits are detected there whole.
    on_cpu = set()
    suspects = {}
    for k in range(batch):
        part = slice(starts[k], starts[k] + counts[k])
        suspect = _odd_shaped(_row0(area[part], plane - area[part].sum()), _row0(box_w[part]), _row0(box_h[part]),
                              params)
        if params.split_radius_px > 0 and suspect.any():
            suspects[k] = suspect
    if suspects:
        frames = torch.as_tensor(sorted(suspects), device=device)
        grown_ranks = grown_rank.cpu().numpy()
        grown_frames = grown_frame.cpu().numpy()
        grown_pixels = (grown_flat % plane).cpu().numpy()
        smooths, means = smooth[frames].cpu().numpy(), mean[frames].cpu().numpy()
        label_maps = label_map[frames, 0].cpu().numpy().astype(np.int32)
        for i, k in enumerate(sorted(suspects)):
            mine = grown_frames == k
            part = slice(starts[k], starts[k] + counts[k])
            boxes = tuple(_row0(v[part]) for v in (left, top, box_w, box_h))
            split = _split_touching(smooths[i], means[i], label_maps[i], int(counts[k]) + 1, suspects[k],
                                    grown_pixels[mine], grown_ranks[mine] - starts[k] + 1, params.split_radius_px,
                                    boxes)
            if split is not None:
                on_cpu.add(k)
    # Step 4: weighted sums by component (OpenCV order), all frames at once, in float64.
    background = mean[frame_of[order], torch.as_tensor(middle_y, device=device),
                      torch.as_tensor(middle_x, device=device)].to(torch.float64)
    weight = torch.clamp(image.reshape(-1)[grown_flat].to(torch.float64) - background[grown_rank], min=0.0)
    gx = (grown_flat % width).to(torch.float64)
    gy = torch.div(grown_flat % plane, width, rounding_mode="floor").to(torch.float64)
    sums = torch.zeros((3, count), dtype=torch.float64, device=device)
    sums[0].index_add_(0, grown_rank, weight)
    sums[1].index_add_(0, grown_rank, weight * gx)
    sums[2].index_add_(0, grown_rank, weight * gy)
    total, sum_x, sum_y = sums.cpu().numpy()
    found = []
    for k in range(batch):
        if k in on_cpu:
            found.append(_blobs(image[k].cpu().numpy(), smooth[k].cpu().numpy(), mean[k].cpu().numpy(), disc, params,
                                x0, y0))
            continue
        part = slice(starts[k], starts[k] + counts[k])
        found.append(_kept(_row0(area[part], plane - area[part].sum()), _row0(box_w[part]), _row0(box_h[part]),
                           *(_row0(v[part], 0.0) for v in (total, sum_x, sum_y)), disc, params, x0, y0))
    return found


def _row0(values: np.ndarray, background=1) -> np.ndarray:
    """``values`` with a row 0 for the background prepended, as OpenCV's stats have (never kept nor split)."""
    return np.concatenate([np.asarray([background], dtype=values.dtype), values])


def _components(torch, kornia, foreground):
    """8-connected components of (B, h, w) masks: label propagation run to its fixed point.

    kornia's propagation (`kornia.contrib.connected_components`: each pixel's id, 1 + its raster index,
    replaced by the largest in its 3x3 neighbourhood, masked, step after step) stopped at the first step
    that changes nothing; the labels are kornia's converged ones (1 + the largest raster index of a
    component's pixels in the batch, int64; background 0). A label only grows, so a step that changes
    nothing is the fixed point. kornia's function takes a fixed number of steps and starts again from the
    ids each call: run with 32 steps and, where one more step still changed something, 64, 128, ... (as
    this was before), test_accel_detect's batches took 59 steps on average and 1.9x the CPU (the same
    labels on every preset's batch, seed 3). ``kornia`` is not called.
    """
    batch, height, width = foreground.shape
    plane = height * width
    dtype = torch.float32 if plane <= 2 ** 24 else torch.float64       # ids exact, as kornia chooses
    mask = foreground[:, None].to(dtype)                              # multiplies faster than a bool mask
    ids = torch.arange(1, plane + 1, device=foreground.device, dtype=dtype).view(1, 1, height, width) * mask
    while True:
        grown = torch.nn.functional.max_pool2d(ids, 3, stride=1, padding=1) * mask
        if torch.equal(grown, ids):
            break
        ids = grown
    offset = torch.arange(batch, device=foreground.device, dtype=torch.int64).view(-1, 1, 1, 1) * plane
    return (ids.to(torch.int64) + offset).mul_(foreground[:, None])[:, 0]
