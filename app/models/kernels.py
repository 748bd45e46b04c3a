"""Compiled hot paths of serial kinematics and the damped-least-squares solver.

Numba (``@njit(cache=True)``: machine code cached on disk beside this file, so only the first run
after an install or an edit compiles) turns these loop-style functions into native code; without
numba, or with ``BOSUN_JIT=0`` in the environment, the same Python functions run interpreted.
Either way the plain-NumPy methods of :class:`~app.models.serial.SerialRobot` and
:class:`~app.ik.jacobian.JacobianSolver` stay as the reference path: ``tests/test_kernels.py``
runs both on the same seeded inputs and asserts equal results (1e-12).

No kernel takes more than 8 arguments (issue 29): what stays fixed between calls travels as one record,
a plain tuple (numba takes it as one argument), built once by its owner and kept, never per call; the
per-call inputs (q, a target, candidates) stay arguments of their own (a lone array takes numba's fast
type check; a tuple is type-checked element by element, so records are kept to a few elements).

* ``robot``, the chain (``SerialRobot.kernel_record``, built once per robot): (dh, M, T), float64,
  C-contiguous: dh (5, L) the links' constant DH values θ₀, d₀, a and the cosine and sine of their
  twists α, one row each; M (2, L, n) the joint map M_θ, M_d (θ = θ₀ + M_θ q, d = d₀ + M_d q);
  T (2, 4, 4) T_world_base, T_flange_tool.  Three arrays, not nine:
  a record of nine arrays cost about 0.2 µs a call more than nine separate arguments (its type
  fingerprint outgrows numba's 40-byte buffer), three cost less.  :func:`_chain` gives the nine
  arrays (views).  The DH link is A = Rz(θ) Tz(d) Tx(a) Rx(α) (standard DH, TAC paper eq. 39).
* ``settings``, the damped-least-squares solver's (``JacobianSolver.kernel_settings``, built once per
  solver): (lower, upper, max_step, lambda_max, epsilon, e_ref, k_avoid, tolerance, max_iterations):
  joint limits and largest step per joint (n,) float64; the largest damping λ_max, the singular region
  ε (σ_min below it is damped) and e_ref (the damping fades as |e| drops below it), floats; the
  limit-avoidance gain (float); the success tolerance [m] (float) and the iterations per descent (int).
  :func:`damped_step` reads the first seven.
* ``limits``, the analytic solver's (``AnalyticSolver._limits``, built once per solver): (lower, upper
  (n,) float64, revolute (n,) bool).
* ``arm``, a Comau-type arm's (``ComauArm.kernel_record``, built once per arm): (a1, d1, a2, a3, L
  float, T_world_base (4, 4) float64), Motion-Lab Table 3.
* ``crane``, an elbow crane's (``ElbowCrane.kernel_record``, built once per crane): (L0, L1, L2 float,
  T_world_1 (4, 4) float64), TAC paper Table 3 and eqs. (42)–(44).
"""

from __future__ import annotations

import contextlib
import hashlib
import math
import os
import re
from pathlib import Path

import numpy as np

try:  # numba is a dependency; the interpreted path keeps Bosun working where it cannot be installed
    import numba
except ImportError:  # pragma: no cover - exercised only without numba
    numba = None

ENABLED = numba is not None and os.environ.get("BOSUN_JIT", "1") != "0"

# Every file holding kernels.  Numba checks a cached kernel against its own file only, yet kernels
# call kernels of other files (the lab step calls this file's Comau candidates) and would keep the old
# machine code after an edit there: each file's cache is cleared when a kernel file it imports changes.
KERNEL_FILES = (
    "models/kernels.py",
    "models/lab_kernels.py",
    "sim/kernels.py",
    "control/lab_kernels.py",
    "scenes/lab_kernels.py",
    "marine/kernels.py",
    "ik/ga_kernels.py",
    "models/crane_head_kernels.py",
    "control/tac_kernels.py",
    "sim/head_kernels.py",
    "scenes/tac_kernels.py",
    "models/pendulum_kernels.py",
    "control/antisway_kernels.py",
    "control/guard_kernels.py",
    "control/lab_clearance_kernels.py",
    "control/predict_kernels.py",
    "scenes/teleop_kernels.py",
    "scenes/lab_transfer_kernels.py",
    "scenes/crane_transfer_kernels.py",
)


