"""Calibration table and New Visibility (MSVD paper, Eq. 5, Tables 1 and 2)."""

from __future__ import annotations

import argparse
import csv
import json
import re
from itertools import pairwise
from pathlib import Path

import pytest

from seahaze.metric import cli as metric_cli
from seahaze.metric.errors import MetricInputError
from seahaze.metric.table import (
    Bound,
    CalibrationPoint,
    load_table,
    make_table,
    new_visibility,
    round_m,
    save_table,
)
from seahaze.visibility import regulation_class

DATA = Path(__file__).parent / "data" / "msvd_table2.csv"
PAPER = Path(__file__).resolve().parents[1] / ".." / "shared" / "reference" / "msvd-paper.tex"


def _table2_rows() -> list[dict[str, str]]:
    with DATA.open(encoding="utf-8") as fh:
        return list(csv.DictReader(fh))


def _baseline():
    rows = [r for r in _table2_rows() if r["method"] == "Baseline"]
    return make_table(
        [CalibrationPoint(float(r["visibility_m"]), float(r["map50"])) for r in rows],
        detector="YOLO11 (paper)",
    )


METHOD_ROWS = [r for r in _table2_rows() if r["method"] != "Baseline"]


def test_transcription_has_every_entry() -> None:
    assert len(_baseline().points) == 11
    assert len(METHOD_ROWS) == 66
    assert sum(r["new_vis_m"] == "-" for r in METHOD_ROWS) == 9


@pytest.mark.skipif(not PAPER.is_file(), reason="paper LaTeX not available")
def test_transcription_matches_the_paper_latex() -> None:
    tex = PAPER.read_text(encoding="utf-8")
    block = tex[tex.index(r"\label{tab2}") : tex.index(r"\end{tabularx}")]
    baseline = re.findall(r"\\textbf\{(0\.\d+)\}", block)
    assert baseline == [f"{p.map50:.3f}" for p in _baseline().points]
    cells = re.findall(r"\\viscell\{(\d+)\}\{([+-]\d+)\}|&\s*(-)\s*(?:\\\\|\n)", block)
    paper_new = [(a, g) if a else ("-", "") for a, g, _ in cells]
    # Method rows are ordered alike in the LaTeX (mAP block) and the CSV.
    maps = re.findall(r"\\citep\{[^}]*\}\s*&([^\\\n]*)\\\\", block)
    paper_maps = [x.strip() for row in maps for x in row.split("&")]
    assert paper_maps == [r["map50"] for r in METHOD_ROWS]
    assert paper_new == [(r["new_vis_m"], r["gain_m"]) for r in METHOD_ROWS]


@pytest.mark.parametrize(
    "row", METHOD_ROWS, ids=[f"{r['method']}-{r['visibility_m']}" for r in METHOD_ROWS]
)
def test_table2_new_visibility(row: dict[str, str]) -> None:
    """Every New Vis entry of Table 2 from the baseline row and the method's mAP50."""
    level = float(row["visibility_m"])
    result = new_visibility(_baseline(), float(row["map50"]), level)
    if row["new_vis_m"] == "-":
        # '-' = over 4000 m: reported as beyond the table, bounded by the top level.
        assert result.bound is Bound.ABOVE
        assert result.visibility_m == 4000
        return
    expected = int(row["new_vis_m"])
    if row["method"] == "SGIF-PFF" and level == 300:
        # 0.074 < 0.078: the paper reports the lowest level, 300 m (+0); we flag it as a bound.
        assert result.bound is Bound.BELOW
        assert result.visibility_m == 300
    else:
        assert result.bound is Bound.WITHIN
    assert abs(result.visibility_m - expected) <= 1
    assert abs(round_m(result.visibility_m) - level - int(row["gain_m"])) <= 1


def test_worked_example_and_regulation_classes() -> None:
    table = _baseline()
    # The hazy scene: 800 m, baseline mAP50 0.424 -> Restricted navigation.
    hazy = new_visibility(table, 0.424, 800)
    assert hazy.visibility_m == pytest.approx(800)
    assert hazy.regulation.key == "restricted"
    # AOD-Net: 0.444 -> 895 m, still below 1000 m -> Restricted navigation.
    weak = new_visibility(table, 0.444, 800)
    assert round_m(weak.visibility_m) == 895
    assert round_m(weak.gain_m or 0) == 95
    assert weak.regulation.key == "restricted"
    # IPC: 0.588 -> 2009 m (+1209 m). The paper's prose calls this "Minor Restrictions", but its
    # Table 1 (and seahaze.visibility) puts [2000, 4000) m in "Normal navigation"; Table 1 wins.
    strong = new_visibility(table, 0.588, 800)
    assert strong.bound is Bound.WITHIN
    assert strong.visibility_m == pytest.approx(2000 + 0.001 / 0.054 * 500)
    assert round_m(strong.visibility_m) == 2009
    assert round_m(strong.gain_m or 0) == 1209
    assert strong.regulation.key == "normal"
    assert regulation_class(1999.9).key == "minor"


