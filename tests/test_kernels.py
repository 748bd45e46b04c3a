"""Issue 14, item 1: the compiled kernels against the NumPy reference path, on the same seeded inputs.

Every serial robot of the library and random chains, random configurations inside (and outside)
the limits; results equal to 1e-12 (they are bitwise equal today)."""

import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from app.ik import make_solver
from app.models import kernels
from app.models.registry import list_robots, load_robot, load_spec
from app.models.serial import SerialRobot
from app.models.xml import parse_robot_xml
from app.warmup import warm_up

SERIAL = [n for n in list_robots() if load_spec(n).type == "serial"]
pytestmark = pytest.mark.skipif(not kernels.ENABLED, reason="numba not installed or BOSUN_JIT=0")


def both(robot, fn):
    robot.use_kernels = True
    a = fn()
    robot.use_kernels = False
    b = fn()
    robot.use_kernels = True
    return a, b


def random_chain(draw_seed: int, n: int) -> SerialRobot:
    rng = np.random.default_rng(draw_seed)
    links = []
    for i in range(n):
        kind = "prismatic" if rng.random() < 0.25 else "revolute"
        a, alpha, const = rng.uniform(-1, 1), rng.choice([0, 90, -90, 180, rng.uniform(-180, 180)]), rng.uniform(-1, 1)
        dh = f'<dh theta="{const * 90:.6f}" a="{a:.6f}" alpha="{alpha:.6f}"/>' if kind == "prismatic" else (
            f'<dh d="{const:.6f}" a="{a:.6f}" alpha="{alpha:.6f}"/>'
        )  # fmt: skip
        lim = '<limits min="-0.5" max="0.5" speed="1"/>' if kind == "prismatic" else (
            '<limits min="-170" max="170" speed="90"/>'
        )  # fmt: skip
        coupling = '<coupling joint="q0" factor="0.5"/>' if i > 0 and rng.random() < 0.2 else ""
        links.append(
            f'<link joint="{kind}">{dh}<joint name="q{i}" sign="{rng.choice([-1, 1])}">{lim}{coupling}</joint></link>'
        )
    text = (
        '<robot name="r" type="serial" angle_unit="deg"><description>d</description><source>s</source><serial>'
        f'<base xyz="0.1 -0.2 0.3" rpy="10 20 30"/>{"".join(links)}<tool xyz="0 0 0.1" rpy="0 90 0"/></serial></robot>'
    )
    return SerialRobot(parse_robot_xml(text))


@pytest.mark.parametrize("name", SERIAL)
def test_fk_jacobian_and_position_equal_the_reference_on_every_library_robot(name):
    robot = load_robot(name)
    rng = np.random.default_rng(14)
    span = robot.upper - robot.lower
    Q = rng.uniform(robot.lower - 0.2 * span, robot.upper + 0.2 * span, size=(200, robot.n_joints))
    for q in Q:
        for method in (robot.frames, robot.jacobian, robot.position):
            a, b = both(robot, lambda m=method, q=q: m(q))
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
    a, b = both(robot, lambda: robot.position(Q))
    np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)


@settings(max_examples=40, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2**31), n=st.integers(1, 8))
def test_kernels_equal_the_reference_on_random_chains(seed, n):
    robot = random_chain(seed, n)
    q = np.random.default_rng(seed + 1).uniform(robot.lower, robot.upper)
    for method in (robot.frames, robot.jacobian, robot.position):
        a, b = both(robot, lambda m=method: m(q))
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", SERIAL)
def test_the_compiled_dls_descent_takes_the_reference_steps(name):
    robot = load_robot(name)
    solver = make_solver("jacobian", robot, seed=0)
    rng = np.random.default_rng(140)
    targets = robot.position(rng.uniform(robot.lower, robot.upper, size=(25, robot.n_joints)))
    targets[-5:] += 0.5 * workspace_scale(robot)  # some out of reach: the descent stalls, not converges
    for i, x in enumerate(targets):
        q0 = solver.default_q0() if i % 2 else rng.uniform(robot.lower, robot.upper)
        (qa, ea, ia), (qb, eb, ib) = both(robot, lambda q0=q0, x=x: solver._descend(q0, x, np.inf))
        assert ia == ib
        np.testing.assert_allclose(qa, qb, rtol=0, atol=1e-12)
        assert abs(ea - eb) <= 1e-12