def clear_stale_caches(root: Path, files: tuple[str, ...] = KERNEL_FILES) -> list[str]:
    """Remove the numba caches (``__pycache__/STEM.*.nbi, *.nbc``) of each of ``files`` (under ``root``,
    the ``app`` folder) whose imported kernel files (top-level ``from app.X import``), or the kernel files those
    import in turn, changed since the last check, recorded in a stamp beside the cache; returns the files whose
    caches were cleared."""
    sources = {name: (root / name).read_bytes() for name in files if (root / name).is_file()}
    modules = {"app." + name[:-3].replace("/", "."): name for name in sources}
    direct = {}
    for name, text in sources.items():
        direct[name] = set()
        for mod, names in re.findall(rb"^from (app[\w.]*) import \(?([\w, ]*)", text, re.M):
            named = [n.split()[0] for n in names.decode().split(",") if n.strip()]  # "kernels as k": kernels
            for m in [mod.decode()] + [f"{mod.decode()}.{n}" for n in named]:
                if m in modules and modules[m] != name:
                    direct[name].add(modules[m])
    cleared = []
    for name in sources:
        deps, todo = set(), list(direct[name])  # what it imports, and what those import (H123: numba inlines them)
        while todo:
            dep = todo.pop()
            if dep not in deps and dep != name:
                deps.add(dep)
                todo.extend(direct[dep])
        digest = hashlib.sha256(b"".join(d.encode() + b"\0" + sources[d] + b"\0" for d in sorted(deps))).hexdigest()
        cache = (root / name).parent / "__pycache__"
        stem = Path(name).stem
        stamp = cache / f"{stem}.bosun-imports.sha256"
        with contextlib.suppress(OSError):
            if stamp.read_text(encoding="utf-8") == digest:
                continue
        for f in [*cache.glob(f"{stem}.*.nbi"), *cache.glob(f"{stem}.*.nbc")]:
            with contextlib.suppress(OSError):
                f.unlink()
        with contextlib.suppress(OSError):  # a read-only install: numba then does not cache either
            cache.mkdir(exist_ok=True)
            stamp.write_text(digest, encoding="utf-8")
        cleared.append(name)
    return cleared


def clear_stale() -> list[str]:
    """:func:`clear_stale_caches` for this installation's kernel files: called by the CLI's entry point, by
    :func:`app.warmup.warm_up` and by the test session before any kernel runs (never at import)."""
    return clear_stale_caches(Path(__file__).resolve().parents[1]) if ENABLED else []


def _jit(fn):
    return numba.njit(cache=True, nogil=True)(fn) if ENABLED else fn


def _defer_interrupts_while_compiling() -> None:
    """Ctrl-C and SIGTERM wait while numba compiles or loads a kernel, and arrive when it is done (safety H91).

    Numba loads a cached kernel under its compiler lock: LLVM asks a Python callback (ctypes) for the machine
    code.  A KeyboardInterrupt raised inside that callback is printed as "Exception ignored" and dropped, and
    LLVM goes on without the code: the process died with SIGSEGV (CI on 2026-11-28 and 2026-11-29, ``sim tac``
    interrupted at its start; reproduced about once in 180 tries), or the interrupt was lost and the run finished
    with status 0.  Numba's documented event ``numba:compiler_lock`` holds the signals off
    (:data:`app.errors.DEFERRED`) from the lock's outermost acquisition to its release."""
    from numba.core import event

    from app.errors import DEFERRED

    class Listener(event.Listener):
        def on_start(self, _event) -> None:
            DEFERRED.enter()

        def on_end(self, _event) -> None:
            DEFERRED.exit()

    event.register("numba:compiler_lock", Listener())


