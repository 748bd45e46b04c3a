"""What today's simulations and engines compute, recorded before the block redesign (issue 29, item 4).

Every case runs at a fixed seed, in this process, and returns named arrays: the time series sampled at
``ROWS`` instants (the last one always among them) and every number of the summaries the commands print.
``tests/data/behaviour_baseline.npz`` holds them as recorded on 2026-11-28 (main at the commit that added
this file); ``tests/test_behaviour_kept.py`` compares a fresh run with them to 1e-9 relative.  One change was
meant since: on 2026-11-29 (issue 30, item 2) the crane-head engine's stick moves the TCP's target and a mode
change disarms, so ``engine_tac`` was recorded again, with ``engine_tac_neutral`` (the same script, stick
centred) beside it; that one gave the 2026-11-28 ``engine_tac`` record bit for bit in all 47 arrays but the
armed and enabled flags after the mode change at 5.1 s (disarmed now, safety H97).  Both were recorded once
more the same day when the crane's hanging load joined the snapshot (item 3): the 47 arrays recorded before
were unchanged, 7 arrays were added (``snap.load.*``, ``snap.scene.hook``).  And again the same day (items 5 and
8): the load hangs on an elastic wire now (``snap.load.hook``, ``swing_deg``, ``tension_factor`` and
``snap.scene.hook`` changed), the snapshot carries the landing and the platform (arrays added), the slack-wire
and snap-load alarms came with the mode change to off, and the head returns to α_d at 0.25 rad/s after it (safety
H103): the head's arrays (``snap.sample.alpha``, ``u``, ``p_c_t``, ``p_c_n``, ``e_c``, ``snap.scene.head``) differ
from the sample at 8.4 s on, after the switch at 8.2 s, and are the record's before it.  Then the load's
anti-swing joined the snapshot (``snap.load.antisway``, ``antisway_offset``: two arrays added, nothing else
changed: off, its offset is exactly zero).  On 2026-11-29 (issue 30, item 5, the lab's landing) ``engine_lab`` was
recorded again: the simulated lab's load hangs on the crane's elastic wire and can land on EM1500, and the lab's
pendulum reports that wire (app/scenes/lab_load.py).  The platforms' arrays are unchanged; the pendulum's, the
swing estimator's and the winch's differ by the two load models' difference (at most 2.6·10⁻⁴ rad of swing,
8·10⁻⁶ m of wire), and after the anti-swing's start at 29.8 s the Comau's and tool's by its offset's (at most
0.2 mm); ``snap.load.*`` was added.  Recorded once more the same day: VVMC now engages from where the tool is, at
the speed it has, onto the work point (safety H106), so from the switch at 23.7 s the Comau's, the tool's, the
winch's and the load's arrays differ (the tool 6 cm off the work point at its worst while it engages; before, the
law stepped onto it); ``engine_tac`` and ``engine_tac_neutral`` got ``snap.target_lost`` (the vessel target,
H105; their 153 other arrays unchanged).  Both were recorded again on 2026-11-29 (safety H108): the switch to off
at 8.2 s now fades the head's, crane's and winch's references from the compensating ones to the hold over 5 s,
so from the sample at 8.4 s the head's, crane's and load's arrays differ and are the record's before it, and the
slack-wire and snap-load alarms that switch raised are gone (their arrays with them).  And once more (issue
31): the snapshot carries the delay and whether the prediction is fed (``snap.delay``, ``snap.predict``: two
arrays added, nothing else changed).  The ``sim vvmc`` cases and ``sim antisway`` were recorded again the same
day for the same reason: their summaries carry ``delay_s`` and ``predict`` (the scenario's ``delay`` and
``predict``), two arrays added each, nothing else changed (checked array by array).  Session 23 (issue 31, items
2 and 3): ``engine_tac`` and ``engine_tac_neutral`` recorded again with the lift window in the snapshot
(``snap.lift.*``: nine arrays added), ``engine_lab`` with the lab's delay (``snap.delay``, ``snap.predict``: two
added); every array recorded before equal (checked array by array).  Session 24 (issue 31, item 4): the load's
state carries the load chart (``snap.load.payload_t``, ``radius``, ``capacity_t``, ``psi``, ``psi_window``,
``swl_percent``: six arrays added to ``engine_tac`` and ``engine_tac_neutral``, two to ``engine_lab``, whose
crane-only fields are None); every array recorded before equal (checked array by array).  Then again the same
session after its review: the radius is the TCP's where the head holds it (not the nominal TCP), so
``snap.load.radius``, ``capacity_t`` and ``swl_percent`` (this session's own fields) differ, and ``snap.load.rated``
is added (three cases); every other array equal.  Session 25 (issue 31, the predictors' cost per tick): the lift
window's refresh is spread over the four engine ticks after its model sample (where both predictors update) and
published at the last, so in ``engine_tac`` and ``engine_tac_neutral`` ``snap.lift.mean``, ``sigma`` and
``probability`` each differ at the snapshots where a refresh fell due, and each such snapshot's is the recorded one
a snapshot before (checked array by array: the same numbers, later); every other array equal.  The same session
(issue 32, item 4): ``engine_teleop``'s snapshot carries the GA's task (``snap.ga_weights``, ``snap.ga_axis_weight``:
two arrays added, the published 1, 1, 1 and 0); every other array equal.  Session 26 (issue 32, item 5: the
direction-aware scaling): ``engine_teleop`` recorded again.  In position mode the reference now walks to the
solver's answer at the joints' speed limits, guarded, instead of jumping to it, and the Comau's upper arm is slowed
by its own column (a capsule pair in its zone), so the arm was still moving where the script changes the robot: the
script gained a second of rest before the change.  Every array up to the first position-mode stick tick (t = 1.9 s:
the velocity-mode drive, the hold, the mode change) equal bit for bit to the record before (checked array by
array); the snapshot carries the hazard (``snap.hazard.*``).  The same session ``engine_tac``, ``engine_tac_neutral``
and ``engine_lab`` recorded again: their snapshots carry the hazard too (``snap.hazard.slowed``: one array added
each, every other array equal, checked array by array: neither script's stick comes near its range's edge).
Session 27: ``engine_teleop`` recorded again.  In position
mode the reference's walk to the solver's answer now moves each joint at its own speed limit (clipped per joint)
instead of scaling the whole step to the slowest-to-arrive joint: with a joint blocked by the guard, the others
crept to their goals ever slower and the arm never came to rest (17 of 520 resting position-mode sticks in ``bosun
bench hold``, safety H114).  Every array up to the first position-mode stick tick (t = 1.9 s) equal bit for bit
(checked array by array); from t = 1.95 s the position mode's differ.
Session 33 (2026-11-30, safety H121): a velocity command's step is now corrected in the tool's metric; the
position mode's walk keeps the joints' (as before).  ``engine_teleop``'s guard acts only in position mode, so it
gives the record of session 27 bit for bit (checked array by array).
Session 37 (2026-12-01, safety H124): with no command (released, centred, E-STOP) the teleop engine's hazard report
names the hazard nearest its stop where the joints are, where it was empty before, so ``engine_teleop``'s
``snap.hazard.value`` and ``snap.hazard.share`` hold 73 samples instead of 53; only those two arrays were replaced
in the file.  Every other array of every case is the code's before the change byte for byte (1,034 arrays run
with and without it and compared).

The cases are the commands' own computations, shortened to keep the suite fast (the commands' defaults
run 300–600 s; every case here passes through the start-up, the ramp and the steady state):

* ``sim tac`` in every mode, and ``sim tac-sweep`` (3 modes × 2 sea states);
* ``sim vvmc`` with the true, MRU and tracker states, each with and without ``--antisway``;
* ``sim antisway``: the free swing with and without the law, and the VVMC study without and with it;
* the engines' snapshots over a scripted session: the teleop engine (arming, stick, release, a solver and
  a mode change, E-STOP, reset), the TAC engine (arming, stick, a mode change) and the Motion-Lab engine
  (platforms engaged on the wave source, VVMC, anti-swing, E-STOP).  The teleop session uses the Jacobian
  and analytic solvers: the GA's per-tick budget is wall-clock time, so its answers depend on the machine.

Record again (only when a change of the numbers is meant, and say so in the commit):
``python -m tests.behaviour --record``.
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

BASELINE = Path(__file__).resolve().parent / "data" / "behaviour_baseline.npz"
ROWS = 64  # sampled instants of each time series


def _rows(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a)
    if a.ndim == 0 or len(a) <= ROWS:
        return a
    idx = np.unique(np.r_[np.linspace(0, len(a) - 1, ROWS).round().astype(int), len(a) - 1])
    return a[idx]


def _numbers(prefix: str, obj, out: dict[str, np.ndarray]) -> None:
    """Every number in ``obj`` (dicts, lists, dataclasses, arrays) as ``out[prefix.key...]`` arrays."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        obj = {f.name: getattr(obj, f.name) for f in dataclasses.fields(obj)}
    if isinstance(obj, dict):
        for k, v in obj.items():
            _numbers(f"{prefix}.{k}", v, out)
    elif isinstance(obj, np.ndarray) and obj.dtype.kind in "biuf":
        out[prefix] = _rows(obj).astype(float)
    elif isinstance(obj, (list, tuple)) and obj and all(isinstance(x, (bool, int, float)) for x in obj):
        out[prefix] = np.asarray(obj, dtype=float)
    elif isinstance(obj, (list, tuple)):
        for i, v in enumerate(obj):
            _numbers(f"{prefix}[{i}]", v, out)
    elif isinstance(obj, (bool, int, float, np.floating, np.integer, np.bool_)) and obj is not None:
        out[prefix] = np.asarray(float(obj))


