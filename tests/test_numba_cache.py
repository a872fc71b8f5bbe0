"""numba's cache of the core is kept valid by what the code says (sim.numba_cache).

Defects it guards against: numba, left to itself, checks a cached kernel against its own file
only, so the chunk kernels of control/loop.py went on running the old plant after only
sim/plant.py was edited; it names a cache entry after the function's line, so an edit of
a docstring or a comment cost the compile of every kernel below it; and with a stamp per
module, an edit of the plant's wire force recompiled the controller's step too."""

from __future__ import annotations

import json
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


_STAMPS = """
import json
from sim import gnc, plant, site
from sim.numba_cache import kernel_stamp
from control import loop, refkernel
kernels = {
    "plant.rk4_step_into": plant.rk4_step_into,
    "plant.hold_needed_xyn": plant.hold_needed_xyn,
    "gnc.ssa": gnc.ssa,
    "site.chunk_rows_into": site.chunk_rows_into,
    "loop.run_chunk": loop.run_chunk,
    "loop.control_step_into": loop.control_step_into,
    "loop.observe_into": loop.observe_into,
    "refkernel.polls_still_away": refkernel.polls_still_away,
}
print(json.dumps({name: kernel_stamp(k.py_func) for name, k in kernels.items()}))
"""


def _stamps(root: Path) -> dict[str, str]:
    """The stamps of a few kernels of the core copied under ``root``, worked out in a fresh
    interpreter (nothing compiled)."""
    env = {**os.environ, "PYTHONPATH": str(root)}
    proc = subprocess.run(
        [sys.executable, "-c", _STAMPS], cwd=root, env=env, capture_output=True, text=True
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    return json.loads(proc.stdout)


def _changed(before: dict[str, str], after: dict[str, str]) -> list[str]:
    return sorted(name for name in before if after[name] != before[name])


def test_comments_and_docstrings_leave_every_stamp_as_it_was(tmp_path: Path) -> None:
    _copy_sources(tmp_path)
    before = _stamps(tmp_path)
    plant = tmp_path / "sim" / "plant.py"
    _edit(plant, '"""Force of the wire on the tree', '"""The force of the wire on the tree')
    _edit(plant, "\nclass PlantArrays(", "\n# a new comment\n\n\nclass PlantArrays(")
    _edit(
        plant, "    if env[E_WEXT] > 0.0:", "    # a comment in the code\n    if env[E_WEXT] > 0.0:"
    )
    assert _stamps(tmp_path) == before


def test_a_formula_edit_changes_the_stamps_of_the_kernels_that_reach_it_only(
    tmp_path: Path,
) -> None:
    """The wire force is in the plant's step, the log row's tension and the landing planner's
    holding force: those kernels and the chunk kernels recompile; the controller's step, the
    angle helper, the reference model's poll and the environment rows do not."""
    _copy_sources(tmp_path)
    before = _stamps(tmp_path)
    _edit(
        tmp_path / "sim" / "plant.py",
        "    d = np.sqrt(dx * dx + dy * dy + dz * dz)\n",
        "    d = np.sqrt(dx * dx + dy * dy + dz * dz) * 1.0\n",
    )
    assert _changed(before, _stamps(tmp_path)) == [
        "loop.observe_into",
        "loop.run_chunk",
        "plant.hold_needed_xyn",
        "plant.rk4_step_into",
    ]


def test_a_controller_edit_leaves_the_plants_kernels_alone(tmp_path: Path) -> None:
    _copy_sources(tmp_path)
    before = _stamps(tmp_path)
    _edit(tmp_path / "control" / "pid.py", "    i_b[2] = i_n[2]\n", "    i_b[2] = i_n[2] * 1.0\n")
    changed = _changed(before, _stamps(tmp_path))
    assert "loop.run_chunk" in changed and "loop.control_step_into" in changed
    assert not {"plant.rk4_step_into", "gnc.ssa", "site.chunk_rows_into"} & set(changed)


def test_a_constant_edit_reaches_the_kernels_that_read_it(tmp_path: Path) -> None:
    """A module constant is frozen into the kernels that read it, while their own bytecode
    stays the same: the stamp must change for them, and only for them."""
    _copy_sources(tmp_path)
    before = _stamps(tmp_path)
    _edit(tmp_path / "sim" / "plant.py", "E_GRIP = 17", "E_GRIP = 18")
    changed = _changed(before, _stamps(tmp_path))
    assert "loop.run_chunk" in changed and "plant.rk4_step_into" in changed
    assert "gnc.ssa" not in changed


def test_a_kernels_options_reach_the_kernels_that_call_it(tmp_path: Path) -> None:
    """Defect: a callee's options (``inline``, ``error_model``, ``fastmath``) shape its
    callers' machine code but are not in its bytecode, so making the observer's unit
    ``inline="always"`` left the chunk kernels' stamps as they were and they loaded the old
    kernel, which still called the unit, from the cache. Here the controller's unit."""
    _copy_sources(tmp_path)
    before = _stamps(tmp_path)
    _edit(
        tmp_path / "control" / "loop.py",
        "@njit(**JIT_NOALLOC)\ndef control_step_into(",
        '@njit(inline="always", **JIT_NOALLOC)\ndef control_step_into(',
    )
    assert _changed(before, _stamps(tmp_path)) == ["loop.control_step_into", "loop.run_chunk"]


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
    assert run() == (False, True), "code ssa does not reach changed: loaded all the same"
    _edit(
        gnc,
        "    wrapped = (angle + np.pi) % (2.0 * np.pi)\n",
        "    wrapped = (angle + np.pi) % (2.0 * np.pi * 1.0)\n",
    )
    assert run() == (True, False), "ssa's own code changed: compiled again"


def test_the_cache_machinery_itself_is_no_kernels_dependency() -> None:
    """A kernel reaches the core's functions it calls, not the cache's own code (which
    ``sim/__init__.py`` runs): an edit of it must not recompile the core."""
    from control import loop

    seen: set[str] = set()
    todo = [loop.run_chunk.py_func]
    while todo:
        func = todo.pop()
        name = f"{func.__module__}.{func.__qualname__}"
        if name not in seen:
            seen.add(name)
            todo += numba_cache._function_part(func)[1]
    assert "sim.plant.rk4_step_into" in seen and "control.ekf.correct_into" in seen
    assert not any(name.startswith(("sim.numba_cache", "sim.__init__")) for name in seen)