if ENABLED:
    _defer_interrupts_while_compiling()


if ENABLED:
    from llvmlite import ir
    from numba.core import types as _types
    from numba.extending import intrinsic

    @intrinsic
    def fma(typingctx, a, b, c):
        """a·b + c rounded once (LLVM's ``llvm.fma.f64``, one instruction on every x86-64 with FMA), for compiled
        code.  Products summed as an ``fma`` chain in index order, the first term a plain product, round as this
        machine's OpenBLAS ``ddot`` and ``dgemm`` do for 3-vectors and 4×4 matrices (checked bit for bit on a
        hundred thousand random inputs; ``tests/test_guard_fast_paths.py`` holds the chains to exact arithmetic): the
        loops that replace those library calls (:func:`_matmul4_into`, the segment distance of
        :mod:`app.control.guard_kernels`) give the same numbers without a call or an allocation."""
        sig = _types.float64(_types.float64, _types.float64, _types.float64)

        def codegen(context, builder, signature, args):
            d = ir.DoubleType()
            fn = builder.module.declare_intrinsic("llvm.fma", [d], ir.FunctionType(d, [d, d, d]))
            return builder.call(fn, args)

        return sig, codegen

else:  # pragma: no cover - the interpreted path (no numba, or BOSUN_JIT=0): rounded twice

    def fma(a, b, c):
        """a·b + c (interpreted: the product and the sum each rounded)."""
        return a * b + c


@_jit
def _matmul4_into(A, B, C):
    """C = A @ B for 4×4 matrices, rounded as BLAS ``dgemm`` on them (an :func:`fma` chain over k in order), with
    no library call or allocation (C must not be A or B): :func:`frames`, whose numbers were ``@``'s.  The plant
    kernels keep :func:`matmul_into` (plain sums), whose rounding their recorded simulations were made with."""
    for i in range(4):
        for j in range(4):
            c = A[i, 0] * B[0, j]
            c = fma(A[i, 1], B[1, j], c)
            c = fma(A[i, 2], B[2, j], c)
            C[i, j] = fma(A[i, 3], B[3, j], c)


@_jit
def matmul_into(A, B, C):
    """C = A @ B for small square matrices (3×3, 4×4) without BLAS or an allocation; shared by the
    plant kernels (a loop of this size beats a library call from compiled code)."""
    n = A.shape[0]
    for i in range(n):
        for j in range(n):
            s = 0.0
            for k in range(n):
                s += A[i, k] * B[k, j]
            C[i, j] = s


@_jit
def _chain(robot):
    """The robot record's arrays as (θ₀, d₀, a, cos α, sin α, M_θ, M_d, T_world_base, T_flange_tool): views,
    nothing copied."""
    dh, M, T = robot
    return dh[0], dh[1], dh[2], dh[3], dh[4], M[0], M[1], T[0], T[1]


