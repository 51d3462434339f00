"""Labelled recordings -> a training and a test set: the work of ``tactip dataset build``.

`build_dataset` reads the labels CSV (`tactip.dataset.labels`), makes one sensor calibration for the
whole set on the first usable rest frame (or takes the one given), turns every recording into taps
through it (`tactip.dataset.recording.recording_taps`, one recording after another), labels each tap
with its row's label as the dataset's identity (the location is one constant: 0, unit ``none``),
splits the taps (`tactip.dataset.split`) and writes, in the output folder:

- ``calibration.h5``: the calibration (`calibration.save_calibration`); ``tactip replay --calibration``
  with it makes taps that line up with the datasets';
- ``train.h5`` and ``test.h5``: ``tactip-dataset/1`` files (`perception.save_dataset`);
- ``summary.json``: the label scheme, taps per class and split, the rows used and left out (with
  their line numbers), the feature pins seen and every warning.

A bad row (a missing or unreadable file, an empty label, no contact in a video, no sensor in view)
is named with its line number and left out; the build fails only when nothing is left. Nothing is
half-written: the files are written to temporary names and renamed at the end, so an error or a
Ctrl-C leaves the folder as it was; existing outputs are refused unless ``overwrite``.
"""

from __future__ import annotations

import dataclasses
import json
import os
import pathlib
from dataclasses import dataclass, field

import numpy as np

from tactip.dataset.labels import LabelRow, LabelScheme, LabelsError, read_labels
from tactip.dataset.recording import RecordingTaps, is_image, recording_errors, recording_taps, rest_frame_of
from tactip.dataset.images import detect_images
from tactip.dataset.split import SPLITS, alternate_split, column_split, group_split

__all__ = ["BuildResult", "build_dataset", "OUTPUTS", "make_calibration"]

#: The files ``build_dataset`` writes into its output folder.
OUTPUTS = ("calibration.h5", "train.h5", "test.h5", "summary.json")


@dataclass
class BuildResult:
    """What `build_dataset` wrote and found.

    Attributes
    ----------
    out_dir : pathlib.Path
    summary : dict
        The content of ``summary.json``.
    """

    out_dir: pathlib.Path
    summary: dict = field(default_factory=dict)

    def text(self) -> str:
        """A few lines for a person: taps per split and class, rows left out, warnings."""
        s = self.summary
        lines = [f"Label {s['label']!r}: {s['scheme_text']}; split {s['split']['method']}: "
                 f"{s['taps']['train']} training and {s['taps']['test']} test taps from {s['recordings']['used']} "
                 f"recordings ({s['recordings']['left_out']} left out)",
                 f"Calibration: {s['calibration']['text']}",
                 f"Feature pins seen per tap: {s['pins']['seen_min']}..{s['pins']['seen_max']} of "
                 f"{s['pins']['feature_pins']} (median {s['pins']['seen_median']:g}); "
                 f"{s['pins']['taps_with_unseen_pins']} taps with unseen pins"]
        lines += [f"  class {c['class']:>10}: train {c['train']:>5}, test {c['test']:>5} ({c['recordings']} recordings)"
                  for c in s["classes"]]
        lines += [f"warning: {w}" for w in s["warnings"]]
        lines.append(f"Wrote {', '.join(str(self.out_dir / name) for name in OUTPUTS)}")
        return "\n".join(lines)


