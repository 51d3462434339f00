"""Taxel sources: CSV recordings and live UDP datagrams give the same taps as the simulator."""

import struct
import threading
import time

import numpy as np
import pytest

from perception import load_dataset
from tactip.errors import SourceError
from tactip.taxel import (CsvTaxelSource, TapSegmenter, TaxelSimulator, UdpTaxelSender, UdpTaxelSource,
                          decode_reading, encode_reading, read_taps, segment_taps, simulate_taxel_datasets,
                          taxel_pressure, write_taxel_csv, write_taxel_test_stream)


@pytest.fixture(scope="module")
def stream():
    """A short fingertip stream: a miss, then four contacts."""
    return TaxelSimulator("fingertip", seed=11).stream([1.0, 9.0, 12.0, 15.0, 18.0], seed=1)


def test_csv_round_trip(tmp_path, stream):
    path = tmp_path / "taps.csv"
    write_taxel_csv(path, stream.timestamps_s, stream.readings)
    assert path.read_text().splitlines()[0].startswith("timestamp_s,taxel00,taxel01")
    source = CsvTaxelSource(path, taxels=12)
    np.testing.assert_allclose(source.timestamps_s, stream.timestamps_s, atol=1e-6)
    np.testing.assert_array_equal(source.readings, stream.readings)
    first = source.read()
    assert first.timestamp_s == pytest.approx(0.0) and first.values.tolist() == stream.readings[0].tolist()
    t, v = source.read_block(10)
    np.testing.assert_array_equal(v, stream.readings[1:11])
    assert len(list(source)) == len(stream.readings) - 11 and source.read() is None


def test_csv_without_header_and_with_comments(tmp_path):
    path = tmp_path / "plain.csv"
    path.write_text("# recorded by hand\n0.00,235,236\n0.02,230,236\n\n0.04,231,235\n")
    source = CsvTaxelSource(path)
    assert source.taxels == 2 and source.readings[:, 0].tolist() == [235, 230, 231]


@pytest.mark.parametrize("content, message", [
    (None, "not found"),
    ("", "holds no readings"),
    ("timestamp_s,taxel00\n0.0,235\n0.02,abc\n", "malformed"),
    ("0.0,235,235\n0.02,235\n", "malformed"),
    ("0.0,235,235\n0.02,235,235\n", "has 2 taxel columns, expected 12"),
    ("0.0,235\n0.0,235\n", "timestamps must increase"),
    ("0.0,235\n0.02,nan\n", "non-finite"),
])
def test_csv_errors_name_the_problem(tmp_path, content, message):
    path = tmp_path / "bad.csv"
    if content is not None:
        path.write_text(content)
    with pytest.raises(SourceError, match=message):
        CsvTaxelSource(path, taxels=12 if "expected 12" in message else None)


def test_csv_recording_gives_the_datasets_taps(tmp_path):
    # The raw test stream written as CSV, read back and segmented at the tap commands, is test.h5.
    paths = simulate_taxel_datasets(tmp_path, sensor="fingertip", seed=5, locations=40)
    csv = write_taxel_test_stream(tmp_path / "test_stream.csv", sensor="fingertip", seed=5, locations=40)
    source = CsvTaxelSource(csv)
    starts = np.arange(40) * 2.0                                 # one tap command every 2 s
    taps = segment_taps(source.timestamps_s, taxel_pressure(source.readings), starts_s=starts).taps
    np.testing.assert_allclose(taps, load_dataset(paths.test).taps, atol=1e-5)


def test_csv_source_through_the_streaming_segmenter(tmp_path, stream):
    path = tmp_path / "taps.csv"
    write_taxel_csv(path, stream.timestamps_s, stream.readings)
    taps = list(read_taps(CsvTaxelSource(path), TapSegmenter(12)))
    batch = segment_taps(stream.timestamps_s, taxel_pressure(stream.readings)).taps
    assert len(taps) == 4 and np.stack(taps).shape == (4, 50, 12)
    np.testing.assert_allclose(np.stack(taps), batch, atol=1e-5)


