"""Motion RAOs of a monohull computed with a boundary-element solver (issue 17, item 1).

Linear potential flow with Capytaine (Ancellin & Dias 2019, JOSS 4(36) 1341; the optional extra
``marine``) on the hull of :mod:`app.marine.hull`, deep water, zero speed.  Per frequency ω the solver
gives the added mass A(ω), the radiation damping B(ω) and the excitation force F(ω, β) (Froude–Krylov +
diffraction); the motion RAO is the solution of the linear equations of motion (Capytaine's e^{−iωt}
convention, rotations about the centre of gravity G):

    [ −ω² (M + A(ω)) − iω (B(ω) + B_v) + C ] X(ω, β) = F(ω, β)

M is the rigid-body inertia from the mass and the radii of gyration (diagonal at G), C the hydrostatic
restoring from the stated metacentric heights (C33 = ρg A_WP, C44 = ρg∇ GM_T, C55 = ρg∇ GM_L: the
loading condition's, not the hull's own), and B_v a viscous roll damping: potential flow gives almost no
roll damping (the hull makes few waves rolling), so — as the MSS toolbox's ship models do (Fossen's
``osv.m``, offshore supply vessel: relative damping ratio in roll ``zeta4 = 0.15``, linear damping of
Fossen 2021 §6) — the total roll damping at the roll natural frequency ω₄ is set to ζ₄₄ = 0.15 of critical,

    B_v,44 = max(0, 2 ζ₄₄ √((M44 + A44(ω₄)) C44) − B44(ω₄)),    ω₄² = C44 / (M44 + A44(ω₄)),

a constant added at every frequency (the "extra roll damping to a target percentage of critical" of
OrcaWave's roll-damping results).  Nothing else is added.

Or (``viscous="ikeda"``, issue 31 item 6) B_v,44 is Ikeda's friction, eddy-making, lift and bilge-keel
components (:mod:`app.marine.roll_damping`) for this hull (its C_B, its section coefficient C_M = C_B/C_WP, OG =
−z_G) and its bilge keels, at the roll natural frequency ω₄ and the roll the vessel makes in a stated sea
(``linearise_sea``: Hs, Tp, heading of a long-crested JONSWAP sea): the amplitude φ_eq = √(9π/8) σ_φ̇ / ω₄ of the
stochastic linearisation, σ_φ̇ from the roll response with that damping, iterated to a fixed point on a fine
frequency grid (the hydrodynamic coefficients interpolated between the solved frequencies); one value at every
frequency, as the stochastic linearisation's B1 + √(8/π) σ_φ̇ B2 is (no ω in it; a fixed amplitude at every
frequency would make the quadratic parts grow with ω).  Not settling in 100 iterations is an error.

The RAOs are then moved to Bosun's vessel frame: the origin O at midship on the waterline (translations
ξ_O = ξ_G + Ω × (O − G)), x forward, y starboard, z down (Capytaine's y to port and z up: sway, heave,
pitch and yaw change sign), the e^{+iωt} convention of :mod:`app.marine.vessel` (complex conjugate), and
headings β measured as there (the direction the waves travel, from x toward starboard; Capytaine's
direction is −β).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field

import numpy as np
from numpy.typing import NDArray

from app.errors import BosunError
from app.marine.hull import HullForm, hull_panels
from app.marine.vessel import RAOTable, VesselParticulars
from app.marine.waves import G

RHO = 1025.0  # sea water [kg/m³]
#: Bounds of a computation (issue 27, item 6: ``--nx 100000`` ran without bound), checked before any work.
#: The mesh: Capytaine's influence matrices are dense, two complex N/2 × N/2 blocks each for the mirrored
#: hull, so memory grows with the panels squared (≈ 64 B × (nx·nz)²: 0.26 GB at the 2 000 panels a side
#: allowed, 6 MB at the default 40 × 8); frequencies within the RAO bounds of the table it makes
#: (``app.marine.vessel.RAO_W_RANGE``); at most 200 of them and 360 headings (one diffraction problem
#: each); water 990–1050 kg/m³ (fresh to the saltiest sea water).  The particulars have their physical
#: ranges in ``app.marine.vessel.PARTICULAR_RANGES``.
NX_RANGE = (4, 200)
NZ_RANGE = (2, 50)
MAX_PANELS_A_SIDE = 2000
MAX_FREQUENCIES = 200
MIN_HEADING_STEP = 1.0  # deg
RHO_RANGE = (990.0, 1050.0)
#: the total roll damping ratio at the roll natural frequency: the MSS toolbox's offshore supply vessel
#: model (Fossen, ``osv.m``: ``vessel.zeta4 = 0.15``, relative damping ratio in roll)
ROLL_DAMPING_DEFAULT = 0.15
VISCOUS = ("zeta", "ikeda")
#: bilge keels for Ikeda's method when none are given (assumed: the paper gives the supply vessel none): length 0.2
#: Lpp and breadth 0.025 B, the proportions of the base ship of Kawahara, Maekawa & Ikeda (2011), whose formulas these
#: are — 16.56 m × 0.48 m on the 82.8 m × 19.2 m supply vessel; chosen before any roll was computed with them
BILGE_KEELS_PROPORTIONS = (0.2, 0.025)
#: the sea the Ikeda damping is linearised in: the TAC paper's test sea (Hs 3 m, Tp 9 s, beam)
LINEARISE_SEA_DEFAULT = (3.0, 9.0, 90.0)
#: Capytaine's frame (y port, z up) to Bosun's (y starboard, z down): a half turn about x
FRAME_SIGN = np.array([1.0, -1.0, -1.0, 1.0, -1.0, -1.0])
DOFS = ("Surge", "Sway", "Heave", "Roll", "Pitch", "Yaw")


class BemError(BosunError):
    """The boundary-element computation cannot be made (one line)."""


def capytaine():
    """The Capytaine module, or a one-line error naming the extra that installs it."""
    try:
        import capytaine as cpt
    except ImportError:
        raise BemError("the boundary-element RAO solver needs Capytaine: pip install 'bosun[marine]'") from None
    return cpt


@dataclass(frozen=True)
class BemInputs:
    """What :func:`compute_raos` computes from; written beside its output so the table can be made again."""

    vessel: VesselParticulars = field(default_factory=VesselParticulars)
    cwp: float | None = None  # waterplane coefficient of the hull form; None: from GM_L − GM_T (app/marine/hull.py)
    roll_damping: float = ROLL_DAMPING_DEFAULT  # ζ44 at the roll natural frequency (viscous "zeta")
    viscous: str = "zeta"  # "zeta": B_v to ζ44 of critical; "ikeda": Ikeda's components (module text)
    #: (length, breadth) [m] for "ikeda"; None: BILGE_KEELS_PROPORTIONS of the vessel; () a naked hull
    bilge_keels: tuple[float, ...] | None = None
    linearise_sea: tuple[float, float, float] = LINEARISE_SEA_DEFAULT  # (Hs [m], Tp [s], heading [deg])
    nx: int = 40  # panels along the half hull
    nz: int = 8  # panels down its girth
    w_min: float = 0.1  # [rad/s]
    w_max: float = 2.0
    n_w: int = 40
    heading_step: float = 10.0  # [deg]: 0, step, … < 360
    rho: float = RHO

    def __post_init__(self) -> None:
        from app.marine.vessel import RAO_W_RANGE

        for name, (lo, hi) in (("nx", NX_RANGE), ("nz", NZ_RANGE)):
            v = getattr(self, name)
            if not (isinstance(v, int) and lo <= v <= hi):
                raise BemError(f"mesh: {name} must be a whole number from {lo} to {hi}, got {v}")
        if self.nx * self.nz > MAX_PANELS_A_SIDE:
            raise BemError(
                f"mesh: {self.nx} × {self.nz} = {self.nx * self.nz} panels a side, more than {MAX_PANELS_A_SIDE} "
                "(the solver's dense matrices grow with the panels squared)"
            )
        lo, hi = RAO_W_RANGE
        if not (math.isfinite(self.w_min) and math.isfinite(self.w_max) and lo <= self.w_min < self.w_max <= hi):
            raise BemError(
                f"frequencies: need {lo:g} ≤ w_min < w_max ≤ {hi:g} rad/s, got {self.w_min:g} and {self.w_max:g}"
            )
        if not (isinstance(self.n_w, int) and 2 <= self.n_w <= MAX_FREQUENCIES):
            raise BemError(f"frequencies: n_w must be from 2 to {MAX_FREQUENCIES}, got {self.n_w}")
        if not (MIN_HEADING_STEP <= self.heading_step <= 180.0 and (360.0 / self.heading_step).is_integer()):
            raise BemError(
                f"heading step must divide 360° and be {MIN_HEADING_STEP:g}° to 180°, got {self.heading_step:g}"
            )
        if self.viscous not in VISCOUS:
            raise BemError(f"viscous roll damping must be one of {', '.join(VISCOUS)}, got {self.viscous!r}")
        if self.viscous == "ikeda":
            from app.marine.waves import SeaStateError, check_sea

            hs, tp, heading = self.linearise_sea
            try:
                check_sea(hs, tp)
            except SeaStateError as err:
                raise BemError(f"the Ikeda damping's sea: {err}") from None
            if not math.isfinite(heading):
                raise BemError("the Ikeda damping's sea: the heading must be a number")
            from app.marine.roll_damping import RollDampingError

            try:
                self.ikeda_hull(cm=0.95, og=0.0)  # the keels against the hull, before any solve
            except RollDampingError as err:
                raise BemError(str(err)) from None
        if not (0.0 < self.roll_damping < 1.0):
            raise BemError(f"roll damping ratio must be in (0, 1), got {self.roll_damping:g}")
        if self.cwp is not None and not (math.isfinite(self.cwp) and 0.0 < self.cwp < 1.0):
            raise BemError(f"waterplane coefficient must be in (0, 1), got {self.cwp:g}")
        if not RHO_RANGE[0] <= self.rho <= RHO_RANGE[1]:
            raise BemError(f"water density must be {RHO_RANGE[0]:g} to {RHO_RANGE[1]:g} kg/m³, got {self.rho:g}")

    def keels(self):
        """The bilge keels Ikeda's method is given (module text): the stated ones, the default proportions, or none."""
        from app.marine.roll_damping import BilgeKeels

        v = self.vessel
        if self.bilge_keels is None:
            return BilgeKeels(BILGE_KEELS_PROPORTIONS[0] * v.lpp, BILGE_KEELS_PROPORTIONS[1] * v.beam)
        return BilgeKeels(*self.bilge_keels) if self.bilge_keels else None

    def ikeda_hull(self, cm: float, og: float):
        """This vessel as Ikeda's method reads it, with the hull's C_M and OG (down positive)."""
        from app.marine.roll_damping import IkedaHull

        v = self.vessel
        return IkedaHull(v.lpp, v.beam, v.draft, v.cb, cm, og, self.keels())

    @property
    def omegas(self) -> NDArray[np.float64]:
        return np.linspace(self.w_min, self.w_max, self.n_w)

    @property
    def headings_deg(self) -> NDArray[np.float64]:
        return np.arange(0.0, 360.0, self.heading_step)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["vessel"] = {k: v for k, v in asdict(self.vessel).items()}
        return d