@_jit
def frames(robot, q):
    """World poses of frame 0, every DH frame and the tool: (L + 2, 4, 4).  ``robot``: the chain record."""
    theta0, d0, a, ca, sa, M_theta, M_d, T_base, T_tool = _chain(robot)
    L = theta0.shape[0]
    n = q.shape[0]
    F = np.empty((L + 2, 4, 4))
    F[0] = T_base
    A = np.zeros((4, 4))
    A[3, 3] = 1.0
    for i in range(L):
        # θ₀ + M_θ q and d₀ + M_d q, link by link: no library call (BLAS gemv) and no arrays.  The same numbers as
        # ``@`` where each link's variable takes at most two joints at ±1 (every robot of the library); a coupling
        # with other factors may round in the last bit otherwise
        th, dd = 0.0, 0.0
        for j in range(n):
            th += M_theta[i, j] * q[j]
            dd += M_d[i, j] * q[j]
        th += theta0[i]
        dd += d0[i]
        ct, st = math.cos(th), math.sin(th)
        A[0, 0], A[0, 1], A[0, 2], A[0, 3] = ct, -st * ca[i], st * sa[i], a[i] * ct
        A[1, 0], A[1, 1], A[1, 2], A[1, 3] = st, ct * ca[i], -ct * sa[i], a[i] * st
        A[2, 0], A[2, 1], A[2, 2], A[2, 3] = 0.0, sa[i], ca[i], dd
        _matmul4_into(F[i], A, F[i + 1])  # the numbers of F[i] @ A, without its library call and allocation
    _matmul4_into(F[L], T_tool, F[L + 1])
    return F


@_jit
def jacobian_from_frames(F, M_theta, M_d):
    """Geometric Jacobian (6, n) of the tool point in the world frame from :func:`frames`."""
    L = F.shape[0] - 2
    n = M_theta.shape[1]
    ox, oy, oz = F[L + 1, 0, 3], F[L + 1, 1, 3], F[L + 1, 2, 3]
    J = np.zeros((6, n))
    # each link's columns (z × r, z) for θ and (z, 0) for d, added to its joints' through M_θ and M_d: the numbers of
    # J_θ M_θ + J_d M_d without the two library calls (BLAS gemm) and their arrays, exactly where a joint moves at
    # most two link variables at ±1 (every robot of the library)
    for i in range(L):
        zx, zy, zz = F[i, 0, 2], F[i, 1, 2], F[i, 2, 2]
        rx, ry, rz = ox - F[i, 0, 3], oy - F[i, 1, 3], oz - F[i, 2, 3]
        cx, cy, cz = zy * rz - zz * ry, zz * rx - zx * rz, zx * ry - zy * rx
        for j in range(n):
            mt = M_theta[i, j]
            if mt != 0.0:
                J[0, j] += cx * mt
                J[1, j] += cy * mt
                J[2, j] += cz * mt
                J[3, j] += zx * mt
                J[4, j] += zy * mt
                J[5, j] += zz * mt
            md = M_d[i, j]
            if md != 0.0:
                J[0, j] += zx * md
                J[1, j] += zy * md
                J[2, j] += zz * md
    return J


@_jit
def position(robot, q):
    """Tool point (3,): the links applied to it last link first (no 4×4 products).  ``robot``: the chain
    record."""
    theta0, d0, a, ca, sa, M_theta, M_d, T_base, T_tool = _chain(robot)
    L = theta0.shape[0]
    theta = theta0 + M_theta @ q
    d = d0 + M_d @ q
    x, y, z = T_tool[0, 3], T_tool[1, 3], T_tool[2, 3]
    for i in range(L - 1, -1, -1):
        y, z = ca[i] * y - sa[i] * z, sa[i] * y + ca[i] * z + d[i]
        x = x + a[i]
        c, s = math.cos(theta[i]), math.sin(theta[i])
        x, y = c * x - s * y, s * x + c * y
    p = np.empty(3)
    for k in range(3):
        p[k] = T_base[k, 0] * x + T_base[k, 1] * y + T_base[k, 2] * z + T_base[k, 3]
    return p


@_jit
def positions(robot, Q):
    """Tool points of many configurations: Q (m, n) → (m, 3).  ``robot``: the chain record."""
    out = np.empty((Q.shape[0], 3))
    for k in range(Q.shape[0]):
        out[k] = position(robot, Q[k])
    return out