def build_dataset(labels_csv, out_dir, *, label: str | None = None, classes: int | None = None,
                  period: float | None = None, unit: str | None = None, split: str = "alternate",
                  test_fraction: float = 0.5, seed: int = 0, rest=None, calibration=None,
                  expected_pins: int | None = None, n_pins: int = 40, min_separation_mm: float = 4.0,
                  sensor: str | None = None, pins_on_pad: int | None = None, pad_diameter_mm: float | None = None,
                  mm_per_px: float | None = None, dark_pins: bool | None = None, n_samples: int = 40,
                  image_samples: int | None = None, rest_frame: int = 0, overwrite: bool = False,
                  progress: bool = False, map_fn=None, device: str = "cpu", together: int = 32) -> BuildResult:
    """Turn labelled recordings into ``calibration.h5``, ``train.h5``, ``test.h5`` and ``summary.json``.

    Parameters
    ----------
    labels_csv : str or path
        The labels CSV: a ``path`` column (relative to the CSV), label columns, optionally ``rest``
        and ``split`` (`tactip.dataset.labels`).
    out_dir : str or path
        The output folder (created when missing).
    label : str, optional
        The label column (default: the only one).
    classes : int, optional
        Bin number labels into this many equal-width classes (angles: centred on 0, period / classes, ...).
    period : float, optional
        The labels are angles of this period (e.g. 360 deg): identities and errors wrap.
    unit : str, optional
        The label's unit (default from the column name, ``depth_mm``: mm).
    split : {"alternate", "group", "column"}
        How taps are split (`tactip.dataset.split`).
    test_fraction : float
        Share of each class's taps in the test set, for ``group``.
    seed : int
        Seed of ``group``'s shuffle.
    rest : str or path, optional
        The rest image of the image rows without a ``rest`` column.
    calibration : str, path or calibration.SensorCalibration, optional
        Use this calibration instead of making one (the sensor options must then be left out).
    expected_pins, n_pins, min_separation_mm, sensor, pins_on_pad, pad_diameter_mm, mm_per_px, dark_pins
        The calibration, as ``tactip replay``'s options: pins in view (default: those found), feature
        pins and their separation (mm), the scale's sensor description, the polarity.
    n_samples : int
        Samples per tap of a video.
    image_samples : int, optional
        Rows of an image's tap (its displacement repeated): default 1, or `n_samples` when the set
        also holds videos (taps of one dataset have one shape).
    rest_frame : int
        The videos' rest frame.
    overwrite : bool
        Replace existing outputs in `out_dir`.
    progress : bool
        Show tqdm bars (recordings, and frames of each video).
    map_fn : callable, optional
        Runs the recordings: ``map_fn(function, rows)``, results in order (many recordings on a Dask
        cluster: `tactip.cluster.cluster_map`, as ``tactip replay --out-dir`` runs an archive); the same
        datasets as made here (default: one recording after another).
    device : {"cpu", "auto", "cuda", "torch-cpu"}
        Where the images' pins are detected: ``cpu`` (default) each image in its turn, OpenCV; ``cuda``
        `together` images at once as torch tensors on the GPU (`pins.accel_detect`, the ``accel`` extra);
        ``auto``: ``cuda`` where torch sees a GPU, else ``cpu`` (torch not needed); ``torch-cpu``: the
        batched path on the CPU (tests). The same datasets.
    together : int
        Images detected together on the GPU (>= 1).

    Returns
    -------
    BuildResult

    Raises
    ------
    LabelsError
        A bad labels file or option, existing outputs without `overwrite`, no recording left, or a
        split with an empty side.
    CalibrationError
        The calibration given cannot be read.
    """
    from calibration import load_calibration

    if split not in SPLITS:
        raise LabelsError(f"unknown split {split!r}; choose from {', '.join(SPLITS)}")
    labels_csv, out_dir = pathlib.Path(labels_csv), pathlib.Path(out_dir)
    outputs = {name: out_dir / name for name in OUTPUTS}
    given_calibration = calibration if isinstance(calibration, (str, os.PathLike)) else None
    _check_outputs(out_dir, outputs, overwrite=overwrite, inputs=[labels_csv, rest], calibration=given_calibration)
    rows, column, problems = read_labels(labels_csv, label=label)
    warnings = [f"line {line}: {reason}; left out" for line, reason in problems]
    left_out: list[dict] = [{"line": line, "reason": reason} for line, reason in problems]

    def leave_out(row: LabelRow, reason: str) -> None:
        left_out.append({"line": row.line, "path": _shown(row.path, labels_csv), "reason": reason})
        warnings.append(f"line {row.line} ({_shown(row.path, labels_csv)}): {reason}; left out")

    usable = []
    for row in rows:
        reason = _row_problem(row, labels_csv, split=split, rest=rest)
        if reason:
            leave_out(row, reason)
        else:
            usable.append(row)
    scheme = LabelScheme.from_values([r.label for r in usable], period=period, classes=classes, unit=unit,
                                     column=column) if usable else None
    labelled = []
    for row in usable:
        try:
            labelled.append((row, scheme.identity(row.label)))
        except LabelsError as exc:
            leave_out(row, str(exc))
    if not labelled:
        raise LabelsError(_nothing_left(labels_csv, left_out))
    warnings += list(scheme.warnings)
    videos = any(not is_image(row.path) for row, _ in labelled)
    if image_samples is None:
        image_samples = n_samples if videos else 1
    if videos and any(is_image(row.path) for row, _ in labelled):
        warnings.append(f"videos and images mixed: each image's tap repeats its displacement over {image_samples} "
                        f"samples (a held press)")
    sensor_options = dict(expected_pins=expected_pins, sensor=sensor, pins_on_pad=pins_on_pad,
                          pad_diameter_mm=pad_diameter_mm, mm_per_px=mm_per_px, dark_pins=dark_pins)
    if calibration is not None:
        clash = [name for name, value in sensor_options.items() if value is not None]
        if clash:
            raise LabelsError(f"{', '.join(clash)} cannot be combined with a calibration (it sets detection, pins "
                              f"and scale)")
        cal = calibration if hasattr(calibration, "reference_pins") else load_calibration(calibration)
        calibrated_on = "given"
    else:
        cal, calibrated_on, labelled = _calibrate_first(labelled, leave_out, rest=rest, rest_frame=rest_frame,
                                                        n_pins=n_pins, min_separation_mm=min_separation_mm,
                                                        labels_csv=labels_csv, left_out=left_out, **sensor_options)
    image_pins = detect_images([row for row, _ in labelled], cal, device=device, together=together, progress=progress)
    per_row = _taps_of_rows(labelled, cal, leave_out, rest=rest, n_samples=n_samples, image_samples=image_samples,
                            rest_frame=rest_frame, progress=progress, labels_csv=labels_csv, warnings=warnings,
                            map_fn=map_fn, image_pins=image_pins)
    if not per_row:
        raise LabelsError(_nothing_left(labels_csv, left_out))
    taps = np.concatenate([t.taps for _, _, t in per_row])
    identity = np.concatenate([np.full(len(t.taps), ident) for _, ident, t in per_row])
    recording = np.concatenate([np.full(len(t.taps), k) for k, (_, _, t) in enumerate(per_row)])
    if split == "alternate":
        test = alternate_split(identity)
    elif split == "group":
        test = group_split(identity, recording, test_fraction=test_fraction, seed=seed)
    else:
        test = column_split([row.split for row, _, t in per_row for _ in range(len(t.taps))])
    warnings += _shared_recordings(recording, test, split)
    for side, mask in (("training", ~test), ("test", test)):
        if not mask.any():
            raise LabelsError(f"the {side} set would be empty (split {split} of {len(test)} taps): "
                              + ("give both 'train' and 'test' rows in the split column" if split == "column"
                                 else "give more taps or recordings"))
    summary = _summary(labels_csv, column, scheme, split, per_row, identity, test, taps, cal, calibrated_on,
                       left_out, warnings, seed=seed, test_fraction=test_fraction)
    _write(outputs, cal, taps, identity, test, scheme, summary, given_calibration=given_calibration,
           samples=taps.shape[1], inputs=[labels_csv, rest])
    return BuildResult(out_dir=out_dir, summary=summary)