# ------------------------------------------------------------------------------------------------ simulations
def _tac(mode: str) -> dict[str, np.ndarray]:
    from app.scenarios.tac import TacScenario, simulate

    res = simulate(TacScenario(mode=mode, duration=60.0, seed=3))
    out: dict[str, np.ndarray] = {}
    names, cols = res.data.columns()
    for name, col in zip(names, cols.T, strict=True):
        out[f"series.{name}"] = _rows(col)
    _numbers("summary", {k: v for k, v in res.summary.items() if "wall" not in k and "speed" not in k}, out)
    _numbers("x_d", res.x_d, out)
    _numbers("p_d_n", res.p_d_n, out)
    return out


def _tac_sweep() -> dict[str, np.ndarray]:
    from app.analysis.tac_report import sweep
    from app.scenarios.tac import TacScenario

    rows = sweep(TacScenario(duration=40.0, seed=2), [1.5, 4.0], ("off", "tac", "cooperative"))
    out: dict[str, np.ndarray] = {}
    for i, row in enumerate(rows):
        _numbers(f"row{i}", {k: v for k, v in row.items() if "wall" not in k and "speed" not in k}, out)
    return out


def _vvmc(sensors: str, antisway: bool) -> dict[str, np.ndarray]:
    from app.scenarios.vvmc import VvmcScenario, simulate, summarize

    sc = VvmcScenario(duration=20.0, seed=4, sensors=sensors, antisway=antisway)
    on, off = simulate(sc, True), simulate(sc, False)
    out: dict[str, np.ndarray] = {}
    _numbers("on", on, out)
    _numbers("off", off, out)
    _numbers("summary", summarize(sc, on, off), out)
    return out