@_jit
def damped_step(J, e, q, settings, avoid):
    """One DLS step with active-set clamping (the same steps as ``JacobianSolver.damped_step``): J (m, n),
    the task error e (m,) at q (n,); ``settings``: the solver's record (its first seven fields); ``avoid``:
    add the limit-avoidance term."""
    lo, hi, max_step, lambda_max, epsilon, e_ref, k_avoid = settings[:7]
    m, n = J.shape
    active = np.ones(n)
    dq = np.zeros(n)
    ee = 0.0
    for k in range(e.shape[0]):
        ee += e[k] * e[k]
    for _ in range(n + 1):
        Ja = J * active
        U, s, Vt = np.linalg.svd(Ja, full_matrices=False)
        rank_rows = max(1, min(int(active.sum()), m))
        s_min = s[:rank_rows].min()
        lam2 = lambda_max**2 * (1.0 - (s_min / epsilon) ** 2) if s_min < epsilon else 0.0
        lam2 *= min(1.0, ee / e_ref**2)
        s_big = max(s.max(), 1.0)
        s_inv = np.zeros_like(s)
        for k in range(s.shape[0]):
            denom = s[k] ** 2 + lam2
            if denom > 1e-24 * s_big**2:
                s_inv[k] = s[k] / denom
        J_pinv = (Vt.T * s_inv) @ U.T
        dq = J_pinv @ e
        if avoid and k_avoid > 0:
            N = np.eye(n) - J_pinv @ Ja
            dq += N @ (-k_avoid * (q - 0.5 * (lo + hi)) * active)
        dq *= active
        ratio = np.max(np.abs(dq) / max_step)
        if ratio > 1:
            dq /= ratio
        again = False
        for k in range(n):
            out = (q[k] <= lo[k] + 1e-12 and dq[k] < 0) or (q[k] >= hi[k] - 1e-12 and dq[k] > 0)
            if out and active[k] > 0:
                active[k] = 0.0
                again = True
        if not again:
            break
    return dq


@_jit
def descend(robot, settings, q, x_t):
    """Position-only DLS descent from q to the tool point x_t (``JacobianSolver._descend`` without its
    clock): (best_q, best_err, it).  ``robot``: the chain record; ``settings``: the solver's record."""
    M_theta, M_d = robot[1][0], robot[1][1]
    lo, hi, tolerance, max_iterations = settings[0], settings[1], settings[7], settings[8]
    best_q, best_err, iterations, stall = q, np.inf, 0, 0
    while iterations < max_iterations:
        iterations += 1
        F = frames(robot, q)
        J = jacobian_from_frames(F, M_theta, M_d)[:3].copy()
        e = x_t - F[F.shape[0] - 1, :3, 3]
        err = math.sqrt(e[0] * e[0] + e[1] * e[1] + e[2] * e[2])
        if err < best_err - 1e-12:
            stall = 0 if err < 0.999 * best_err else stall + 1
            best_q, best_err = q, err
        else:
            stall += 1
        if err <= tolerance or stall > 15:
            break
        step = damped_step(J, e, q, settings, True)
        q = np.minimum(np.maximum(q + step, lo), hi)
    return best_q, best_err, iterations


@_jit
def descend_to(robot, settings, q, x_t):
    """:func:`descend`, then the reached tool point and its distance to x_t: (q, p, error, cost, iterations)."""
    best_q, best_err, iterations = descend(robot, settings, q, x_t)
    p = position(robot, best_q)
    d = p - x_t
    return best_q, p, math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]), best_err, iterations


# ----------------------------------------------------------------------------- closed-form IK
@_jit
def _inverse_apply(T, x, y, z):
    """invert_transform(T) @ (x, y, z, 1) for a rigid T: Rᵀ p − Rᵀ t."""
    out = np.empty(3)
    for i in range(3):
        out[i] = T[0, i] * x + T[1, i] * y + T[2, i] * z - (T[0, i] * T[0, 3] + T[1, i] * T[1, 3] + T[2, i] * T[2, 3])
    return out