def make_calibration(frame: np.ndarray, *, expected_pins: int | None = None, n_pins: int = 40,
                     min_separation_mm: float = 4.0, sensor: str | None = None, pins_on_pad: int | None = None,
                     pad_diameter_mm: float | None = None, mm_per_px: float | None = None,
                     dark_pins: bool | None = None, source: str = ""):
    """A sensor calibration from one rest frame (or a list of them, averaged as `calibration.calibrate_sensor`
    averages them), with replay's defaults for what is not said.

    The pins in view default to those found (`pins.find_pin_field`); the scale is `pins.sensor_scale`'s
    (the sensor's pin pitch, or `pins_on_pad` pins on a `pad_diameter_mm` pad, 40 mm assumed).

    Returns
    -------
    calibration.SensorCalibration

    Raises
    ------
    CalibrationError
        No sensor in view, a pin count far from `expected_pins`, or too few pins.
    """
    from pins import DEFAULT_PAD_DIAMETER_MM, NoSensorError, SensorDescription, find_pin_field, sensor_preset

    from calibration import CalibrationError, calibrate_sensor

    frames = list(frame) if isinstance(frame, (list, tuple)) else [frame]
    if expected_pins is None:
        seen = frames[0] if len(frames) == 1 else np.rint(np.mean(np.stack(frames), axis=0)).astype(np.uint8)
        try:
            expected_pins = find_pin_field(seen, dark_pins=dark_pins).count
        except NoSensorError as exc:
            raise CalibrationError(f"no sensor in view: {exc}") from None
    description = sensor_preset(sensor) if sensor else None
    if pins_on_pad is not None:
        description = (dataclasses.replace(description, pins=int(pins_on_pad)) if description else
                       SensorDescription("pad", int(pins_on_pad), pad_diameter_mm or DEFAULT_PAD_DIAMETER_MM))
    return calibrate_sensor(frames, expected_pins=int(expected_pins), pad_diameter_mm=pad_diameter_mm,
                            selected_pins=min(int(n_pins), int(expected_pins)), min_separation_mm=min_separation_mm,
                            mm_per_px=mm_per_px, dark_pins=dark_pins, description=description,
                            sensor={"source": source or "tactip dataset build", "preset": sensor or ""})


