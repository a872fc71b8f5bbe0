"""Every script the README or a page of docs/ tells a reader to run as
``.venv/bin/python <path>.py`` starts as written there: run from the repository root by its
path (not as a module), with ``--help``, it imports what it needs and prints its usage.
(``benchmarks/plant_benchmark.py`` once failed at its first import this way, while
``scripts/readme_figures.py`` ran it with ``-m`` and never saw it.)"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = re.compile(r"\.venv/bin/python ((?:benchmarks|scripts)/[A-Za-z0-9_]+\.py)")


def guide_pages() -> list[Path]:
    """README.md and the pages of docs/ a reader follows."""
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def readme_scripts() -> list[str]:
    """The script paths the README and docs name after ``.venv/bin/python``, each once, in
    order."""
    text = "\n".join(page.read_text() for page in guide_pages())
    return list(dict.fromkeys(SCRIPT.findall(text)))


def test_the_readme_and_docs_name_the_benchmarks() -> None:
    found = readme_scripts()
    assert "benchmarks/landing_montecarlo.py" in found
    assert "scripts/compare_laws.py" in found
    assert all((ROOT / path).is_file() for path in found), found


@pytest.mark.parametrize("path", readme_scripts())
def test_a_readme_script_starts_as_written(path: str) -> None:
    done = subprocess.run(
        [sys.executable, path, "--help"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert done.returncode == 0, f"{path} --help failed:\n{done.stderr[-2000:]}"
    assert "usage:" in done.stdout, done.stdout[:500]


def test_benchmarks_name_their_machine(tmp_path: Path) -> None:
    sys.path.insert(0, str(ROOT))
    from benchmarks import machine

    info = tmp_path / "cpuinfo"
    info.write_text("processor\t: 0\nvendor_id\t: AuthenticAMD\nmodel name\t: AMD EPYC 7B13\n")
    assert machine.cpu_model(info) == "AMD EPYC 7B13"
    assert machine.cpu_model(tmp_path / "missing") != ""
    assert machine.simd_of({"avx2": True, "avx512f": True}) == "AVX-512"
    assert machine.simd_of({"avx2": True, "avx512f": False}) == "AVX2"
    here = machine.describe()
    assert set(here) == {"cpu", "llvm_cpu", "simd", "cores"}
    assert here["cores"] >= 1
    assert machine.text(here).endswith(f"{here['simd']}, {here['cores']} cores)")
