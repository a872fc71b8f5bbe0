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