def test_table_edges_are_inside() -> None:
    table = _baseline()
    assert new_visibility(table, 0.078).visibility_m == 300
    assert new_visibility(table, 0.078).bound is Bound.WITHIN
    top = new_visibility(table, 0.695)
    assert top.bound is Bound.WITHIN and top.visibility_m == pytest.approx(4000)
    assert new_visibility(table, 0.6950001).bound is Bound.ABOVE
    assert new_visibility(table, 0.0).bound is Bound.BELOW
    assert new_visibility(table, 1.0).regulation.key == "clear"


@pytest.mark.parametrize("value", [-0.1, 1.5, float("nan")])
def test_map_out_of_range_is_rejected(value: float) -> None:
    with pytest.raises(MetricInputError, match=r"\[0, 1\]"):
        new_visibility(_baseline(), value)


NON_MONOTONE = [(300, 0.1), (400, 0.3), (500, 0.25), (800, 0.4)]


def _table(points: list[tuple[float, float]]):
    return make_table([CalibrationPoint(v, m) for v, m in points])


def test_non_monotone_table_is_reported_and_uses_the_running_maximum() -> None:
    table = _table(NON_MONOTONE)
    assert not table.is_monotone
    assert [(a.visibility_m, b.visibility_m) for a, b in table.violations()] == [(400, 500)]
    assert table.envelope == (0.1, 0.3, 0.3, 0.4)
    # 0.28 lies in [300, 400] (first crossing) and also in the dip: lowest visibility wins.
    assert new_visibility(table, 0.28).visibility_m == pytest.approx(390)
    # Above the dip the envelope runs from (500 m, 0.3) to (800 m, 0.4); the raw first
    # crossing (500 m, 0.25) -> (800 m, 0.4) would give the larger 700 m.
    assert new_visibility(table, 0.35).visibility_m == pytest.approx(650)
    # On the plateau the lowest visibility is reported.
    assert new_visibility(table, 0.3).visibility_m == pytest.approx(400)


def test_best_value_not_at_the_top_level() -> None:
    table = _table([(300, 0.2), (400, 0.5), (500, 0.4)])
    above = new_visibility(table, 0.6)
    assert above.bound is Bound.ABOVE and above.visibility_m == 400
    assert new_visibility(table, 0.45).visibility_m == pytest.approx(300 + 0.25 / 0.3 * 100)


def test_monotone_table_equals_eq5_on_every_interval() -> None:
    table = _baseline()
    assert table.is_monotone
    pts = table.points
    for lo, hi in pairwise(pts):
        mid = (lo.map50 + hi.map50) / 2
        assert new_visibility(table, mid).visibility_m == pytest.approx(
            (lo.visibility_m + hi.visibility_m) / 2
        )


# ---------------------------------------------------------------- files


def test_save_and_load_round_trip(tmp_path: Path) -> None:
    table = make_table(
        [CalibrationPoint(800, 0.424, level="v0800"), CalibrationPoint(300, 1 / 3)],
        detector="yolo11n",
    )
    csv_path, json_path = save_table(table, tmp_path / "sub" / "t.json")
    assert (csv_path.name, json_path.name) == ("t.csv", "t.json")
    assert csv_path.read_text().splitlines() == [
        "visibility_m,map50",
        f"300,{1 / 3!r}",
        "800,0.424",
    ]
    doc = json.loads(json_path.read_text())
    assert doc["detector"] == "yolo11n" and doc["levels"][1]["level"] == "v0800"
    assert load_table(json_path) == table
    assert load_table(csv_path).map50s == table.map50s
    assert load_table(tmp_path / "sub" / "t").detector == "yolo11n"  # no suffix: JSON first


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("visibility_m,map50\n300,0.1\n", r"t\.csv: .*at least 2 levels"),
        ("visibility_m,map50\n300,0.1\n400,abc\n", r"t\.csv:3: map50 must be a number"),
        ("visibility_m,map50\n300,0.1\n400\n", r"t\.csv:3: expected 2 comma-separated"),
        ("vis,map\n300,0.1\n400,0.2\n", r"t\.csv:1: header must name the columns"),
        ("visibility_m,map50\n300,0.1\n400,1.2\n", r"t\.csv:3: map50 must be in \[0, 1\]"),
        ("visibility_m,map50\n300,0.1\n-400,0.2\n", r"t\.csv:3: visibility_m must be > 0"),
        ("visibility_m,map50\n300,0.1\n300,0.2\n", r"t\.csv: visibility 300 m appears twice"),
        ("", r"t\.csv: empty table"),
    ],
)
def test_bad_csv_tables(tmp_path: Path, text: str, message: str) -> None:
    path = tmp_path / "t.csv"
    path.write_text(text)
    with pytest.raises(MetricInputError, match=message):
        load_table(path)


