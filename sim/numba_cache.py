"""Where numba keeps the compiled numeric core: one cache folder per version of its sources.

numba checks a cached function against its own source file only. A kernel that calls into, or
inlines, functions of another file (the chunk kernels of ``control.loop`` hold the whole plant
step of ``sim.plant``) keeps running its cached machine code after only that other file
changed: an edited plant would go on running the old one, silently. So, unless the user sets
``NUMBA_CACHE_DIR`` themselves, the cache goes to ``.numba-cache/<digest>`` beside the
packages, the digest taken over every source file of ``sim`` and ``control`` (where all the
compiled code lives). A change to any of them starts a fresh folder, compiled again by
``python -m app.precompile --if-needed`` (which the set-up script runs) or, failing that, on
first use.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import sys
from collections.abc import Iterable
from pathlib import Path

PACKAGES = ("sim", "control")
"""The packages whose sources the digest covers (every numba kernel is in one of them)."""
ROOT = Path(__file__).resolve().parent.parent
"""The folder holding the packages (the repository root in a development install)."""
FOLDER = ".numba-cache"
"""The cache's folder under ``ROOT``."""
CHOSEN: Path | None = None
"""The folder ``configure`` chose (None: the user set ``NUMBA_CACHE_DIR``)."""


def source_files(root: Path = ROOT) -> list[Path]:
    """The ``.py`` files of ``PACKAGES`` under ``root``, sorted by their relative path."""
    files = [p for pkg in PACKAGES for p in (root / pkg).rglob("*.py")]
    return sorted(files, key=lambda p: p.relative_to(root).as_posix())


def source_digest(files: Iterable[Path], root: Path = ROOT) -> str:
    """A 16-hex-digit digest of the files' relative paths and contents."""
    h = hashlib.sha256()
    for path in files:
        h.update(path.relative_to(root).as_posix().encode())
        h.update(b"\0")
        h.update(path.read_bytes())
        h.update(b"\0")
    return h.hexdigest()[:16]


def default_cache_dir(root: Path = ROOT) -> Path:
    """``root/.numba-cache/<digest of the sources>``."""
    return root / FOLDER / source_digest(source_files(root), root)


def configure() -> Path | None:
    """Point numba at ``default_cache_dir()`` unless ``NUMBA_CACHE_DIR`` is set already.
    Returns the folder chosen (None: the user's own). Runs when ``sim`` is imported, before
    any kernel is compiled or loaded."""
    global CHOSEN
    if os.environ.get("NUMBA_CACHE_DIR"):
        return None
    path = default_cache_dir()
    os.environ["NUMBA_CACHE_DIR"] = str(path)
    CHOSEN = path
    if "numba" in sys.modules:  # imported before us: numba read its settings then
        from numba.core import config

        config.reload_config()
    return path


def prune(keep: Path) -> list[Path]:
    """Remove the other source versions' folders beside ``keep`` (the folders of earlier
    sources). Returns those removed."""
    gone = [p for p in keep.parent.iterdir() if p.is_dir() and p != keep]
    for p in gone:
        shutil.rmtree(p, ignore_errors=True)
    return gone