def _check_outputs(out_dir: pathlib.Path, outputs: dict, *, overwrite: bool, inputs, calibration) -> None:
    """Refuse an output folder that is a file, outputs that exist (unless overwrite) or that are inputs."""
    from _shared import refuse_overwriting_inputs

    if out_dir.exists() and not out_dir.is_dir():
        raise LabelsError(f"--out {out_dir} is a file, not a folder")
    same = calibration is not None and _same_file(pathlib.Path(calibration), outputs["calibration.h5"])
    existing = [name for name, path in outputs.items() if path.exists() and not (same and name == "calibration.h5")]
    if existing and not overwrite:
        raise LabelsError(f"{out_dir} already holds {', '.join(existing)}: give --overwrite to replace them, or "
                          f"another --out")
    refuse_overwriting_inputs([p for n, p in outputs.items() if not (same and n == "calibration.h5")],
                              [*inputs, calibration])


def _same_file(a: pathlib.Path, b: pathlib.Path) -> bool:
    try:
        return a.resolve() == b.resolve() or (a.exists() and b.exists() and os.path.samefile(a, b))
    except OSError:
        return False


def _shown(path: pathlib.Path, labels_csv: pathlib.Path) -> str:
    """A recording's path as the CSV gives it (relative to the CSV's folder)."""
    try:
        return str(path.relative_to(labels_csv.parent))
    except ValueError:
        return str(path)


def _row_problem(row: LabelRow, labels_csv: pathlib.Path, *, split: str, rest) -> str:
    """Why a row cannot be used before its recording is read, or ""."""
    if row.path == labels_csv.parent:
        return "empty path"
    if not row.path.exists():
        return f"no such file or folder {_shown(row.path, labels_csv)}"
    if row.label == "":
        return "empty label"
    if split == "column" and row.split not in ("train", "test"):
        return f"split must be 'train' or 'test', got {row.split!r}"
    if is_image(row.path):
        image_rest = row.rest or (pathlib.Path(rest) if rest is not None else None)
        if image_rest is None:
            return "an image needs a rest image: give --rest IMAGE or a 'rest' column"
        if not image_rest.is_file():
            return f"no such rest image {_shown(image_rest, labels_csv)}"
    return ""


def _calibrate_first(labelled, leave_out, *, rest, rest_frame, labels_csv, left_out, **options):
    """The calibration made on the first row whose rest frame shows the sensor; rows before it left out."""
    for k, (row, _) in enumerate(labelled):
        try:
            frame = rest_frame_of(row.path, rest=row.rest or rest, rest_frame=rest_frame)
            cal = make_calibration(frame, source=f"tactip dataset build {labels_csv.name}", **options)
        except recording_errors() as exc:
            leave_out(row, f"cannot calibrate on its rest frame ({' '.join(str(exc).split())})")
            continue
        return cal, {"line": row.line, "path": _shown(row.path, labels_csv)}, labelled[k:]
    raise LabelsError(f"no recording could be calibrated on: {_nothing_left(labels_csv, left_out)}")


