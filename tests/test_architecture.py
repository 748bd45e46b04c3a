"""Architecture guards: the core stays Qt-free; lint stays clean; CI runs the README's command."""

import ast
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.helpers import needs_source

ROOT = Path(__file__).resolve().parents[1]
pytestmark = needs_source  # checks of the source tree itself
FORBIDDEN = ("PyQt5", "pyqtgraph", "ui")


def forbidden_imports(source: str) -> list[str]:
    """Top-level modules from FORBIDDEN imported anywhere in the source (incl. inside functions)."""
    found = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module]
        else:
            continue
        found += [n for n in names if n.split(".")[0] in FORBIDDEN]
    return found


def test_guard_detects_a_qt_import():
    assert forbidden_imports("def f():\n    from PyQt5.QtCore import QTimer\n") == ["PyQt5.QtCore"]
    assert forbidden_imports("import pyqtgraph as pg") == ["pyqtgraph"]
    assert forbidden_imports("import numpy\nfrom app.models import load_robot") == []


def test_core_never_imports_qt():
    offenders = {
        str(p.relative_to(ROOT)): bad
        for p in (ROOT / "app").rglob("*.py")
        if (bad := forbidden_imports(p.read_text(encoding="utf-8")))
    }
    assert offenders == {}


def _tool(name: str) -> str:
    exe = Path(sys.executable).with_name(name)
    path = str(exe) if exe.exists() else shutil.which(name)
    if path is None:
        pytest.skip(f"{name} is not installed")
    return path


def test_import_linter_contracts_hold():
    res = subprocess.run([_tool("lint-imports"), "--no-cache"], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "0 broken" in res.stdout


@pytest.mark.slow
@pytest.mark.parametrize(
    ("where", "line", "contract"),
    [
        ("sim/_bad.py", "from app.control import tac", "never import each other"),
        ("models/_bad.py", "from app.sim import motionlab", "floors"),
        ("analysis/_bad.py", "from app.engine import server", "floors"),
        ("plc/_bad.py", "from app.engine import lab_session", "floors"),
        ("control/_bad.py", "from app.scenes import lab", "floors"),
    ],
    ids=[
        "plant-imports-controller",
        "models-import-plants",
        "studies-import-engine",
        "ads-bridge-imports-engine",
        "controller-imports-its-scene",
    ],
)
def test_the_layer_contracts_catch_an_import_across_floors(tmp_path, where, line, contract):
    """The floors of ARCHITECTURE.md are enforced, not only written down: a copy of the core with one
    import against them breaks its contract (issue 15, item 7)."""
    shutil.copytree(ROOT / "app", tmp_path / "app", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path)
    (tmp_path / "ui").mkdir()
    (tmp_path / "ui" / "__init__.py").write_text("", encoding="utf-8")
    (tmp_path / "app" / where).write_text(line + "\n", encoding="utf-8")
    res = subprocess.run(
        [_tool("lint-imports"), "--no-cache"], cwd=tmp_path, capture_output=True, text=True, timeout=120
    )
    assert res.returncode != 0
    broken = [ln for ln in res.stdout.splitlines() if ln.endswith("BROKEN")]
    text = " ".join(res.stdout.split())  # contract names may wrap
    assert broken and contract in text and f"app.{where[:-3].replace('/', '.')}" in text, res.stdout


def test_ruff_is_clean():
    res = subprocess.run(
        [_tool("ruff"), "check", "--no-cache", "."], cwd=ROOT, capture_output=True, text=True, timeout=120
    )
    assert res.returncode == 0, res.stdout + res.stderr


def test_ci_runs_the_readme_test_command():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```(?:sh|bash)\n(.*?)```", readme, flags=re.S)
    commands = [line.strip() for b in blocks[:2] for line in b.splitlines() if line.strip()]
    assert len(commands) == 2, "the README starts with exactly two set-up commands"
    ci = (ROOT / ".ci" / "run").read_text(encoding="utf-8")
    assert commands[1] in ci


def test_no_module_of_the_core_or_the_gui_is_a_hall():
    """Issue 29, item 5: no module of ``app/`` or ``ui/`` over 800 lines (the CLI was 1,860, the Motion-Lab tab
    1,337, the engine server 964, the drawings 977: each is a package of rooms now)."""
    sizes = {
        str(p.relative_to(ROOT)): len(p.read_text(encoding="utf-8").splitlines())
        for folder in ("app", "ui")
        for p in (ROOT / folder).rglob("*.py")
    }
    assert len(sizes) > 100
    assert {name: n for name, n in sizes.items() if n > 800} == {}


def test_no_compiled_function_takes_more_than_eight_arguments():
    """Issue 29, item 3: a kernel takes records (tuples of arrays and numbers), not a frozen row of positional
    parameters (the lab step took 69, the crane-head chunk 27): adding a block to a scene adds a record
    field, not a parameter to every signature."""
    import ast

    kernels, over = 0, {}
    for path in (ROOT / "app").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.FunctionDef) and any(ast.unparse(d) == "_jit" for d in node.decorator_list):
                kernels += 1
                a = node.args
                count = len(a.posonlyargs) + len(a.args) + len(a.kwonlyargs) + bool(a.vararg) + bool(a.kwarg)
                if count > 8:
                    over[f"{path.relative_to(ROOT)}:{node.name}"] = count
    assert kernels > 40
    assert over == {}