def test_bad_json_and_missing_tables(tmp_path: Path) -> None:
    bad = tmp_path / "t.json"
    bad.write_text("{not json")
    with pytest.raises(MetricInputError, match=r"t\.json:1: not valid JSON"):
        load_table(bad)
    bad.write_text(json.dumps({"levels": [{"visibility_m": 300}]}))
    with pytest.raises(MetricInputError, match=r"levels\[0\] must be an object with"):
        load_table(bad)
    with pytest.raises(MetricInputError, match=r"nope\.csv: calibration table not found"):
        load_table(tmp_path / "nope.csv")


# ---------------------------------------------------------------- CLI (newvis --map)


def _run(argv: list[str]) -> int:
    parser = argparse.ArgumentParser(prog="seahaze")
    metric_cli.register(parser.add_subparsers(dest="command"))
    args = parser.parse_args(argv)
    return args.func(args)


@pytest.fixture
def paper_table(tmp_path: Path) -> Path:
    csv_path, _ = save_table(_baseline(), tmp_path / "paper")
    return csv_path


def test_cli_newvis_worked_example(paper_table: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert (
        _run(["metric", "newvis", "--table", str(paper_table), "--map", "0.588", "--level", "800"])
        == 0
    )
    out = capsys.readouterr().out
    assert "new visibility: 2009 m" in out
    assert "gain: +1209 m over 800 m" in out
    assert "regulation class: Normal navigation" in out


def test_cli_newvis_bounds(paper_table: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert (
        _run(
            ["metric", "newvis", "--table", str(paper_table), "--map", "0.733", "--level", "v4000"]
        )
        == 0
    )
    out = capsys.readouterr().out
    assert "new visibility: > 4000 m" in out and "the paper prints '-'" in out
    assert (
        _run(
            [
                "metric",
                "newvis",
                "--table",
                str(paper_table),
                "--map",
                "0.074",
                "--level",
                "300",
                "--json",
            ]
        )
        == 0
    )
    doc = json.loads(capsys.readouterr().out)
    assert doc["bound"] == "below" and doc["visibility_m"] == 300
    assert doc["regulation"]["qualifier"] == "at most"


def test_cli_newvis_warns_on_non_monotone(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "t.csv"
    path.write_text("visibility_m,map50\n" + "".join(f"{v},{m}\n" for v, m in NON_MONOTONE))
    assert _run(["metric", "newvis", "--table", str(path), "--map", "0.35"]) == 0
    captured = capsys.readouterr()
    assert "new visibility: 650 m" in captured.out
    assert "table is not monotone" in captured.err and "400 m" in captured.err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--map", "2"], "mAP50 must be a number in [0, 1]"),
        (["--map", "0.5", "--level", "abc"], "--level 'abc'"),
        ([], "give either --map VALUE or --pred DIR"),
        (["--pred", "x"], "--pred needs --dataset DIR and --level"),
    ],
)
def test_cli_newvis_bad_input(
    paper_table: Path, capsys: pytest.CaptureFixture[str], argv: list[str], message: str
) -> None:
    assert _run(["metric", "newvis", "--table", str(paper_table), *argv]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_cli_newvis_short_table(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "one.csv"
    path.write_text("visibility_m,map50\n300,0.1\n")
    assert _run(["metric", "newvis", "--table", str(path), "--map", "0.2"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("seahaze metric newvis: error: ") and "one.csv" in err
    assert "at least 2 levels" in err


def test_a_table_never_overwrites_a_file_seahaze_did_not_write(tmp_path) -> None:
    table = _baseline()
    mine = tmp_path / "t.csv"
    mine.write_text("my own spreadsheet\n")
    with pytest.raises(MetricInputError, match=r"t\.csv exists and is not a calibration table"):
        save_table(table, tmp_path / "t")
    assert mine.read_text() == "my own spreadsheet\n" and not (tmp_path / "t.json").exists()
    other = tmp_path / "o.json"
    other.write_text('{"format": "something else"}')
    with pytest.raises(MetricInputError, match=r"o\.json exists"):
        save_table(table, tmp_path / "o")
    assert other.read_text() == '{"format": "something else"}'
    # Its own table, written before, is replaced.
    csv_path, json_path = save_table(table, tmp_path / "again")
    assert save_table(table, tmp_path / "again") == (csv_path, json_path)
