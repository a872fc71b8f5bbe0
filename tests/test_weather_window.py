"""The weather window (issue 44): the bad-forecast corpus, the alpha tables, a forecast whose
windows are known, and the command's JSON. No simulation: the operability table is given."""

from __future__ import annotations

import json
import subprocess
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from pathlib import Path

import pytest

from missions import weather_window as ww
from tests.cli import cli

CORPUS = Path(__file__).parent / "corpus"
FORECASTS = CORPUS / "forecasts"
HEADER = "time,hs_m,tp_s,wave_dir_deg,current_mps,current_dir_deg"


@dataclass(frozen=True)
class BadForecast:
    file: str
    line: int
    row: str
    column: str
    words: tuple[str, ...]


def read_corpus() -> list[BadForecast]:
    cases = []
    for raw in (CORPUS / "bad_forecasts.txt").read_text().splitlines():
        if not raw.strip() or raw.startswith("#"):
            continue
        file, line, row, column, words = (p.strip() for p in raw.split(" | "))
        cases.append(
            BadForecast(file, int(line), row, column, tuple(w.strip() for w in words.split(",")))
        )
    return cases


CASES = read_corpus()


def test_the_corpus_covers_every_file_and_every_kind_of_problem():
    assert sorted(c.file for c in CASES) == sorted(p.name for p in FORECASTS.glob("*.csv"))
    kinds = " ".join(w for c in CASES for w in c.words)
    for kind in ("gap", "must rise", "NaN", "missing", "outside", "UTC", "no value"):
        assert kind in kinds


@pytest.mark.parametrize("case", CASES, ids=[c.file for c in CASES])
def test_a_bad_forecast_gets_one_line_naming_its_line_row_and_column(case: BadForecast):
    with pytest.raises(ww.ForecastError) as err:
        ww.read_forecast(FORECASTS / case.file)
    text = str(err.value)
    assert "\n" not in text
    where = f"{case.file} line {case.line} ({case.row}), column {case.column}: "
    assert where in text, text
    missing = [w for w in case.words if w not in text]
    assert not missing, f"{text!r} lacks {missing}"


def table(allowable_hs_m: float = 3.0, current_mps: float = 0.3) -> dict:
    """An operability table as ``operability --json`` writes it (the window reads only these
    keys): allowable Hs 3 m at Tp 8 and 10 s in head seas and beam seas to starboard."""
    return {
        "mission": "full-landing-seaway",
        "vessel_heading_deg": 180.0,
        "vessel_into_waves": False,
        "mission_hours": 0.11,
        "current": {"speed_mps": current_mps, "direction_deg": 225.0},
        "allowable": [
            {"tp_s": tp, "wave_heading_deg": h, "hs_m": hs, "limiting": "contact_speed"}
            for tp in (8.0, 10.0)
            for h, hs in ((90.0, allowable_hs_m - 1.0), (180.0, allowable_hs_m))
        ],
    }


START = datetime(2026, 3, 1, tzinfo=UTC)
GO_HOURS = set(range(0, 10)) | set(range(13, 31)) | set(range(32, 48))
"""Hours 0-9 go (10 h, shorter than the 12 h reference period), 10-12 not, 13-30 go (18 h),
31 not (the current too strong), 32-47 go (16 h, to the forecast's end)."""


def known_forecast(path: Path) -> Path:
    """48 hourly rows, waves towards north (a head sea for the vessel heading 180): Hs 2.0 m
    where go (under 0.775 x 3 m = 2.325 m), 2.6 m where not."""
    lines = [HEADER]
    for k in range(48):
        t = (START + timedelta(hours=k)).strftime("%Y-%m-%dT%H:%M:%SZ")
        hs = 2.0 if k in GO_HOURS or k == 31 else 2.6
        current = 0.5 if k == 31 else 0.2
        lines.append(f"{t},{hs},9.0,0,{current},225")
    path.write_text("\n".join(lines) + "\n")
    return path


def test_alpha_base_table_at_12_hours_interpolates_between_the_hs_columns():
    base = ww.ALPHA_TABLES["base"]
    assert base.alpha(12.0, 1.0) == pytest.approx(0.65)  # the table's first column: 1 m
    assert base.alpha(12.0, 2.0) == pytest.approx(0.76)
    assert base.alpha(12.0, 3.0) == pytest.approx(0.775)  # halfway from 2 m (0.76) to 4 m
    assert base.alpha(13.0, 3.0) == pytest.approx((0.73 + 0.76) / 2)  # the 24 h row
    assert base.alpha(72.0, 2.0) == pytest.approx(0.63)
    assert base.alpha(12.0, 0.5) == 0.65 and base.alpha(12.0, 20.0) == 0.80
    with pytest.raises(ValueError, match="weather-unrestricted"):
        base.alpha(73.0, 2.0)


def test_alpha_falls_with_the_reference_period_and_rises_with_the_limit():
    """The base table's shape: a longer period is less certain (each column falls), and a
    small limit is relatively more uncertain than a large one (each row rises)."""
    base = ww.ALPHA_TABLES["base"]
    for k in range(len(base.hs_m)):
        column = [row[k] for row in base.values]
        assert column == sorted(column, reverse=True)
    for row in base.values:
        assert list(row) == sorted(row)
    assert "remembered" in base.source and "--alpha-table" in base.source
    assert list(ww.ALPHA_TABLES) == ["base"]  # no table built in that nobody can source