@pytest.mark.parametrize("encoding", ["binary", "ascii"])
def test_datagram_encodings_round_trip(encoding):
    values = np.array([235, 0, 255, 17] * 3)
    datagram = encode_reading(12.5, values, encoding=encoding)
    if encoding == "binary":
        assert len(datagram) == 20 and struct.unpack("<d", datagram[:8])[0] == 12.5
    else:
        assert datagram.startswith(b"12.500000,235,0,255,17")
    reading = decode_reading(datagram, 12, encoding=encoding)
    assert reading.timestamp_s == 12.5 and reading.values.tolist() == values.tolist()


@pytest.mark.parametrize("datagram, encoding, message", [
    (b"\x00" * 7, "binary", "expected 20 bytes"),
    (b"1.0,2,3", "ascii", "expected a timestamp and 12 values"),
    (b"\xff\xfe garbage", "ascii", "not an ASCII CSV line"),
    (b"1.0," + b"nan," * 11 + b"1", "ascii", "non-finite"),
])
def test_malformed_datagrams_are_refused(datagram, encoding, message):
    with pytest.raises(SourceError, match=message):
        decode_reading(datagram, 12, encoding=encoding)


@pytest.mark.parametrize("encoding", ["binary", "ascii"])
def test_udp_source_receives_readings_on_an_ephemeral_port(encoding, stream):
    with UdpTaxelSource(12, port=0, timeout_s=2.0, encoding=encoding) as source, \
            UdpTaxelSender(source.address, encoding=encoding) as sender:
        host, port = source.address
        assert host == "127.0.0.1" and port > 0 and source.live
        for i in range(20):
            sender.send(stream.timestamps_s[i], stream.readings[i])
        t, v = source.read_block(20)
    np.testing.assert_allclose(t, stream.timestamps_s[:20], atol=1e-6)
    np.testing.assert_array_equal(v, stream.readings[:20])


def test_udp_timeout_and_garbage_raise_source_error():
    with UdpTaxelSource(12, port=0, timeout_s=0.2) as source:
        began = time.monotonic()
        with pytest.raises(SourceError, match=r"no taxel reading within 0.2 s on udp://127.0.0.1:\d+"):
            source.read()
        assert time.monotonic() - began < 10.0                 # the timeout fired (a bound on a hang, not a speed)
        with UdpTaxelSender(source.address) as sender:
            sender.send_raw(b"not a reading")
            with pytest.raises(SourceError, match="expected 20 bytes"):
                source.read()
    with pytest.raises(SourceError, match="closed"):
        source.read()


def test_udp_bind_failure_is_a_source_error():
    with UdpTaxelSource(12, port=0) as first:
        with pytest.raises(SourceError, match="cannot bind"):
            UdpTaxelSource(12, port=first.address[1])


def test_live_udp_stream_gives_the_same_taps_as_the_recording(stream):
    """A sender thread streams readings; read_taps cuts them as they arrive (bounded by timeouts)."""
    with UdpTaxelSource(12, port=0, timeout_s=3.0) as source:
        stop = threading.Event()

        def send():
            with UdpTaxelSender(source.address) as sender:
                for i in range(len(stream.readings)):
                    if stop.is_set():
                        return
                    sender.send(stream.timestamps_s[i], stream.readings[i])
                    if i % 10 == 9:
                        time.sleep(0.005)                          # paced: a UDP receiver buffer is finite

        thread = threading.Thread(target=send, daemon=True)
        thread.start()
        try:
            taps = list(read_taps(source, TapSegmenter(12), max_taps=4))
        finally:
            stop.set()
            thread.join(timeout=5.0)
    assert not thread.is_alive()
    batch = segment_taps(stream.timestamps_s, taxel_pressure(stream.readings)).taps
    np.testing.assert_allclose(np.stack(taps), batch, atol=1e-5)