@_jit
def comau_candidates(arm, p, q1_hint, signs):
    """Motion-Lab eqs. (7)–(20) for every base branch and elbow sign: (q (k, 3), exact (k,)).  ``arm``: the
    arm's record; p (3,) the tool point in the world; q1_hint: q1 where the point is on the base axis;
    signs (k,) float64: the elbow signs of eq. (13)."""
    a1, d1, a2, a3, L, T_base = arm
    v = _inverse_apply(T_base, p[0], p[1], p[2])
    x, y, z = v[0], v[1], v[2]
    q1_front = -math.atan2(y, x) if math.hypot(x, y) > 1e-9 else q1_hint  # eq. (7)
    B = math.hypot(a3, L)  # eq. (8)
    phi = math.atan2(a3, L)  # eq. (19)
    ns = signs.shape[0]
    Q = np.empty((2 * ns, 3))
    exact = np.empty(2 * ns, dtype=np.bool_)
    A1 = np.zeros((4, 4))
    A1[3, 3] = 1.0
    ca, sa = math.cos(math.pi / 2), math.sin(math.pi / 2)
    k = 0
    for branch in range(2):
        q1 = q1_front + math.pi * branch
        ct, st = math.cos(-q1), math.sin(-q1)  # θ1 = −q1 (Table 3)
        A1[0, 0], A1[0, 1], A1[0, 2], A1[0, 3] = ct, -st * ca, st * sa, a1 * ct
        A1[1, 0], A1[1, 1], A1[1, 2], A1[1, 3] = st, ct * ca, -ct * sa, a1 * st
        A1[2, 0], A1[2, 1], A1[2, 2], A1[2, 3] = 0.0, sa, ca, d1
        w = _inverse_apply(A1, x, y, z)  # eq. (9)
        xp, yp = w[0], w[1]
        C = math.hypot(xp, yp)  # eq. (11)
        D = (C**2 - a2**2 - B**2) / (2 * a2 * B)  # eq. (12)
        ex = abs(D) <= 1.0
        D = min(1.0, max(-1.0, D))
        for j in range(ns):
            alpha = math.atan2(signs[j] * math.sqrt(1.0 - D**2), D)  # eqs. (13)–(15)
            theta_a = math.atan2(yp, xp)  # eq. (16)
            theta_b = math.atan2(B * math.sin(alpha), a2 + B * math.cos(alpha))  # eq. (17)
            q2 = math.pi / 2 - (theta_a - theta_b)  # eq. (18)
            Q[k, 0], Q[k, 1], Q[k, 2] = q1, q2, alpha - phi - q2  # eq. (20)
            exact[k] = ex
            k += 1
    return Q, exact


@_jit
def crane_candidates(crane, p, beta0_hint, signs):
    """TAC paper eqs. (42)–(44) for both slew branches and every elbow sign: (q (k, 3), exact (k,)).  ``crane``:
    the crane's record; p (3,) the tool point in the world; beta0_hint: β0 where the point is on the slew
    axis; signs (k,) float64: the elbow signs of eq. (43)."""
    L0, L1, L2, T_world_1 = crane
    v = _inverse_apply(T_world_1, p[0], p[1], p[2])  # eq. (42)
    x, y, z = v[0], v[1], v[2]
    r = math.hypot(x, y)
    beta0_front = math.atan2(y, x) if r > 1e-9 else beta0_hint  # eq. (43)
    delta = (x**2 + y**2 + (z - L0) ** 2 - L1**2 - L2**2) / (2 * L1 * L2)  # eq. (44)
    ex = abs(delta) <= 1.0
    delta = min(1.0, max(-1.0, delta))
    ns = signs.shape[0]
    Q = np.empty((2 * ns, 3))
    exact = np.empty(2 * ns, dtype=np.bool_)
    k = 0
    for branch in range(2):
        beta0 = beta0_front + math.pi * branch
        radial = r if branch == 0 else -r
        for j in range(ns):
            beta2 = math.atan2(signs[j] * math.sqrt(1.0 - delta**2), delta)
            beta1 = math.atan2(z - L0, radial) - math.atan2(L2 * math.sin(beta2), L1 + L2 * math.cos(beta2))
            Q[k, 0], Q[k, 1], Q[k, 2] = beta0, beta1, beta2
            exact[k] = ex
            k += 1
    return Q, exact


