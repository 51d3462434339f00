"""Detection of a dataset's images in batches on a torch device (`pins.accel_detect`), for `build_dataset`.

With no GPU (``device`` cpu, or auto without one) nothing is detected here and torch is not imported:
each image row is detected on its own with OpenCV, as before.
"""

from __future__ import annotations

from tactip.dataset.labels import LabelsError
from tactip.dataset.recording import is_image, recording_errors

__all__ = ["detect_images"]


def detect_images(rows, cal, *, device: str, together: int, progress: bool) -> dict:
    """The pins of the image rows' images, detected `together` at a time on a torch device: {line: (M, 2) px}.

    ``rows`` are `tactip.dataset.labels.LabelRow` (the image rows among them are detected), ``cal`` the
    dataset's `calibration.SensorCalibration`, ``device`` as `tactip.dataset.build_dataset` takes it.

    Empty for the NumPy path (``device`` cpu, or auto without a GPU), and without images. An image
    that cannot be read or has another size than the calibration's frames is left to its row, which
    fails on it with the usual error.
    """
    from tactip.replay.batch import _torch_device

    if int(together) != together or together < 1:
        raise LabelsError(f"together must be a positive integer, got {together}")
    torch_device = _torch_device(device)
    rows = [row for row in rows if is_image(row.path)]
    if torch_device is None or not rows:
        return {}
    from _shared.progress import progress_bar as tqdm
    from pins.accel_detect import detect_pins_batched

    from tactip.dataset.recording import read_grey_image

    lines = []

    def images():
        for row in rows:
            try:
                image = read_grey_image(row.path)
            except recording_errors():  # the row fails on it later, with the usual error
                continue
            if (image.shape[1], image.shape[0]) == tuple(cal.frame_size):
                lines.append(row.line)
                yield image

    with tqdm(total=len(rows), desc=f"images ({torch_device})", unit="image", disable=not progress) as bar:
        found = detect_pins_batched(images(), params=cal.detection, disc=cal.disc, device=torch_device,
                                    together=int(together), progress=bar.update)
    return dict(zip(lines, found))