@pytest.mark.parametrize("name", SERIAL)
def test_the_compiled_velocity_step_equals_the_reference(name):
    """Velocity mode's one DLS step per tick (eq. 4), compiled and NumPy, from random poses (some on a
    limit, where the active set clamps) with random tool velocities: the same θ̇, error and verdict."""
    robot = load_robot(name)
    solver = make_solver("jacobian", robot, seed=0)
    rng = np.random.default_rng(41)
    for k in range(40):
        q = rng.uniform(robot.lower, robot.upper)
        if k % 4 == 0:
            q[rng.integers(robot.n_joints)] = robot.upper[0] if rng.random() < 0.5 else robot.lower[0]
            q = robot.clip(q)
        v = rng.normal(size=3) * 0.3
        a, b = both(robot, lambda q=q, v=v: solver.solve_velocity(q, v, 0.002))
        np.testing.assert_allclose(a.qdot, b.qdot, rtol=0, atol=1e-12)
        np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-12)
        assert abs(a.error - b.error) <= 1e-12 and a.success == b.success


def workspace_scale(robot) -> float:
    from app.models.workspace import workspace_box

    return workspace_box(robot).diagonal


def test_warm_up_compiles_every_kernel_and_says_how_long():
    seen = []
    seconds = warm_up(progress=lambda k, n: seen.append((k, n)))
    assert seconds >= 0 and seen[-1][0] == seen[-1][1] == len(seen)
    # then every kernel file has a fresh cache (set-up's second run spawns no compile processes)
    from app.warmup import KERNEL_MODULES, cold

    assert cold(KERNEL_MODULES) == []


@pytest.mark.parametrize("name", ["comau_smart5_3dof", "kuka_youbot", "scara"])
def test_the_one_call_warm_solve_returns_what_the_reference_path_returns(name):
    """Teleoperation's case (targets 1 cm apart, each from the previous solution) through the compiled
    one-call path and through the whole NumPy path: the same q, error, iterations and verdict."""
    from app.analysis.ik_studies import warm_path

    robot = load_robot(name)
    solver = make_solver("jacobian", robot, seed=0)
    X = warm_path(robot, 120, np.random.default_rng(7))
    runs = []
    for flag in (True, False):
        robot.use_kernels = flag
        q, out = solver.solve_position(X[0]).q, []
        for x in X[1:]:
            res = solver.solve_position(x, q)
            q = res.q
            out.append((res.q, res.error, res.iterations, res.success, res.position))
        runs.append(out)
    robot.use_kernels = True
    for (qa, ea, ia, sa, pa), (qb, eb, ib, sb, pb) in zip(*runs, strict=True):
        np.testing.assert_allclose(qa, qb, rtol=0, atol=1e-12)
        np.testing.assert_allclose(pa, pb, rtol=0, atol=1e-12)
        assert abs(ea - eb) <= 1e-12 and ia == ib and sa == sb


