"""Two recorded runs side by side (``rov-console compare A B``, ``report --compare``): the
figures are each run's own debrief figures, the better run is named where better has a
meaning, what differs in the set-ups is said, and bad alignments get one line."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from app.compare import CompareError, compare, comparison_image
from app.report import debrief
from tests.cli import cli


@pytest.fixture(scope="module")
def two_runs(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    """The same step at model scale: A with the priority allocation (the library's), B with
    the pseudo-inverse, which loses the heading in the impossible step (RMS heading over
    100 deg against A's under 2 deg)."""
    out = tmp_path_factory.mktemp("compare")
    a, b = out / "a.mcap", out / "b.mcap"
    for log, extra in ((a, ("--seed", "0")), (b, ("--seed", "1", "--allocation", "pinv"))):
        run = cli("run", "model-step-priority", *extra, "--log", str(log))
        assert run.returncode in (0, 1) and log.is_file(), run.stderr
    return a, b


def _row(rows: list[dict], figure: str) -> dict:
    return next(r for r in rows if r["figure"] == figure)


def test_compare_names_the_better_run_with_each_runs_own_figures(two_runs) -> None:
    a, b = two_runs
    done = cli("compare", str(a), str(b), "--json")
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout)
    da, db = debrief(a), debrief(b)
    rows = out["differences"]
    heading = _row(rows, "RMS heading error")
    assert heading["a"] == pytest.approx(da.result.rms_heading_deg)
    assert heading["b"] == pytest.approx(db.result.rms_heading_deg)
    assert heading["a"] < 5.0 < 100.0 < heading["b"] and heading["better"] == "a"
    settle = _row(rows, "leg 1 (settle on the wire): RMS north")
    assert settle["better"] == "same", "the legs before the step are alike"
    assert out["aligned_at"] == {"event": "mission", "a_s": 0.0, "b_s": 0.0}
    assert out["differs"] == ["seed: 0 against 1", "settings.allocation: priority against pinv"]


def test_a_run_compared_with_itself_differs_in_nothing(two_runs) -> None:
    a, _ = two_runs
    c = compare(a, a)
    assert c.differs == []
    assert {d.better for d in c.differences} <= {"same", ""}
    assert any(d.better == "same" for d in c.differences)


@pytest.mark.parametrize(
    "align, words",
    [
        ("contact", "never touched the frame: align elsewhere"),
        ("event:no such words", "has no event whose text holds 'no such words'"),
        ("halfway", "align must be one of mission, contact, start or event:WORDS"),
    ],
)
def test_an_alignment_that_cannot_be_made_is_one_line(two_runs, align: str, words: str) -> None:
    a, b = two_runs
    done = cli("compare", str(a), str(b), "--align", align)
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert done.stderr.startswith("error:") and words in done.stderr


def test_a_malformed_alignment_is_refused_before_the_logs_are_read(tmp_path: Path) -> None:
    """It took some 3 s to say: both logs were read and debriefed first."""
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"not a log at all")
    with pytest.raises(CompareError, match="align must be one of mission, contact, start"):
        compare(bad, bad, "halfway")
    with pytest.raises(CompareError, match="or event:WORDS, got 'event: '"):
        compare(bad, bad, "event: ")


def test_a_missing_or_bad_second_file_is_one_line(two_runs, tmp_path: Path) -> None:
    a, _ = two_runs
    done = cli("compare", str(a), str(tmp_path / "none.mcap"))
    assert done.returncode == 2 and "no log file" in done.stderr
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(b"not a log at all")
    done = cli("compare", str(a), str(bad))
    assert done.returncode == 2 and "not an MCAP" in done.stderr and "Traceback" not in done.stderr


def test_the_debrief_includes_the_comparison_and_its_plot(two_runs, tmp_path: Path) -> None:
    a, b = two_runs
    out = tmp_path / "report.html"
    done = cli("report", str(a), "--compare", str(b), "-o", str(out))
    assert done.returncode == 0, done.stderr
    page = out.read_text()
    assert "Compared with another run" in page and "settings.allocation" in page
    assert page.count("data:image/png;base64,") == 4, "pose, track, forces and the comparison"
    plot = tmp_path / "both.png"
    assert cli("compare", str(a), str(b), "--plot", str(plot)).returncode == 0
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_the_pages_plot_is_the_command_lines_figure_as_an_image(two_runs) -> None:
    a, b = two_runs
    image = comparison_image(compare(a, b, "start"))
    assert image.dtype == np.uint8 and image.ndim == 3 and image.shape[2] == 3
    assert image.shape[0] > 300 and image.shape[1] > 300
    assert image.min() < 50 < 200 < image.max(), "lines drawn on a white figure"
