"""Architecture guards: the core stays Qt-free; lint stays clean; CI runs the README's command."""

import ast
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
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
