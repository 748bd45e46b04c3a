"""The simulated Motion-Lab (``bosun server --plant lab``): the scene's :class:`~app.scenes.lab.MotionLab`
is the plant, stepped here.

The lab HMI's feedback (issue 16, item 5) is made from the model's own state, so the GUI shows it as it
shows the PLC's: each platform's Rexroth status word (:func:`motion_status`, mapping below) and the
"Machine and Sensor States" lights (:meth:`SimulatedLab.machines`).  The platforms start with the lab
PLC's sine-generator defaults (``sineAmplitude`` 0, 0, 0.2 m, 2°, 2°, 0 at ``sineOmega`` 0.6283 rad/s;
motionlab_plc.json: Norwegian Motion-Laboratory repository, commit f5fbf84, MIT), as the lab's do.

Bosun platform (``status``)            E_StewartState   E_StewartStatus        E_StewartOpMode
=====================================  ===============  =====================  ===============
settled                                SETTLED          SYSTEM_OK, WARNING     NORMAL
raising, settling                      TRANSIT          while LEG LIMIT
neutral                                NEUTRAL          (a target scaled back
engaging, engaged, disengaging         ENGAGED          to the strokes);
E-STOP latched (braking, then held),   NEUTRAL_FREEZE   ERROR never (no faults
  not settled, not engaged; holding                     are simulated)
E-STOP latched while engaged           ENGAGED_FREEZE
=====================================  ===============  =====================  ===============

Disengaging stays ENGAGED (the platform still follows the fading source, as the Rexroth follows the
setpoints it is sent until TO_NEUTRAL); a SETTLED platform stays SETTLED under an E-STOP (it rests on
its end stops).  The Rexroth's OFF, OIL_HEATING and MANUAL are not simulated.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from app.errors import BosunError
from app.marine.vessels import vessel_rao
from app.net.snapshots import MachineLight, MotionStatus, PlantLink
from app.plant.base import REMOTE_TIMEOUT, BackendError, LabBackend, lab_generator
from app.plc.symbols import decode_status, encode_status
from app.scenes.lab import MotionLab
from app.sim.stewart import Platform, WaveSimulation, parse_timeseries_csv


def motion_status(p: Platform) -> MotionStatus:
    """The Rexroth status word a simulated platform reports (the table of the module's docstring)."""
    if p.mode == "settled" and not p.transition:
        state = "SETTLED"
    elif p.frozen or p.mode == "holding":
        state = "ENGAGED_FREEZE" if p.frozen and p.mode == "engaged" else "NEUTRAL_FREEZE"
    elif p.transition in ("raising", "settling"):
        state = "TRANSIT"
    elif p.mode == "engaged":
        state = "ENGAGED"
    else:
        state = "NEUTRAL"
    word = encode_status(state, "WARNING" if p.leg_clamped else "SYSTEM_OK", "NORMAL")
    return MotionStatus(**decode_status(word), word=word)


def _well_conditioned(J: NDArray[np.float64]) -> bool:
    """J far from singular: |det J| > 1e-3 ‖J‖_F³ (the bound under which the REMOTE step's least squares
    leaves the exact inverse, app/sim/kernels.py ``lstsq3``)."""
    return bool(abs(np.linalg.det(J)) > 1e-3 * np.linalg.norm(J) ** 3)


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
        self.jog = np.zeros(3)  # the Comau's joint jog [rad/s] (REMOTE)
        self._remote_t = -np.inf  # monotonic time of the last remote pose (the "remote" light)
        for plat in lab.platforms:  # the lab PLC's generator defaults (FB_StewartInterface.FB_init)
            if plat.source_name == "generator":
                plat.set_source("generator", lab_generator(plat))

    # ------------------------------------------------------------------ commands
    def platform(self, k: int, action: str) -> None:
        _refused(self.lab.platforms[k].command, action)

    def source(self, k: int, source: str, p: dict[str, Any]) -> dict[str, Any]:
        plat = self.lab.platforms[k]
        try:
            if plat.mode == "engaged":
                raise BackendError(f"{self.names[k]} is ENGAGED; disengage before changing the motion source")
            if source == "generator":
                obj = lab_generator(plat, p)
                info: dict[str, Any] = {"amplitude": obj.amplitude.tolist(), "frequency": obj.frequency.tolist()}
            elif source == "simulation":
                if self._rao is None:
                    self._rao = vessel_rao()  # the default vessel (issue 17: RAOs by boundary elements)
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

    def set_vessel_rao(self, table: Any) -> None:
        self._rao = table

    def remote_pose(self, k: int, eta: Any) -> None:
        _refused(self.lab.platforms[k].remote.set, eta)
        self._remote_t = time.monotonic()

    def comau_mode(self, mode: str) -> None:
        _refused(self.lab.set_comau_mode, mode)
        self.jog = np.zeros(3)

    def comau_jog(self, qd: NDArray[np.float64]) -> None:
        """Joint speeds [rad/s] in REMOTE, applied in every step through the joint filter (the profile's
        limits, speed and velocity-boundary law) as the tool velocity J(q) q̇ the REMOTE step turns back
        into q̇ (eq. 21): exact (only the jogged joint moves) where J is well conditioned; refused near a
        singular configuration, where the least-squares inverse would move other joints too."""
        qd = np.asarray(qd, dtype=float).reshape(3)
        if np.any(qd != 0.0):
            lab = self.lab
            if lab.comau_mode != "remote" or lab.frozen:
                raise BackendError(f"Comau jog needs REMOTE (the Comau is {lab.comau_mode.upper()})")
            if not _well_conditioned(lab.comau.jacobian(lab.joints.x)):
                raise BackendError("Comau jog refused: the arm is near a singular configuration")
        self.jog = qd

    def winch_mode(self, mode: str) -> None:
        _refused(self.lab.set_winch_mode, mode)

    def winch_speed(self, speed: float) -> None:
        self.lab.winch.speed_command = float(speed)

    def vvmc(self, on: bool) -> None:
        self.lab.set_vvmc(on)

    def drive(self, tool_velocity_r: NDArray[np.float64], winch_speed: float) -> None:
        lab = self.lab
        if lab.comau_mode in ("remote", "motion_comp"):  # under VVMC: the work point's velocity in {b2}
            lab.tool_velocity_cmd = tool_velocity_r  # replaced in each step while a joint is jogged
        if lab.winch.mode in ("remote", "motion_comp"):  # under VVMC: lowers the load relative to EM1500
            lab.winch.speed_command = float(winch_speed)

    def estop(self) -> None:
        self.jog = np.zeros(3)
        self.lab.estop()

    def reset(self) -> None:
        self.lab.reset()

    # ------------------------------------------------------------------ loop and state
    def step(self, dt: float, n: int) -> None:
        lab = self.lab
        # the REMOTE step asks the joint filter for q + q̇ dt with the feed-forward q̇ (q̇ = J⁻¹ ṗ, eq. 21), which
        # the filter turns into (1 + dt/τ) q̇: divided out, so the jog runs at the speed asked
        gain = 1.0 + dt / max(float(lab.joints.tau), dt)
        for _ in range(n):
            if np.any(self.jog != 0.0):
                J = lab.comau.jacobian(lab.joints.x)
                if lab.comau_mode == "remote" and not lab.frozen and _well_conditioned(J):
                    lab.tool_velocity_cmd = J @ self.jog / gain
                else:  # left REMOTE, stopped, or jogged into a singular configuration: the jog ends
                    self.jog = np.zeros(3)
                    lab.tool_velocity_cmd = np.zeros(3)
            lab.step(dt)
            if self.after_step is not None:
                self.after_step(dt)

    def link(self, now: float) -> PlantLink:
        return PlantLink(backend=self.NAME, link="simulated", connected=True)

    def motion_status(self, k: int) -> MotionStatus:
        return motion_status(self.lab.platforms[k])

    def machines(self, now: float) -> list[MachineLight]:
        """The platforms, the Comau and the MRUs run while the model runs (the MRUs as the streaming sensors the
        controllers read when ``MotionLab.set_sensors`` gave them, else the true motion); the laser tracker is
        connected only while one feeds the controllers; "remote" is a client sending remote poses
        (``lab_remote_pose``) within the lab remote interface's 0.5 s timeout."""
        sim = "simulated"
        names = [getattr(getattr(x, "spec", None), "name", "") for x in getattr(self.lab, "sensors", None) or ()]
        tracker = [n for n in names if "tracker" in n.lower()]
        remote = time.monotonic() - self._remote_t <= REMOTE_TIMEOUT

        def mru(k: int) -> MachineLight:
            platform = self.names[k].upper()
            fed = k < len(names) and "mru" in names[k].lower()
            detail = f"simulated {names[k]} on {platform}, read by the controllers" if fed else f"simulated: {platform}"
            return MachineLight(name=f"mru{k + 1}", state="active", detail=detail)

        return [
            MachineLight(name="em8000", state="active", detail=sim),
            MachineLight(name="em1500", state="active", detail=sim),
            MachineLight(name="comau", state="active", detail=sim),
            mru(0),
            mru(1),
            MachineLight(
                name="tracker",
                state="active" if tracker else "absent",
                detail=f"simulated {tracker[0]}" if tracker else "not connected (no laser tracker in the simulation)",
            ),
            MachineLight(
                name="remote",
                state="active" if remote else "absent",
                detail="remote poses arriving" if remote else "not connected (no remote pose within 0.5 s)",
            ),
        ]
