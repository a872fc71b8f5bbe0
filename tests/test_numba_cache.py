"""numba's cache is kept per version of the numeric core's sources (sim.numba_cache).

Defect: numba checks a cached kernel against its own file only, so the chunk kernels of
control/loop.py (which inline the plant step of sim/plant.py) went on running the old plant
after sim/plant.py alone was edited (seen in the third speed pass)."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from app import precompile
from sim import numba_cache

ROOT = Path(__file__).resolve().parent.parent


def _copy_sources(dest: Path) -> None:
    for pkg in numba_cache.PACKAGES:
        shutil.copytree(ROOT / pkg, dest / pkg, ignore=shutil.ignore_patterns("__pycache__"))


def test_digest_changes_with_any_source_of_sim_or_control(tmp_path: Path) -> None:
    _copy_sources(tmp_path)
    first = numba_cache.default_cache_dir(tmp_path)
    assert first.parent == tmp_path / ".numba-cache" and len(first.name) == 16
    assert numba_cache.default_cache_dir(tmp_path) == first, "same sources, same folder"
    plant = tmp_path / "sim" / "plant.py"
    plant.write_text(plant.read_text() + "\n# an edit of the plant alone\n")
    edited = numba_cache.default_cache_dir(tmp_path)
    assert edited != first, "an edited sim/plant.py gets a new cache folder"
    (tmp_path / "control" / "extra.py").write_text("X = 1\n")
    assert numba_cache.default_cache_dir(tmp_path) not in (first, edited), "a new file too"
    (tmp_path / "control" / "extra.py").unlink()
    assert numba_cache.default_cache_dir(tmp_path) == edited


def _cache_dir_in_fresh_process(code: str, env_extra: dict[str, str]) -> str:
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env.update(env_extra)
    out = subprocess.run(
        [sys.executable, "-c", code + "\nfrom numba.core import config; print(config.CACHE_DIR)"],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        check=True,
        timeout=120,
    )
    return out.stdout.strip().splitlines()[-1]


def test_importing_the_core_points_numba_at_this_versions_folder() -> None:
    want = str(numba_cache.default_cache_dir())
    assert _cache_dir_in_fresh_process("import control.pid", {}) == want
    # numba imported before the core: its settings are read again
    assert _cache_dir_in_fresh_process("import numba\nimport sim.gnc", {}) == want


def test_a_cache_folder_the_user_chose_is_kept(tmp_path: Path) -> None:
    mine = str(tmp_path / "mine")
    assert _cache_dir_in_fresh_process("import control.pid", {"NUMBA_CACHE_DIR": mine}) == mine


def test_precompile_if_needed_compiles_once_per_version_and_prunes_the_others(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    base = tmp_path / ".numba-cache"
    old = base / "0123456789abcdef"
    old.mkdir(parents=True)
    here = base / "fedcba9876543210"
    monkeypatch.setattr(precompile, "cache_dir", lambda: here)
    monkeypatch.setattr(numba_cache, "CHOSEN", here)
    calls: list[int] = []
    parts: list[int] = []
    # neither compiles here: what is under test is the mark and the pruning around them (the
    # parts' subprocesses would load the whole core from the real cache, 8 s a call)
    monkeypatch.setattr(precompile, "compile_parts_at_once", lambda: parts.append(1))
    monkeypatch.setattr(precompile, "compile_all", lambda: calls.append(1))
    precompile.main(["--if-needed"])
    assert calls == [1] and (here / precompile.DONE_MARK).is_file()
    assert not old.exists(), "the folder of the earlier sources is removed"
    precompile.main(["--if-needed"])
    assert calls == [1], "compiled already: nothing to do"
    precompile.main([])
    assert calls == [1, 1], "without --if-needed it compiles again"
    if (os.cpu_count() or 1) >= 2:
        assert parts == [1, 1], "the parts side by side first, each time it compiles"


def test_precompile_leaves_the_folders_beside_a_users_cache_alone(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    theirs = tmp_path / "other-project-cache"
    theirs.mkdir()
    mine = tmp_path / "my-cache"
    monkeypatch.setattr(precompile, "cache_dir", lambda: mine)
    monkeypatch.setattr(numba_cache, "CHOSEN", None)  # NUMBA_CACHE_DIR set by the user
    monkeypatch.setattr(precompile, "compile_parts_at_once", lambda: None)
    monkeypatch.setattr(precompile, "compile_all", lambda: None)
    precompile.main([])
    assert theirs.is_dir() and (mine / precompile.DONE_MARK).is_file()


_USED = """
import json, sys
from numba.core.registry import CPUDispatcher
if sys.argv[1] == "precompile":
    from app.precompile import compile_all
    compile_all()
else:
    from missions.runner import run_mission
    from missions.schema import load_mission
    for name in sys.argv[1:]:
        run_mission(load_mission(name))
used = {}
for module_name, module in list(sys.modules.items()):
    if module_name.split(".")[0] in ("sim", "control"):
        for obj in vars(module).values():
            if isinstance(obj, CPUDispatcher):
                name = obj.py_func.__module__ + "." + obj.py_func.__qualname__
                used.setdefault(name, set()).update(str(s) for s in obj.signatures)
print(json.dumps({name: sorted(sigs) for name, sigs in used.items() if sigs}))
"""


def _kernels_used(*args: str) -> dict[str, set[str]]:
    """(kernel, argument types) a fresh process called, loaded or compiled, doing ``args``."""
    proc = subprocess.run([sys.executable, "-c", _USED, *args], capture_output=True, text=True)
    assert proc.returncode == 0, f"{args}: {proc.stderr[-2000:]}"
    return {name: set(sigs) for name, sigs in json.loads(proc.stdout.splitlines()[-1]).items()}


def test_the_precompile_covers_every_kernel_a_library_mission_calls() -> None:
    """Defect: a fresh set-up's first docking run took 19.7 s instead of 1.5 s, compiling the
    kernels Python calls directly (the landing plan's ``plant.hold_needed_xyn``, the scoring's
    ``gnc.ssa_each``, the site's ``wire.horizontal_offset_c``, ...), which the precompile left
    out; the unit tests likewise spent 55-98 s compiling them. Every kernel, with the argument
    types, that a docking, the sea trial and an EKF mission use must be one the precompile
    loads or compiles."""
    precompiled = _kernels_used("precompile")
    used = _kernels_used("full-docking-current-0.3", "sea-trial-appendix-c", "model-square-ekf-400")
    missing = {name: sorted(sigs - precompiled.get(name, set())) for name, sigs in used.items()}
    missing = {name: sigs for name, sigs in missing.items() if sigs}
    assert not missing, f"compiled on first use after a fresh set-up: {missing}"
    assert "sim.plant.hold_needed_xyn" in used, "the docking's landing plan was checked"