def _shared_recordings(recording: np.ndarray, test: np.ndarray, split: str) -> list[str]:
    """A warning when recordings have taps on both sides: the test figures then score taps of recordings
    the model was trained on (taps of one recording are alike), and flatter a model on new recordings."""
    both = np.intersect1d(recording[test], recording[~test])
    if not both.size:
        return []
    total = len(np.unique(recording))
    advice = "--split group keeps each recording on one side" if split != "group" else ""
    return [f"{both.size} of {total} recordings have taps in both training and test: the test figures score "
            f"recordings the model has seen and flatter it on new ones" + (f" ({advice})" if advice else "")]


def _taps_of_rows(labelled, cal, leave_out, *, rest, n_samples, image_samples, rest_frame, progress, labels_csv,
                  warnings, map_fn=None, image_pins=None) -> list[tuple[LabelRow, float, RecordingTaps]]:
    """Each usable row's taps: one recording after another (a tqdm bar over them), or through ``map_fn``.

    ``image_pins`` ({line: pins}, `tactip.dataset.images.detect_images`) are the pins of images already detected.
    """
    import functools

    from _shared.progress import progress_bar as tqdm

    from _shared import map_pieces

    one = functools.partial(_row_taps, calibration=cal, rest=rest, n_samples=n_samples, image_samples=image_samples,
                            rest_frame=rest_frame, progress=progress and map_fn is None)
    bar = functools.partial(tqdm, desc="recordings", unit="recording", disable=not progress)
    done = []
    pieces = [(row, (image_pins or {}).get(row.line)) for row, _ in labelled]
    for (row, identity), (got, problem) in zip(labelled, map_pieces(one, pieces, map_fn=map_fn, progress=bar)):
        if problem is not None:
            leave_out(row, problem)
            continue
        warnings += [f"line {row.line} ({_shown(row.path, labels_csv)}): {w}" for w in got.warnings]
        done.append((row, identity, got))
    return done


def _row_taps(piece, *, calibration, rest, n_samples, image_samples, rest_frame, progress):
    """(taps, None) of one row's recording, or (None, why it is left out): a piece that travels to a worker.

    ``piece`` is (row, its image's pins already detected or None).
    """
    row, image_pins = piece
    try:
        return recording_taps(row.path, calibration, rest=row.rest or rest, n_samples=n_samples,
                              image_samples=image_samples, rest_frame=rest_frame, progress=progress,
                              image_pins=image_pins), None
    except recording_errors() as exc:
        return None, " ".join(str(exc).split())


def _nothing_left(labels_csv, left_out: list[dict]) -> str:
    shown = "; ".join(f"line {r['line']}: {r['reason']}" for r in left_out[:5])
    more = f" (and {len(left_out) - 5} more)" if len(left_out) > 5 else ""
    return f"no taps from {labels_csv}: every row was left out ({shown or 'no data rows'}{more})"


