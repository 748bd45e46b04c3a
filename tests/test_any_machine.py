"""Tests that pass on any machine, and paths as users give them (issue 28, items 1 and 2).

* Every place a user gives a path takes one with spaces and letters beyond ASCII, in a folder deeper than
  a developer's: robot files, ``--out``, RAO and scatter files, the CSV logger, time series (CLI
  subprocesses where the behaviour is the CLI's, as a user starts it).
* A refusal that must shorten a path keeps the file name and elides the middle; a refusal naming a file
  keeps ``file:line``.

scripts/hostile_lane.sh runs the fast lane again under a long ``--basetemp`` with "Øvelse 1" in it,
LANG=C.UTF-8, TZ=Pacific/Chatham and, in CI, as nobody.
"""

from __future__ import annotations

import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from app.errors import RobotXmlError, error_line, printable_path

ROOT = Path(__file__).resolve().parents[1]
ROBOT = ROOT / "robots" / "comau_smart5_3dof.xml"


@pytest.fixture
def hostile(tmp_path) -> Path:
    """A folder as a user's may be: spaces, Norwegian letters, an en dash, 100 characters below tmp_path."""
    d = tmp_path / "Øvelse 1" / "Kran på dekk – forsøk med lange navn" / "målinger fra laboratoriet i Ålesund, vår 2026"
    d.mkdir(parents=True)
    return d


