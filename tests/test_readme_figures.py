"""The figure blocks of README.md and docs/*.md: well-formed markers, each block in one file,
and each block exactly what scripts/readme_figures.py renders from its stored results (so a
number typed by hand fails). The studies themselves are not rerun here (minutes); the script
does that."""

import importlib.util
import json
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def _script():
    spec = importlib.util.spec_from_file_location(
        "readme_figures", ROOT / "scripts" / "readme_figures.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


rf = _script()


def test_every_block_in_the_readme_and_docs_is_what_the_script_renders_from_its_results():
    texts = {path: path.read_text() for path in rf.figure_files()}
    assert ROOT / "README.md" in texts and ROOT / "docs" / "planner.md" in texts
    where = rf.homes(texts)
    assert set(where) == set(rf.BLOCKS)
    stored = json.loads(rf.RESULTS.read_text())
    assert set(rf.BLOCKS) <= set(stored)
    for name, path in where.items():
        block = rf.blocks_in(texts[path])[name]
        assert block == rf.BLOCKS[name][1](stored[name]), (
            f"figures:{name} in {path.relative_to(ROOT)} was edited by hand"
        )
    for path, text in texts.items():
        assert rf.render_blocks(text, stored) == text, path


def test_a_block_stands_in_one_file_and_is_known(tmp_path):
    a, b = ROOT / "README.md", ROOT / "docs" / "x.md"
    block = "<!-- figures:laws -->\nx\n<!-- /figures:laws -->\n"
    assert rf.homes({a: block, b: "no blocks\n"}) == {"laws": a}
    with pytest.raises(ValueError, match="figures:laws stands in README.md and in docs/x.md"):
        rf.homes({a: block, b: block})
    with pytest.raises(ValueError, match="docs/x.md: figures:nope is not a block"):
        rf.homes({b: "<!-- figures:nope -->\n<!-- /figures:nope -->\n"})


LAWS = {
    "rows": [
        {
            "scenario": "full-square-400",
            "law": "thesis",
            "rms_north_m": 0.08312,
            "rms_east_m": 0.0801,
            "rms_heading_deg": 0.4123,
        },
        {
            "scenario": "full-square-400",
            "law": "feedforward",
            "rms_north_m": 0.003449,
            "rms_east_m": 0.002951,
            "rms_heading_deg": 0.333,
        },
    ]
}


def test_table_renderer_writes_the_rows_to_two_significant_figures():
    assert rf.render_laws(LAWS).split("\n") == [
        "  | scenario | law | RMS N [m] | RMS E [m] | RMS heading [deg] |",
        "  |---|---|---|---|---|",
        "  | full-square-400 | thesis | 0.083 | 0.080 | 0.41 |",
        "  | full-square-400 | feedforward | 0.0034 | 0.0030 | 0.33 |",
    ]


def test_a_block_is_rewritten_in_place_and_the_rest_kept():
    text = "intro\n  <!-- figures:laws -->\n  old table\n  <!-- /figures:laws -->\nafter\n"
    out = rf.replace_block(text, "laws", rf.render_laws(LAWS))
    assert out.startswith("intro\n  <!-- figures:laws -->\n  | scenario |")
    assert out.endswith("| 0.33 |\n  <!-- /figures:laws -->\nafter\n")
    assert rf.blocks_in(out)["laws"] == rf.render_laws(LAWS)
    with pytest.raises(ValueError, match="no figures:limits block"):
        rf.replace_block(text, "limits", "x")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("<!-- figures:a -->\nx\n", "line 1: figures:a is never closed"),
        ("x\n<!-- /figures:a -->\n", "line 2: /figures:a closes nothing"),
        ("<!-- figures:a -->\n<!-- /figures:b -->\n", "line 2: /figures:b closes figures:a"),
        ("<!-- figures:a -->\n<!-- figures:b -->\n", "line 2: figures:b opens inside figures:a"),
        (
            "<!-- figures:a -->\n<!-- /figures:a -->\n<!-- figures:a -->\n<!-- /figures:a -->\n",
            "line 3: figures:a appears twice",
        ),
        ("text <!-- figures:a -->\n<!-- /figures:a -->\n", "line 1: .* on its own line"),
    ],
)
def test_malformed_markers_are_refused_naming_the_line(text, message):
    with pytest.raises(ValueError, match=message):
        rf.blocks_in(text)


def test_wording_follows_the_ratio():
    """Table 4.1's heading went from 'down two orders of magnitude' (typed) to what the ratio
    says; the words are chosen by the numbers."""
    assert rf.reduction(3.0, 0.03) == "down 2 orders of magnitude, 100 times"
    assert rf.reduction(8.5, 0.2) == "down 42 times"
    assert rf.reduction(3.0, 0.3125) == "down 9.6 times, about an order of magnitude"
    assert rf.reduction(0.75, 0.37) == "halved"
    assert rf.reduction(0.75, 0.25) == "3.0 times smaller"
    assert rf.reduction(0.0024, 0.0025) == "about the same"
    assert rf.reduction(0.1, 0.3) == "3.0 times larger"
    assert rf.sig(0.0062) == "0.0062" and rf.sig(7.349) == "7.3" and rf.sig(3170.4) == "3170"


