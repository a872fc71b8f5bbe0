"""numba's on-disk cache of the compiled core, kept valid by what the code says.

numba, left to itself, checks a cached kernel against the bytes of its own source file and
names the cache file after the line the function starts on. Both are wrong for this core:

- a kernel that calls kernels of another file (``control.loop``'s chunk kernels call the
  plant's step in ``sim.plant``) would keep running its old machine code after only that
  other file changed;
- an edit of a comment or a docstring changes the file's bytes and moves the lines below
  it, and so would cost the compile of every kernel of the file.

So the kernels of ``sim`` and ``control`` use ``CoreLocator``: their cache lives in
``.numba-cache/`` beside the packages (or under ``NUMBA_CACHE_DIR`` when the user sets it),
one index per kernel named after the kernel alone, and a kernel's stamp is a digest of the
code of its module and of every module of the core it imports, directly or through
others, each read as its syntax tree without docstrings (comments are not in the tree).
numba adds the kernel's own bytecode to each entry's key. An edit of a comment or a
docstring therefore recompiles nothing; an edit of code recompiles, when they are next
called, the kernels of that module and of the modules that import it, and no others.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import logging
import os
import time
from pathlib import Path
from typing import Any

from numba.core import caching, event

PACKAGES = ("sim", "control")
"""The packages whose kernels this locator caches (every numba kernel is in one of them)."""
ROOT = Path(__file__).resolve().parent.parent
"""The folder holding the packages (the repository root in a development install)."""
FOLDER = ".numba-cache"
"""The cache's folder under ``ROOT`` (unless ``NUMBA_CACHE_DIR`` is set)."""


def cache_root() -> Path:
    """Where the core's kernels are cached: ``NUMBA_CACHE_DIR`` if set, else ``ROOT/FOLDER``."""
    chosen = os.environ.get("NUMBA_CACHE_DIR")
    return Path(chosen) if chosen else ROOT / FOLDER


def _without_docstrings(tree: ast.AST) -> ast.AST:
    """``tree`` with the docstring of the module and of every class and function removed."""
    for node in ast.walk(tree):
        if isinstance(node, ast.Module | ast.ClassDef | ast.FunctionDef | ast.AsyncFunctionDef):
            body = node.body
            first = body[0] if body else None
            if (
                isinstance(first, ast.Expr)
                and isinstance(first.value, ast.Constant)
                and isinstance(first.value.value, str)
            ):
                node.body = body[1:] or [ast.Pass()]
    return tree


@functools.cache
def code_digest(path: Path) -> str:
    """A digest of the code in ``path``: its syntax tree without docstrings or positions, so
    comments, docstrings, blank lines and line breaks do not change it."""
    tree = _without_docstrings(ast.parse(path.read_bytes(), filename=str(path)))
    return hashlib.sha256(ast.dump(tree, include_attributes=False).encode()).hexdigest()


def _module_file(root: Path, dotted: str) -> Path | None:
    """The source file of module ``dotted`` under ``root`` (a package's ``__init__.py``),
    None when it is not one of the core's."""
    parts = dotted.split(".")
    if parts[0] not in PACKAGES:
        return None
    base = root.joinpath(*parts)
    for candidate in (base.with_suffix(".py"), base / "__init__.py"):
        if candidate.is_file():
            return candidate
    return None


