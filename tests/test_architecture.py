"""The numeric core never imports the server or the browser view."""

import ast
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FORBIDDEN = {"fastapi", "uvicorn", "viser", "app", "web", "starlette"}


@pytest.mark.parametrize("package", ["sim", "control", "missions"])
def test_core_packages_do_not_import_server_or_view(package):
    files = sorted((ROOT / package).rglob("*.py"))
    assert files, f"no python files found in {package}"
    for path in files:
        tree = ast.parse(path.read_text(), filename=str(path))
        for node in ast.walk(tree):
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                names = [node.module]
            else:
                continue
            for name in names:
                assert name.split(".")[0] not in FORBIDDEN, f"{path} imports {name}"


def _imports(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(), filename=str(path))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out.extend(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            # "from missions import schema" names the module missions.schema
            out.extend(
                f"{node.module}.{a.name}" if node.module in {"missions", "app"} else node.module
                for a in node.names
            )
    return out


def test_web_uses_only_the_console_api_and_the_mission_schema():
    """The view talks to the console through ``app.console`` (its public API), never to the
    session, the simulation or the control system directly."""
    allowed_project = {"app.console", "missions.schema", "web"}
    for path in sorted((ROOT / "web").rglob("*.py")):
        for name in _imports(path):
            top = name.split(".")[0]
            if top in {"sim", "control", "missions", "app", "web"}:
                assert name in allowed_project or name.startswith("web."), (
                    f"{path.name} imports {name}"
                )


def test_log_offsets_are_read_only_by_the_declaration_and_the_kernel():
    """Everyone else reads the log row by block name (control.columns.LogRows / LAYOUT)."""
    pattern = (
        "L_T",
        "L_TREE",
        "L_ROV",
        "L_ETA_D",
        "L_ETA_HAT",
        "L_UTIL",
        "L_TAU_ROV",
        "L_MODE",
        "L_ACCEPT",
        "L_NIS",
        "L_TENSION",
        "L_CRANE",
        "L_Y",
        "L_F",
    )
    allowed = {ROOT / "control" / "columns.py", ROOT / "control" / "loop.py"}
    for folder in ("sim", "control", "missions", "app", "web", "tests", "benchmarks", "scripts"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            if path in allowed or path.name == "test_architecture.py":
                continue
            text = path.read_text()
            for name in pattern:
                assert f"loop.{name}" not in text and f"import {name}" not in text, (
                    f"{path.relative_to(ROOT)} reads log offset {name}"
                )


def test_one_simulation_owner():
    """Only control/simulation.py steps the plant; the old owners are gone."""
    assert not (ROOT / "sim" / "simulator.py").exists()
    assert not (ROOT / "control" / "closed_loop.py").exists()
    # the set-up's precompile calls the plant's kernels once each, to compile them; it owns
    # no simulation
    compiles_only = {ROOT / "app" / "precompile.py"}
    for folder in ("missions", "app", "web"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            if path in compiles_only:
                continue
            text = path.read_text()
            for kernel in ("run_chunk(", "run_open_chunk(", "rk4_step(", "plant.advance("):
                assert kernel not in text, f"{path.relative_to(ROOT)} steps the plant itself"


NEWTON_AS_N = re.compile(
    r"\b\w*(weight|tension|force|thrust|heave|drag|load|buoyancy|stiffness)"
    r"_(n|nm|n_per_m)\b"
)
"""Names that would read newtons as '_n' (which means NED): force_n, tension_n, ..."""
NED_FORCES = {"wire_force_n", "contact_force_n", "_force_n"}
"""Force vectors that really are in NED."""


def test_newtons_are_never_spelt_n():
    """`_n` means NED in our names; newtons are `_newton` (newton metres `_newton_m`). The old
    spellings live on only as accepted aliases of user files and in the reader of old logs."""
    for folder in ("sim", "control", "missions", "app", "web"):
        for path in sorted((ROOT / folder).rglob("*.py")) + sorted((ROOT / folder).rglob("*.toml")):
            for lineno, line in enumerate(path.read_text().splitlines(), start=1):
                if "AliasChoices" in line or "validation_alias" in line:
                    continue
                for match in NEWTON_AS_N.finditer(line):
                    assert match.group(0) in NED_FORCES, (
                        f"{path.relative_to(ROOT)}:{lineno}: {match.group(0)} spells newtons _n"
                    )


PACKAGES = ("sim", "control", "missions", "app", "web")
KNOWN_RINGS: set[frozenset[str]] = set()
"""Rings the test lets pass while they are being broken; empty once they are."""


def _module_name(path: Path) -> str:
    parts = list(path.relative_to(ROOT).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _own_module(name: str, modules: set[str]) -> str | None:
    """The module of ours that importing ``name`` runs: itself, or its nearest package."""
    while name and name not in modules:
        name = name.rpartition(".")[0]
    return name or None


def _imported(node: ast.Import | ast.ImportFrom, importer: str, is_package: bool) -> list[str]:
    """The dotted names an import statement brings in: ``from pkg import mod`` names
    ``pkg.mod`` (a module, or a name in pkg, which ``_own_module`` then takes to pkg)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names]
    base = node.module or ""
    if node.level:
        package = importer.split(".") if is_package else importer.split(".")[:-1]
        package = package[: len(package) - (node.level - 1)]
        base = ".".join([*package, *([node.module] if node.module else [])])
    return [f"{base}.{a.name}" for a in node.names]


def import_graph() -> dict[str, set[str]]:
    """Our modules and the modules of ours each imports: every import, at module level, in a
    function or under ``if TYPE_CHECKING:`` (a ring of type-only imports is still a ring a
    reader has to hold in their head)."""
    paths = {_module_name(p): p for pkg in PACKAGES for p in sorted((ROOT / pkg).rglob("*.py"))}
    modules = set(paths)
    graph: dict[str, set[str]] = {}
    for name, path in paths.items():
        tree = ast.parse(path.read_text(), filename=str(path))
        targets = {
            _own_module(imported, modules)
            for node in ast.walk(tree)
            if isinstance(node, ast.Import | ast.ImportFrom)
            for imported in _imported(node, name, path.name == "__init__.py")
        }
        graph[name] = {t for t in targets if t is not None and t != name}
    return graph


def strongly_connected(graph: dict[str, set[str]]) -> list[list[str]]:
    """Tarjan's strongly connected components of more than one node, each sorted (R. Tarjan,
    'Depth-first search and linear graph algorithms', 1972), iterative: no recursion limit."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    rings: list[list[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, edges = work[-1]
            for nxt in edges:
                if nxt not in index:
                    index[nxt] = low[nxt] = len(index)
                    stack.append(nxt)
                    on_stack.add(nxt)
                    work.append((nxt, iter(sorted(graph[nxt]))))
                    break
                if nxt in on_stack:
                    low[node] = min(low[node], index[nxt])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[node])
                if low[node] == index[node]:
                    ring = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        ring.append(member)
                        if member == node:
                            break
                    if len(ring) > 1:
                        rings.append(sorted(ring))
    return rings


def test_strongly_connected_finds_rings_and_leaves_chains():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a", "d"}, "d": {"e"}, "e": {"d"}, "f": {"a"}}
    assert sorted(strongly_connected(graph)) == [["a", "b", "c"], ["d", "e"]]
    assert strongly_connected({"a": {"b"}, "b": set()}) == []


def test_import_graph_counts_every_kind_of_import():
    graph = import_graph()
    # module level, "from pkg import module", a package's __init__
    assert "missions.schema" in graph["missions.runner"]
    assert "app.console" in graph["web.panels"]
    # relative ("from . import store")
    assert "app.campaign.store" in graph["app.campaign.runner"]
    # under TYPE_CHECKING (Simulation only annotates the fault views)
    assert "control.simulation" in graph["app.console.snapshot"]


def test_no_import_rings():
    """No two of our modules import each other, directly or round a ring: a module can be read
    (and tested) knowing only the ones below it. Break a ring by moving what both need into a
    module below both, not by hiding the import in a function."""
    found = strongly_connected(import_graph())
    gone = KNOWN_RINGS - {frozenset(r) for r in found}
    assert not gone, f"no longer rings, take them out of KNOWN_RINGS: {gone}"
    rings = [r for r in found if frozenset(r) not in KNOWN_RINGS]
    assert not rings, "modules that import each other in a ring: " + "; ".join(
        " <-> ".join(r) for r in rings
    )