@dataclass
class BemResult:
    """The table and what it took: hydrostatics, the roll damping added, panels, wall time."""

    table: RAOTable
    info: dict


def _inertia(v: VesselParticulars) -> NDArray[np.float64]:
    m = v.mass
    return np.diag([m, m, m, m * v.r44**2, m * v.r55**2, m * v.r66**2])


def _stiffness(v: VesselParticulars, form: HullForm, rho: float) -> NDArray[np.float64]:
    C = np.zeros((6, 6))
    nabla = v.mass / rho
    C[2, 2] = rho * G * form.waterplane_area
    C[3, 3] = rho * G * nabla * v.gm_t
    C[4, 4] = rho * G * nabla * v.gm_l
    return C


def centre_of_gravity_z(v: VesselParticulars, form: HullForm) -> float:
    """z_G (z up, waterline 0) from the hull's buoyancy and the stated GM_T: z_G = z_B + BM_T − GM_T."""
    x = np.linspace(-0.5 * form.lpp, 0.5 * form.lpp, 2001)
    z = np.linspace(-form.draft, 0.0, 801)
    X, Z = np.meshgrid(x, z, indexing="ij")
    area = 2.0 * form.half_breadth(X, Z)  # breadth at (x, z)
    vol = np.trapezoid(np.trapezoid(area, z, axis=1), x)
    z_b = np.trapezoid(np.trapezoid(area * Z, z, axis=1), x) / vol
    b0 = form.half_breadth(x, np.zeros_like(x))
    i_t = np.trapezoid(2.0 * b0**3 / 3.0, x)
    return float(z_b + i_t / vol - v.gm_t)


