"""The simulated Motion-Lab (``bosun server --plant lab``): the scene's :class:`~app.sim.motionlab.MotionLab`
is the plant, stepped here."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from app.errors import BosunError
from app.marine.vessel import VesselParticulars, parametric_rao
from app.net.snapshots import PlantLink
from app.plant.base import BackendError, LabBackend
from app.sim.motionlab import MotionLab
from app.sim.stewart import Generator, WaveSimulation, parse_timeseries_csv


def _refused(fn, *args) -> Any:
    try:
        return fn(*args)
    except BosunError as err:
        raise BackendError(str(err)) from None


class SimulatedLab(LabBackend):
    """The lab's machines simulated by :mod:`app.sim`."""

    NAME = "simulated"

    def __init__(self, lab: MotionLab) -> None:
        super().__init__(lab)
        self._rao = None

    # ------------------------------------------------------------------ commands
    def platform(self, k: int, action: str) -> None:
        _refused(self.lab.platforms[k].command, action)

    def source(self, k: int, source: str, p: dict[str, Any]) -> dict[str, Any]:
        plat = self.lab.platforms[k]
        try:
            if plat.mode == "engaged":
                raise BackendError(f"{self.names[k]} is ENGAGED; disengage before changing the motion source")
            if source == "generator":
                obj = Generator.make(
                    p.get("amplitude", [0.0] * 6),
                    p.get("frequency", [0.1] * 6),
                    p.get("phase", [0.0] * 6),
                    plat.model,
                    plat.command_box,
                )
                info: dict[str, Any] = {"amplitude": obj.amplitude.tolist(), "frequency": obj.frequency.tolist()}
            elif source == "simulation":
                if self._rao is None:
                    self._rao = parametric_rao(VesselParticulars())
                args = (
                    self._rao,
                    p.get("spectrum", "jonswap"),
                    p.get("hs", 2.0),
                    p.get("tp", 8.0),
                    p.get("heading", 150.0 if k == 0 else 90.0),
                    int(p.get("seed", 1)),
                )
                src = WaveSimulation(*args, np.ones(6))
                auto = WaveSimulation.auto_scale(src.significant, plat.model, box=plat.command_box)
                scale = np.asarray(p["scale"], dtype=float) if p.get("scale") else auto
                if scale.shape != (6,) or np.any(scale < 0) or np.any(scale > 10):
                    raise BackendError("scale needs six factors between 0 and 10")
                obj = WaveSimulation(*args, scale)
                info = {"hs": args[2], "tp": args[3], "heading": args[4], "scale": scale.tolist()}
                info["significant"] = src.significant.tolist()
            elif source == "timeseries":
                if not p.get("csv"):
                    raise BackendError("timeseries needs the CSV text (columns t,x,y,z,phi,theta,psi)")
                obj = parse_timeseries_csv(p["csv"], p.get("name", "time series"))
                info = {"duration": obj.duration, "samples": int(obj.t.size)}
            else:
                obj, info = None, {}
            plat.set_source(source, obj)
        except BackendError:
            raise
        except BosunError as err:
            raise BackendError(str(err)) from None
        return info

    def remote_pose(self, k: int, eta: Any) -> None:
        _refused(self.lab.platforms[k].remote.set, eta)

    def comau_mode(self, mode: str) -> None:
        _refused(self.lab.set_comau_mode, mode)

    def winch_mode(self, mode: str) -> None:
        _refused(self.lab.set_winch_mode, mode)

    def winch_speed(self, speed: float) -> None:
        self.lab.winch.speed_command = float(speed)

    def vvmc(self, on: bool) -> None:
        self.lab.set_vvmc(on)

    def drive(self, tool_velocity_r: NDArray[np.float64], winch_speed: float) -> None:
        lab = self.lab
        if lab.comau_mode == "remote":
            lab.tool_velocity_cmd = tool_velocity_r
        if lab.winch.mode == "remote":
            lab.winch.speed_command = float(winch_speed)

    def estop(self) -> None:
        self.lab.estop()

    def reset(self) -> None:
        self.lab.reset()

    # ------------------------------------------------------------------ loop and state
    def step(self, dt: float, n: int) -> None:
        for _ in range(n):
            self.lab.step(dt)

    def link(self, now: float) -> PlantLink:
        return PlantLink(backend=self.NAME, link="simulated", connected=True)
