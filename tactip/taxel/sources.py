"""Taxel reading sources: a recorded CSV file and a live UDP stream, with one reading interface.

CSV file
    One reading per line: the timestamp in seconds, then one column per taxel (raw 8-bit counts),
    comma separated. An optional header line (``timestamp_s,taxel00,...``) and ``#`` comments are
    skipped. `write_taxel_csv` writes this format.
UDP datagrams
    One datagram per reading, in one of two encodings:

    - ``"binary"`` (default): little-endian ``struct`` format ``"<d" + K * "B"``: the timestamp as a
      float64 in seconds, then one unsigned byte per taxel (20 bytes for the 12-taxel fingertip,
      56 for the 48-taxel skin);
    - ``"ascii"``: the CSV line of the reading in ASCII, e.g. ``b"12.34,235,236,...\\n"``.

    `UdpTaxelSource` binds a socket (port 0: an ephemeral port, see ``address``) and waits at most
    ``timeout_s`` per reading: a silent sender or a malformed datagram raises `SourceError` naming the
    problem. `UdpTaxelSender` is the matching sender (used by tests and to replay recordings).

Every source yields `TaxelReading` objects (``read()``, iteration) and reads blocks for the
pre-processing (``read_block``); `read_taps` turns any source into pre-processed taps through a
`TapSegmenter`, the same arrays the simulator and the optical front end give.

Example
-------
>>> with UdpTaxelSource(12, port=0, timeout_s=2.0) as source:       # doctest: +SKIP
...     for tap in read_taps(source, TapSegmenter(12), max_taps=5):
...         print(tap.shape)                                          # (50, 12)
"""

from __future__ import annotations

import pathlib
import socket
import struct
from dataclasses import dataclass
from typing import Iterator

import numpy as np

from tactip.errors import SourceError
from tactip.taxel.segment import TapSegmenter

__all__ = [
    "ENCODINGS", "TaxelReading", "TaxelSource", "CsvTaxelSource", "UdpTaxelSource", "UdpTaxelSender",
    "encode_reading", "decode_reading", "write_taxel_csv", "read_taps",
]

ENCODINGS = ("binary", "ascii")


@dataclass(frozen=True)
class TaxelReading:
    """One reading of every taxel.

    Attributes
    ----------
    timestamp_s : float
        Time of the reading, s (the sender's clock).
    values : (K,) ndarray of float64
        Raw reading of each taxel, counts.
    """

    timestamp_s: float
    values: np.ndarray


def encode_reading(timestamp_s: float, values, *, encoding: str = "binary") -> bytes:
    """One datagram for a reading (format in the module docstring).

    Parameters
    ----------
    timestamp_s : float
    values : (K,) array_like of int in 0..255
    encoding : {"binary", "ascii"}
    """
    v = np.asarray(values)
    if encoding == "binary":
        if v.ndim != 1 or np.any(v < 0) or np.any(v > 255):
            raise ValueError("values must be a 1-D array of 0..255 counts for the binary encoding")
        return struct.pack(f"<d{len(v)}B", float(timestamp_s), *np.rint(v).astype(np.uint8).tolist())
    if encoding == "ascii":
        return (f"{float(timestamp_s):.6f}," + ",".join(f"{x:g}" for x in v.tolist()) + "\n").encode("ascii")
    raise ValueError(f"unknown encoding {encoding!r}; choose from {', '.join(ENCODINGS)}")


def decode_reading(datagram: bytes, taxels: int, *, encoding: str = "binary") -> TaxelReading:
    """Parse one datagram.

    Parameters
    ----------
    datagram : bytes
    taxels : int
        Expected number of taxels ``K``.
    encoding : {"binary", "ascii"}

    Raises
    ------
    SourceError
        The datagram does not hold one reading of ``taxels`` values in that encoding.
    """
    if encoding == "binary":
        size = 8 + taxels
        if len(datagram) != size:
            raise SourceError(f"malformed taxel datagram: expected {size} bytes ('<d' + {taxels} 'B'), "
                              f"got {len(datagram)}")
        timestamp = struct.unpack_from("<d", datagram)[0]
        values = np.frombuffer(datagram, dtype=np.uint8, offset=8).astype(np.float64)
    elif encoding == "ascii":
        try:
            fields = [float(x) for x in datagram.decode("ascii").strip().split(",")]
        except (UnicodeDecodeError, ValueError):
            raise SourceError(f"malformed taxel datagram: not an ASCII CSV line: {datagram[:40]!r}") from None
        if len(fields) != taxels + 1:
            raise SourceError(f"malformed taxel datagram: expected a timestamp and {taxels} values, "
                              f"got {len(fields)} fields")
        timestamp, values = fields[0], np.array(fields[1:])
    else:
        raise ValueError(f"unknown encoding {encoding!r}; choose from {', '.join(ENCODINGS)}")
    if not np.isfinite(timestamp) or not np.all(np.isfinite(values)):
        raise SourceError("malformed taxel datagram: non-finite timestamp or value")
    return TaxelReading(float(timestamp), values)


