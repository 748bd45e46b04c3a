"""Issue 13, item 2: robot files validated as physics, not only as XML.

The corpus in tests/data/robot_fuzz/ (written by scripts/make_robot_fuzz.py, one mutation
class per file-name prefix) must be refused cleanly or loaded validly by the loader, the CLI
and the engine alike."""

import io
import math
import subprocess
import sys
import time
from contextlib import redirect_stderr, redirect_stdout
from pathlib import Path

import numpy as np
import pytest

from app.cli import main as cli_main
from app.engine.session import CommandError, Session
from app.errors import BosunError, RobotXmlError
from app.models.registry import MODEL_FACTORIES, load_robot
from app.models.workspace import limit_corners, workspace_box
from app.models.xml import MAX_JOINTS, parse_robot_file, parse_robot_xml

ROOT = Path(__file__).resolve().parents[1]
CORPUS = sorted((ROOT / "tests" / "data" / "robot_fuzz").glob("*.xml"))
KINDS = {"entity", "number", "huge", "tiny", "joints", "stewart", "coupling", "bytes", "valid"}


def outcome(path):
    """('ok', model) or ('refused', message); anything else raises and fails the test."""
    try:
        spec = parse_robot_file(path)
    except RobotXmlError as err:
        return "refused", str(err)
    return "ok", MODEL_FACTORIES[spec.type](spec)


def assert_physical(model):
    """What every loaded robot must satisfy, checked here independently of the loader."""
    if model.kind == "stewart":
        legs = model.leg_lengths(np.zeros(6))
        assert np.all((legs >= model.leg_min - 1e-9) & (legs <= model.leg_max + 1e-9))
        assert np.all(model.speed_max >= 1e-6) and np.all(np.isfinite(model.leg_jacobian(np.zeros(6))))
        return
    assert model.n_joints <= MAX_JOINTS
    assert np.all(model.lower < model.upper)
    assert np.all(model.speed >= 1e-6) and np.all(model.speed <= 1000)
    q = np.random.default_rng(1).uniform(model.lower, model.upper, size=(32, model.n_joints))
    if model.kind == "delta":
        q = np.full((1, 3), 0.5 * (model.lower[0] + model.upper[0]))
    assert np.all(np.isfinite(model.position(q)))
    assert np.all(np.isfinite(model.jacobian(q)))


def test_the_corpus_covers_every_class():
    kinds = {p.name.split("_")[0] for p in CORPUS}
    assert len(CORPUS) >= 300 and kinds == KINDS


def test_every_corpus_file_is_refused_with_its_name_or_loads_a_physical_robot():
    loaded = refused = 0
    for path in CORPUS:
        result, value = outcome(path)
        if result == "refused":
            refused += 1
            assert "\n" not in value and value.startswith(str(path)), value
        else:
            loaded += 1
            assert_physical(value)
            if value.kind == "serial":
                box = workspace_box(value, n_samples=500)
                assert np.all(np.isfinite(box.lower)) and np.all(np.isfinite(box.upper))
    # every attacking class is refused whole; the scaled copies mostly load
    by_kind = {}
    for path in CORPUS:
        by_kind.setdefault(path.name.split("_")[0], []).append(outcome(path)[0])
    for kind in ("number", "tiny", "joints", "stewart", "coupling"):
        assert set(by_kind[kind]) == {"refused"}, kind
    assert by_kind["valid"].count("ok") >= len(by_kind["valid"]) // 2
    assert loaded > 0 and refused > 200


@pytest.mark.slow
def test_the_cli_never_prints_a_traceback_and_agrees_with_the_loader(tmp_path):
    """`bosun check` over the whole corpus in one process, and `bosun fk` on every file in-process."""
    proc = subprocess.run(
        [sys.executable, "-m", "app", "check", *map(str, CORPUS)],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=ROOT,
    )
    assert "Traceback" not in proc.stdout + proc.stderr
    assert proc.returncode == 2
    lines = proc.stdout.splitlines()
    assert len(lines) == len(CORPUS)
    for path, line in zip(CORPUS, lines, strict=True):
        expected = outcome(path)[0]
        assert line.startswith("ok " if expected == "ok" else "refused "), line
        assert str(path) in line
    for path in CORPUS:
        out, err = io.StringIO(), io.StringIO()
        with redirect_stdout(out), redirect_stderr(err):
            code = cli_main(["fk", str(path), "--q", "0"])
        assert code in (0, 2), (path, code)
        assert "Traceback" not in err.getvalue()
        if code == 2:
            assert err.getvalue().count("\n") == 1 and err.getvalue().startswith("bosun: error: ")


def test_the_engine_refuses_or_loads_each_file_and_keeps_running():
    """set_robot in the teleop session: a refusal leaves the old robot driving, a load is physical."""
    session = Session(robot_name="scara", robots_dirs=(str(CORPUS[0].parent),))
    t = 0.0
    for path in CORPUS:
        before = session.robot
        try:
            session.set_robot(str(path))
        except CommandError as err:
            assert "\n" not in str(err)
            assert session.robot is before
        else:
            assert_physical(session.robot)
        t += 0.005
        session.tick(t, 0.005)
        snap = session.snapshot()
        assert all(math.isfinite(x) for x in snap.q)


# ---------------------------------------------------------------------------- physical bounds
SCARA = (ROOT / "robots" / "scara.xml").read_text(encoding="utf-8")
EM8000 = (ROOT / "robots" / "em8000.xml").read_text(encoding="utf-8")


