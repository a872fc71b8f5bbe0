"""numba's cache of the core is kept valid by what the code says (sim.numba_cache).

Defects it guards against: numba, left to itself, checks a cached kernel against its own file
only, so the chunk kernels of control/loop.py went on running the old plant after only
sim/plant.py was edited; and it names a cache entry after the function's line, so an edit of
a docstring or a comment cost the compile of every kernel below it (with the whole core's
digest as the cache's folder, ten minutes of compile for any edit of sim/ or control/)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from sim import numba_cache

ROOT = Path(__file__).resolve().parent.parent


def _copy_sources(dest: Path) -> None:
    for pkg in numba_cache.PACKAGES:
        shutil.copytree(ROOT / pkg, dest / pkg, ignore=shutil.ignore_patterns("__pycache__"))


def _edit(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert old in text, f"{old!r} not in {path}"
    path.write_text(text.replace(old, new, 1))


def test_comments_and_docstrings_leave_every_stamp_as_it_was(tmp_path: Path) -> None:
    _copy_sources(tmp_path)
    plant, loop = tmp_path / "sim" / "plant.py", tmp_path / "control" / "loop.py"
    before = {p: numba_cache.stamp(p, tmp_path) for p in (plant, loop)}
    _edit(plant, '"""Everything the compiled plant needs', '"""All the compiled plant needs')
    _edit(plant, "\nclass PlantArrays(", "\n# a new comment\n\n\nclass PlantArrays(")
    numba_cache.code_digest.cache_clear()
    assert {p: numba_cache.stamp(p, tmp_path) for p in (plant, loop)} == before


def test_a_code_edit_changes_the_stamps_of_its_module_and_its_importers_only(
    tmp_path: Path,
) -> None:
    _copy_sources(tmp_path)
    files = {
        name: tmp_path / name
        for name in ("sim/plant.py", "control/loop.py", "control/pid.py", "sim/gnc.py")
    }
    before = {name: numba_cache.stamp(p, tmp_path) for name, p in files.items()}
    _edit(files["control/pid.py"], "    return out\n", "    return out * 1.0\n")
    numba_cache.code_digest.cache_clear()
    after = {name: numba_cache.stamp(p, tmp_path) for name, p in files.items()}
    changed = sorted(name for name in files if after[name] != before[name])
    # loop.py imports pid.py; the plant and gnc do not
    assert changed == ["control/loop.py", "control/pid.py"]


def test_a_constant_edit_reaches_the_kernels_of_the_modules_that_import_it(
    tmp_path: Path,
) -> None:
    """A module constant is frozen into the kernels that read it, while their own bytecode
    stays the same: the stamp must change for them."""
    _copy_sources(tmp_path)
    plant, loop = tmp_path / "sim" / "plant.py", tmp_path / "control" / "loop.py"
    before = numba_cache.stamp(loop, tmp_path)
    _edit(plant, "E_GRIP = 17", "E_GRIP = 18")
    numba_cache.code_digest.cache_clear()
    assert numba_cache.stamp(loop, tmp_path) != before


def test_dependencies_follow_imports_through_other_modules() -> None:
    deps = {
        p.relative_to(ROOT).as_posix() for p in numba_cache.dependencies(ROOT / "control/loop.py")
    }
    # loop imports sim.plant, which imports sim.gnc: both reach the loop's kernels
    assert {"control/loop.py", "sim/plant.py", "sim/gnc.py", "control/ekf.py"} <= deps
    assert "app/cli.py" not in deps and "control/simulation.py" not in deps


_RUN = """
from sim import gnc
print(gnc.ssa(7.0))
"""


def test_the_core_is_cached_beside_the_packages_and_a_docstring_edit_reloads_it(
    tmp_path: Path,
) -> None:
    """In a copy of the core: a first call compiles and saves, a second process loads; after
    a docstring edit a third still loads (nothing compiled), after a code edit a fourth
    compiles again."""
    _copy_sources(tmp_path)
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(PYTHONPATH=str(tmp_path), NUMBA_DEBUG_CACHE="1")

    def run() -> tuple[bool, bool]:
        proc = subprocess.run(
            [sys.executable, "-c", _RUN], cwd=tmp_path, env=env, capture_output=True, text=True
        )
        assert proc.returncode == 0, proc.stderr[-2000:]
        lines = [line for line in proc.stdout.splitlines() if "gnc.ssa" in line]
        return any("data saved" in x for x in lines), any("data loaded" in x for x in lines)

    assert run() == (True, False), "compiled and saved"
    assert (tmp_path / ".numba-cache" / "sim").is_dir()
    assert run() == (False, True), "loaded"
    gnc = tmp_path / "sim" / "gnc.py"
    _edit(gnc, "def ssa(angle", "# a comment above ssa\n\n\ndef ssa(angle")
    assert run() == (False, True), "a comment moved the lines: loaded all the same"
    _edit(gnc, "import numpy as np\n", "import numpy as np\n\nUNUSED_CONSTANT = 1.0\n")
    assert run() == (True, False), "the module's code changed: compiled again"


def test_the_cache_machinery_itself_is_no_kernels_dependency() -> None:
    """``from sim import plant`` depends on sim/plant.py, not on sim/__init__.py (which
    imports this module): an edit of the cache's own code must not recompile the core."""
    for kernels in ("sim/plant.py", "control/loop.py", "control/ekf.py"):
        deps = {p.relative_to(ROOT).as_posix() for p in numba_cache.dependencies(ROOT / kernels)}
        assert "sim/numba_cache.py" not in deps and "sim/__init__.py" not in deps, kernels
