"""The debrief (``rov-console report LOG -o report.html``): scored from the recorded rows, its
figures agree with the run's own, it is one self-contained file, and bad logs get one line."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from app.report import debrief
from tests.cli import cli


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict]:
    out = tmp_path_factory.mktemp("report")
    log = out / "step.mcap"
    run = cli("run", "model-step-priority", "--seed", "0", "--json", "--log", str(log))
    # exit 1: the impossible step ends 3.6 m off its target, outside the leg's tolerance
    assert run.returncode in (0, 1) and run.stdout, run.stderr
    return log, json.loads(run.stdout)


def test_report_scores_agree_with_the_run(recorded: tuple[Path, dict]) -> None:
    """The recording keeps rows at 20 Hz, the run scores all 100 Hz rows: RMS over a fifth of
    the samples of a smooth signal agrees to well within 2 % (measured: 4 decimals)."""
    log, summary = recorded
    d = debrief(log)
    assert [leg.type for leg in d.result.legs] == [leg["type"] for leg in summary["legs"]]
    for ours, theirs in zip(d.result.legs, summary["legs"], strict=True):
        assert ours.name == theirs["name"]
        assert ours.duration_s == pytest.approx(theirs["duration_s"], abs=0.06)
        for key in ("rms_north_m", "rms_east_m", "rms_heading_deg"):
            assert getattr(ours, key) == pytest.approx(theirs[key], rel=0.02, abs=1e-4), key
    assert d.result.rms_north_m == pytest.approx(summary["rms_north_m"], rel=0.02)
    assert d.thrust_impulse_newton_s > 0.0
    assert any(e["kind"] == "leg" for e in d.events)


def test_report_is_one_self_contained_html_file(recorded: tuple[Path, dict], tmp_path: Path):
    log, _ = recorded
    out = tmp_path / "deep" / "report.html"
    done = cli("report", str(log), "-o", str(out))
    assert done.returncode == 0, done.stderr
    page = out.read_text()
    assert page.count("data:image/png;base64,") == 3, "pose, track and forces, inline"
    assert not re.search(r'src="(?!data:)', page), "nothing loaded from elsewhere"
    leg = debrief(log).result.legs[1]
    assert f"{leg.rms_north_m:.4f}" in page and leg.name in page


@pytest.mark.parametrize(
    "content, words", [(b"", "not an MCAP"), (b"hello, not a log", "not an MCAP")]
)
def test_report_of_a_bad_file_is_one_line(tmp_path: Path, content: bytes, words: str) -> None:
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(content)
    done = cli("report", str(bad), "-o", str(tmp_path / "r.html"))
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert done.stderr.startswith("error:") and len(done.stderr.strip().splitlines()) == 1


def test_report_of_a_missing_file_says_so(tmp_path: Path) -> None:
    done = cli("report", str(tmp_path / "none.mcap"))
    assert done.returncode == 2 and "no log file" in done.stderr
