"""The tap dataset: the contract between front ends, calibration and perception.

A dataset is a set of taps, each a ``(samples, dims)`` time series of sensor values, labelled
with the location (e.g. depth in mm) and identity (e.g. gap width in mm) it was collected at.
On disk it is one HDF5 file of schema ``tactip-dataset/1``:

==============  ==========================  ============================================
name            kind                        content
==============  ==========================  ============================================
``taps``        float32 (N, samples, dims)  sensor values of each tap; NaN where missing
``location``    float64 (N,)                location of each tap (``location_unit``)
``identity``    float64 (N,)                identity of each tap (``identity_unit``)
``lateral``     float64 (N,), optional      lateral placement offset of each tap, mm
``schema``      attribute                   ``"tactip-dataset/1"``
``front_end``   attribute                   ``"tactip"`` (pin displacements) or ``"taxel"``
``location_unit``, ``identity_unit``        attributes, e.g. ``"mm"`` (``"none"`` for a constant)
``dim_names``   attribute, list of str      one name per dimension (``"pin03_x"``, ``"taxel07"``)
``sensor``      attribute, JSON string      sensor description (kind, pins or taxels, preset, ...)
``identity_period``  attribute, optional    period of a circular identity (e.g. 360 for an angle in deg)
``identity_names``   attribute, optional    class names of a named identity (its values are indices 0..K-1)
==============  ==========================  ============================================

A missing value is NaN: a TacTip tap holds NaN in the dx and dy dimensions of a feature pin unseen
for the whole tap (`tactip.pipeline.contact_features`); every likelihood model marginalises such
dimensions (`perception.likelihood`). Labels are never missing, no value is infinite, and every tap
has at least one observed value.

`save_dataset` writes a whole dataset atomically; `DatasetWriter` appends taps one at a time
(flushing each, so a crash loses at most the tap in progress) and resumes an existing file.

This module is the dataset's public face; its parts live in modules named after them: the
container (`perception._dataset_container`), the checks of labels, taps and schema
(`perception._dataset_checks`), the HDF5 file (`perception._dataset_file`) and the writer
(`perception._dataset_writer`).

Example
-------
>>> import numpy as np
>>> taps = np.zeros((2, 40, 80), np.float32)
>>> ds = Dataset(taps, np.array([0.0, 0.5]), np.array([1.0, 1.0]), None, "tactip")
>>> ds.dims, ds.samples, ds.dim_names[0]
(80, 40, 'dim00')
"""

from __future__ import annotations

from ._dataset_checks import COUNT_ATTRIBUTE, FRONT_ENDS, SCHEMA, check_identity_labels
from ._dataset_container import Dataset
from ._dataset_file import load_dataset, save_dataset
from ._dataset_writer import DatasetWriter

__all__ = ["SCHEMA", "FRONT_ENDS", "Dataset", "save_dataset", "load_dataset", "DatasetWriter", "check_identity_labels"]