def _natural_frequency(m: float, c: float, omegas: NDArray, added: NDArray) -> float:
    """ω with ω² = c / (m + a(ω)), a(ω) interpolated in the computed added mass (fixed point from √(c/m))."""
    w = math.sqrt(c / m)
    for _ in range(100):
        w_new = math.sqrt(c / max(m + float(np.interp(w, omegas, added)), 1e-9 * m))
        if abs(w_new - w) < 1e-10:
            break
        w = 0.5 * (w + w_new)
    return w


def compute_raos(inputs: BemInputs | None = None, progress: Callable[[int, int], None] | None = None) -> BemResult:
    """Solve the radiation and diffraction problems and return Bosun's RAO table (see the module)."""
    inp = inputs or BemInputs()
    v = inp.vessel
    t0 = time.perf_counter()
    if inp.cwp is None:
        form = HullForm.from_particulars(v.lpp, v.beam, v.draft, v.cb, v.gm_t, v.gm_l)
    else:
        form = HullForm(v.lpp, v.beam, v.draft, v.cb, inp.cwp)
    verts, faces = hull_panels(form, inp.nx, inp.nz)
    cpt = capytaine()  # after the particulars are checked: a bad hull is said also without the solver
    cpt.set_logging("ERROR")  # its mesh-resolution warnings are the user's choice of panels (info: panels)
    half = cpt.Mesh(verts, faces, name="half hull")
    mesh = cpt.ReflectionSymmetricMesh(half, plane="xOz", name="hull")
    lid = mesh.generate_lid(z=-0.01 * v.draft)  # removes the irregular frequencies of the interior
    z_g = centre_of_gravity_z(v, form)
    cog = np.array([0.0, 0.0, z_g])
    body = cpt.FloatingBody(
        mesh=mesh, lid_mesh=lid, dofs=cpt.rigid_body_dofs(rotation_center=cog), center_of_mass=cog, mass=v.mass,
        name="hull",
    )  # fmt: skip
    solver = cpt.BEMSolver()
    omegas, heads = inp.omegas, inp.headings_deg
    dirs = np.mod(-np.radians(heads), 2 * np.pi)  # Capytaine's wave direction of Bosun's heading
    nw, nh = omegas.size, heads.size
    A, B = np.zeros((nw, 6, 6)), np.zeros((nw, 6, 6))
    F = np.zeros((nw, nh, 6), dtype=complex)
    for i, w in enumerate(omegas):  # one frequency: one influence matrix for the 6 + nh problems
        rad = [cpt.RadiationProblem(body=body, radiating_dof=d, omega=w, rho=inp.rho, g=G) for d in DOFS]
        dif = [cpt.DiffractionProblem(body=body, wave_direction=b, omega=w, rho=inp.rho, g=G) for b in dirs]
        results = solver.solve_all(rad + dif, progress_bar=False)
        for j, res in enumerate(results[:6]):
            A[i, :, j] = [res.added_mass[d] for d in DOFS]
            B[i, :, j] = [res.radiation_damping[d] for d in DOFS]
        for j, (pb, res) in enumerate(zip(dif, results[6:], strict=True)):
            fk = cpt.bem.airy_waves.froude_krylov_force(pb)
            F[i, j, :] = [res.forces[d] + fk[d] for d in DOFS]
        if progress is not None:
            progress(i + 1, nw)
    M = _inertia(v)
    C = _stiffness(v, form, inp.rho)
    # roll natural frequency with the frequency-dependent added inertia, then the damping to ζ44 there
    w4 = _natural_frequency(M[3, 3], C[3, 3], omegas, A[:, 3, 3])
    A44, B44 = float(np.interp(w4, omegas, A[:, 3, 3])), float(np.interp(w4, omegas, B[:, 3, 3]))
    crit = 2.0 * math.sqrt((M[3, 3] + A44) * C[3, 3])
    ikeda: dict = {}
    if inp.viscous == "ikeda":
        b_v, ikeda = _ikeda_damping(inp, form, z_g, omegas, heads, A, B, F, M, C, w4)
        b_visc = float(np.interp(w4, omegas, b_v))
    else:
        b_visc = max(0.0, inp.roll_damping * crit - B44)
        b_v = np.full(nw, b_visc)
    X = np.zeros((6, nw, nh), dtype=complex)
    for i, w in enumerate(omegas):
        Bv = np.zeros((6, 6))
        Bv[3, 3] = b_v[i]
        Z = -(w**2) * (M + A[i]) - 1j * w * (B[i] + Bv) + C
        X[:, i, :] = np.linalg.solve(Z, F[i].T)
    # translations of O (midship, waterline) = those of G + Ω × (O − G), O − G = (0, 0, −z_G)
    X[0] = X[0] - z_g * X[4]
    X[1] = X[1] + z_g * X[3]
    H = FRAME_SIGN[:, None, None] * np.conj(X)
    src = (
        f"Capytaine {cpt.__version__} BEM, {v.name}: Lpp {v.lpp:g} m, B {v.beam:g} m, T {v.draft:g} m, "
        f"C_B {v.cb:g}, C_WP {form.cwp:.4g}, GM_T {v.gm_t:g} m, GM_L {v.gm_l:g} m, "
        + (f"zeta44 {inp.roll_damping:g}" if inp.viscous == "zeta" else "Ikeda roll damping")
    )
    table = RAOTable(omegas, np.radians(heads), np.abs(H), np.angle(H), source=src)
    info = {
        "capytaine": cpt.__version__,
        "panels": int(mesh.nb_faces),
        "lid_panels": int(lid.nb_faces),
        "z_g_m": z_g,
        "displacement_m3": form.volume,
        "waterplane_area_m2": form.waterplane_area,
        "hull_exponents": {"p": form.p, "q": form.q},
        "waterplane_coefficient": form.cwp,
        "midship_section_coefficient": form.cb / form.cwp,
        "roll_natural_frequency_rad_s": w4,
        "roll_added_inertia_kgm2": A44,
        "roll_radiation_damping": B44,
        "roll_viscous_damping": b_visc,
        "roll_critical_damping": crit,
        "roll_viscous_damping_ratio": b_visc / crit,
        **({"ikeda": ikeda} if ikeda else {}),
        "roll_radiation_damping_ratio": B44 / crit,
        "heave_natural_frequency_rad_s": _natural_frequency(M[2, 2], C[2, 2], omegas, A[:, 2, 2]),
        "pitch_natural_frequency_rad_s": _natural_frequency(M[4, 4], C[4, 4], omegas, A[:, 4, 4]),
        "wall_s": time.perf_counter() - t0,
    }
    return BemResult(table, info)