@pytest.mark.parametrize(
    "old, new, words",
    [
        ('speed="386"', 'speed="5e-324"', "speed bound"),  # was 0 rad/s, accepted
        ('speed="1.1"', 'speed="2000"', "speed bound"),
        ('a="0.325"', 'a="1e154"', "length bound"),  # k_v = inf killed the engine's load
        ('min="-105"', 'min="-9000"', "angle bound"),
        ('alpha="180"', 'alpha="1e30"', "angle bound"),
    ],
)
def test_values_outside_the_physical_bounds_are_refused_by_name(old, new, words):
    assert old in SCARA
    with pytest.raises(RobotXmlError, match=words) as info:
        parse_robot_xml(SCARA.replace(old, new, 1), "x.xml")
    assert str(info.value).startswith("x.xml:")


def chain(n: int) -> str:
    link = (
        '<link joint="revolute"><dh a="0.1" alpha="90"/>'
        '<joint name="q{i}"><limits min="-90" max="90" speed="90"/></joint></link>'
    )
    links = "".join(link.format(i=i) for i in range(n))
    head = '<robot name="c" type="serial" angle_unit="deg"><description>d</description><source>s</source>'
    return f"{head}<serial>{links}</serial></robot>"


def test_joint_count_has_a_documented_maximum():
    assert load_robot  # the library loader uses the same parser
    assert parse_robot_xml(chain(MAX_JOINTS)).dof == MAX_JOINTS
    with pytest.raises(RobotXmlError, match=f"at most {MAX_JOINTS}"):
        parse_robot_xml(chain(MAX_JOINTS + 1))
    with pytest.raises(RobotXmlError, match=f"at most {MAX_JOINTS}"):
        parse_robot_xml(chain(26))  # exhausted memory in the workspace box before


def test_the_workspace_box_never_builds_two_to_the_n_corners():
    class Wide:
        n_joints, lower, upper = 40, np.zeros(40), np.ones(40)

        def position(self, q):
            return q[:, :3]

    corners = limit_corners(Wide(), np.random.default_rng(0))
    assert corners.shape == (4096, 40) and set(np.unique(corners)) == {0.0, 1.0}
    assert np.allclose(workspace_box(Wide(), n_samples=100).upper, 1.0, atol=0.02)
    twelve = parse_robot_xml(chain(12))
    robot = MODEL_FACTORIES["serial"](twelve)
    assert limit_corners(robot, np.random.default_rng(0)).shape == (4096, 12)  # all of them


@pytest.mark.parametrize(
    "old, new, words",
    [
        ('min_length="1.6864" max_length="3.44"', 'min_length="3.5" max_length="4.5"', "at the neutral pose"),
        ('min_length="1.6864" max_length="3.44"', 'min_length="1.6864" max_length="2.2"', "alone"),
        ('min_length="1.6864"', 'min_length="NaN"', "finite number"),
    ],
)
def test_stewart_legs_must_reach_the_neutral_pose_and_each_pose_limit(old, new, words):
    assert old in EM8000
    with pytest.raises(RobotXmlError, match=words):
        parse_robot_xml(EM8000.replace(old, new, 1), "em.xml")


def test_a_huge_coupling_is_refused_before_it_makes_the_jacobian_infinite():
    text = (ROOT / "robots" / "comau_smart5_3dof.xml").read_text(encoding="utf-8")
    assert 'factor="1"' in text
    with pytest.raises(RobotXmlError, match="factor bound"):
        parse_robot_xml(text.replace('factor="1"', 'factor="1e308"', 1))


def test_bosun_check_names_each_file(tmp_path, capsys):
    bad = tmp_path / "bad.xml"
    bad.write_text(SCARA.replace('speed="386"', 'speed="0.0000000001"'), encoding="utf-8")
    assert cli_main(["check", "scara", str(bad)]) == 2
    out = capsys.readouterr().out.splitlines()
    assert out[0].startswith("ok ") and "scara" in out[0]
    assert out[1].startswith(f"refused  {bad}:") and "speed bound" in out[1]
    assert cli_main(["check", "scara"]) == 0
    with pytest.raises(BosunError):
        parse_robot_file(tmp_path / "missing.xml")


@pytest.mark.slow
def test_a_live_engine_answers_every_corpus_file_and_a_ping_after_it():
    """`bosun server --robots-dir tests/data/robot_fuzz`: by path for every third file, by text for
    every seventh; each is answered (loaded or refused in one line) and the engine still answers."""
    from app.net.transport import Client, TransportError
    from ui.engine_process import free_port

    port = free_port()
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "app",
            "server",
            "--bind",
            f"tcp://127.0.0.1:{port}",
            "--robot",
            "scara",
            "--robots-dir",
            str(CORPUS[0].parent),
            "--rate",
            "100",
        ],
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    op = None
    try:
        deadline = time.monotonic() + 60
        while op is None:
            try:
                op = Client(f"tcp://127.0.0.1:{port}", role="operator", name="fuzz", timeout=10.0)
            except TransportError:
                if time.monotonic() > deadline or proc.poll() is not None:
                    raise
                time.sleep(0.2)
        answered = 0
        for i, path in enumerate(CORPUS):
            fields = None
            if i % 3 == 0:
                fields = {"robot": str(path)}
            elif i % 7 == 0 and path.stat().st_size < 60_000:
                fields = {"robot": path.name, "xml": path.read_bytes().decode("utf-8", "replace")}
            if fields is None:
                continue
            result, model = outcome(path)
            expected = "ok" if result == "ok" and model.kind == "serial" else "refused"  # it drives arms
            try:
                op.request("set_robot", **fields)
                got = "ok"
            except TransportError as err:
                got = "refused"
                assert "\n" not in str(err) and "Traceback" not in str(err)
            if "xml" not in fields:
                assert got == expected, path
            answered += 1
            op.request("ping")
        assert answered > 100 and proc.poll() is None
    finally:
        if op is not None:
            op.close()
        proc.terminate()
        proc.wait(timeout=20)