def test_campaign_block_has_no_batch_table_even_when_the_results_hold_one():
    """The batch stepper is gone; results stored while it existed still render."""
    campaign = {"workers": 1, "runs": 200, "simulated_s": 1.0, "failed": 0, "wall_s": 1.0}
    campaign["simulated_s_per_wall_s"] = 1.0
    text = rf.render_campaign(
        {"campaigns": [campaign], "load_average_before": [0.5], "batch": {"runs": 64}}
    )
    assert "batch" not in text.lower()
    assert "| 1 | 1.0 | 1 |" in text


MACHINE = {"cpu": "AMD EPYC", "llvm_cpu": "znver3", "simd": "AVX2", "cores": 2}


def _speed_results(machine: dict | None) -> dict:
    loop = {
        "us_per_step": 5.4,
        "steps_per_s": 186_374,
        "real_time_factor": 1_864,
        "per_call_us": {"EKF predict": 0.31},
        "load_average": [1.0, 1.1, 1.2],
    }
    plant = {
        "us_per_step": 4.1,
        "steps_per_s": 243_000,
        "real_time_factor": 2_430,
        "load_average": [1.0, 1.1, 1.2],
    }
    if machine is not None:
        plant["machine"] = loop["machine"] = machine
    console = {
        "jitter_median_ms": 0.1,
        "jitter_p99_ms": 0.5,
        "jitter_max_ms": 1.5,
        "overruns": 0,
        "simulated_s_per_wall_s": 1.0,
        "load_average": [0.8],
    }
    return {"plant": plant, "loop": loop, "console": {"1x": console}}


def test_speed_block_names_the_machine_its_figures_were_measured_on():
    text = rf.render_speed(_speed_results(MACHINE))
    assert text.startswith("Measured on AMD EPYC (znver3, AVX2, 2 cores):")
    assert "| 4.1 us a 10 ms step, 2,430x real time | 1.0 |" in text
    assert "| console at 1x, five telemetry clients (`console_benchmark`) " in text
    assert "| ticks late by 0.10 ms median, 0.50 ms p99, 0 overruns | 0.8 |" in text
    # figures stored before the benchmarks recorded their machine do not name one
    old = rf.render_speed(_speed_results(None))
    assert old.startswith("| what | figure |")
    assert "Measured on" not in old


def test_campaign_block_names_the_machine_its_figures_were_measured_on():
    campaign = {
        "workers": 2,
        "runs": 200,
        "failed": 21,
        "simulated_s": 94_816.0,
        "wall_s": 40.0,
        "simulated_s_per_wall_s": 2_370.0,
    }
    res = {
        "load_average_before": [1.8],
        "one_run_simulated_s_per_s": 1_100.0,
        "campaigns": [campaign],
        "machine": MACHINE,
    }
    assert "on AMD EPYC (znver3, AVX2, 2 cores) (load average 1.8 before)" in " ".join(
        rf.render_campaign(res).split()
    )
    del res["machine"]
    assert "on this 2-core machine (load average" in " ".join(rf.render_campaign(res).split())


def test_an_edit_made_while_the_studies_run_is_kept(tmp_path, monkeypatch):
    """Defect: the script read every figure file at its start and wrote them back at its end,
    so an edit made meanwhile (its studies take minutes) was undone, and so were the results
    another run stored meanwhile. Each file is read again when its blocks are written."""
    readme, docs = tmp_path / "README.md", tmp_path / "docs"
    docs.mkdir()
    page = docs / "page.md"
    results = docs / "figures" / "readme_figures.json"
    results.parent.mkdir()
    results.write_text(json.dumps({"fake": {"n": 1}, "other": {"n": 7}}))
    readme.write_text("# title\n")
    page.write_text("before\n<!-- figures:fake -->\nn = 1\n<!-- /figures:fake -->\nafter\n")

    def study() -> dict:
        # meanwhile: a person edits the page, another run stores its results
        page.write_text(page.read_text().replace("after", "after, edited meanwhile"))
        stored = json.loads(results.read_text())
        results.write_text(json.dumps({**stored, "other": {"n": 8}}))
        return {"n": 2}

    monkeypatch.setattr(rf, "ROOT", tmp_path)
    monkeypatch.setattr(rf, "README", readme)
    monkeypatch.setattr(rf, "DOCS", docs)
    monkeypatch.setattr(rf, "RESULTS", results)
    monkeypatch.setattr(rf, "BLOCKS", {"fake": (study, lambda r: f"n = {r['n']}\n")})
    assert rf.main(["--only", "fake"]) == 0
    assert page.read_text() == (
        "before\n<!-- figures:fake -->\nn = 2\n<!-- /figures:fake -->\nafter, edited meanwhile\n"
    )
    assert json.loads(results.read_text()) == {"fake": {"n": 2}, "other": {"n": 8}}
    assert readme.read_text() == "# title\n"
