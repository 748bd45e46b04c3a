"""Start the engine as a child process of the GUI (the desktop default)."""

from __future__ import annotations

import re
import subprocess
import sys
import time

from app.net.transport import TransportError


class EngineProcess:
    """``python -m app server`` on a free loopback port; stopped with the GUI."""

    def __init__(
        self,
        robot: str = "comau_smart5_3dof",
        solver: str = "jacobian",
        mode: str = "velocity",
        timeout: float = 30.0,
        plant: str = "teleop",
    ) -> None:
        cmd = [sys.executable, "-m", "app", "server", "--bind", "tcp://127.0.0.1:0", "--plant", plant]
        if plant == "teleop":
            cmd += ["--robot", robot, "--solver", solver, "--mode", mode]
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.url = None
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            line = self.proc.stdout.readline()
            if not line:
                break
            m = re.search(r"requests on (tcp://\S+),", line)
            if m:
                self.url = m.group(1)
                break
        if self.url is None:
            err = self.proc.stderr.read() if self.proc.poll() is not None else ""
            self.stop()
            raise TransportError(
                f"the engine did not start: {err.strip().splitlines()[-1] if err.strip() else 'timeout'}"
            )

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