def _summary(labels_csv, column, scheme: LabelScheme, split, per_row, identity, test, taps, cal, calibrated_on,
             left_out, warnings, *, seed, test_fraction) -> dict:
    """The content of summary.json."""
    pins = cal.n_selected
    seen = np.array([n for _, _, t in per_row for n in t.pins_seen])
    pin_seen = ~np.isnan(taps[:, 0, :pins])  # (taps, P): the dx column of each feature pin
    classes = []
    for value in np.unique(identity):
        ours = identity == value
        classes.append({"class": scheme.class_name(value), "identity": float(value),
                        "train": int((ours & ~test).sum()), "test": int((ours & test).sum()),
                        "recordings": sum(1 for _, ident, _ in per_row if ident == value)})
        if not (ours & test).any() or not (ours & ~test).any():
            side = "test" if not (ours & test).any() else "training"
            warnings.append(f"class {scheme.class_name(value)} has no {side} taps")
    rows, k = [], 0
    for row, ident, got in per_row:
        n = len(got.taps)
        rows.append({"line": row.line, "path": _shown(row.path, labels_csv), "label": row.label, "identity": ident,
                     "taps": n, "contacts": got.contacts, "left_out_contacts": got.left_out,
                     "kinds": sorted(set(got.kinds)), "train": int((~test[k:k + n]).sum()),
                     "test": int(test[k:k + n].sum())})
        k += n
    return {
        "labels": str(labels_csv), "label": column, "scheme": scheme.to_dict(), "scheme_text": scheme.describe(),
        "identity_unit": scheme.unit, "location": {"value": 0.0, "unit": "none"},
        "split": {"method": split, "seed": seed if split == "group" else None,
                  "test_fraction": test_fraction if split == "group" else None},
        "taps": {"train": int((~test).sum()), "test": int(test.sum()), "samples": int(taps.shape[1]),
                 "dims": int(taps.shape[2])},
        "classes": classes,
        "recordings": {"used": len(per_row), "left_out": len(left_out)},
        "rows": rows, "left_out": left_out,
        "pins": {"feature_pins": pins, "seen_min": int(seen.min()), "seen_max": int(seen.max()), "seen_median": float(np.median(seen)),
                 "taps_with_unseen_pins": int((seen < pins).sum()),
                 "seen_fraction_per_pin": [round(float(f), 4) for f in pin_seen.mean(axis=0)],
                 "never_seen": [int(p) for p in np.flatnonzero(~pin_seen.any(axis=0))]},
        "calibration": {"text": cal.describe(), "made_on": calibrated_on, "pins": int(len(cal.reference_pins)),
                        "feature_pins": pins, "mm_per_px": float(cal.mm_per_px)},
        "warnings": list(warnings),
    }


def _write(outputs: dict, cal, taps, identity, test, scheme: LabelScheme, summary: dict, *, given_calibration,
           samples: int, inputs) -> None:
    """Write every output to a temporary name, then rename them all: nothing half-written."""
    from _shared import fsync_path, remove_stale_temporaries, temporary_name
    from pins import feature_dim_names

    from calibration import save_calibration
    from perception import Dataset, save_dataset

    out_dir = outputs["train.h5"].parent
    out_dir.mkdir(parents=True, exist_ok=True)
    sensor = {"kind": "tactip", "pins": int(cal.expected_pins), "selected_pins": cal.n_selected,
              "min_separation_mm": float(cal.min_separation_mm), "mm_per_px": round(float(cal.mm_per_px), 6),
              "source": "tactip dataset build", "samples": int(samples)}
    names = tuple(scheme.names)
    parts: dict[str, pathlib.Path] = {}
    for path in outputs.values():
        remove_stale_temporaries(path)  # left by a build that was killed
    try:
        skip_calibration = given_calibration is not None and _same_file(pathlib.Path(given_calibration),
                                                                        outputs["calibration.h5"])
        if not skip_calibration:
            parts["calibration.h5"] = temporary_name(outputs["calibration.h5"])
            save_calibration(parts["calibration.h5"], cal)
        for name, mask in (("train.h5", ~test), ("test.h5", test)):
            dataset = Dataset(taps[mask], np.zeros(int(mask.sum())), identity[mask], None, "tactip",
                              location_unit="none", identity_unit=scheme.unit, dim_names=feature_dim_names(cal.n_selected),
                              sensor=sensor, identity_period=scheme.period, identity_names=names)
            parts[name] = temporary_name(outputs[name])
            save_dataset(parts[name], dataset, inputs=inputs)
        parts["summary.json"] = temporary_name(outputs["summary.json"])
        with open(parts["summary.json"], "w", encoding="utf-8") as f:
            json.dump(summary, f, indent=1)
            f.write("\n")
            f.flush()
            os.fsync(f.fileno())
        for name in OUTPUTS:  # summary.json last: it says the set is whole
            if name in parts:
                os.replace(parts[name], outputs[name])
        fsync_path(out_dir, folder=True)
    finally:
        for part in parts.values():
            part.unlink(missing_ok=True)
