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


def test_an_epsilon_that_drowns_the_counts_is_refused(tmp_path, capsys):
    from perception import save_dataset
    from tests.perception.synthetic import gap_dataset

    save_dataset(tmp_path / "train.h5", gap_dataset(seed=1, taps_per_class=2, depths=3, widths=2, samples=5, dims=4))
    assert main(["train", str(tmp_path / "train.h5"), "--out", str(tmp_path / "m.h5"), "--epsilon", "1e308"]) == 1
    assert "--epsilon must be a number in (0, 1e+06]" in capsys.readouterr().err
    assert not (tmp_path / "m.h5").exists()


def test_a_model_with_negative_tap_counts_is_refused(tmp_path, capsys):
    import h5py

    from perception import save_dataset
    from tests.perception.synthetic import gap_dataset

    save_dataset(tmp_path / "train.h5", gap_dataset(seed=1, taps_per_class=2, depths=3, widths=2, samples=5, dims=4))
    assert main(["train", str(tmp_path / "train.h5"), "--out", str(tmp_path / "m.h5"), "--locations", "3"]) == 0
    with h5py.File(tmp_path / "m.h5", "a") as f:
        counts = f["taps_per_class"][()]
        del f["taps_per_class"]
        f["taps_per_class"] = counts * 0 - 3
    capsys.readouterr()
    assert main(["validate", str(tmp_path / "m.h5"), str(tmp_path / "train.h5"), "--runs", "10", "--quiet"]) == 1
    assert "taps_per_class must hold a whole number >= 0" in capsys.readouterr().err


def test_an_unknown_gap_is_refused_before_the_simulated_station_prepares(tmp_path, monkeypatch, capsys):
    """inspect --sim --gap g99 trained for 541 s before saying there is no g99: now it says so at once."""
    monkeypatch.setenv("TACTIP_SIM_DIR", str(tmp_path / "sim"))
    assert main(["inspect", "--sim", "--gap", "g99", "--quiet"]) == 1
    captured = capsys.readouterr()
    assert f"simulated station in {tmp_path / 'sim'}" in captured.out
    assert "no gap 'g99' on station" in captured.err and "g01, g02" in captured.err
    assert not (tmp_path / "sim").exists()                     # nothing calibrated, collected or trained


def test_the_simulated_station_lives_in_one_place_whatever_the_folder(tmp_path, monkeypatch):
    from tactip.station.config import default_sim_dir, simulated_station_config

    monkeypatch.delenv("TACTIP_SIM_DIR", raising=False)
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    places = set()
    for here in (tmp_path / "a", tmp_path / "b"):
        here.mkdir()
        monkeypatch.chdir(here)
        places.add(simulated_station_config().data_dir)
    assert places == {tmp_path / "data" / "tactip" / "sim"} == {default_sim_dir()}


@pytest.mark.parametrize("verb", ["inspect", "serve"])
def test_data_dir_without_sim_is_refused_not_ignored(tmp_path, capsys, verb):
    from pathlib import Path

    toml = Path(__file__).parents[2] / "samples" / "station_sim.toml"
    argv = [verb, "--config", str(toml), "--data-dir", str(tmp_path / "x")]
    assert main(argv) == 1
    assert "--data-dir goes with --sim" in capsys.readouterr().err


@pytest.mark.parametrize("source", [7, "/etc/passwd"])
def test_a_source_the_simulated_arm_would_ignore_is_refused(tmp_path, source):
    from tactip.station.config import ConfigError, parse_station_config
    from tests.tactip.conftest import small_station_table

    table = small_station_table(tmp_path, sensor={"source": source})
    with pytest.raises(ConfigError, match='sensor.source must be "synthetic" with the simulated arm'):
        parse_station_config(table, base_dir=tmp_path)


def test_a_model_of_another_kind_than_the_station_names_is_refused(sim_station, tmp_path):
    from perception import ModelError
    from tactip.station.config import parse_station_config
    from tactip.station.inspection import load_station_model
    from tests.tactip.conftest import small_station_table

    table = small_station_table(sim_station.root, perception={"likelihood": "gaussian"})   # its model: histogram
    config = parse_station_config(table, base_dir=sim_station.root)
    with pytest.raises(ModelError, match='is a histogram model but \\[perception\\] likelihood = "gaussian"'):
        load_station_model(config, sim_station.calibration)


def test_a_decision_threshold_without_a_model_is_refused_not_ignored(tmp_path, capsys):
    from pathlib import Path

    video = Path(__file__).parents[2] / "samples" / "synthetic_tap.mp4"
    assert main(["replay", str(video), "--out", str(tmp_path / "r.h5"), "--decision-threshold", "0.8"]) == 1
    assert "--decision-threshold sets the model's decisions: it needs --model" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("count", ["1e30", "1000000000000000000000000000000", "0"])
def test_an_expected_pin_count_beyond_any_pad_is_refused_not_warned_about(capsys, count):
    from pathlib import Path

    frame = Path(__file__).resolve().parents[2] / "samples" / "synthetic_frame.png"
    with pytest.raises(SystemExit) as exit_:
        main(["detect", str(frame), "--expected-pins", count])
    err = capsys.readouterr().err.strip().splitlines()
    assert exit_.value.code == 2 and "--expected-pins" in err[-1] and "%" not in err[-1]


@pytest.mark.parametrize("argv", [["detect", "{frame}", "--annotate", "{loop}"], ["detect", "{frame}", "--json", "{loop}"],
                                  ["record", "synthetic", "--frames", "2", "--out", "{loop}"]])
def test_a_symlink_loop_as_an_output_is_one_line(tmp_path, capsys, argv):
    from pathlib import Path

    frame = Path(__file__).resolve().parents[2] / "samples" / "synthetic_frame.png"
    (tmp_path / "a.png").symlink_to(tmp_path / "b.png")
    (tmp_path / "b.png").symlink_to(tmp_path / "a.png")
    words = [w.format(frame=frame, loop=tmp_path / "a.png") for w in argv]
    with pytest.raises(SystemExit) as exit_:
        main(words)
    err = capsys.readouterr().err.strip().splitlines()
    assert exit_.value.code == 2 and "Too many levels of symbolic links" in err[-1] and "Traceback" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.png", "b.png"]