class TaxelSource:
    """Base of the taxel sources: iteration, blocks and a context manager around ``read``.

    Attributes
    ----------
    taxels : int
        Number of taxels ``K``.
    live : bool
        True for a live stream (no end; a timeout is an error).
    """

    taxels: int
    live: bool = False

    def read(self) -> TaxelReading | None:
        """The next reading, or None at the end of a recording."""
        raise NotImplementedError

    def read_block(self, max_readings: int) -> tuple[np.ndarray, np.ndarray]:
        """Up to ``max_readings`` readings: ``(timestamps (T,), values (T, K))`` (T = 0 at the end)."""
        readings = []
        for _ in range(int(max_readings)):
            reading = self.read()
            if reading is None:
                break
            readings.append(reading)
        t = np.array([r.timestamp_s for r in readings], dtype=np.float64)
        v = np.array([r.values for r in readings], dtype=np.float64).reshape(len(readings), self.taxels)
        return t, v

    def close(self) -> None:
        """Release the source (idempotent)."""

    def __iter__(self) -> Iterator[TaxelReading]:
        while (reading := self.read()) is not None:
            yield reading

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()


class CsvTaxelSource(TaxelSource):
    """Readings recorded in a CSV file (timestamp in s, then one column of counts per taxel).

    Parameters
    ----------
    path : str or os.PathLike
    taxels : int, optional
        Expected number of taxels; default: all columns after the timestamp.

    Raises
    ------
    SourceError
        Missing or unreadable file, no readings, a malformed line, the wrong number of columns,
        or timestamps that do not increase (the message names the file).
    """

    live = False

    def __init__(self, path, *, taxels: int | None = None):
        self.path = pathlib.Path(path)
        if not self.path.is_file():
            raise SourceError(f"taxel recording not found: {self.path}")
        try:
            with open(self.path, encoding="ascii") as f:
                lines = [line for line in f if line.strip() and not line.lstrip().startswith("#")]
        except (OSError, UnicodeDecodeError) as exc:
            raise SourceError(f"cannot read taxel recording {self.path}: {exc}") from None
        if lines and not _is_number(lines[0].split(",")[0]):
            lines = lines[1:]                                  # header
        if not lines:
            raise SourceError(f"taxel recording {self.path} holds no readings")
        try:
            data = np.loadtxt(lines, delimiter=",", ndmin=2, dtype=np.float64)
        except ValueError as exc:
            raise SourceError(f"malformed taxel recording {self.path}: {exc}") from None
        if data.shape[1] < 2 or (taxels is not None and data.shape[1] != taxels + 1):
            expected = "at least 1" if taxels is None else str(taxels)
            raise SourceError(f"taxel recording {self.path} has {data.shape[1] - 1} taxel columns, expected {expected}")
        if not np.all(np.isfinite(data)):
            raise SourceError(f"taxel recording {self.path} holds non-finite values")
        if np.any(np.diff(data[:, 0]) <= 0):
            raise SourceError(f"taxel recording {self.path}: timestamps must increase")
        self.timestamps_s = data[:, 0]
        self.readings = data[:, 1:]
        self.taxels = self.readings.shape[1]
        self._next = 0

    def __repr__(self) -> str:
        return f"CsvTaxelSource({str(self.path)!r}, taxels={self.taxels}, readings={len(self.timestamps_s)})"

    def read(self) -> TaxelReading | None:
        """The next reading, or None at the end of the file."""
        if self._next >= len(self.timestamps_s):
            return None
        i = self._next
        self._next += 1
        return TaxelReading(float(self.timestamps_s[i]), self.readings[i].copy())

    def read_block(self, max_readings: int) -> tuple[np.ndarray, np.ndarray]:
        """Up to ``max_readings`` readings as arrays (vectorised slice of the file)."""
        i, j = self._next, min(self._next + int(max_readings), len(self.timestamps_s))
        self._next = j
        return self.timestamps_s[i:j].copy(), self.readings[i:j].copy()