@pytest.mark.parametrize("name", ["comau_smart5_3dof", "offshore_crane"])
@pytest.mark.parametrize("elbow", ["auto", "up", "down"])
def test_compiled_closed_form_candidates_and_choice_equal_the_reference(name, elbow):
    """Motion-Lab eqs. (7)–(20) and TAC eqs. (42)–(44) compiled: the same candidate chosen (q, error,
    exact, inside) for reachable and unreachable targets, and the same answer for reachable ones.
    (Unreachable ones go on to a time-budgeted refinement, which no two runs share.)"""
    robot = load_robot(name)
    solver = make_solver("analytic", robot, seed=0, elbow=elbow)
    rng = np.random.default_rng(5)
    X = robot.position(rng.uniform(robot.lower, robot.upper, size=(200, 3)))
    X[-40:] *= 3.0  # out of reach
    refs = rng.uniform(robot.lower, robot.upper, size=(200, 3))
    for x, ref in zip(X, refs, strict=True):
        (qa, _, ea, xa, ia), (qb, _, eb, xb, ib) = both(robot, lambda x=x, ref=ref: solver._closed_form(x, ref))
        np.testing.assert_allclose(qa, qb, rtol=0, atol=1e-12)
        assert abs(ea - eb) <= 1e-12 and bool(xa) == xb and bool(ia) == ib
    for x in X[:-40]:
        a, b = both(robot, lambda x=x: solver.solve_position(x))
        if b.reason == "closed form":  # exact and inside the limits: one compiled pass
            np.testing.assert_allclose(a.q, b.q, rtol=0, atol=1e-12)
            np.testing.assert_allclose(a.position, b.position, rtol=0, atol=1e-12)
            assert a.success and a.reason == b.reason and abs(a.error - b.error) <= 1e-12


def test_no_serial_kernel_takes_more_than_8_arguments_and_the_records_are_built_once():
    """Issue 29: no compiled function of app/models/kernels.py takes more than 8 arguments; what stays
    fixed travels as a record built once by its owner (robot, solver, arm), the same tuple on every call."""
    import ast
    import inspect

    tree = ast.parse(inspect.getsource(kernels))
    jitted = {
        f.name: len(f.args.args)
        for f in tree.body
        if isinstance(f, ast.FunctionDef) and any(getattr(d, "id", None) == "_jit" for d in f.decorator_list)
    }
    assert {"frames", "position", "descend", "select_candidate", "comau_candidates"} <= set(jitted)
    assert {name: n for name, n in jitted.items() if n > 8} == {}
    robot = load_robot("comau_smart5_3dof")
    jac, ana = make_solver("jacobian", robot), make_solver("analytic", robot)

    def records():
        return robot.kernel_record, jac.kernel_settings, ana._limits, ana.arm.kernel_record

    first = records()
    assert all(type(r) is tuple for r in first)
    x = robot.position(np.full(3, 0.3))
    for _ in range(2):
        jac.solve_position(x, np.zeros(3))
        ana.solve_position(x)
    assert all(a is b for a, b in zip(records(), first, strict=True))


# ---------------------------------------------------------------------------- plant updates
def lockstep(make, drive, steps):
    """Two plants, compiled and reference, driven alike; every state compared after every step."""
    a, b = make(), make()
    a.use_kernels, b.use_kernels = True, False
    for k in range(steps):
        drive(a, k)
        drive(b, k)
        yield a, b


