"""The tap dataset's container: labelled taps of one front end, validated on construction
(`perception.dataset` describes the contract and the file).
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field

import numpy as np

from ._dataset_checks import FRONT_ENDS, _check_observed, check_identity_labels
from .errors import DatasetError

__all__ = ["Dataset"]


@dataclass(frozen=True)
class Dataset:
    """Labelled taps of one front end, validated on construction.

    Parameters
    ----------
    taps : (N, samples, dims) array, converted to float32
        Sensor values of each tap (pin displacements in px, or taxel readings); NaN where missing
        (e.g. the dimensions of a pin unseen during the tap).
    location : (N,) array, converted to float64
        Location of each tap in ``location_unit`` (e.g. depth in mm).
    identity : (N,) array, converted to float64
        Identity of each tap in ``identity_unit`` (e.g. gap width in mm).
    lateral : (N,) array or None
        Lateral placement offset of each tap in mm (paper 002, Fig. 11), or None.
    front_end : {"tactip", "taxel"}
        The sensor front end that produced the taps.
    location_unit, identity_unit : str
        Units of `location` and `identity` (``"none"`` for a constant identity).
    dim_names : tuple of str
        One name per dimension; empty generates ``("dim00", "dim01", ...)``.
    sensor : dict
        JSON-serialisable sensor description (kind, pins or taxels, preset, ...).
    identity_period : float or None
        Period of a circular identity in ``identity_unit`` (e.g. 360 for a slide direction in deg):
        errors between identities wrap (315 and 0 deg are 45 deg apart). None: not circular.
    identity_names : tuple of str
        Names of a named identity (e.g. shapes): identity k is class ``identity_names[k]``, and
        errors between names are only right or wrong. Empty: the identity is a number.

    Raises
    ------
    DatasetError
        Naming the field: wrong shapes, NaN or infinite labels, infinite tap values, a tap with no
        observed value, unknown front end, wrong number of dim names, a sensor description that is not JSON.
    """

    taps: np.ndarray
    location: np.ndarray
    identity: np.ndarray
    lateral: np.ndarray | None
    front_end: str
    location_unit: str = "mm"
    identity_unit: str = "mm"
    dim_names: tuple[str, ...] = ()
    sensor: dict = field(default_factory=dict)
    identity_period: float | None = None
    identity_names: tuple[str, ...] = ()

    def __post_init__(self):
        taps = np.asarray(self.taps, dtype=np.float32)
        if taps.ndim != 3 or taps.shape[1] < 1 or taps.shape[2] < 1:
            raise DatasetError(f"taps must have shape (N, samples, dims) with samples, dims >= 1, got {taps.shape}")
        n = taps.shape[0]
        arrays = {"taps": taps}
        for name in ("location", "identity", "lateral"):
            value = getattr(self, name)
            if value is None and name == "lateral":
                continue
            value = np.asarray(value, dtype=np.float64)
            if value.shape != (n,):
                raise DatasetError(f"{name} must have shape ({n},) to match taps {taps.shape}, got {value.shape}")
            arrays[name] = value
        for name, value in arrays.items():
            bad = np.isinf(value) if name == "taps" else ~np.isfinite(value)
            if bad.any():
                first = int(np.argwhere(bad)[0][0])
                kind = "infinite values" if name == "taps" else "NaN or infinite values"
                raise DatasetError(f"{name} holds {kind} (first in tap {first})")
        _check_observed(taps)
        if self.front_end not in FRONT_ENDS:
            raise DatasetError(f"front_end must be one of {FRONT_ENDS}, got {self.front_end!r}")
        dims = taps.shape[2]
        names = tuple(str(n) for n in self.dim_names) or tuple(f"dim{k:02d}" for k in range(dims))
        if len(names) != dims:
            raise DatasetError(f"dim_names has {len(names)} names for {dims} dims")
        try:
            sensor = json.loads(json.dumps(dict(self.sensor or {})))
        except (TypeError, ValueError) as exc:
            raise DatasetError(f"sensor must be a JSON-serialisable dict: {exc}") from None
        for name, value in arrays.items():
            object.__setattr__(self, name, value)
        object.__setattr__(self, "dim_names", names)
        object.__setattr__(self, "sensor", sensor)
        period, labels = check_identity_labels(self.identity_period, self.identity_names, arrays["identity"])
        object.__setattr__(self, "identity_period", period)
        object.__setattr__(self, "identity_names", labels)

    def __repr__(self) -> str:
        return f"<Dataset {self.describe()}>"

    def __len__(self) -> int:
        """Number of taps N."""
        return self.taps.shape[0]

    @property
    def samples(self) -> int:
        """Time samples per tap."""
        return self.taps.shape[1]

    @property
    def observed(self) -> np.ndarray:
        """(N, samples, dims) bool: the values that are not missing (not NaN)."""
        return ~np.isnan(self.taps)

    @property
    def complete(self) -> bool:
        """Whether no value of any tap is missing."""
        return not np.isnan(self.taps).any()

    @property
    def dims(self) -> int:
        """Data dimensions per sample (2 per pin for the TacTip, 1 per taxel)."""
        return self.taps.shape[2]

    def subset(self, index) -> Dataset:
        """The dataset restricted to some taps.

        Parameters
        ----------
        index : (N,) bool array or int array
            Which taps to keep (a mask, or tap indices).
        """
        index = np.asarray(index)
        lateral = None if self.lateral is None else self.lateral[index]
        return Dataset(self.taps[index], self.location[index], self.identity[index], lateral, self.front_end,
                       self.location_unit, self.identity_unit, self.dim_names, self.sensor, self.identity_period,
                       self.identity_names)

    def describe(self) -> str:
        """One line: front end, taps, samples x dims, location and identity ranges."""
        def span(values, unit):
            if len(values) == 0:
                return "-"
            return f"{values.min():g}..{values.max():g} {unit} ({len(np.unique(values))} values)"
        incomplete = int(np.isnan(self.taps).any(axis=(1, 2)).sum())
        missing = f" ({incomplete} with missing dims)" if incomplete else ""
        return (f"{self.front_end} dataset: {len(self)} taps of {self.samples} samples x {self.dims} dims{missing}; "
                f"location {span(self.location, self.location_unit)}; identity {span(self.identity, self.identity_unit)}")