def _bosun(*argv: str, cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
    """``bosun ARGS`` as a user runs it: a subprocess, from a folder of its own (not the checkout)."""
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    proc = subprocess.run(
        [sys.executable, "-m", "app", *argv], capture_output=True, text=True,
        cwd=cwd, env=env, timeout=timeout,
    )  # fmt: skip
    assert "Traceback" not in proc.stderr, proc.stderr
    return proc


# ----------------------------------------------------------------------------- item 2: refusals name the file
def test_printable_path_keeps_the_file_name_and_elides_the_middle():
    long = "/home/operatør/" + "a very long folder name/" * 12 + "kran 2.xml"
    for limit in (40, 80, 120):
        s = printable_path(long, limit)
        assert len(s) == limit and s.endswith("kran 2.xml") and s.startswith("/home") and "…" in s
    assert printable_path("/short/kran.xml", 80) == "/short/kran.xml"
    assert printable_path("/a/b\nc.xml", 80) == "/a/b?c.xml"  # a newline never splits the line


def test_a_refusal_under_a_long_path_keeps_file_and_line():
    path = "/srv/" + "ståltau og vinsj/" * 30 + "kran.xml"  # 500 characters
    err = RobotXmlError(path, 9, "not valid UTF-8 (byte 0xb1) " + "x" * 400)
    for limit in (120, 300, 500):
        line = error_line(err, limit)
        assert len(line) <= limit and "\n" not in line, line
        assert "kran.xml:9: not valid UTF-8" in line and line.startswith("/srv/"), line
    short = RobotXmlError("arm.xml", 3, "schema: bad")
    assert error_line(short, 300) == "arm.xml:3: schema: bad" == str(short)
    assert error_line(RobotXmlError("arm.xml", None, "not a regular file"), 300) == "arm.xml: not a regular file"
    assert error_line(ValueError("a\nb"), 300) == "a b"


def test_the_engine_refuses_a_broken_robot_in_a_deep_folder_naming_file_and_line(hostile):
    """set_robot's refusal was cut at 300 characters from its start: under deep folders the file name and
    line went first."""
    from app.engine.scene import CommandError
    from app.engine.session import Session

    deep = hostile.joinpath(*[f"undermappe {i} med eit langt namn – ærleg talt" for i in range(6)])
    deep.mkdir(parents=True)
    bad = deep / "ødelagt arm.xml"
    bad.write_text(ROBOT.read_text(encoding="utf-8").replace("</robot>", "<nope/></robot>"), encoding="utf-8")
    session = Session(robot_name="comau_smart5_3dof", robots_dirs=(str(hostile.parent),))
    with pytest.raises(CommandError) as info:
        session.set_robot(str(bad))
    msg = str(info.value)
    assert len(msg) <= 300 and "\n" not in msg, msg
    assert "ødelagt arm.xml:" in msg and "nope" in msg, msg
    assert str(hostile.parent.parent) not in msg, msg  # the engine's folders above the allowed one: not shown
    assert session.robot_name == "comau_smart5_3dof"


def test_an_unreadable_robot_file_is_refused_without_the_engines_path(monkeypatch):
    """An OSError's text holds the whole path (the engine's folders), and was cut at its end."""
    import app.engine.session as session_module
    from app.engine.scene import CommandError

    secret = "/srv/bosun/" + "hemmelig mappe/" * 20 + "arm.xml"

    def refuse(*_args, **_kw):
        raise PermissionError(13, "Permission denied", secret)

    session = session_module.Session(robot_name="comau_smart5_3dof")
    monkeypatch.setattr(session_module, "load_robot_file", refuse)
    with pytest.raises(CommandError) as info:
        session.set_robot(secret)
    assert str(info.value) == "arm.xml: cannot read: Permission denied"


# ----------------------------------------------------------------------------- item 1: paths as users give them
def test_robot_files_in_a_folder_with_spaces_and_letters_beyond_ascii(hostile):
    robot = hostile / "Comau på prøve.xml"
    shutil.copy(ROBOT, robot)
    proc = _bosun("check", str(robot), cwd=hostile)
    assert proc.returncode == 0 and f"ok       {robot}: " in proc.stdout, (proc.stdout, proc.stderr)
    proc = _bosun("fk", str(robot), "--q", "0", "0", "0", "--json", cwd=hostile)
    assert proc.returncode == 0, proc.stderr
    assert len(json.loads(proc.stdout)["position"]) == 3
    bad = hostile / "ødelagt – arm.xml"
    bad.write_text(ROBOT.read_text(encoding="utf-8").replace("</robot>", "<nope/></robot>"), encoding="utf-8")
    proc = _bosun("check", str(bad), cwd=hostile)
    assert proc.returncode == 2 and f"refused  {bad}:" in proc.stdout, (proc.stdout, proc.stderr)


def test_out_and_an_rao_file_in_a_folder_with_spaces_and_letters_beyond_ascii(hostile):
    from app.marine.vessels import shipped_table_path

    rao = hostile / "RAO for «Havbåt» – lastet.csv"
    shutil.copy(shipped_table_path(), rao)
    out = hostile / "resultat – kjøring 1"
    proc = _bosun("sim", "tac", "--duration", "10", "--vessel", str(rao), "--out", str(out), "--json", cwd=hostile)
    assert proc.returncode == 0, proc.stderr
    assert (out / "summary.json").is_file() and (out / "timeseries.csv").is_file()
    bad = hostile / "RAO med feil – høy.csv"
    head = "w,heading_deg," + ",".join(f"{d}_amp,{d}_phase" for d in ("surge", "sway", "heave", "roll", "pitch", "yaw"))
    row = "{w},0,0.1,0,0.1,0,{heave},3.1,0.01,0,0.01,0,0.01,0"
    bad.write_text(f"{head}\n{row.format(w=0.5, heave=1)}\n{row.format(w=0.6, heave='1e300')}\n", encoding="utf-8")
    proc = _bosun("sim", "tac", "--duration", "10", "--vessel", str(bad), "--out", str(out / "x"), cwd=hostile)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    assert f"{bad}:3: field heave_amp: 1e300" in proc.stderr, proc.stderr  # the whole path, then the line


def test_a_scatter_file_in_a_folder_with_spaces_and_letters_beyond_ascii(hostile):
    from app.analysis.operability import load_scatter

    scatter = hostile / "spredning – Nordsjøen.csv"
    scatter.write_text("hs\\tp,7,9\n1.5,30,20\n3.0,30,\n", encoding="utf-8")
    assert load_scatter(scatter).hs.tolist() == [1.5, 3.0]
    bad = hostile / "spredning med feil – æøå.csv"
    bad.write_text("hs\\tp,7,9\n1.5,0.1,x\n", encoding="utf-8")
    proc = _bosun("study", "operability", "--scatter", str(bad), "--out", str(hostile / "studie"), cwd=hostile)
    assert proc.returncode == 2 and proc.stderr.count("\n") == 1, proc.stderr
    assert f"{bad}:2: Tp 9 s: 'x' is not a number" in proc.stderr, proc.stderr
    assert not (hostile / "studie").exists()


def test_the_csv_logger_writes_to_a_folder_with_spaces_and_letters_beyond_ascii(hostile):
    from dataclasses import replace

    pytest.importorskip("PyQt5")  # the logger is the GUI's (plain Python, in ui/)
    from app.net.snapshots import InputFlags, TeleopSnapshot
    from ui.csv_logger import StateCsvLogger

    state = TeleopSnapshot(
        q=[0.1, 0.2], qdot=[0, 0], tool=[1, 2, 3], target=[1, 2, 3], signal=[0, 0, 0], solver_error=None,
        solver_time=0.001, flags=InputFlags(stale_input=False, enabled=True),
    )  # fmt: skip
    path = hostile / "logg – kjøring 1.csv"
    log = StateCsvLogger(str(path), ["q", "tool"], duration=0.05, joint_names=["a", "b"])
    written = sum(bool(log.add(replace(state, t=k * 0.02))) for k in range(10))
    assert written == 3 and log.done
    with open(path, encoding="utf-8", newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["t", "q_a", "q_b", "tool_x", "tool_y", "tool_z"] and len(rows) == 4


def test_a_time_series_from_a_folder_with_spaces_and_letters_beyond_ascii(hostile):
    """The lab's time-series source as the GUI sends it: the file's text and its name."""
    import numpy as np

    from app.sim.stewart import parse_timeseries_csv, timeseries_to_csv

    t = np.arange(0.0, 2.0, 0.1)
    eta = np.zeros((t.size, 6))
    eta[:, 2] = 0.05 * np.sin(t)
    path = hostile / "bølgebevegelse – Ålesund.csv"
    path.write_text(timeseries_to_csv(t, eta), encoding="utf-8")
    series = parse_timeseries_csv(path.read_text(encoding="utf-8"), str(path))
    assert np.allclose(series.t, t)
    bad = hostile / "bølgebevegelse med feil.csv"
    bad.write_text(path.read_text(encoding="utf-8").replace("\n0.5,", "\n0.5x,", 1), encoding="utf-8")
    with pytest.raises(Exception, match=rf"^{_re(str(bad))}:\d+: "):
        parse_timeseries_csv(bad.read_text(encoding="utf-8"), str(bad))


def _re(text: str) -> str:
    import re

    return re.escape(text)


def test_the_tests_import_this_checkouts_app():
    """From any working directory (the hostile lane runs from its HOME), the tests test the checkout's app/
    beside them, not another one an editable install points at (the core job's tree has none: the wheel's)."""
    import app

    if (ROOT / "app").is_dir():
        assert Path(app.__file__).resolve().parent == (ROOT / "app").resolve()
    else:
        assert "site-packages" in app.__file__


# ----------------------------------------------------------------------------- item 1: text in UTF-8, any locale


def _text_opens_without_encoding(path: Path) -> list[str]:
    """``open``/``Path.open`` in text mode, ``read_text`` and ``write_text`` calls in one file that name no
    encoding (they take the locale's: a Latin-1 or C locale breaks '±', '°' and 'Ø')."""
    import ast

    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not isinstance(node, ast.Call):
            continue
        f = node.func
        name = f.attr if isinstance(f, ast.Attribute) else getattr(f, "id", None)
        keywords = {k.arg for k in node.keywords}
        if "encoding" in keywords or name not in ("open", "read_text", "write_text"):
            continue
        if name == "open":
            # builtin open(file, mode) or path.open(mode); plc.open() and the like take no mode and no file
            positional = node.args[1:] if isinstance(f, ast.Name) else node.args
            modes = [a.value for a in positional[:1] if isinstance(a, ast.Constant)]
            modes += [k.value.value for k in node.keywords if k.arg == "mode" and isinstance(k.value, ast.Constant)]
            if isinstance(f, ast.Attribute) and not node.args and not node.keywords and not _is_path(f.value):
                continue
            if any(isinstance(m, str) and "b" in m for m in modes):
                continue
        found.append(f"{path.name}:{node.lineno}: {ast.unparse(node)[:70]}")
    return found


def _is_path(node) -> bool:
    """A receiver that reads as a path (``path``, ``tmp_path / "x"``, ``Path(...)``): ``x.open()`` on it is a
    text-mode file open."""
    import ast

    text = ast.unparse(node)
    return isinstance(node, ast.BinOp) or "path" in text.lower() or text.startswith("Path(")


def test_every_text_file_the_code_opens_is_utf8_whatever_the_locale():
    import app

    roots = [Path(app.__file__).parent, ROOT / "tests", ROOT / "scripts"]
    if (ROOT / "ui").is_dir():
        roots.append(ROOT / "ui")
    found = [hit for r in roots for p in sorted(r.rglob("*.py")) for hit in _text_opens_without_encoding(p)]
    assert found == [], "text opened in the locale's encoding:\n" + "\n".join(found)