@_jit
def select_candidate(robot, limits, Q, exact, ref, x_t):
    """The analytic solver's choice among candidates Q (k, n) with their flags exact (k,) for the tool
    point x_t (``AnalyticSolver._search``): revolute joints wrapped into their limits, then valid first, the
    smaller error (to 1e-9 m), the nearest to ref (n,).  ``robot``: the chain record; ``limits``: the
    solver's (lower, upper, revolute).  Returns (q clipped, tool point, error, exact, inside)."""
    lo, hi, revolute = limits
    best_q = np.zeros(Q.shape[1])
    best_p = np.zeros(3)
    best = (2, np.inf, np.inf)
    best_err, best_exact, best_inside = np.inf, False, False
    two_pi = 2 * np.pi
    for k in range(Q.shape[0]):
        q = Q[k].copy()
        for i in range(q.shape[0]):
            if revolute[i] and not (lo[i] <= q[i] <= hi[i]):
                cand = q[i] + two_pi * np.ceil((lo[i] - q[i]) / two_pi)
                if cand <= hi[i]:
                    q[i] = cand
        inside = True
        for i in range(q.shape[0]):
            if q[i] < lo[i] - 1e-9 or q[i] > hi[i] + 1e-9:
                inside = False
        q_c = np.minimum(np.maximum(q, lo), hi)
        p = position(robot, q_c)
        d = p - x_t
        err = math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        dq = q_c - ref
        key = (0 if (exact[k] and inside) else 1, round(err, 9), math.sqrt(np.sum(dq * dq)))
        if key < best:
            best = key
            best_q, best_p, best_err, best_exact, best_inside = q_c, p, err, exact[k], inside
    return best_q, best_p, best_err, best_exact, best_inside


def warm_up_steps() -> list:
    """Zero-argument calls that compile (or load) every kernel of this file with the argument types its
    callers pass (for :func:`app.warmup.warm_up`)."""
    L, n = 3, 3
    z3, zLn = np.zeros(L), np.zeros((L, n))
    eye = np.eye(4)
    dh = np.stack((z3, z3, np.ones(L), np.ones(L), z3))
    robot = (dh, np.stack((np.eye(L, n), zLn)), np.stack((eye, eye)))  # a chain's record
    settings = (-np.ones(n), np.ones(n), np.ones(n), 0.1, 0.01, 0.1, 0.05, 1e-4, 2)  # a DLS solver's record
    limits = (-np.ones(n), np.ones(n), np.ones(n, dtype=np.bool_))  # the analytic solver's record
    arm = (0.1, 0.5, 1.0, 0.2, 1.0, eye)  # a Comau arm's record
    crane = (0.5, 1.0, 1.0, eye)  # an elbow crane's record
    steps = [
        lambda: frames(robot, np.zeros(n)),
        lambda: jacobian_from_frames(frames(robot, np.zeros(n)), np.eye(L, n), zLn),
        lambda: positions(robot, np.zeros((2, n))),
        lambda: position(robot, np.zeros(n)),
        lambda: descend(robot, settings, np.zeros(n), np.ones(3)),
        lambda: descend_to(robot, settings, np.zeros(n), np.ones(3)),
        lambda: damped_step(np.ones((3, n)), np.ones(3), np.zeros(n), settings, False),
        lambda: select_candidate(
            robot,
            limits,
            comau_candidates(arm, np.ones(3), 0.0, np.ones(2))[0],
            crane_candidates(crane, np.ones(3), 0.0, np.ones(2))[1],
            np.zeros(n),
            np.ones(3),
        ),
    ]
    return steps
