"""The numeric core never imports the server or the browser view."""

import ast
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
