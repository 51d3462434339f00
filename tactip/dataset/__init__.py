"""Your own labelled recordings -> a training and a test set (``tactip dataset build``).

- `tactip.dataset.labels`: the labels CSV and how a label becomes an identity (numbers, names, angles,
  equal-width classes);
- `tactip.dataset.recording`: one recording (video, folder of frames, image) -> its taps, through one
  sensor calibration;
- `tactip.dataset.split`: which taps train and which test (alternate, group, column);
- `tactip.dataset.build`: the whole build, written atomically with its calibration and summary.
"""

from tactip.dataset.build import OUTPUTS, BuildResult, build_dataset, make_calibration
from tactip.dataset.labels import LabelRow, LabelScheme, LabelsError, read_labels
from tactip.dataset.recording import RecordingTaps, is_image, recording_taps, rest_frame_of
from tactip.dataset.split import SPLITS, alternate_split, column_split, group_split

__all__ = ["OUTPUTS", "BuildResult", "build_dataset", "make_calibration",
           "LabelRow", "LabelScheme", "LabelsError", "read_labels",
           "RecordingTaps", "is_image", "recording_taps", "rest_frame_of",
           "SPLITS", "alternate_split", "column_split", "group_split"]
