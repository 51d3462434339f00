"""`tactip results list|export` end to end on a small database."""

import csv
import io
import json

from tactip.cli import main
from tactip.line.results import ResultsStore


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


def test_plot_draws_the_finished_inspections(tmp_path, capsys):
    import matplotlib.image

    out = tmp_path / "widths.png"
    assert main(["results", "plot", "--db", str(_db(tmp_path)), "--out", str(out)]) == 0
    image = matplotlib.image.imread(out)
    assert image.shape[0] > 300 and image.shape[1] > 300
    # red fail markers are drawn (g02 failed), not only the grey tolerance bands and green passes
    red = (image[..., 0] > 0.7) & (image[..., 1] < 0.3) & (image[..., 2] < 0.3)
    assert red.sum() > 10


def test_plot_with_nothing_finished_is_one_line(tmp_path, capsys):
    path = tmp_path / "r.sqlite"
    with ResultsStore(path) as store:
        store.abort_inspection(store.start_inspection("g1", nominal_width=1, tolerance=0.1, policy="active"), "stop")
    assert main(["results", "plot", "--db", str(path), "--out", str(tmp_path / "x.png")]) == 1
    assert "no finished inspections" in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()