def _antisway() -> dict[str, np.ndarray]:
    from app.scenarios.antisway import antisway_study, free_swing
    from app.scenarios.vvmc import VvmcScenario

    out: dict[str, np.ndarray] = {}
    for active in (False, True):
        _numbers(f"free_{active}", free_swing(active, duration=10.0), out)
    study = antisway_study(VvmcScenario(duration=20.0, seed=5))
    _numbers("study", {k: v for k, v in study.items() if k != "runs"}, out)
    _numbers("runs", list(study["runs"]), out)
    return out


# ---------------------------------------------------------------------------------------------------- engines
def _snap(session, t: float, out: dict[str, list], every: int, k: int) -> None:
    if k % every:
        return
    flat: dict[str, np.ndarray] = {}
    _numbers("", session.snapshot(), flat)
    for name, v in flat.items():
        if name.endswith((".t_raised", ".t_cleared", "solver_time")) or name.startswith(".engine.") or "wall" in name:
            continue  # wall-clock readings, not the machine's state
        out.setdefault(name, []).append(np.ravel(v))


def _drive(session, script: list[tuple[float, Callable[[], None] | None, tuple, bool]], dt: float, every: int):
    """Run ``script`` (seconds, an action at its start or None, the stick's axes, the enable button) and take a
    snapshot every ``every`` ticks."""
    from app.teleop.devices import InputSample

    out: dict[str, list] = {}
    t, k = 0.0, 0
    for seconds, action, axes, enable in script:
        if action is not None:
            action()
        for _ in range(round(seconds / dt)):
            t += dt
            k += 1
            session.feed(InputSample(tuple(axes), (enable, False), "script"), t)
            session.tick(t, dt)
            _snap(session, t, out, every, k)
    keep = {}
    for name, rows in out.items():
        sizes = sorted({len(r) for r in rows})
        for n in sizes:  # a robot change changes the joint count: each size apart
            keep[f"snap{name}" + (f"@{n}" if len(sizes) > 1 else "")] = np.array([r for r in rows if len(r) == n])
    return keep


