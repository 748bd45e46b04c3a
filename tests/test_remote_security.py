"""Issue 13, items 4–6: launch secret, roles with a documented lapse, CURVE, throttled authentication,
and a quiet Ctrl-C.  Every server is bound to 127.0.0.1; loops are bounded."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from app.engine.server import EngineServer
from app.engine.session import Session
from app.net.security import ClientCurve, KeyFileError, ServerCurve, create_keys
from app.net.transport import Client, TransportError
from app.teleop.client import RoleLostError, _check_replies
from tests.helpers import needs_pygame, wait_for

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture
def serve_session(serve):
    """An engine around a fresh teleop session; returns the server."""
    return lambda **kw: serve(Session(), **kw)[0]


@pytest.fixture
def keys(tmp_path):
    """An engine pair, an allowed client pair (public key in the engine's folder) and a stranger's pair."""
    allowed = tmp_path / "allowed"
    allowed.mkdir()
    _, engine_secret = create_keys(tmp_path / "engine", "engine")
    op_public, op_secret = create_keys(tmp_path / "op", "op")
    (allowed / "op.key").write_bytes(op_public.read_bytes())
    _, stranger_secret = create_keys(tmp_path / "stranger", "stranger")
    return {
        "server": ServerCurve.from_files(str(engine_secret), str(allowed)),
        "op": ClientCurve.from_files(str(op_secret), str(tmp_path / "engine" / "engine.key")),
        "stranger": ClientCurve.from_files(str(stranger_secret), str(tmp_path / "engine" / "engine.key")),
        "dir": tmp_path,
    }


# ---------------------------------------------------------------------------- CURVE
@pytest.mark.slow
def test_curve_admits_an_allowed_key_and_refuses_others_counting_the_failures(serve_session, keys):
    srv = serve_session(curve=keys["server"])
    op = Client(srv.url, role="operator", name="op", curve=keys["op"], timeout=5.0)
    try:
        assert op.role == "operator"
        assert op.recv_state(timeout=5.0) is not None  # the state stream is encrypted too, and readable
        with pytest.raises(TransportError, match="CURVE"):
            Client(srv.url, role="operator", name="stranger", curve=keys["stranger"], timeout=1.5)
        with pytest.raises(TransportError):  # a plain (NULL mechanism) client is not even answered
            Client(srv.url, role="viewer", name="plain", timeout=1.5)
        state = wait_for(op, lambda s: s.engine.auth_failures >= 1, timeout=10.0)
        assert state.engine.auth_failures >= 1 and state.engine.operator == "op"
    finally:
        op.close()


def test_bosun_keys_writes_a_pair_and_refuses_to_overwrite(tmp_path, capsys):
    from app.cli import main

    assert main(["keys", "engine", "--dir", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "engine.key" in out and "engine.key_secret" in out
    assert (tmp_path / "engine.key_secret").stat().st_mode & 0o077 == 0  # secret: owner only
    assert "secret-key" not in (tmp_path / "engine.key").read_text()
    assert main(["keys", "engine", "--dir", str(tmp_path)]) == 2  # never overwrites a key
    with pytest.raises(KeyFileError, match="holds no secret key"):
        ClientCurve.from_files(str(tmp_path / "engine.key"), str(tmp_path / "engine.key"))


def test_a_non_loopback_bind_needs_curve_and_works_with_it(keys):
    with pytest.raises(TransportError, match="needs CURVE keys"):
        EngineServer(Session(), bind="tcp://0.0.0.0:0", token="a token is not enough")
    srv = EngineServer(Session(), bind="tcp://0.0.0.0:0", curve=keys["server"])
    srv.close()


# ---------------------------------------------------------------------------- token throttling
@pytest.mark.slow
def test_wrong_tokens_are_throttled_and_counted(serve_session):
    srv = serve_session(token="s3cret")
    for k in range(30):
        with pytest.raises(TransportError, match="wrong or missing token"):
            Client(srv.url, role="viewer", name=f"guess{k}", token=f"guess{k}", timeout=2.0)
    # past 10 failures in a second even the right token is refused unexamined: guessing is slowed to 10/s
    with pytest.raises(TransportError, match="wrong or missing token"):
        Client(srv.url, role="viewer", name="right-too-soon", token="s3cret", timeout=2.0)
    assert srv.auth.failures >= 10 and srv.auth.throttled >= 1
    time.sleep(1.2)
    ok = Client(srv.url, role="viewer", name="ok", token="s3cret", timeout=2.0)
    try:
        assert wait_for(ok, lambda s: s.engine.auth_failures >= 10, timeout=5.0)
    finally:
        ok.close()


# ---------------------------------------------------------------------------- launch secret
def test_only_the_holder_of_the_launch_secret_operates(serve_session):
    srv = serve_session(operator_secret="launch-secret")
    stranger = Client(srv.url, role="operator", name="stranger", timeout=3.0)
    gui = Client(srv.url, role="operator", name="gui", secret="launch-secret", timeout=3.0)
    try:
        assert stranger.role == "viewer" and "program that started it" in stranger.note
        assert gui.role == "operator"
    finally:
        stranger.close()
        gui.close()


@pytest.mark.slow
def test_a_gui_started_engine_takes_its_secret_from_the_environment_not_the_command_line():
    """Issue 13, item 6: a SIGKILLed GUI left its engine running and a stranger's hello became operator."""
    from ui.engine_process import EngineProcess

    proc = EngineProcess()
    stranger = gui = None
    try:
        cmdline = Path(f"/proc/{proc.proc.pid}/cmdline").read_bytes()
        assert proc.secret.encode() not in cmdline
        stranger = Client(proc.url, role="operator", name="stranger", timeout=10.0)
        assert stranger.role == "viewer"
        gui = Client(proc.url, role="operator", name="gui", secret=proc.secret, timeout=10.0)
        assert gui.role == "operator"
    finally:
        for c in (stranger, gui):
            if c is not None:
                c.close()
        proc.stop()


# ---------------------------------------------------------------------------- roles
@pytest.mark.slow
def test_the_role_lapses_only_after_the_timeout_with_a_warning_and_the_displaced_operator_is_told(serve_session):
    srv = serve_session(operator_timeout=1.5, lapse_warning=0.5)
    first = Client(srv.url, role="operator", name="first", timeout=3.0)
    viewer = Client(srv.url, role="viewer", name="watcher", timeout=3.0)
    second = None
    try:
        time.sleep(0.8)  # first is silent past the warning, not past the timeout
        second = Client(srv.url, role="operator", name="second", timeout=3.0)
        assert second.role == "viewer" and "held by first" in second.note
        second.close()
        logs = []
        deadline = time.monotonic() + 10
        while time.monotonic() < deadline and not any("lapses at 1.5 s" in t for t in logs):
            msg = viewer.sub.recv_multipart(flags=0) if viewer.sub.poll(200) else None
            if msg:
                from app.net.codec import decode_engine

                m = decode_engine(msg[0])
                if m["type"] == "log":
                    logs.append(m["text"])
        assert any("operator first silent for 0.5 s" in t for t in logs)  # every client is warned
        time.sleep(1.2)
        second = Client(srv.url, role="operator", name="second", timeout=3.0)
        assert second.role == "operator"  # lapsed after the documented timeout
        first.send_input([0.5, 0, 0], [True], "stick")
        with pytest.raises(RoleLostError, match=r"first is no longer the operator: the role lapsed after 1\.5 s"):
            deadline = time.monotonic() + 5
            while time.monotonic() < deadline:
                _check_replies(first)
                time.sleep(0.05)
    finally:
        for c in (first, viewer, second):
            if c is not None:
                c.close()


@pytest.mark.slow
def test_keep_alives_keep_the_role_without_input(serve_session):
    srv = serve_session(operator_timeout=1.0, lapse_warning=0.4)
    op = Client(srv.url, role="operator", name="op", timeout=3.0)
    try:
        end = time.monotonic() + 2.5
        while time.monotonic() < end:
            op.request("ping")
            time.sleep(0.3)
        other = Client(srv.url, role="operator", name="other", timeout=3.0)
        assert other.role == "viewer"
        other.close()
    finally:
        op.close()


@pytest.mark.slow
@needs_pygame
def test_bosun_joystick_without_a_joystick_exits_with_a_clear_message(serve_session):
    srv = serve_session()
    env = dict(os.environ, SDL_JOYSTICK_DISABLED="1", SDL_VIDEODRIVER="dummy")
    proc = subprocess.run(
        [sys.executable, "-m", "app", "joystick", "--connect", srv.url],
        capture_output=True,
        text=True,
        timeout=60,
        cwd=ROOT,
        env=env,
    )
    assert proc.returncode == 2
    assert "no joystick found" in proc.stderr and "Traceback" not in proc.stderr
    assert proc.stderr.count("\n") == 1


# ---------------------------------------------------------------------------- Ctrl-C
@pytest.mark.slow
@pytest.mark.parametrize("args", [["robots"], ["server", "--bind", "tcp://127.0.0.1:0", "--duration", "30"]])
def test_ctrl_c_at_any_moment_of_start_up_prints_no_traceback(args):
    """From the moment Python runs Bosun's code, Ctrl-C ends it with one line, never a traceback.

    A SIGINT that lands while the interpreter itself is still starting (its ``site`` module, runpy
    looking for ``app``, the console script's first import) gets CPython's own report, whose frames
    are all the interpreter's; no program can catch that.  So: no traceback may show a frame of
    Bosun's own files, and most of the instants tried must land in Bosun and end quietly."""
    import re

    quiet = 0
    for delay in (0.05, 0.15, 0.3, 0.45, 0.6, 0.9, 1.2):
        proc = subprocess.Popen(
            [sys.executable, "-m", "app", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT
        )
        time.sleep(delay)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
        frames = re.findall(r'File "([^"]+)"', err)
        ours = [f for f in frames if f.startswith(str(ROOT)) and "/.venv/" not in f]
        assert not ours, (delay, err)
        if "Traceback" not in err:
            quiet += 1
            assert proc.returncode in (0, 130, -signal.SIGINT), (delay, proc.returncode, err)
    assert quiet >= 4
