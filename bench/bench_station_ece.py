"""ECE of the torch model's width belief after 1, 3 and 5 taps on the small simulated station, per collection seed.

Builds the test suite's small station (four gaps, 0.5 mm depth step, ``--repeats`` taps per depth) for each
collection seed (``[protocol] seed`` and ``[sim] seed``), prepares it with ``likelihood = "torch"`` (train,
fixation, threshold and tap tempering on held-out training taps), then runs ``tactip validate --policy active
--json`` on the test collection and prints the ECE after 1, 3 and 5 taps and the tap tempering written.
Slow (minutes per seed). Usage: ``python bench/bench_station_ece.py --seeds 0 1 2 --out /tmp/ece``.
"""

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from perception import load_model  # noqa: E402
from tactip.station.config import parse_station_config  # noqa: E402
from tactip.station.procedures import prepare_model  # noqa: E402
from tests.tactip.conftest import run_cli, small_station_table, write_station  # noqa: E402


def measure(root: Path, seed: int, repeats: int, runs: int) -> dict:
    """Build, prepare and validate one station; its ECE after 1, 3 and 5 taps and its schedule."""
    table = small_station_table(root, perception={"likelihood": "torch"}, protocol={"seed": seed, "repeats": repeats},
                                sim={"seed": seed})
    toml = write_station(root, table)
    for command in (["calibrate", "--config", toml],
                    ["collect", "--config", toml, "--out", root / "datasets", "--workers", "2", "--quiet"]):
        if not (root / "datasets" / "test.h5").exists() or command[0] == "calibrate" and \
                not (root / "calibration.h5").exists():
            code, _, err = run_cli(command)
            if code != 0:
                raise SystemExit(err)
    lines = []
    prepare_model(parse_station_config(table, base_dir=root), progress=False, log=lines.append)
    out = root / "validation.json"
    code, _, err = run_cli(["validate", root / "model.h5", root / "datasets" / "test.h5", "--policy", "active",
                            "--runs", str(runs), "--json", out, "--quiet"])
    if code != 0:
        raise SystemExit(err)
    row = json.loads(out.read_text())[0]
    model = load_model(root / "model.h5")
    return {"seed": seed, "repeats": repeats, "ece": [row[f"ece_{t}_taps"] for t in (1, 3, 5)],
            "tap_tempering": list(model.tap_tempering), "tempering": model.tempering,
            "recommended": model.recommended, "lines": [line for line in lines if "fixation depth" in line]}


def main() -> None:
    """Measure every seed asked for and print one JSON line each."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--runs", type=int, default=1000)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    for seed in args.seeds:
        result = measure(args.out / f"seed{seed}_r{args.repeats}", seed, args.repeats, args.runs)
        print(json.dumps(result), flush=True)


if __name__ == "__main__":
    main()
