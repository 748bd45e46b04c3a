"""The bosun command line: output, JSON, and one-line errors with exit status 2."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from app.cli import main
from tests.helpers import needs_qt
from tests.test_robot_xml import GOOD


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_robots_table(capsys):
    code, out, err = run(capsys, "robots")
    assert code == 0 and err == ""
    assert "comau_smart5_3dof" in out and "stewart" in out and "11 robot(s)" in out


def test_robots_json(capsys):
    code, out, _ = run(capsys, "robots", "--json")
    assert code == 0
    data = json.loads(out)
    by_name = {r["name"]: r for r in data["robots"]}
    assert by_name["kuka_youbot"]["dof"] == 5 and by_name["tac_delta_head"]["type"] == "delta"


@needs_qt
def test_no_command_opens_the_gui_or_says_why(capsys, monkeypatch):
    # the default command is the GUI; without any display it explains itself in one line
    for var in ("DISPLAY", "WAYLAND_DISPLAY", "QT_QPA_PLATFORM"):
        monkeypatch.delenv(var, raising=False)
    assert main([]) == 2
    err = capsys.readouterr().err
    assert "no display to open the GUI on" in err and err.count("\n") == 1


@pytest.mark.slow
@needs_qt
def test_gui_attaches_to_a_running_engine_and_quits(capsys):
    import threading

    from app.engine.server import EngineServer
    from app.engine.session import Session

    srv = EngineServer(Session(), bind="tcp://127.0.0.1:0")
    th = threading.Thread(target=srv.run, kwargs={"duration": 30.0}, daemon=True)
    th.start()
    try:
        assert main(["gui", "--connect", srv.url, "--quit-after", "1.5"]) == 0  # offscreen platform (conftest)
    finally:
        srv.stop()
        th.join(timeout=5)
        srv.close()


def test_fk_comau_json_done_when(capsys):
    # Issue acceptance: bosun fk comau_smart5_3dof --deg --q 0 20 -60 --json prints the tool point.
    code, out, _ = run(capsys, "fk", "comau_smart5_3dof", "--deg", "--q", "0", "20", "-60", "--json")
    assert code == 0
    data = json.loads(out)
    assert data["robot"] == "comau_smart5_3dof"
    np.testing.assert_allclose(data["q"], np.deg2rad([0, 20, -60]))
    q2, q3 = np.deg2rad([20, -60])
    L = 1.492 + 0.210 + 0.567
    r = 0.350 - L * np.sin(q3) - 0.250 * np.cos(q3) + 1.160 * np.sin(q2)  # Motion-Lab eq. (3)
    z = 0.830 + L * np.cos(q3) + 1.160 * np.cos(q2) - 0.250 * np.sin(q3)
    np.testing.assert_allclose(data["position"], [r, 0, z], atol=1e-12)
    assert np.asarray(data["rotation"]).shape == (3, 3) and data["within_limits"] is True


def test_fk_text_and_limit_warning(capsys):
    code, out, err = run(capsys, "fk", "comau_smart5_3dof", "--deg", "--q", "0", "20", "0")
    assert code == 0 and "position [m]" in out and "NO" in out
    assert "q3 outside the joint limits" in err


def test_prismatic_values_stay_in_metres_with_deg(capsys):
    code, out, _ = run(capsys, "fk", "scara", "--deg", "--q", "0", "0", "0.1", "0", "--json")
    assert code == 0
    data = json.loads(out)
    np.testing.assert_allclose(data["position"], [0.6, 0, 0.387 - 0.1], atol=1e-12)


def test_jacobian_json(capsys):
    code, out, _ = run(capsys, "jacobian", "offshore_crane", "--deg", "--q", "-90", "45", "-45", "--json")
    data = json.loads(out)
    J = np.asarray(data["matrix"])
    assert code == 0 and J.shape == (6, 3) and data["columns"] == ["beta0", "beta1", "beta2"]
    assert data["position_condition"] > 1


def test_jacobian_text(capsys):
    code, out, _ = run(capsys, "jacobian", "scara", "--q", "0", "0.5", "0.1", "0")
    assert code == 0 and "condition" in out and "-0.00000" not in out


@pytest.mark.parametrize(
    "argv, message",
    [
        (["fk", "nope", "--q", "1"], "unknown robot 'nope'"),
        (["fk", "scara", "--q", "1", "2"], "scara has 4 joints (j1, j2, j3, j4); got 2 value(s)"),
        (["fk", "scara", "--q", "1", "abc", "0", "0"], "argument --q: 'abc' is not a number"),
        (["fk", "scara", "--q", "nan", "0", "0", "0"], "argument --q: 'nan' is not a finite number"),
        (["jacobian", "scara", "--q", "inf", "0", "0", "0"], "'inf' is not a finite number"),
        (["fk", "scara"], "the following arguments are required: --q"),
        (["fk", "em8000", "--q", "0", "0", "0", "0", "0", "0"], "em8000 is a stewart mechanism; this command takes"),
        (["ik", "tac_delta_head", "--target", "0", "0", "1"], "tac_delta_head is a delta mechanism; the IK solvers"),
        (["ik", "em1500", "--target", "0", "0", "1"], "em1500 is a stewart mechanism; the IK solvers"),
        (["fk", "missing/robot.xml", "--q", "0"], "robot file not found: missing/robot.xml"),
        (["frobnicate"], "invalid choice: 'frobnicate'"),
    ],
)
def test_errors_are_one_line_exit_2(capsys, argv, message):
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse usage errors
        code = exc.code
    assert code == 2
    _, err = capsys.readouterr()
    assert message in err
    assert err.count("\n") == 1 and "Traceback" not in err


def test_bad_xml_file_names_file_and_line(capsys, tmp_path):
    f = tmp_path / "arm.xml"
    f.write_text(GOOD.replace('min="-90" max="90"', 'min="90" max="-90"'), encoding="utf-8")
    code, _, err = run(capsys, "fk", str(f), "--q", "0", "0")
    assert code == 2
    assert err.strip() == f"bosun: error: {f}:9: joint q1 limits: min (90) must be less than max (-90)"


def test_invalid_library_file_is_reported_not_fatal(capsys, tmp_path, monkeypatch):
    (tmp_path / "good.xml").write_text(GOOD.replace('name="two_link"', 'name="good"'), encoding="utf-8")
    (tmp_path / "broken.xml").write_text("<robot>", encoding="utf-8")
    monkeypatch.setenv("BOSUN_ROBOTS_DIR", str(tmp_path))
    code, out, err = run(capsys, "robots")
    assert code == 2 and "good" in out and "broken.xml:1: XML syntax error" in err


@pytest.mark.slow
@pytest.mark.parametrize("entry", [["bosun"], [sys.executable, "-m", "app"]], ids=["console-script", "python-m-app"])
def test_entry_points_in_a_real_process(entry):
    exe = os.path.join(os.path.dirname(sys.executable), "bosun")
    cmd = [exe, *entry[1:]] if entry == ["bosun"] else entry
    ok = subprocess.run(
        [*cmd, "fk", "comau_smart5_3dof", "--deg", "--q", "0", "20", "-60", "--json"],
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert ok.returncode == 0, ok.stderr
    assert json.loads(ok.stdout)["position"][0] == pytest.approx(2.5868, abs=1e-4)
    bad = subprocess.run(
        [*cmd, "fk", "comau_smart5_3dof", "--q", "0", "x", "0"], capture_output=True, text=True, timeout=60
    )
    assert bad.returncode == 2 and "Traceback" not in bad.stderr and "'x' is not a number" in bad.stderr


# ---------------------------------------------------------------------------- optional extras (issue 15, item 6)
@pytest.mark.parametrize(
    ("argv", "module", "extra"),
    [
        (["gui"], "PyQt5", "gui"),
        ([], "PyQt5", "gui"),
        (["view", "--connect", "tcp://127.0.0.1:5555"], "pyqtgraph", "gui"),
        (["joystick", "--connect", "tcp://127.0.0.1:5555"], "pygame", "joystick"),
        (["joystick", "--connect", "tcp://127.0.0.1:5555", "--virtual"], "pygame", "joystick"),
    ],
    ids=["gui", "default", "view", "joystick", "virtual-joystick"],
)
def test_a_command_whose_extra_is_missing_says_what_to_install(capsys, monkeypatch, argv, module, extra):
    """The core installs without the GUI and joystick extras; their commands then say in one line what to
    install (exit 2), never a traceback.  A module set to None in sys.modules cannot be imported."""
    for name in [m for m in sys.modules if m == module or m.startswith(module + ".")]:
        monkeypatch.delitem(sys.modules, name)
    monkeypatch.setitem(sys.modules, module, None)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    needed = {"gui": ("PyQt5", "pyqtgraph", "OpenGL"), "joystick": ("pygame",)}[extra]  # the first one missing
    assert any(f"needs {m}," in err for m in needed) and f"pip install 'bosun[{extra}]'" in err, err


def _cpu_seconds(pid: int) -> float:
    with open(f"/proc/{pid}/stat", encoding="utf-8") as f:
        fields = f.read().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


@pytest.mark.slow
@pytest.mark.skipif(not os.path.isdir("/proc"), reason="reads the process's CPU time from /proc")
@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM", "SIGINT"])
def test_an_interrupt_inside_a_compiled_kernel_is_one_line_and_130(tmp_path, sig):
    """Issue 27, item 10: Ctrl-C or SIGTERM while ``bosun analyze`` ran the GA's compiled kernel printed
    ``SystemError: CPUDispatcher(…) returned a result with an exception set`` and exit 1 (6 of 6 interrupts).
    The signal is sent once the process has spent 6 s of CPU (imports and loading the cached kernels take
    2.8 s on the 2-core VM; the study then solves for over 20 s): the GA's solves, most of whose time is the
    compiled kernel."""
    import signal
    import time

    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    proc = subprocess.Popen(
        [sys.executable, "-m", "app", "analyze", "comau_smart5_6dof", "--grid", "14", "--out", str(tmp_path / "a")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env={**os.environ, "PYTHONPATH": root},
    )  # fmt: skip
    try:
        end = time.monotonic() + 240
        while True:
            assert proc.poll() is None, proc.communicate()[1][-800:]
            assert time.monotonic() < end, "the study did not start solving"
            if _cpu_seconds(proc.pid) > 6.0:
                break
            time.sleep(0.1)
        proc.send_signal(getattr(signal, sig))
        _, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130 and err == "bosun: interrupted\n", err[-800:]
    assert not (tmp_path / "a").exists()


# ---------------------------------------------------------------------------- choices kept as constants
def test_the_choices_of_the_parser_are_those_of_the_code():
    """The parser's choices are constants of app/cli, so that building it (every start) imports no scene,
    simulation or sensor module; each must stay equal to what it stands for."""
    from app.analysis.operability import MAX_RUNS, RUNS_CEILING
    from app.cli.args import SPECTRA, TAC_MODES
    from app.cli.reference import SCENES
    from app.cli.sim import _SENSOR_NAMES
    from app.cli.study import MAX_STUDY_RUNS, STUDY_RUNS_CEILING
    from app.marine.sensors import SENSORS
    from app.marine.waves import SPECTRA as WAVE_SPECTRA
    from app.scenarios.tac import MODES
    from app.scenes.diagram import DIAGRAMS

    assert list(SCENES) == sorted(DIAGRAMS)
    assert tuple(WAVE_SPECTRA) == SPECTRA
    assert tuple(MODES) == TAC_MODES
    assert tuple(_SENSOR_NAMES) == ("true", *SENSORS)
    assert (MAX_STUDY_RUNS, STUDY_RUNS_CEILING) == (MAX_RUNS, RUNS_CEILING)


def test_building_the_parser_does_not_import_the_diagrams_nor_the_studies():
    code = (
        "import sys; from app.cli import build_parser; build_parser(); "
        "print('app.scenes.diagram' in sys.modules, 'app.analysis.operability' in sys.modules)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "False False"


def test_alarms_json_has_every_alarm_and_null_for_a_boolean_ones_limit(capsys):
    from app.engine.alarm_catalog import catalog

    code, out, _ = run(capsys, "alarms", "--json")
    assert code == 0
    alarms = {a["key"]: a for a in json.loads(out)["alarms"]}
    assert set(alarms) == {a.key for a in catalog()}
    assert alarms["estop"]["limit"] is None
    assert all(alarms[a.key]["limit"] == a.limit for a in catalog() if a.analog)


def test_bosun_ik_takes_the_ga_task(capsys):
    """Issue 32, item 4: ``--ga-weights``, ``--ga-axis``, ``--ga-axis-weight`` shape the GA's cost from the command
    line; with another solver, or out of range, they are refused in one line (exit 2)."""

    from app.models.registry import load_robot

    args = ["ik", "franka_panda", "--target", "0.45", "0.1", "0.35", "--solver", "ga-restart", "--seed", "1"]
    assert main([*args, "--ga-axis", "0", "0", "-1", "--time-budget", "2", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["success"]
    z_tool = load_robot("franka_panda").fk(np.array(out["q"]))[:3, 2]
    assert z_tool[2] < -0.98  # the tool points down
    for extra, message in (
        (["--solver", "jacobian", "--ga-weights", "1", "1", "2"], "apply to --solver ga or ga-restart only"),
        (["--ga-weights", "0", "0", "0"], "not all 0"),
        (["--ga-axis-weight", "2"], "--ga-axis-weight needs --ga-axis"),
    ):
        assert main(["ik", "franka_panda", "--target", "0.45", "0.1", "0.35", *extra]) == 2
        err = capsys.readouterr().err
        assert message in err and len(err.strip().splitlines()) == 1, err
