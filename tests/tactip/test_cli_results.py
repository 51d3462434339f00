"""`tactip results list|export` end to end on a small database."""

import csv
import io
import json

from tactip.cli import main
from tactip.results import ResultsStore


def _db(tmp_path):
    path = tmp_path / "results.sqlite"
    with ResultsStore(path) as store:
        for gap, est, decided in (("g01", 0.25, True), ("g02", 1.0, True), ("g03", None, False)):
            i = store.start_inspection(gap, nominal_width=0.5, tolerance=0.3, policy="active")
            store.finish_inspection(i, estimated_width=est, estimated_depth=4.0, belief=0.9, taps=3,
                                    decided=decided)
        i = store.start_inspection("g04", nominal_width=0.5, tolerance=0.3, policy="active")
        store.abort_inspection(i, "protective stop")
    return path


def test_list_shows_results(tmp_path, capsys):
    assert main(["results", "list", "--db", str(_db(tmp_path))]) == 0
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert "pass" in lines[2] and "FAIL" in lines[3] and "undecided" in lines[4] and "ABORTED" in lines[5]


def test_export_csv_and_json(tmp_path, capsys):
    db = _db(tmp_path)
    assert main(["results", "export", "--db", str(db), "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)
    assert [r["passed"] for r in rows] == [True, False, None, None]
    out = tmp_path / "r.csv"
    assert main(["results", "export", "--db", str(db), "--csv", "--out", str(out)]) == 0
    table = list(csv.DictReader(io.StringIO(out.read_text())))
    assert [r["gap"] for r in table] == ["g01", "g02", "g03", "g04"] and table[3]["status"] == "aborted"


def test_missing_database_is_one_line(tmp_path, capsys):
    assert main(["results", "list", "--db", str(tmp_path / "none.sqlite")]) == 1
    err = capsys.readouterr().err
    assert "no results database" in err and len(err.strip().splitlines()) == 1
