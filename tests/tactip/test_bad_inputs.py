"""Bad inputs met by a probe of the CLI (issue 22): each a one-line error, never a traceback, nothing left behind."""

import struct
import zlib

import pytest

from tactip.cli import main


def _png_claiming(path, width, height):
    """A PNG whose header claims ``width`` x ``height`` px (with almost no data)."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    header = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(b"\0" * 100))
                     + chunk(b"IEND", b""))
    return path


@pytest.mark.parametrize("verb", ["detect", "replay"])
def test_an_image_claiming_more_pixels_than_the_decoder_takes_is_named(tmp_path, capsys, verb):
    image = _png_claiming(tmp_path / "huge.png", 60000, 60000)
    argv = [verb, str(image)] + (["--out", str(tmp_path / "r.h5")] if verb == "replay" else [])
    assert main(argv) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "larger than the decoder's limit (60000 x 60000 px)" in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["huge.png"]


@pytest.mark.parametrize("pins", ["0", "2000000"])
def test_a_synthetic_source_out_of_range_is_refused_before_recording(tmp_path, capsys, pins):
    assert main(["record", f"synthetic:{pins}", "--out", str(tmp_path / "x.mp4"), "--frames", "2", "--quiet"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"'synthetic:{pins}'" in err[0] and "pins must be an integer in 7..5000" in err[0]
    assert list(tmp_path.iterdir()) == []