def test_the_window_finder_finds_the_known_windows(tmp_path: Path):
    fc = ww.read_forecast(known_forecast(tmp_path / "f.csv"))
    verdicts = ww.judge_hours(fc, table(), ww.ALPHA_TABLES["base"], 12.0, 180.0)
    assert [k for k, v in enumerate(verdicts) if v.go] == sorted(GO_HOURS)
    assert verdicts[10].limit_hs_m == pytest.approx(0.775 * 3.0)
    assert "current 0.5 m/s above the table's 0.3 m/s" in verdicts[31].reason
    found = ww.windows(verdicts, fc.step, 12.0)
    assert [(w.start, w.end) for w in found] == [
        (START + timedelta(hours=13), START + timedelta(hours=31)),
        (START + timedelta(hours=32), START + timedelta(hours=48)),
    ]
    assert len(ww.go_spells(verdicts, fc.step)) == 3  # the 10 h spell is too short
    assert ww.windows(verdicts, fc.step, 17.0)[0].hours == 18.0
    assert ww.windows(verdicts, fc.step, 19.0) == []


def test_headings_and_periods_outside_the_table_are_no_go(tmp_path: Path):
    t = table()
    assert ww.allowable_at(t, 9.0, 180.0) == (3.0, "")
    assert ww.allowable_at(t, 9.0, 135.0) == (2.0, "")  # between 90 and 180: the lower
    assert ww.allowable_at(t, 8.0, 90.0) == (2.0, "")
    hs, why = ww.allowable_at(t, 12.0, 180.0)
    assert hs is None and "outside the table's 8-10 s" in why
    hs, why = ww.allowable_at(t, 9.0, 270.0)
    assert hs is None and "not covered" in why


def window_cli(*args: str) -> subprocess.CompletedProcess[str]:
    return cli("window", *args)


def test_window_json_has_alpha_hours_and_windows(tmp_path: Path):
    saved = tmp_path / "operability.json"
    saved.write_text(json.dumps(table()))
    forecast = known_forecast(tmp_path / "forecast.csv")
    proc = window_cli(
        "full-landing-seaway",
        "--forecast",
        str(forecast),
        "--table",
        str(saved),
        "--operation-hours",
        "6",
        "--json",
    )
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    assert out["alpha"] == pytest.approx(0.775)
    assert out["reference_hours"] == 12.0 and out["contingency_hours"] == 6.0
    assert len(out["hours"]) == 48 and {"time", "go"} <= set(out["hours"][0])
    assert out["hours"][0]["time"] == "2026-03-01T00:00:00Z"
    assert [w["start"] for w in out["windows"]] == ["2026-03-01T13:00:00Z", "2026-03-02T08:00:00Z"]
    assert [w["end"] for w in out["windows"]] == ["2026-03-02T07:00:00Z", "2026-03-03T00:00:00Z"]
    assert Path(out["figure"]).stat().st_size > 10_000


@pytest.mark.parametrize("name", ["gap.csv", "nan_hs.csv", "missing_column.csv"])
def test_window_refuses_a_bad_forecast_in_one_line(tmp_path: Path, name: str):
    proc = window_cli("full-landing-seaway", "--forecast", str(FORECASTS / name), "--json")
    assert proc.returncode == 2 and proc.stdout == ""
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and "column" in lines[0]
    assert "Traceback" not in proc.stderr


def test_window_refuses_a_reference_period_beyond_72_hours(tmp_path: Path):
    saved = tmp_path / "operability.json"
    saved.write_text(json.dumps(table()))
    forecast = known_forecast(tmp_path / "forecast.csv")
    proc = window_cli(
        "full-landing-seaway",
        "--forecast",
        str(forecast),
        "--table",
        str(saved),
        "--operation-hours",
        "40",
    )
    assert proc.returncode == 2 and "weather-unrestricted" in proc.stderr


def test_a_vessel_heading_into_the_waves_meets_them_at_180_every_hour(tmp_path: Path):
    lines = [
        HEADER,
        "2026-03-01T00:00:00Z,2.0,9.0,90,0.2,225",
        "2026-03-01T01:00:00Z,2.0,9.0,270,0.2,225",
    ]
    fc = ww.read_forecast(_write(tmp_path / "f.csv", lines))
    into = ww.judge_hours(fc, table(), ww.ALPHA_TABLES["base"], 12.0, None)
    assert [v.wave_heading_deg for v in into] == [180.0, 180.0] and all(v.go for v in into)
    fixed = ww.judge_hours(fc, table(), ww.ALPHA_TABLES["base"], 12.0, 180.0)
    assert [v.wave_heading_deg for v in fixed] == [270.0, 90.0]
    assert not fixed[0].go and "not covered" in fixed[0].reason  # 270: no table heading near
    assert fixed[1].limit_hs_m == pytest.approx(0.76 * 2.0)  # 90 deg: allowable 2 m
    assert not fixed[1].go


def _write(path: Path, lines: list[str]) -> Path:
    path.write_text("\n".join(lines) + "\n")
    return path


def test_an_alpha_table_of_ones_own_is_read_and_checked(tmp_path: Path):
    own = ww.read_alpha_table(
        _write(tmp_path / "mine.csv", ["reference_hours,1,4", "24,0.8,0.9", "48,0.7,0.8"])
    )
    assert own.alpha(20.0, 2.5) == pytest.approx(0.85) and own.alpha(30.0, 1.0) == 0.7
    with pytest.raises(ValueError, match="weather-unrestricted"):
        own.alpha(49.0, 1.0)
    bad = _write(tmp_path / "bad.csv", ["reference_hours,1,4", "24,0.8,1.2"])
    with pytest.raises(ValueError, match=r"alpha must lie in \(0, 1\]"):
        ww.read_alpha_table(bad)
    with pytest.raises(ValueError, match="must start with reference_hours"):
        ww.read_alpha_table(_write(tmp_path / "h.csv", ["hours,1", "24,0.8"]))
