"""`tactip calibrate --frames`: a user with recordings and no station calibrates on their rest frames
(issue 20, outcome 5: detect, calibrate and replay derive one scale from the same frames).

Before, `tactip calibrate` needed a station TOML; a video source needs a real arm ("sensor.source must
be 'synthetic' with the simulated arm"), so a user with recordings alone could not run it at all.
"""

import cv2
import numpy as np
import pytest

from calibration import load_calibration
from pins import find_pin_field, sensor_scale
from tactip.cli import main
from tactip.sim import SyntheticTacTip


@pytest.mark.parametrize("name, seed", [("radial-led-120", 11), ("white-dark-331", 12)])
def test_calibrate_on_rest_frames_agrees_with_detect_and_the_truth(tmp_path, capsys, name, seed):
    sensor = SyntheticTacTip.from_preset(name, seed=seed)
    folder = tmp_path / "rest"
    folder.mkdir()
    frames = [sensor.render().image for _ in range(3)]
    for k, image in enumerate(frames):
        cv2.imwrite(str(folder / f"{k:02d}.png"), image)
    out = tmp_path / "cal.h5"
    assert main(["calibrate", "--frames", str(folder), "--sensor", name, "--rest-frames", "3", "--out", str(out)]) == 0
    assert "calibrated on 3 rest frames" in capsys.readouterr().out
    calibrated = load_calibration(out)
    detect = sensor_scale(find_pin_field(frames[0]).centres, sensor=name).mm_per_px
    assert calibrated.mm_per_px == pytest.approx(detect, rel=0.02)
    assert calibrated.mm_per_px == pytest.approx(sensor.mm_per_px, rel=0.03)
    truth = sensor.rest_centres[sensor.pin_centres()[1]]
    distance = np.linalg.norm(calibrated.reference_pins[:, None] - truth[None], axis=2).min(axis=1)
    assert len(calibrated.reference_pins) >= 0.97 * len(truth) and np.all(distance < 1.0)
    assert calibrated.n_selected == 40


def test_calibrate_frames_of_a_video_replays_with_the_calibration(tmp_path, capsys):
    sensor = SyntheticTacTip.from_preset("radial-led-120", seed=13)
    video = tmp_path / "taps.avi"
    writer = cv2.VideoWriter(str(video), cv2.VideoWriter_fourcc(*"MJPG"), 120.0, sensor.image_size, True)
    for frame in sensor.taps(1, indentation_mm=2.5, rest_s=0.05, press_s=0.05, hold_s=0.05, lift_s=0.05):
        writer.write(cv2.cvtColor(frame.image, cv2.COLOR_GRAY2BGR))
    writer.release()
    cal = tmp_path / "cal.h5"
    assert main(["calibrate", "--frames", str(video), "--sensor", "radial-led-120", "--rest-frames", "4",
                 "--out", str(cal)]) == 0
    assert main(["replay", str(video), "--out", str(tmp_path / "r.h5"), "--calibration", str(cal), "--quiet"]) == 0
    capsys.readouterr()


def test_calibrate_frames_needs_an_output_and_keeps_station_flags_apart(tmp_path, capsys):
    image = tmp_path / "rest.png"
    cv2.imwrite(str(image), SyntheticTacTip.from_preset("tactip-127", seed=1).render().image)
    assert main(["calibrate", "--frames", str(image)]) == 1
    assert "--frames needs --out" in capsys.readouterr().err
    assert main(["calibrate", "--config", str(tmp_path / "s.toml"), "--pins-on-pad", "127"]) == 1
    assert "--pins-on-pad go with --frames" in capsys.readouterr().err
    with pytest.raises(SystemExit):  # one or the other
        main(["calibrate", "--frames", str(image), "--config", str(tmp_path / "s.toml"), "--out", str(tmp_path / "c")])
    capsys.readouterr()