@functools.cache
def core_imports(path: Path, root: Path = ROOT) -> frozenset[Path]:
    """The core's modules that ``path`` imports itself (``import sim.x``, ``from sim import
    x``, ``from sim.x import y``), as files under ``root``: for ``from package import name``
    the module ``name`` if it is one, else the package."""
    found: set[Path | None] = set()
    for node in ast.walk(ast.parse(path.read_bytes(), filename=str(path))):
        if isinstance(node, ast.Import):
            found.update(_module_file(root, alias.name) for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            for alias in node.names:
                # ``from sim import plant`` depends on sim/plant.py, not on sim/__init__.py;
                # ``from sim.gnc import mv3_into`` on sim/gnc.py
                sub = _module_file(root, f"{node.module}.{alias.name}")
                found.add(sub if sub is not None else _module_file(root, node.module))
    return frozenset(f for f in found if f is not None and f != path)


def dependencies(path: Path, root: Path = ROOT) -> list[Path]:
    """``path`` and every module of the core it imports, directly or through others, sorted."""
    seen = {path}
    todo = [path]
    while todo:
        for dep in core_imports(todo.pop(), root):
            if dep not in seen:
                seen.add(dep)
                todo.append(dep)
    return sorted(seen)


def stamp(path: Path, root: Path = ROOT) -> str:
    """The cache stamp of the kernels in ``path``: the code digests of the module and of all
    it depends on, with their paths relative to ``root``."""
    h = hashlib.sha256()
    for dep in dependencies(path, root):
        h.update(dep.relative_to(root).as_posix().encode() + b"\0")
        h.update(code_digest(dep).encode() + b"\0")
    return h.hexdigest()[:32]


class CoreLocator(caching._CacheLocator):
    """numba's cache locator for the kernels of ``PACKAGES`` (see the module's docstring)."""

    def __init__(self, py_file: Path) -> None:
        self._py_file = py_file
        relative = py_file.parent.relative_to(ROOT)
        self._cache_path = str(cache_root().joinpath(relative))

    def get_cache_path(self) -> str:
        return self._cache_path

    def get_source_stamp(self) -> str:
        return stamp(self._py_file)

    def get_disambiguator(self) -> str:
        return "core"  # not the line number: the entry survives lines moving above it

    @classmethod
    def from_function(cls, py_func: object, py_file: str) -> CoreLocator | None:
        path = Path(py_file).resolve()
        if not path.is_file() or not path.is_relative_to(ROOT):
            return None
        if path.relative_to(ROOT).parts[0] not in PACKAGES:
            return None
        self = cls(path)
        try:
            self.ensure_cache_path()
        except OSError:  # not writable (an installed copy): numba's own locators decide
            return None
        return self


COMPILE_LOG = logging.getLogger("sim.compile")
"""Where compiles are told (``CompileEvents``); the command line shows them (``app.compiling``)."""


class CompileEvents(event.Listener):
    """numba's compile events as debug records of ``COMPILE_LOG``, with the attributes
    ``kernel`` (module and name), ``depth`` (1: a kernel Python itself called; more: one a
    kernel being compiled calls), ``phase`` ("start" or "end") and, at the end, ``took_s``.
    Nothing is made when nobody listens at that level."""

    def __init__(self) -> None:
        self.depth = 0
        self.started: list[float] = []

    @staticmethod
    def _kernel(ev: event.Event) -> str:
        func = ev.data["dispatcher"].py_func
        return f"{func.__module__}.{func.__qualname__}"

    def on_start(self, ev: event.Event) -> None:
        self.depth += 1
        self.started.append(time.perf_counter())
        if COMPILE_LOG.isEnabledFor(logging.DEBUG):
            kernel = self._kernel(ev)
            info = {"kernel": kernel, "depth": self.depth, "phase": "start"}
            COMPILE_LOG.debug("compiling %s", kernel, extra=info)

    def on_end(self, ev: event.Event) -> None:
        took = time.perf_counter() - self.started.pop()
        if COMPILE_LOG.isEnabledFor(logging.DEBUG):
            kernel = self._kernel(ev)
            info = {"kernel": kernel, "depth": self.depth, "phase": "end", "took_s": took}
            COMPILE_LOG.debug("compiled %s in %.1f s", kernel, took, extra=info)
        self.depth -= 1


_EVENTS = CompileEvents()
_installed = False


def install() -> None:
    """Put ``CoreLocator`` first in numba's list of cache locators and tell compiles to
    ``COMPILE_LOG`` (once). Runs when ``sim`` is imported, before any kernel is compiled or
    loaded."""
    global _installed
    if _installed:
        return
    _installed = True
    event.register("numba:compile", _EVENTS)
    locators: list[Any] = caching.CacheImpl._locator_classes
    if CoreLocator not in locators:
        locators.insert(0, CoreLocator)