@pytest.mark.parametrize("dt", [0.002, 0.01, 0.02])
def test_compiled_joint_servo_steps_equal_the_reference(dt):
    from app.sim.actuators import JointActuators

    rng = np.random.default_rng(int(dt * 1e4))
    n = 40
    speed, acc = rng.uniform(0.2, 3.0, n), np.where(rng.random(n) < 0.2, np.inf, rng.uniform(0.5, 20.0, n))
    q0, refs = rng.uniform(-1, 1, n), rng.uniform(-2.5, 2.5, size=(20, n))
    make = lambda: JointActuators(-np.ones(n), np.ones(n), speed, acc, tau=0.05, q0=q0)  # noqa: E731
    for a, b in lockstep(make, lambda p, k: p.step(refs[k // 50], dt), 1000):
        for x, y in ((a.q, b.q), (a.qdot, b.qdot), (a.qddot, b.qddot)):
            np.testing.assert_allclose(x, y, rtol=0, atol=1e-12)


@pytest.mark.parametrize("with_v_ref", [False, True])
def test_compiled_platform_motion_filter_steps_equal_the_reference(with_v_ref):
    from app.sim.stewart import MotionFilter

    rng = np.random.default_rng(7 + with_v_ref)
    lo, hi = -rng.uniform(0.2, 1.0, 6), rng.uniform(0.2, 1.0, 6)
    speed, acc = rng.uniform(0.2, 1.0, 6), rng.uniform(0.5, 5.0, 6)
    refs, vrefs = rng.uniform(-1.5, 1.5, size=(20, 6)), rng.uniform(-0.5, 0.5, size=(20, 6))
    make = lambda: MotionFilter(lo, hi, speed, acc, tau=0.1)  # noqa: E731

    def drive(p, k):
        p.step(refs[k // 50], vrefs[k // 50] if with_v_ref else None, 0.01, speed_scale=0.8 if k % 300 < 150 else 1.0)

    for a, b in lockstep(make, drive, 1000):
        for x, y in ((a.x, b.x), (a.v, b.v), (a.a, b.a)):
            np.testing.assert_allclose(x, y, rtol=0, atol=1e-12)


CHECK_SIGNATURES = r"""
import json, numpy as np
from app.models import kernels
from app.sim import kernels as sim
from app.ik import ga_kernels as ga
from app.marine import kernels as marine
from app.control import tac_kernels as tac
from app.models import crane_head_kernels as head
from app.sim import head_kernels as motors
from app.scenes import tac_kernels as tac_scene
from app.warmup import warm_up
MODULES = (kernels, sim, ga, marine, head, tac, motors, tac_scene)
warm_up()
before = {n: len(f.signatures) for m in MODULES for n, f in vars(m).items() if hasattr(f, "signatures")}
from app.engine.session import Session
from app.engine.lab_session import LabSession
from app.engine.tac_session import TacSession
from app.teleop.devices import InputSample
from app.ik import make_solver
from app.models.registry import load_robot
for robot, solver in [("comau_smart5_3dof", "analytic"), ("offshore_crane", "analytic"), ("kuka_youbot", "jacobian"),
                      ("scara", "ga"), ("comau_smart5_6dof", "jacobian")]:
    s = Session(robot_name=robot, solver_name=solver)
    t = 0.0
    for k in range(200):
        t += 0.002
        s.feed(InputSample((0.3, -0.2, 0.1), (k > 20,), "stick", t), t)
        s.tick(t, 0.002)
    r = load_robot(robot)
    for name in ("jacobian", "ga") + (("analytic",) if solver == "analytic" else ()):
        sv = make_solver(name, r, seed=0)
        x = r.position(r.lower + 0.3 * (r.upper - r.lower))
        sv.solve_position(x, r.lower + 0.25 * (r.upper - r.lower))
        sv.solve_position(list(x))
for session in (LabSession(), TacSession()):
    t = 0.0
    for k in range(100):
        t += 0.02
        session.tick(t, 0.02)
after = {n: len(f.signatures) for m in MODULES for n, f in vars(m).items() if hasattr(f, "signatures")}
print(json.dumps({"before": before, "after": after}))
"""


@pytest.mark.slow
def test_no_kernel_compiles_after_warm_up_in_any_engine():
    """Issue 14, item 1: compile ahead, never in a control tick.  Arrays of another layout (a strided
    slice) made numba compile a second specialisation of the platform filter in the lab engine's
    first tick (seconds); every call site now passes C-contiguous float64, so after ``warm_up``
    the teleop, lab and crane-head engines and every solver run without a single new compile."""
    import json
    import subprocess
    import sys

    out = subprocess.run([sys.executable, "-c", CHECK_SIGNATURES], capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr[-2000:]
    counts = json.loads(out.stdout.strip().splitlines()[-1])
    assert counts["after"] == counts["before"], counts
    assert all(n <= 1 for n in counts["after"].values()), counts


FOREIGN_SIGNATURES = r"""
import importlib, json, sys
from app.warmup import KERNEL_MODULES
mods = {n: importlib.import_module(n) for n in KERNEL_MODULES}
for step in mods[sys.argv[1]].warm_up_steps():
    step()
print(json.dumps([f"{n}.{a}" for n, m in mods.items() if n != sys.argv[1]
                  for a, f in vars(m).items() if getattr(f, "__module__", "") == n and getattr(f, "signatures", None)]))
"""


@pytest.mark.slow
def test_each_kernel_files_warm_up_writes_only_its_own_cache_entries():
    """Set-up compiles the kernel files in parallel processes (``warm_up(workers=2)``); that is safe because a
    file's steps give no other file's kernel a signature (a callee in another file is compiled into the
    caller), so no two processes write one cache entry.  Each file's steps alone, in a fresh process."""
    import json
    import subprocess
    import sys

    from app.warmup import KERNEL_MODULES, shares

    for name in KERNEL_MODULES:
        cmd = [sys.executable, "-c", FOREIGN_SIGNATURES, name]
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
        assert out.returncode == 0, out.stderr[-2000:]
        assert json.loads(out.stdout.strip().splitlines()[-1]) == [], name
    for workers in (1, 2, 3, 8):
        parts = shares(workers)
        assert sorted(n for p in parts for n in p) == sorted(KERNEL_MODULES)
        assert len(parts) == min(workers, len(KERNEL_MODULES))


def test_a_kernel_files_cache_is_cleared_when_a_kernel_file_it_imports_changes(tmp_path):
    """Numba checks a cached kernel against its own file only; the lab step calls this package's
    Comau candidates, so an edit of app/models/kernels.py must clear app/sim/kernels.py's cache too."""
    from app.models.kernels import clear_stale_caches

    (tmp_path / "models").mkdir()
    (tmp_path / "sim").mkdir()
    (tmp_path / "models/kernels.py").write_text("def f(): pass\n", encoding="utf-8")
    (tmp_path / "sim/kernels.py").write_text("from app.models import kernels as model_kernels\n", encoding="utf-8")
    files = ("models/kernels.py", "sim/kernels.py")
    assert clear_stale_caches(tmp_path, files) == list(files)  # first look: no stamps yet
    cached = [
        tmp_path / "sim/__pycache__/kernels.step-10.py311.nbi",
        tmp_path / "models/__pycache__/kernels.f-1.py311.nbi",
    ]
    for f in cached:
        f.write_text("machine code", encoding="utf-8")
    assert clear_stale_caches(tmp_path, files) == []  # nothing changed: caches kept
    assert all(f.exists() for f in cached)
    (tmp_path / "models/kernels.py").write_text("def f(): return 1\n", encoding="utf-8")
    assert clear_stale_caches(tmp_path, files) == ["sim/kernels.py"]  # its import changed
    assert not cached[0].exists() and cached[1].exists()  # numba itself handles models/kernels.py's own edit
    (tmp_path / "sim/kernels.py").write_text(
        "from app.models import kernels as model_kernels\n# edited\n", encoding="utf-8"
    )
    assert clear_stale_caches(tmp_path, files) == []  # an edit of the file itself is numba's to notice


def test_a_kernel_files_cache_is_cleared_when_a_file_its_imports_import_changes(tmp_path):
    """H123: numba compiles a called kernel into its caller, and the scene's lab step calls the guard's clearances
    through the guard (app/scenes/lab_kernels.py → app/control/lab_kernels.py → lab_clearance_kernels.py): an edit
    of the clearances left the lab step's cache — and its old clearances — in place (2026-12-01)."""
    from app.models.kernels import clear_stale_caches

    (tmp_path / "control").mkdir()
    (tmp_path / "scenes").mkdir()
    (tmp_path / "control/clearances.py").write_text("def f(): pass\n", encoding="utf-8")
    (tmp_path / "control/guard.py").write_text("from app.control.clearances import f\n", encoding="utf-8")
    (tmp_path / "scenes/step.py").write_text("from app.control.guard import (  # noqa\n    g,\n)\n", encoding="utf-8")
    files = ("control/clearances.py", "control/guard.py", "scenes/step.py")
    assert clear_stale_caches(tmp_path, files) == list(files)
    step = tmp_path / "scenes/__pycache__/step.lab_step-1.py311.nbi"
    step.write_text("machine code", encoding="utf-8")
    assert clear_stale_caches(tmp_path, files) == []
    (tmp_path / "control/clearances.py").write_text("def f(): return 1\n", encoding="utf-8")
    assert clear_stale_caches(tmp_path, files) == ["control/guard.py", "scenes/step.py"]
    assert not step.exists()


def test_every_file_with_a_compiled_kernel_has_its_cache_cleared_when_what_it_imports_changes():
    """H123: app/control/lab_clearance_kernels.py (the lab guard's clearances) and predict_kernels.py were not in
    ``KERNEL_FILES``: after an edit of the clearances the lab's guard (app/control/lab_kernels.py, which calls them)
    kept its old machine code from numba's cache — 20 % of 3,000 random guard calls differed from the reference
    when the clearances' load model changed (2026-12-01).  Every file that compiles a kernel is listed."""
    import re
    from pathlib import Path

    from app.models import kernels
    from app.models.kernels import KERNEL_FILES

    root = Path(kernels.__file__).resolve().parents[1]  # the app package imported (the core job's: installed)
    compiled = {
        f.relative_to(root).as_posix()
        for f in root.rglob("*.py")
        if re.search(r"^@_jit\b", f.read_text(encoding="utf-8"), re.M)
    }
    assert compiled and compiled <= set(KERNEL_FILES), sorted(compiled - set(KERNEL_FILES))


NOTHING_AT_IMPORT = r"""
import importlib, json, os, pathlib
touched = []
for name in ("unlink", "write_text", "write_bytes", "mkdir"):
    original = getattr(pathlib.Path, name)
    def spy(self, *a, _name=name, _original=original, **k):
        touched.append(f"{_name} {self}")
        return _original(self, *a, **k)
    setattr(pathlib.Path, name, spy)
real_remove = os.remove
os.remove = os.unlink = lambda p, *a, **k: (touched.append(f"remove {p}"), real_remove(p, *a, **k))[1]
from app.warmup import KERNEL_MODULES
for n in KERNEL_MODULES:
    importlib.import_module(n)
print(json.dumps(touched))
"""


def test_importing_the_kernel_files_changes_no_file(tmp_path):
    """Issue 29, item 5 (nothing happens at import): importing a kernel file used to clear stale numba caches
    (and write their stamps); the CLI, ``warm_up`` and the test session do it now, so an import writes and
    removes nothing, even in a copy of the package with no stamps at all."""
    import json
    import shutil
    import subprocess
    import sys
    from pathlib import Path

    app_dir = Path(__file__).resolve().parents[1] / "app"
    if not app_dir.is_dir():
        pytest.skip("needs the checkout's app/")
    shutil.copytree(app_dir, tmp_path / "app", ignore=shutil.ignore_patterns("__pycache__"))
    env = {**os.environ, "PYTHONPATH": str(tmp_path)}
    out = subprocess.run(
        [sys.executable, "-c", NOTHING_AT_IMPORT], capture_output=True, text=True, timeout=300, cwd=tmp_path, env=env
    )
    assert out.returncode == 0, out.stderr[-2000:]
    assert json.loads(out.stdout.strip().splitlines()[-1]) == []


def test_warm_up_and_the_cli_clear_stale_caches_first(monkeypatch):
    from app import cli, warmup
    from app.models import kernels

    calls = []
    monkeypatch.setattr(kernels, "clear_stale", lambda: calls.append("cleared") or [])
    monkeypatch.setattr(warmup, "_steps", lambda modules: [])
    warmup.warm_up()
    assert calls == ["cleared"] or not kernels.ENABLED
    assert cli.main(["robots"]) == 0
    assert calls[-1] == "cleared"


INTERRUPT_WHILE_LOADING = r"""
import signal, sys
from numba.core import codegen

when = sys.argv[1]  # "compile": the first time LLVM asks the object cache; "load": when it hands over cached code
fired = []
ask = codegen.CPUCodeLibrary._object_getbuffer_hook.__func__


def ctrl_c_inside_the_callback(cls, ll_module):
    lib = getattr(ll_module, "_CPUCodeLibrary__library", None)
    cached = lib is not None and getattr(lib, "_compiled_object", None)
    if not fired and (when == "compile" or cached):
        fired.append(1)
        signal.raise_signal(signal.SIGINT)  # Ctrl-C while LLVM is inside numba's ctypes callback
    return ask(cls, ll_module)


codegen.CPUCodeLibrary._object_getbuffer_hook = classmethod(ctrl_c_inside_the_callback)
import numba
from app.models import kernels  # registers the deferral


@numba.njit(cache=True)
def f(x):
    return 2.0 * x + 1.0


try:
    f(1.0)
    print("not interrupted", fired, flush=True)
except KeyboardInterrupt:
    print("interrupted after", f.signatures, flush=True)
print("then", f(2.0), flush=True)
"""


@pytest.mark.parametrize("when", ["compile", "load"])
def test_ctrl_c_while_numba_compiles_or_loads_a_kernel_arrives_after_it(tmp_path, when):
    """A KeyboardInterrupt inside numba's ctypes callback was dropped: LLVM went on without the cached machine
    code and the process died with SIGSEGV (``sim tac`` interrupted at its start, CI 2026-11-28 and -29), or the
    interrupt was lost and the command finished.  The signal now waits for the compiler lock's release."""
    import subprocess
    import sys

    script = tmp_path / "interrupt_while_loading.py"
    script.write_text(INTERRUPT_WHILE_LOADING, encoding="utf-8")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache")}
    if when == "load":  # a first run writes the cache (it is interrupted too: "compile" covers it)
        subprocess.run([sys.executable, str(script), "none"], env=env, capture_output=True, timeout=300, check=True)
    out = subprocess.run(
        [sys.executable, "-X", "faulthandler", str(script), when], env=env, capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, (out.returncode, out.stderr[-2000:])
    assert "Exception ignored" not in out.stderr, out.stderr[-2000:]
    assert out.stdout.splitlines() == ["interrupted after [(float64,)]", "then 5.0"], out.stdout


SIGNAL_DURING_A_KERNEL = r"""
import os, signal, sys, threading, time
import numba
import numpy as np
from app.errors import raise_interrupt

sig = getattr(signal, sys.argv[1])
signal.signal(sig, raise_interrupt)  # what app/launch.py sets for both


@numba.njit(nogil=True)
def slow(n):
    out, ok = np.zeros(3), np.zeros(3, dtype=np.bool_)
    for i in range(n):
        out[i % 3] += 1e-9 * i
    return out, ok  # boxing the arrays calls numba's _numba_unpickle: the first Python code after the signal


slow(10)
t0 = time.perf_counter()
slow(20_000_000)
n = max(1, int(20_000_000 * 0.6 / (time.perf_counter() - t0)))  # about 0.6 s
threading.Timer(0.2, os.kill, args=(os.getpid(), sig)).start()
try:
    slow(n)
    time.sleep(2.0)  # the program goes on: the interrupt arrives here
    print("not interrupted", flush=True)
except KeyboardInterrupt:
    print("interrupted after the kernel", flush=True)
"""


@pytest.mark.parametrize("name", ["SIGINT", "SIGTERM"])
def test_a_signal_during_a_kernel_that_returns_an_array_interrupts_after_it(tmp_path, name):
    """Safety H92: a signal that arrives while a kernel runs is handled by the first Python code after it, which
    is numba's ``_numba_unpickle`` as the kernel boxes its array; a KeyboardInterrupt raised there reached the
    machine code as a NULL object and the process died with SIGSEGV (``sim tac`` stopped while the Delta head's
    workspace was computed) or, here, a ``SystemError`` "returned a result with an exception set".  Bosun's handler
    puts the signal off until the kernel has returned."""
    import subprocess
    import sys

    script = tmp_path / "signal_during_a_kernel.py"
    script.write_text(SIGNAL_DURING_A_KERNEL, encoding="utf-8")
    out = subprocess.run(
        [sys.executable, "-X", "faulthandler", str(script), name], capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, (out.returncode, out.stderr[-2000:])
    assert out.stdout.strip() == "interrupted after the kernel", out.stdout


DROPPED_INTERRUPT = r"""
import os, signal, sys, time, weakref
from app.errors import keep_dropped_interrupts, raise_interrupt

if sys.argv[1] == "hook":
    sys.unraisablehook = keep_dropped_interrupts  # as app/launch.py sets it
signal.signal(signal.SIGINT, raise_interrupt)


class Thing:
    pass


thing = Thing()
ref = weakref.ref(thing, lambda _: os.kill(os.getpid(), signal.SIGINT))  # Ctrl-C inside a weakref callback
try:
    del thing  # the callback runs; Python drops the KeyboardInterrupt raised in it
    time.sleep(2.0)
    print("not interrupted", flush=True)
except KeyboardInterrupt:
    print("interrupted", flush=True)
"""


def test_an_interrupt_python_drops_is_raised_again(tmp_path):
    """Safety H93: a KeyboardInterrupt raised where Python cannot pass it on (a weakref callback: matplotlib's,
    in a ``sim tac`` run) was printed as "Exception ignored" and lost, and the command ran on.  The command's
    unraisable hook makes it pending again; without the hook, the same script is not interrupted."""
    import subprocess
    import sys

    script = tmp_path / "dropped_interrupt.py"
    script.write_text(DROPPED_INTERRUPT, encoding="utf-8")
    runs = {
        how: subprocess.run([sys.executable, str(script), how], capture_output=True, text=True, timeout=120)
        for how in ("hook", "python")
    }
    assert runs["hook"].stdout.strip() == "interrupted", runs["hook"]
    assert "Exception ignored" not in runs["hook"].stderr, runs["hook"].stderr
    assert runs["python"].stdout.strip() == "not interrupted", runs["python"]  # the hazard, as Python has it


SIGNAL_DURING_A_FIGURE = r"""
import os, signal, sys
from pathlib import Path
from app.errors import raise_interrupt
from app.analysis.figures import pyplot, save_figure

signal.signal(signal.SIGINT, raise_interrupt)
plt = pyplot()
from matplotlib.backends.backend_agg import RendererAgg

draw = RendererAgg.draw_path
fired = []


def ctrl_c_while_drawing(self, *args, **kwargs):
    if not fired:
        fired.append(1)
        os.kill(os.getpid(), signal.SIGINT)  # Ctrl-C while Agg draws (its renderer calls Python back)
    return draw(self, *args, **kwargs)


RendererAgg.draw_path = ctrl_c_while_drawing
fig, ax = plt.subplots()
ax.plot([0, 1, 2], [0, 1, 0])
path = Path(sys.argv[1])
try:
    save_figure(plt, fig, path)
    print("not interrupted", flush=True)
except KeyboardInterrupt:
    print("interrupted", "written" if path.is_file() and path.stat().st_size > 0 else "not written", flush=True)
"""


def test_ctrl_c_while_a_figure_is_drawn_comes_after_it_is_written(tmp_path):
    """Safety H94: a SIGINT while Agg drew a figure (``sim tac`` writing its figures) came out of matplotlib's
    renderer as "ValueError: Invalid bounding box", a traceback (1 of 200 timed tries).  The interrupt now waits
    until the figure is written, then ends the command as Ctrl-C does."""
    import subprocess
    import sys

    script = tmp_path / "signal_during_a_figure.py"
    script.write_text(SIGNAL_DURING_A_FIGURE, encoding="utf-8")
    out = subprocess.run(
        [sys.executable, str(script), str(tmp_path / "f.png")], capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stderr[-2000:]
    assert out.stdout.strip() == "interrupted written", out.stdout