def _ikeda_damping(inp, form, z_g, omegas, heads, A, B, F, M, C, w4) -> tuple[NDArray[np.float64], dict]:
    """B_v,44 at each solved frequency by Ikeda's components, linearised in ``inp.linearise_sea`` (module text),
    and what it took: the amplitude, the components at ω₄, the iterations, the parameters outside the method's
    range."""
    from app.marine.roll_damping import components, out_of_range
    from app.marine.waves import jonswap

    hull = inp.ikeda_hull(form.cb / form.cwp, -z_g)
    hs, tp, heading = inp.linearise_sea
    j = int(np.argmin(np.abs((heads - heading + 180.0) % 360.0 - 180.0)))  # the solved heading nearest the sea's
    fine = np.linspace(omegas[0], omegas[-1], 4000)
    spec = jonswap(fine, hs, tp)
    # the hydrodynamic coefficients between the solved frequencies (smooth in ω), for the roll peak's width
    A_f = np.stack([np.interp(fine, omegas, A[:, r, c]) for r in range(6) for c in range(6)], axis=1).reshape(-1, 6, 6)
    B_f = np.stack([np.interp(fine, omegas, B[:, r, c]) for r in range(6) for c in range(6)], axis=1).reshape(-1, 6, 6)
    F_f = np.stack([np.interp(fine, omegas, F[:, j, r].real) + 1j * np.interp(fine, omegas, F[:, j, r].imag)
                    for r in range(6)], axis=1)  # fmt: skip

    def damping(phi: float) -> float:
        """The components at ω₄ and the amplitude φ: the stochastic linearisation's equivalent is one number for
        every frequency (B_eq = B1 + √(8/π) σ_φ̇ B2: no ω in it), exact where the damping matters, at the peak."""
        c = components(hull, w4, phi, inp.rho, G)
        return c["friction"] + c["eddy"] + c["lift"] + c["bilge_keels"]

    phi, steps, converged = math.radians(5.0), 0, False
    while steps < 100:
        steps += 1
        b_fine = np.full(fine.size, damping(phi))
        Z = -(fine**2)[:, None, None] * (M + A_f) - 1j * fine[:, None, None] * (B_f + _roll(b_fine)) + C
        roll = np.linalg.solve(Z, F_f[..., None])[:, 3, 0]
        sigma_rate = math.sqrt(float(np.trapezoid(fine**2 * np.abs(roll) ** 2 * spec, fine)))
        new = math.sqrt(9.0 * math.pi / 8.0) * sigma_rate / w4
        if abs(new - phi) < 1e-6 * max(phi, 1e-6):
            phi, converged = new, True
            break
        phi = 0.5 * (phi + new)
    if not converged:
        raise BemError(f"Ikeda's roll damping did not settle in {steps} iterations (the roll amplitude {phi:.3g} rad)")
    at_w4 = components(hull, w4, phi, inp.rho, G)
    info = {
        "bilge_keels_m": None if hull.keels is None else [hull.keels.length, hull.keels.breadth],
        "linearise_sea": {"hs": hs, "tp": tp, "heading": float(heads[j]), "spectrum": "jonswap"},
        "roll_amplitude_deg": math.degrees(phi), "iterations": steps,
        "midship_section_coefficient": hull.cm, "og_m": hull.og,
        "at_roll_natural_frequency": {k: at_w4[k] for k in ("friction", "eddy", "lift", "bilge_keels")},
        "outside_the_method_s_range": out_of_range(hull, w4),
    }  # fmt: skip
    return np.full(omegas.size, damping(phi)), info


def _roll(b: NDArray[np.float64]) -> NDArray[np.float64]:
    """(n, 6, 6) with ``b`` in the roll-roll place."""
    out = np.zeros((b.size, 6, 6))
    out[:, 3, 3] = b
    return out