def _engine_teleop() -> dict[str, np.ndarray]:
    from app.engine.session import Session

    s = Session(robot_name="comau_smart5_6dof", solver_name="jacobian", mode="velocity")
    z = (0.0, 0.0, 0.0)

    def analytic_3dof():
        s.set_robot("comau_smart5_3dof")
        s.set_solver("analytic")

    script = [
        (0.1, None, z, False),
        (0.1, None, z, True),  # armed
        (1.0, None, (0.6, -0.4, 0.3), True),
        (0.5, None, z, True),  # centred: holds
        (0.1, lambda: s.set_mode("position"), z, False),
        (0.1, None, z, True),
        (1.0, None, (-0.5, 0.2, 0.4), True),
        (1.0, None, z, False),  # released: the arm comes to rest (slowed by its column, issue 32 item 5)
        (0.2, analytic_3dof, z, False),  # a robot change, and the closed-form solver
        (0.1, None, z, True),
        (0.8, None, (0.3, 0.3, -0.3), True),
        (0.2, lambda: s.estop("script"), (0.3, 0.3, -0.3), True),
        (0.2, s.reset, z, False),
        (0.1, None, z, True),
        (0.5, None, (0.0, 0.5, 0.0), True),
    ]
    return _drive(s, script, dt=0.002, every=25)


def _engine_tac(stick: tuple = (0.5, 0.0, -0.3)) -> dict[str, np.ndarray]:
    """The crane-head engine's scripted session.  Since issue 30 (item 2) the armed stick moves the TCP's target:
    ``engine_tac`` was recorded again on 2026-11-29 with it; ``engine_tac_neutral`` is the same script with the
    stick centred, which must give the 2026-11-28 record (the engine before the stick) bit for bit."""
    from app.engine.tac_session import TacSession

    s = TacSession()
    z = (0.0, 0.0, 0.0)
    script = [
        (2.0, None, z, False),
        (0.1, None, z, True),
        (3.0, None, stick, True),
        (0.1, lambda: s.set_tac_mode("cooperative"), z, True),
        (3.0, None, z, True),
        (0.1, lambda: s.set_tac_mode("off"), z, False),
        (2.0, None, z, False),
    ]
    return _drive(s, script, dt=0.02, every=10)


def _engine_lab() -> dict[str, np.ndarray]:
    from app.engine.lab_session import LabSession

    s = LabSession()
    z = (0.0, 0.0, 0.0)

    def neutral():
        for p in s.names:
            s.lab_platform(p, "neutral")

    def engage():
        for k, p in enumerate(s.names):
            s.lab_source(p, "simulation", hs=2.0, tp=8.0, heading=150.0 - 60.0 * k, seed=7 + k)
            s.lab_platform(p, "engage")

    script = [
        (0.5, None, z, False),
        (0.1, neutral, z, False),
        (15.0, None, z, False),  # raised at a fifth of the Table 8 speeds
        (0.1, engage, z, False),
        (8.0, None, z, False),
        (0.1, lambda: s.lab_vvmc(True), z, False),
        (6.0, None, z, False),
        (0.1, lambda: s.lab_antisway("activate"), z, False),
        (6.0, None, z, False),
        (0.1, lambda: s.estop("script"), z, False),
        (2.0, None, z, False),
    ]
    try:
        return _drive(s, script, dt=0.02, every=25)
    finally:
        s.close()


CASES: dict[str, Callable[[], dict[str, np.ndarray]]] = {
    "sim_tac_off": lambda: _tac("off"),
    "sim_tac_tac": lambda: _tac("tac"),
    "sim_tac_cooperative": lambda: _tac("cooperative"),
    "sim_tac_sweep": _tac_sweep,
    **{
        f"sim_vvmc_{sensors}{'_antisway' if a else ''}": (lambda sensors=sensors, a=a: _vvmc(sensors, a))
        for sensors in ("true", "mru", "tracker")
        for a in (False, True)
    },
    "sim_antisway": _antisway,
    "engine_teleop": _engine_teleop,
    "engine_tac": _engine_tac,
    "engine_tac_neutral": lambda: _engine_tac((0.0, 0.0, 0.0)),
    "engine_lab": _engine_lab,
}


def run_case(name: str) -> dict[str, np.ndarray]:
    out = CASES[name]()
    bad = [k for k, v in out.items() if not np.all(np.isfinite(v) | np.isnan(v))]
    assert not bad, bad
    return out


def load_baseline() -> dict[str, dict[str, np.ndarray]]:
    with np.load(BASELINE) as z:
        cases: dict[str, dict[str, np.ndarray]] = {}
        for key in z.files:
            case, name = key.split("/", 1)
            cases.setdefault(case, {})[name] = z[key]
    return cases


def record() -> None:
    arrays = {}
    for name in CASES:
        for k, v in run_case(name).items():
            arrays[f"{name}/{k}"] = v
        print(f"recorded {name}", flush=True)
    BASELINE.parent.mkdir(exist_ok=True)
    np.savez_compressed(BASELINE, **arrays)
    print(f"wrote {BASELINE} ({len(arrays)} arrays, {BASELINE.stat().st_size / 1e3:.0f} kB)")


if __name__ == "__main__":
    if sys.argv[1:] != ["--record"]:
        sys.exit("usage: python -m tests.behaviour --record")
    record()
