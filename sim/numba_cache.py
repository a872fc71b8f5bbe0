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
one index per kernel named after the kernel alone, and a kernel's stamp is a digest of what
it reaches (``kernel_stamp``): its own code, the code of every function and kernel of the
core it calls, directly or through others, their options (``inline``, ``error_model``: they
shape the callers' code too) and the values of the names they read (a module constant is
frozen into the machine code). Code is read as its bytecode, names and
constants, without line numbers or docstrings. An edit of a comment or a docstring therefore
recompiles nothing; an edit of a formula recompiles, when they are next called, the kernels
that reach it, and no others: an edit of the wire force recompiles the plant's step and the
chunk kernels that call it, not the controller's step.
"""

from __future__ import annotations

import enum
import functools
import hashlib
import logging
import os
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from types import CodeType, FunctionType, ModuleType
from typing import Any

import numpy as np
from numba.core import caching, event
from numba.core.dispatcher import Dispatcher

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


def _code_parts(code: CodeType, function: bool) -> Iterator[str]:
    """What ``code`` does, as text: its bytecode, names and constants, its nested code
    objects' too; not its line numbers, and not a function's docstring (the first constant
    of a function's code, or None when it has none)."""
    yield code.co_code.hex()
    yield repr((code.co_names, code.co_varnames, code.co_freevars, code.co_cellvars))
    yield repr((code.co_argcount, code.co_posonlyargcount, code.co_kwonlyargcount))
    for i, const in enumerate(code.co_consts):
        if isinstance(const, CodeType):
            yield from _code_parts(const, not const.co_name.startswith("<"))
        elif not (function and i == 0 and isinstance(const, str)):
            yield repr(const)


def _names(code: CodeType) -> set[str]:
    """The global and attribute names ``code`` and its nested code read."""
    names = set(code.co_names)
    for const in code.co_consts:
        if isinstance(const, CodeType):
            names |= _names(const)
    return names


def _in_core(module_name: str | None) -> bool:
    return bool(module_name) and str(module_name).split(".")[0] in PACKAGES


def _value_text(value: object, functions: list[FunctionType]) -> str:
    """A value a kernel reads, as text that changes when the value does (a constant is frozen
    into the machine code); the core's functions and kernels it holds go into
    ``functions``, to be followed."""
    if isinstance(value, Dispatcher):
        value = value.py_func
    if isinstance(value, FunctionType):
        if _in_core(value.__module__):
            functions.append(value)
        return f"function {value.__module__}.{value.__qualname__}"
    if isinstance(value, type):
        if not _in_core(value.__module__):
            return f"type {value.__module__}.{value.__qualname__}"
        fields = getattr(value, "_fields", None)
        annotations = getattr(value, "__annotations__", {})
        defaults = getattr(value, "_field_defaults", {})
        return f"class {value.__qualname__} {fields!r} {annotations!r} {defaults!r}"
    if isinstance(value, np.ndarray):
        digest = hashlib.sha256(np.ascontiguousarray(value).tobytes()).hexdigest()
        return f"array {value.dtype.str} {value.shape} {digest}"
    if isinstance(value, tuple | list):
        return repr(type(value)) + "(" + ",".join(_value_text(v, functions) for v in value) + ")"
    if value is None or isinstance(value, bool | int | float | complex | str | bytes | np.generic):
        return repr(value)
    if isinstance(value, enum.Enum):
        return repr(value)
    return f"object {type(value).__module__}.{type(value).__qualname__}"


@functools.cache
def _function_part(func: FunctionType) -> tuple[str, tuple[FunctionType, ...]]:
    """One function's share of a stamp: its code and the values of the names it reads (the
    core's modules opened at those names), and the core's functions it reaches directly."""
    code = func.__code__
    names = _names(code)
    parts = [f"{func.__module__}.{func.__qualname__}", *_code_parts(code, True)]
    kernel = func.__globals__.get(func.__name__)
    if isinstance(kernel, Dispatcher) and kernel.py_func is func:
        # its options (inline, error_model, fastmath) shape its code and its callers'
        parts.append(f"options {sorted(kernel.targetoptions.items())!r}")
    functions: list[FunctionType] = []
    values: list[tuple[str, object]] = []
    for name in sorted(names):
        if name in func.__globals__:
            values.append((name, func.__globals__[name]))
    cells = func.__closure__ or ()
    values += [
        (name, cell.cell_contents) for name, cell in zip(code.co_freevars, cells, strict=True)
    ]
    values += [(f"default {i}", v) for i, v in enumerate(func.__defaults__ or ())]
    while values:
        name, value = values.pop(0)
        if isinstance(value, ModuleType):
            # ``plant.rk4_step_into``: the module's members the code names, followed in turn
            if _in_core(value.__name__):
                values += [
                    (f"{name}.{n}", getattr(value, n)) for n in sorted(names) if hasattr(value, n)
                ]
            continue
        parts.append(f"{name} = {_value_text(value, functions)}")
    return "\n".join(parts), tuple(functions)


def kernel_stamp(func: FunctionType) -> str:
    """The cache stamp of the kernel whose Python function is ``func``: a digest of its code
    and of everything of the core it reaches, followed through the kernels and functions it
    calls (their machine code is linked into its own) and the constants it reads."""
    seen: dict[str, str] = {}
    todo = [func]
    while todo:
        f = todo.pop()
        key = f"{f.__module__}.{f.__qualname__}"
        if key in seen:
            continue
        seen[key], reached = _function_part(f)
        todo += reached
    h = hashlib.sha256(f"python {sys.version_info[:2]}".encode())
    for key in sorted(seen):
        h.update(seen[key].encode() + b"\0")
    return h.hexdigest()[:32]


class KernelStamp:
    """A kernel's stamp, worked out when numba first compares or saves it. numba asks for the
    stamp when the kernel is decorated, while its module is still being imported and the
    names it reads further down are not yet defined; it only compares it with the index's
    stamp (a str) and pickles it."""

    def __init__(self, func: FunctionType) -> None:
        self._func = func
        self._value: str | None = None

    @property
    def value(self) -> str:
        if self._value is None:
            self._value = kernel_stamp(self._func)
        return self._value

    def __eq__(self, other: object) -> bool:
        if isinstance(other, KernelStamp):
            return self.value == other.value
        return self.value == other if isinstance(other, str) else NotImplemented

    def __hash__(self) -> int:
        return hash(self.value)

    def __reduce__(self) -> tuple[type[str], tuple[str]]:
        return (str, (self.value,))  # saved in the index as the plain digest

    def __repr__(self) -> str:
        return f"KernelStamp({self.value})"


class CoreLocator(caching._CacheLocator):
    """numba's cache locator for the kernels of ``PACKAGES`` (see the module's docstring)."""

    def __init__(self, py_func: FunctionType, py_file: Path) -> None:
        self._py_func = py_func
        self._py_file = py_file
        relative = py_file.parent.relative_to(ROOT)
        self._cache_path = str(cache_root().joinpath(relative))

    def get_cache_path(self) -> str:
        return self._cache_path

    def get_source_stamp(self) -> Any:
        return KernelStamp(self._py_func)

    def get_disambiguator(self) -> str:
        return "core"  # not the line number: the entry survives lines moving above it

    @classmethod
    def from_function(cls, py_func: object, py_file: str) -> CoreLocator | None:
        path = Path(py_file).resolve()
        if not path.is_file() or not path.is_relative_to(ROOT):
            return None
        if path.relative_to(ROOT).parts[0] not in PACKAGES:
            return None
        self = cls(py_func, path)  # type: ignore[arg-type]
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
