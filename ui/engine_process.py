"""Start the engine as a child process of the GUI (the desktop default), and start it again if it dies."""

from __future__ import annotations

import collections
import os
import re
import secrets
import socket
import subprocess
import sys
import threading
import time

from app.net.security import ENV_OPERATOR_SECRET
from app.net.transport import TransportError


def free_port() -> int:
    """A TCP port on 127.0.0.1 that is free now (the engine keeps it across restarts)."""
    with socket.socket() as so:
        so.bind(("127.0.0.1", 0))
        return so.getsockname()[1]


class EngineProcess:
    """``python -m app server`` on a loopback port of its own; stopped with the GUI.

    The port is chosen once, so :meth:`restart` brings the engine back on the same URL and the
    GUI's link finds it again by itself (a new ``hello``; the new engine starts holding, disarmed).
    """

    def __init__(
        self,
        robot: str = "comau_smart5_3dof",
        solver: str = "jacobian",
        mode: str = "velocity",
        timeout: float = 120.0,  # a first start after install may compile the kernels (~25 s)
        plant: str = "teleop",
    ) -> None:
        self.plant = plant
        self.timeout = timeout
        url = f"tcp://127.0.0.1:{free_port()}"
        # --exit-with-parent: a GUI that is killed or crashes leaves no engine running behind it
        self.cmd = [sys.executable, "-m", "app", "server", "--bind", url, "--plant", plant, "--exit-with-parent"]
        if plant == "teleop":
            self.cmd += ["--robot", robot, "--solver", solver, "--mode", mode]
        # only a hello with this secret gets the operator role: another program on the host can watch, not
        # drive; it goes in the child's environment (readable by this user only), never on its command line
        self.secret = secrets.token_urlsafe(32)
        self.url = None
        self.restarts = 0
        self.output: collections.deque[str] = collections.deque(maxlen=200)
        self._start()

    def _start(self) -> None:
        env = dict(os.environ, **{ENV_OPERATOR_SECRET: self.secret})
        self.proc = subprocess.Popen(self.cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
        url = None
        deadline = time.monotonic() + self.timeout
        try:
            while time.monotonic() < deadline:
                line = self.proc.stdout.readline()
                if not line:
                    break
                m = re.search(r"requests on (tcp://\S+),", line)
                if m:
                    url = m.group(1)
                    break
        except BaseException:
            # Ctrl-C or SIGTERM while the engine starts: the caller has no EngineProcess to stop yet, so this
            # one stops its process (it was left to run on until its own start-up ended, seconds on a busy
            # machine: the hog run of 2026-11-28)
            self.stop()
            raise
        if url is None:
            err = self.proc.stderr.read() if self.proc.poll() is not None else ""
            self.stop()
            raise TransportError(
                f"the engine did not start: {err.strip().splitlines()[-1] if err.strip() else 'timeout'}"
            )
        self.url = url
        # keep reading what the engine prints: a full pipe would block its loop (the last lines are kept)
        for pipe in (self.proc.stdout, self.proc.stderr):
            threading.Thread(target=self._drain, args=(pipe,), daemon=True).start()

    def _drain(self, pipe) -> None:
        for line in iter(pipe.readline, ""):
            self.output.append(line.rstrip())

    def exited(self) -> int | None:
        """The exit code if the process has ended, else None."""
        return self.proc.poll()

    def restart(self) -> None:
        """Start the engine again on the same URL (after it died)."""
        self.stop()
        self.restarts += 1
        self._start()

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