class UdpTaxelSource(TaxelSource):
    """Live readings received as UDP datagrams on a bound socket (format in the module docstring).

    Parameters
    ----------
    taxels : int
        Number of taxels ``K`` per reading.
    host : str
        Address to bind (``"127.0.0.1"``; ``"0.0.0.0"`` for every interface).
    port : int
        Port to bind; 0 picks a free ephemeral port (see ``address``).
    timeout_s : float
        Longest wait for one reading, s.
    encoding : {"binary", "ascii"}

    Raises
    ------
    SourceError
        The socket cannot be bound; later, from `read`: no reading within ``timeout_s`` or a
        malformed datagram.
    """

    live = True

    def __init__(self, taxels: int, *, host: str = "127.0.0.1", port: int = 0, timeout_s: float = 1.0,
                 encoding: str = "binary"):
        if encoding not in ENCODINGS:
            raise ValueError(f"unknown encoding {encoding!r}; choose from {', '.join(ENCODINGS)}")
        if not timeout_s > 0:
            raise ValueError(f"timeout_s must be > 0, got {timeout_s}")
        self.taxels = int(taxels)
        self.encoding = encoding
        self.timeout_s = float(timeout_s)
        self._socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        try:
            self._socket.bind((host, int(port)))
        except OSError as exc:
            self._socket.close()
            raise SourceError(f"cannot bind UDP taxel source to {host}:{port}: {exc.strerror or exc}") from None
        self._socket.settimeout(self.timeout_s)
        self.address: tuple[str, int] = self._socket.getsockname()

    def __repr__(self) -> str:
        host, port = self.address
        return f"UdpTaxelSource({self.taxels}, udp://{host}:{port}, encoding={self.encoding!r})"

    def read(self) -> TaxelReading:
        """The next reading (waits at most ``timeout_s``).

        Raises
        ------
        SourceError
            Timeout, a closed source, or a malformed datagram.
        """
        if self._socket.fileno() < 0:
            raise SourceError("UDP taxel source is closed")
        try:
            datagram = self._socket.recv(65536)
        except socket.timeout:
            host, port = self.address
            raise SourceError(f"no taxel reading within {self.timeout_s:g} s on udp://{host}:{port}") from None
        return decode_reading(datagram, self.taxels, encoding=self.encoding)

    def close(self) -> None:
        """Close the socket (idempotent)."""
        self._socket.close()


class UdpTaxelSender:
    """Send readings as UDP datagrams to a `UdpTaxelSource` (or any receiver of the format).

    Parameters
    ----------
    address : tuple of (str, int)
        Destination host and port.
    encoding : {"binary", "ascii"}
    """

    def __init__(self, address: tuple[str, int], *, encoding: str = "binary"):
        if encoding not in ENCODINGS:
            raise ValueError(f"unknown encoding {encoding!r}; choose from {', '.join(ENCODINGS)}")
        self.address = (str(address[0]), int(address[1]))
        self.encoding = encoding
        self._socket = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)

    def send(self, timestamp_s: float, values) -> None:
        """Send one reading."""
        self._socket.sendto(encode_reading(timestamp_s, values, encoding=self.encoding), self.address)

    def send_raw(self, datagram: bytes) -> None:
        """Send arbitrary bytes (for testing receivers)."""
        self._socket.sendto(datagram, self.address)

    def close(self) -> None:
        """Close the socket (idempotent)."""
        self._socket.close()

    def __enter__(self) -> UdpTaxelSender:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def write_taxel_csv(path, timestamps_s, readings) -> None:
    """Write readings as a CSV recording (header, then timestamp and one column per taxel).

    Parameters
    ----------
    path : str or os.PathLike
    timestamps_s : (T,) array_like
        Reading times, s.
    readings : (T, K) array_like
        Raw readings, counts (integers are written as integers).
    """
    t = np.asarray(timestamps_s, dtype=np.float64)
    v = np.asarray(readings)
    if v.ndim != 2 or t.shape != (len(v),):
        raise ValueError(f"timestamps_s (T,) and readings (T, K) do not match: {t.shape} and {v.shape}")
    header = "timestamp_s," + ",".join(f"taxel{k:02d}" for k in range(v.shape[1]))
    value_format = "%d" if np.issubdtype(v.dtype, np.integer) else "%.6g"
    from _shared import atomic_path

    with atomic_path(path) as tmp:  # temporary name, fsync, rename: a full disk leaves no half a recording
        np.savetxt(tmp, np.column_stack([t, v]), delimiter=",", header=header, comments="",
                   fmt=["%.6f"] + [value_format] * v.shape[1])


def read_taps(source: TaxelSource, segmenter: TapSegmenter | None = None, *, max_taps: int | None = None,
              block: int = 50) -> Iterator[np.ndarray]:
    """Pre-processed taps from a source, as they complete.

    Parameters
    ----------
    source : TaxelSource
    segmenter : TapSegmenter, optional
        How to cut taps (default: by magnitude, with the source's taxel count).
    max_taps : int, optional
        Stop after this many taps (a live source otherwise reads until it times out).
    block : int
        Readings per block fed to the segmenter.

    Yields
    ------
    (samples, K) ndarray of float32
    """
    segmenter = segmenter or TapSegmenter(source.taxels)
    count = 0
    while max_taps is None or count < max_taps:
        t, values = source.read_block(1 if source.live else block)
        if len(t) == 0:
            return
        for tap in segmenter.feed(t, values):
            yield tap
            count += 1
            if max_taps is not None and count >= max_taps:
                return


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True
