"""Linear wave-induced vessel motion from motion RAOs, and an MRU/IMU model.

Conventions (Fossen 2011; TAC paper Table 2, eq. 35):

* η = [x, y, z, φ, θ, ψ] in {n} (NED, z down), ν = [u, v, w, p, q, r] in {b} (x forward,
  y starboard, z down).  R_b^n = Rz(ψ) Ry(θ) Rx(φ).
* Wave heading β (as in the MSS toolbox): the direction the waves travel, measured from x_b
  towards y_b: 0 = following sea, 90° = beam sea travelling to starboard, 180° = head sea.
* A motion RAO H_j(ω, β) is complex: amplitude [m/m for surge–heave, rad/m for roll–yaw] and
  phase [rad] against the wave elevation at the body origin, so that for a sea of regular
  components ζ(t) = Σ a_k cos(ω_k t + ε_k)

      η_j(t) = Σ a_k |H_j(ω_k, β_k)| cos(ω_k t + ε_k + ∠H_j(ω_k, β_k))        (zero speed).

Two RAO sources:

* :func:`parametric_rao` — a closed-form model from the main particulars: heave and pitch
  from Jensen, Mansour & Olsen (2004), "Estimation of ship motions using closed-form
  expressions", Ocean Eng. 31, 61–85 (zero speed: α = 1, B → C_B·B), with one addition: for
  oblique waves the heave and pitch forces are averaged over the waterline breadth,
  sinc(k |sin β| B / 2) (JMO treat the wave as uniform across the section).  Roll is a damped
  one-degree-of-freedom oscillator driven by the wave slope, ω_n = √(g GM_T) / (r44 √(1 + a44)),
  excitation reduced by exp(−kT/2) and the breadth average, with an
  equivalent linear damping ratio ζ44.  Surge, sway and yaw are not modelled by the closed
  form and are zero.  The defaults are the MSS supply vessel of the
  TAC paper (§9): Lpp 82.8 m, B 19.2 m, T 6.0 m, C_B 0.651, GM_T 2.144 m, GM_L 103.6 m,
  r44/r55/r66 6.84/20.7/20.7 m, m 6.36e6 kg.
* :func:`load_rao` — the MSS vessel ``.mat`` format (``vessel.motionRAO.amp/phase`` cells of
  (frequency × heading × speed) arrays, ``.w``, ``vessel.headings``; speed index 0) or the
  CSV format documented in :func:`load_rao_csv` (ShipX/VERES/WAMIT results, one row per
  frequency and heading).
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from app.csvtext import cells, content_lines, finite_number
from app.errors import BosunError
from app.geometry import euler_zyx_to_matrix
from app.marine import kernels
from app.marine.waves import G, WaveComponents

DOF_NAMES = ("surge", "sway", "heave", "roll", "pitch", "yaw")
CSV_COLUMNS = ("w", "heading_deg") + tuple(f"{d}_{part}" for d in DOF_NAMES for part in ("amp", "phase"))

#: Physical bounds of an RAO table (issue 27, item 8), checked by every loader (CSV file, the protocol's
#: ``set_vessel`` upload, MSS ``.mat``) before a table is used: a heave RAO of 1e300 m/m made the crane-head
#: state infinite.  Frequencies: 0.01–20 rad/s, periods 0.31 s to 10.5 min, around the ocean's gravity and
#: infragravity waves (periods 1 s to 5 min: Munk 1950, "Origin and generation of waves", Proc. 1st Conf.
#: Coastal Eng., Fig. 1, the ocean-wave spectrum).  Amplitudes: a linear RAO is the hull's long-wave response
#: (1 m/m in heave; the wave slope ω²/g, at most 0.1 rad/m below the 1 rad/s under which hull roll and pitch
#: resonances lie) times the dynamic amplification 1/(2ζ), at most 100 for a resonance damped at ζ = 0.5 %
#: of critical (potential-flow roll damping alone: 0.63 % for the shipped supply vessel's table, its header's
#: ``roll_radiation_damping_ratio``): translations ≤ 100 m/m, rotations ≤ 10 rad/m.  Phases within ±1000 rad
#: (float64 keeps cos φ to 1e-13 there; an unwrapped phase k·x is ≤ 20 rad at 2 rad/s 50 m from the origin);
#: headings within ±720°.
RAO_W_RANGE = (0.01, 20.0)  # rad/s
RAO_AMP_MAX = (100.0, 100.0, 100.0, 10.0, 10.0, 10.0)  # m/m (surge, sway, heave), rad/m (roll, pitch, yaw)
RAO_PHASE_MAX = 1000.0  # rad
RAO_HEADING_MAX = 720.0  # deg
#: an RAO file's size, checked before it is read (the shipped 40 × 36 table is 0.3 MB; an upload is ≤ 4 MiB)
MAX_RAO_BYTES = 10_000_000


class VesselError(BosunError):
    """Bad vessel particulars or RAO data (names the file, line and field when it can)."""


# ----------------------------------------------------------------------------- RAO table
@dataclass(frozen=True, eq=False)
class RAOTable:
    """Motion RAOs on a frequency × heading grid.

    Attributes
    ----------
    w : ndarray (nw,)   wave frequencies [rad/s], strictly increasing
    headings : ndarray (nh,)   wave headings β [rad], strictly increasing within [0, 2π)
    amp : ndarray (6, nw, nh)   |H_j| [m/m or rad/m]
    phase : ndarray (6, nw, nh)   ∠H_j [rad]
    source : str   where the table came from
    """

    w: NDArray[np.float64]
    headings: NDArray[np.float64]
    amp: NDArray[np.float64]
    phase: NDArray[np.float64]
    source: str = "table"
    _complex: NDArray[np.complex128] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        w = np.asarray(self.w, dtype=float)
        h = np.asarray(self.headings, dtype=float)
        amp = np.asarray(self.amp, dtype=float)
        phase = np.asarray(self.phase, dtype=float)
        where = self.source
        if w.ndim != 1 or w.size < 2 or np.any(np.diff(w) <= 0) or w[0] <= 0:
            raise VesselError(f"{where}: frequencies must be positive and strictly increasing (got {w.size})")
        if h.ndim != 1 or h.size < 1 or np.any(np.diff(h) <= 0) or h[0] < 0 or h[-1] >= 2 * np.pi + 1e-9:
            raise VesselError(f"{where}: headings must be strictly increasing within [0°, 360°)")
        shape = (6, w.size, h.size)
        for name, arr in (("amp", amp), ("phase", phase)):
            if arr.shape != shape:
                raise VesselError(f"{where}: RAO {name} has shape {arr.shape}, expected {shape}")
            if not np.all(np.isfinite(arr)):
                raise VesselError(f"{where}: RAO {name} has NaN or infinite values")
        if np.any(amp < 0):
            raise VesselError(f"{where}: RAO amplitudes must not be negative")
        lo, hi = RAO_W_RANGE
        if w[0] < lo or w[-1] > hi:
            bad = w[0] if w[0] < lo else w[-1]
            raise VesselError(
                f"{where}: frequency {bad:.6g} rad/s is outside {lo:g} … {hi:g} rad/s (RAO bounds, README)"
            )
        for d, top in enumerate(RAO_AMP_MAX):
            if amp[d].size and amp[d].max() > top:
                i, j = np.unravel_index(int(np.argmax(amp[d])), amp[d].shape)
                unit = "m/m" if d < 3 else "rad/m"
                raise VesselError(
                    f"{where}: {DOF_NAMES[d]} amplitude {amp[d, i, j]:.6g} {unit} at w = {w[i]:g} rad/s, heading "
                    f"{math.degrees(h[j]):g}° is above {top:g} {unit} (RAO bounds, README)"
                )
        if np.abs(phase).max(initial=0.0) > RAO_PHASE_MAX:
            raise VesselError(f"{where}: RAO phases must be within ±{RAO_PHASE_MAX:g} rad (RAO bounds, README)")
        for name, arr in (("w", w), ("headings", h), ("amp", amp), ("phase", phase)):
            object.__setattr__(self, name, arr)
        object.__setattr__(self, "_complex", amp * np.exp(1j * phase))

    def __call__(self, w: ArrayLike, beta: ArrayLike) -> NDArray[np.complex128]:
        """Complex RAOs at frequencies ``w`` and headings ``beta`` (same shape, rad/s and rad).

        Bilinear in frequency and (periodic) heading on the complex values, so the table's own
        grid points are reproduced exactly.  Below the first and above the last frequency the
        end values are held.  Returns shape (6, *w.shape).
        """
        w, beta = np.broadcast_arrays(np.asarray(w, dtype=float), np.asarray(beta, dtype=float))
        shape = w.shape
        w, beta = w.ravel(), np.mod(beta.ravel(), 2 * np.pi)
        # frequency: index and weight, clamped at the ends
        wc = np.clip(w, self.w[0], self.w[-1])
        i = np.clip(np.searchsorted(self.w, wc, side="right") - 1, 0, self.w.size - 2)
        fw = (wc - self.w[i]) / (self.w[i + 1] - self.w[i])
        # heading: periodic
        h = self.headings
        if h.size == 1:
            j0 = j1 = np.zeros(w.size, dtype=int)
            fh = np.zeros(w.size)
        else:
            hx = np.append(h, h[0] + 2 * np.pi)
            b = np.where(beta < h[0], beta + 2 * np.pi, beta)
            j0 = np.clip(np.searchsorted(hx, b, side="right") - 1, 0, h.size - 1)
            fh = (b - hx[j0]) / (hx[j0 + 1] - hx[j0])
            j1 = (j0 + 1) % h.size
        c = self._complex
        out = (
            c[:, i, j0] * ((1 - fw) * (1 - fh))
            + c[:, i + 1, j0] * (fw * (1 - fh))
            + c[:, i, j1] * ((1 - fw) * fh)
            + c[:, i + 1, j1] * (fw * fh)
        )
        return out.reshape((6, *shape))


def significant_response(rao, spectrum_values: ArrayLike, w: ArrayLike, heading: float) -> NDArray[np.float64]:
    """Significant (4σ) amplitude of each DOF for a long-crested sea, shape (6,).

    σ_j² = ∫ |H_j(ω, β)|² S(ω) dω (trapezoid over the given ω grid).
    """
    w = np.asarray(w, dtype=float)
    S = np.asarray(spectrum_values, dtype=float)
    H = rao(w, np.full_like(w, heading))
    return 4.0 * np.sqrt(np.trapezoid(np.abs(H) ** 2 * S, w, axis=1))


# ----------------------------------------------------------------------------- parametric model
#: Physical ranges of main particulars (issue 27, item 6: ``--lpp 1e300`` overflowed, ``--mass 1e300`` ran a
#: whole BEM computation into NaN): field -> (lowest, highest, unit).  They bracket every hull afloat, from a
#: 5 m workboat to the largest ship built (Seawise Giant: 458 m, B 68.9 m, T 24.6 m, 657 000 t displacement):
#: C_B from fast craft (0.35) to a box barge (1); GM_L up to a box barge's BM_L = L²/(12 T) at 500 m × 0.2 m.
PARTICULAR_RANGES: dict[str, tuple[float, float, str]] = {
    "lpp": (5.0, 500.0, " m"),
    "beam": (1.0, 100.0, " m"),
    "draft": (0.2, 35.0, " m"),
    "cb": (0.3, 1.0, ""),
    "gm_t": (0.01, 1000.0, " m"),
    "gm_l": (0.1, 1e5, " m"),
    "r44": (0.1, 50.0, " m"),
    "r55": (0.5, 250.0, " m"),
    "r66": (0.5, 250.0, " m"),
    "mass": (1e3, 1e9, " kg"),
}


@dataclass(frozen=True)
class VesselParticulars:
    """Main particulars for :func:`parametric_rao`; defaults: the MSS supply vessel (TAC §9)."""

    lpp: float = 82.8  # length between perpendiculars [m]
    beam: float = 19.2  # [m]
    draft: float = 6.0  # [m]
    cb: float = 0.651  # block coefficient
    gm_t: float = 2.144  # transverse metacentric height [m]
    gm_l: float = 103.6  # longitudinal metacentric height [m]
    r44: float = 6.84  # radii of gyration [m]
    r55: float = 20.7
    r66: float = 20.7
    mass: float = 6.36e6  # [kg]
    roll_damping: float = 0.15  # ζ44, equivalent linear roll damping ratio (assumed, see README)
    roll_added_inertia: float = 0.10  # a44 = A44 / I44 (assumed)
    name: str = "MSS supply vessel (parametric)"

    def __post_init__(self) -> None:
        for f in ("lpp", "beam", "draft", "cb", "gm_t", "gm_l", "r44", "r55", "r66", "mass"):
            v = getattr(self, f)
            if not (math.isfinite(v) and v > 0):
                raise VesselError(f"vessel particulars: {f} must be a positive number, got {v}")
        if not 0 < self.cb <= 1:
            raise VesselError(f"vessel particulars: cb must be in (0, 1], got {self.cb}")
        for f, (lo, hi, unit) in PARTICULAR_RANGES.items():
            v = getattr(self, f)
            if not lo <= v <= hi:
                raise VesselError(
                    f"vessel particulars: {f} {v:.6g}{unit} is outside {lo:g} … {hi:g}{unit} (physical ranges, README)"
                )
        if not (math.isfinite(self.roll_damping) and 0 < self.roll_damping < 1):
            raise VesselError(f"vessel particulars: roll_damping must be in (0, 1), got {self.roll_damping}")
        if not (math.isfinite(self.roll_added_inertia) and self.roll_added_inertia >= 0):
            raise VesselError("vessel particulars: roll_added_inertia must be ≥ 0")

    @property
    def roll_natural_frequency(self) -> float:
        """ω_n44 = √(g GM_T) / (r44 √(1 + a44)) [rad/s]."""
        return math.sqrt(G * self.gm_t) / (self.r44 * math.sqrt(1.0 + self.roll_added_inertia))


def _sinc(x: NDArray[np.float64]) -> NDArray[np.float64]:
    return np.sinc(x / np.pi)  # sin(x)/x with the limit 1 at 0


def parametric_complex_rao(p: VesselParticulars, w: ArrayLike, beta: ArrayLike) -> NDArray[np.complex128]:
    """Complex RAOs of the closed-form model, shape (6, *w.shape); see the module docstring.

    Heave and pitch (Jensen, Mansour & Olsen 2004, eqs. for F, G, η at Fn = 0; B → C_B B):

        k = ω²/g, k_e = k |cos β|, κ = exp(−k_e T), A = 2 sin(k B_e / 2) exp(−k T),
        f = √((1 − kT)² + (A²/(k B_e))²),   η = 1/√((1 − 2kT)² + (A²/(k B_e))²),
        F = κ f sin(k_e L/2) / (k_e L/2),   G = κ f 24/(k_e² L³) [sin(k_e L/2) − (k_e L/2) cos(k_e L/2)],
        |heave| = η F,  |pitch| = η G  (times the breadth average sinc(k |sin β| B/2)).

    Phases (long-wave limit: the hull follows the surface): heave z (down) = −ζ, so ∠ = π;
    pitch θ (bow up) = ∂ζ/∂x, ∠ = −π/2 for waves travelling forward (cos β > 0), +π/2 for
    head seas; roll φ (starboard down) = −∂ζ/∂y, times the oscillator 1/(1 − r² + 2iζ44 r).
    """
    w, beta = np.broadcast_arrays(np.asarray(w, dtype=float), np.asarray(beta, dtype=float))
    if np.any(w <= 0):
        raise VesselError("wave frequencies must be positive")
    L, T, Be = p.lpp, p.draft, p.cb * p.beam
    k = w**2 / G
    cb_, sb_ = np.cos(beta), np.sin(beta)
    ke = k * np.abs(cb_)
    kap = np.exp(-ke * T)
    A = 2.0 * np.sin(0.5 * k * Be) * np.exp(-k * T)
    rad = (A**2) / (k * Be)
    f = np.sqrt((1.0 - k * T) ** 2 + rad**2)
    eta = 1.0 / np.sqrt((1.0 - 2.0 * k * T) ** 2 + rad**2)
    x = 0.5 * ke * L
    F = kap * f * _sinc(x)
    # G: 24/(k_e² L³)(sin x − x cos x) = (3/L) · k_e · [3 (sin x − x cos x)/x³], the bracket → 1 at x → 0
    xs = np.where(x < 1e-4, 1.0, x)
    bracket = np.where(x < 1e-4, 1.0 - x**2 / 10.0, 3.0 * (np.sin(xs) - xs * np.cos(xs)) / xs**3)
    Gp = kap * f * ke * bracket
    breadth = _sinc(0.5 * k * np.abs(sb_) * p.beam)
    heave = eta * F * breadth
    pitch = eta * Gp * breadth
    # roll: damped 1-DOF driven by the wave slope k sin β
    wn = p.roll_natural_frequency
    r = w / wn
    roll_exc = k * sb_ * np.exp(-0.5 * k * T) * _sinc(0.5 * k * np.abs(sb_) * p.beam)
    roll = roll_exc * np.exp(0.5j * np.pi) / (1.0 - r**2 + 2j * p.roll_damping * r)
    out = np.zeros((6, *w.shape), dtype=complex)
    out[2] = heave * np.exp(1j * np.pi)
    out[3] = roll
    out[4] = pitch * np.where(cb_ >= 0, np.exp(-0.5j * np.pi), np.exp(0.5j * np.pi))
    return out


def parametric_rao(
    particulars: VesselParticulars | None = None,
    w: ArrayLike | None = None,
    headings_deg: ArrayLike | None = None,
) -> RAOTable:
    """The closed-form model sampled on a table (default 0.05–3.5 rad/s × 0–350° in 10° steps)."""
    p = particulars or VesselParticulars()
    w = np.linspace(0.05, 3.5, 300) if w is None else np.asarray(w, dtype=float)
    h = np.deg2rad(np.arange(0, 360, 10) if headings_deg is None else np.asarray(headings_deg, dtype=float))
    W, Hd = np.meshgrid(w, h, indexing="ij")
    c = parametric_complex_rao(p, W, Hd)
    return RAOTable(w, h, np.abs(c), np.angle(c), source=p.name)


# ----------------------------------------------------------------------------- loaders
def load_rao(path: str | Path) -> RAOTable:
    """Load motion RAOs from an MSS ``.mat`` vessel file or the CSV format (by extension)."""
    path = Path(path)
    if not path.is_file():
        raise VesselError(f"{path}: no such RAO file")
    suffix = path.suffix.lower()
    if suffix not in (".mat", ".csv"):
        raise VesselError(f"{path}: unknown RAO file type '{suffix}' (use .mat or .csv)")
    try:
        size = path.stat().st_size
    except OSError as err:
        raise VesselError(f"{path}: cannot be read: {err.strerror or err}") from None
    if size > MAX_RAO_BYTES:
        raise VesselError(f"{path}: {size:,} bytes; an RAO file is at most {MAX_RAO_BYTES:,} bytes")
    if suffix == ".mat":
        return load_rao_mat(path)
    try:
        text = path.read_text(encoding="utf-8-sig")  # a spreadsheet's "CSV UTF-8" starts with a byte-order mark
    except UnicodeDecodeError as err:
        raise VesselError(f"{path}: not UTF-8 text (byte {err.start}): save it as CSV UTF-8") from None
    except OSError as err:
        raise VesselError(f"{path}: cannot be read: {err.strerror or err}") from None
    return load_rao_csv(text, str(path))


def load_rao_mat(path: str | Path) -> RAOTable:
    """MSS toolbox vessel structure (Fossen & Perez): ``vessel.motionRAO.{amp,phase,w}``, ``vessel.headings``.

    ``amp`` and ``phase`` are cells of six arrays (frequency × heading × speed); the zero-speed
    slice (index 0) is taken.
    """
    import scipy.io

    path = Path(path)
    try:
        m = scipy.io.loadmat(str(path), squeeze_me=True, struct_as_record=False)
    except Exception as exc:  # scipy raises several types for broken files
        raise VesselError(f"{path}: not a readable MATLAB file ({exc})") from None
    try:
        vessel = m["vessel"]
        rao = vessel.motionRAO
        w = np.asarray(rao.w, dtype=float)
        headings = np.asarray(vessel.headings, dtype=float)
        amp = [np.asarray(a, dtype=float) for a in rao.amp]
        phase = [np.asarray(a, dtype=float) for a in rao.phase]
    except (KeyError, AttributeError, TypeError) as exc:
        raise VesselError(f"{path}: not an MSS vessel file (missing {exc})") from None
    if len(amp) != 6 or len(phase) != 6:
        raise VesselError(f"{path}: motionRAO.amp/phase must hold 6 DOFs, got {len(amp)}/{len(phase)}")

    def zero_speed(a: NDArray[np.float64]) -> NDArray[np.float64]:
        return a[..., 0] if a.ndim == 3 else a.reshape(w.size, headings.size)

    name = getattr(getattr(vessel, "main", None), "name", "vessel")
    return RAOTable(
        w,
        headings,
        np.stack([zero_speed(a) for a in amp]),
        np.stack([zero_speed(a) for a in phase]),
        source=f"{path} ({name})",
    )


PACE_ROWS = 8  # rows :func:`load_rao_csv` parses between two calls of its ``pace``


def _no_pace() -> None:
    pass


def _csv_bounds(column: str) -> tuple[float, float, str]:
    """The RAO bounds of one CSV column: (lowest, highest, unit)."""
    if column == "w":
        return (*RAO_W_RANGE, "rad/s")
    if column == "heading_deg":
        return (-RAO_HEADING_MAX, RAO_HEADING_MAX, "deg")
    dof, part = column.rsplit("_", 1)
    if part == "phase":
        return (-RAO_PHASE_MAX, RAO_PHASE_MAX, "rad")
    d = DOF_NAMES.index(dof)
    return (0.0, RAO_AMP_MAX[d], "m/m" if d < 3 else "rad/m")


def load_rao_csv(text: str, where: str = "<csv>", pace: Callable[[], None] | None = None) -> RAOTable:
    """RAO table from CSV text.

    Format: a header row with the columns ``w, heading_deg, surge_amp, surge_phase, sway_amp,
    sway_phase, heave_amp, heave_phase, roll_amp, roll_phase, pitch_amp, pitch_phase, yaw_amp,
    yaw_phase`` (any order), then one row per (frequency, heading) pair of a full grid.
    Units: w in rad/s, heading in degrees (0 = following, 180 = head sea), amplitudes in m/m
    (surge, sway, heave) and rad/m (roll, pitch, yaw), phases in rad.  Lines starting with
    ``#`` are comments; a leading byte-order mark (Excel's "CSV UTF-8") is skipped.  Every value is checked
    against the RAO bounds (``RAO_W_RANGE``, ``RAO_AMP_MAX``, …: the module's constants) on its line.

    ``pace``: called every :data:`PACE_ROWS` rows (an engine's parse off its control loop waits there for
    the loop's idle time, or raises to stop); no step between two calls holds the interpreter for long,
    also for a table of megabytes (issue 27, item 2).
    """
    if len(text) > MAX_RAO_BYTES:
        raise VesselError(f"{where}: {len(text):,} characters; an RAO table is at most {MAX_RAO_BYTES:,}")
    numbers, lines = content_lines(text, pace)
    if not lines:
        raise VesselError(f"{where}: empty RAO file")
    header_line, header = numbers[0], lines[0]
    cols = [c.strip() for c in cells(header)]
    missing = [c for c in CSV_COLUMNS if c not in cols]
    if missing:
        raise VesselError(f"{where}:{header_line}: missing column(s) {', '.join(missing)}")
    idx = [cols.index(c) for c in CSV_COLUMNS]
    bounds = [_csv_bounds(c) for c in CSV_COLUMNS]
    data = np.empty((len(lines) - 1, len(CSV_COLUMNS)))  # filled a row at a time (np.array of a list: one long call)
    line_of = np.empty(len(lines) - 1, dtype=np.int64)
    for k in range(len(lines) - 1):
        n, line = numbers[k + 1], lines[k + 1]
        if pace is not None and k % PACE_ROWS == 0:
            pace()
        row = cells(line)
        if len(row) != len(cols):
            raise VesselError(f"{where}:{n}: expected {len(cols)} fields, got {len(row)}")
        vals = []
        for c, i, (lo, hi, unit) in zip(CSV_COLUMNS, idx, bounds, strict=True):
            try:
                v = finite_number(row[i])
            except ValueError as err:
                raise VesselError(f"{where}:{n}: field {c}: '{row[i].strip()}' is {err}") from None
            if c.endswith("_amp") and v < 0:
                raise VesselError(f"{where}:{n}: field {c}: amplitude must not be negative")
            if not lo <= v <= hi:
                raise VesselError(
                    f"{where}:{n}: field {c}: {row[i].strip()} {unit} is outside {lo:g} … {hi:g} {unit} "
                    "(RAO bounds, README)"
                )
            vals.append(v)
        data[k] = vals
        line_of[k] = n
    if not data.shape[0]:
        raise VesselError(f"{where}: no data rows")
    step = pace if pace is not None else _no_pace  # also between the whole-table steps below (each a few ms)
    w = np.unique(data[:, 0])
    step()
    hd = np.unique(np.mod(data[:, 1], 360.0))
    rows = data.shape[0]
    if w.size * hd.size != rows:
        raise VesselError(
            f"{where}: rows do not form a full grid ({rows} rows for {w.size} frequencies × {hd.size} headings)"
        )
    step()
    i = np.searchsorted(w, data[:, 0])
    j = np.searchsorted(hd, np.mod(data[:, 1], 360.0))
    step()
    _, first = np.unique(i * hd.size + j, return_index=True)  # stable: each cell's first row
    if first.size != data.shape[0]:
        repeat = np.ones(data.shape[0], dtype=bool)
        repeat[first] = False
        k = int(np.argmax(repeat))  # the first row whose cell an earlier row filled
        v = data[k]
        raise VesselError(f"{where}:{line_of[k]}: duplicate row for w = {v[0]}, heading = {v[1]}")
    step()
    amp = np.zeros((6, w.size, hd.size))
    amp[:, i, j] = data[:, 2::2].T
    step()
    phase = np.zeros_like(amp)
    phase[:, i, j] = data[:, 3::2].T
    step()
    return RAOTable(w, np.deg2rad(hd), amp, phase, source=where)


def rao_to_csv(table: RAOTable) -> str:
    """The table in the CSV format of :func:`load_rao_csv`."""
    out = io.StringIO()
    out.write(f"# motion RAOs: {table.source}\n")
    wr = csv.writer(out, lineterminator="\n")
    wr.writerow(CSV_COLUMNS)
    for i, w in enumerate(table.w):
        for j, h in enumerate(table.headings):
            row = [f"{w:.12g}", f"{math.degrees(h):.12g}"]
            for d in range(6):
                row += [f"{table.amp[d, i, j]:.8g}", f"{table.phase[d, i, j]:.8g}"]
            wr.writerow(row)
    return out.getvalue()


# ----------------------------------------------------------------------------- time series
@dataclass(frozen=True, eq=False)
class VesselState:
    """Vessel motion samples: η [m, rad] in {n}; ν, ν̇ in {b}; each of shape (n, 6)."""

    t: NDArray[np.float64]
    eta: NDArray[np.float64]
    nu: NDArray[np.float64]
    nu_dot: NDArray[np.float64]


class VesselMotion:
    """Wave-induced 6-DOF motion of a vessel at zero speed in a sea of regular components.

    η(t) = Re Σ_k a_k H(ω_k, β_k) e^{i(ω_k t + ε_k)}; η̇, η̈ by multiplying with iω_k, −ω_k².
    ν from η̇ by the kinematics of Fossen (2011) eq. 2.40: ν₁ = R_b^nᵀ ṗ, ν₂ = T(Θ)⁻¹ Θ̇, and
    ν̇ by differentiating these exactly.  The motion is linear (small-amplitude) by
    construction; the nonlinear kinematics only keep ν and η consistent with each other.

    :meth:`at` gives η, η̇ at one instant (a platform's per-step source), compiled unless
    ``use_kernels`` is False; :meth:`eta_derivatives` is its reference.
    """

    def __init__(self, rao, sea: WaveComponents) -> None:
        self.sea = sea
        self.w = np.ascontiguousarray(sea.omega, dtype=float)
        H = rao(self.w, sea.direction)  # (6, n)
        self._c = (sea.amplitude * H).T * np.exp(1j * sea.phase)[:, None]  # (n, 6) complex
        c1 = self._c * (1j * self.w)[:, None]
        # (6, n) C-contiguous float64: the compiled kernel has one signature
        self._parts = tuple(np.ascontiguousarray(p.T) for p in (self._c.real, self._c.imag, c1.real, c1.imag))
        self.use_kernels = kernels.ENABLED

    def at(self, t: float, scale: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """η and η̇ at one time t [s], each (6,) and times ``scale`` per DOF when given."""
        s = np.ones(6) if scale is None else np.ascontiguousarray(scale, dtype=float)
        if self.use_kernels:
            return kernels.vessel_motion(self.w, *self._parts, float(t), s)
        eta, deta, _ = self.eta_derivatives(np.array([t]))
        return eta[0] * s, deta[0] * s

    def eta_derivatives(self, t: ArrayLike, chunk: int = 2048) -> tuple[NDArray, NDArray, NDArray]:
        """η, η̇, η̈ at times ``t`` (s), each (len(t), 6)."""
        t = np.atleast_1d(np.asarray(t, dtype=float))
        out = np.empty((3, t.size, 6))
        iw = 1j * self.w
        c0, c1, c2 = self._c, self._c * iw[:, None], self._c * (iw**2)[:, None]
        step = self._uniform_step(t) if min(t.size, chunk) * self.w.size <= 2_000_000 else None  # table ≤ 32 MB
        for s in range(0, t.size, chunk):
            ts = t[s : s + chunk]
            if step is not None:
                # a uniform grid t₀ + j·Δt: e^{iω(t₀+jΔt)} = e^{iωt₀} e^{iωjΔt}; the first factor goes into
                # the coefficients, the second is one table for every chunk (a product, not an exp each)
                E = self._grid_table(step, ts.size)
                phase = np.exp(iw * ts[0])[:, None]
                c0s, c1s, c2s = c0 * phase, c1 * phase, c2 * phase
            else:
                E = np.exp(1j * np.multiply.outer(ts, self.w))
                c0s, c1s, c2s = c0, c1, c2
            out[0, s : s + chunk] = (E @ c0s).real
            out[1, s : s + chunk] = (E @ c1s).real
            out[2, s : s + chunk] = (E @ c2s).real
        return out[0], out[1], out[2]

    @staticmethod
    def _uniform_step(t: NDArray[np.float64]) -> float | None:
        """Δt when ``t`` (more than 64 times) is t₀ + j·Δt to 1e-12 s, else None."""
        if t.size <= 64:
            return None
        dt = (t[-1] - t[0]) / (t.size - 1)
        if not dt > 0 or np.max(np.abs(t - (t[0] + dt * np.arange(t.size)))) > 1e-12 * max(1.0, abs(t[-1])):
            return None
        return float(dt)

    def _grid_table(self, dt: float, n: int) -> NDArray[np.complex128]:
        """e^{iω_k jΔt} for j < n (n, components), kept for the next chunk of the same grid."""
        key = (dt, n)
        if getattr(self, "_table_key", None) != key:
            self._table = np.exp(1j * np.multiply.outer(dt * np.arange(n), self.w))
            self._table_key = key
        return self._table

    def state(self, t: ArrayLike) -> VesselState:
        t = np.atleast_1d(np.asarray(t, dtype=float))
        eta, deta, ddeta = self.eta_derivatives(t)
        if self.use_kernels:  # the same formulas compiled (app/marine/kernels.py), tested equal
            nu, nu_dot = kernels.body_velocities(eta, deta, ddeta)
        else:
            nu, nu_dot = body_velocities(eta, deta, ddeta)
        return VesselState(t, eta, nu, nu_dot)


def body_velocities(eta: NDArray, deta: NDArray, ddeta: NDArray) -> tuple[NDArray, NDArray]:
    """ν and ν̇ in {b} from η, η̇, η̈ (Fossen 2011, eqs. 2.18, 2.29, 2.40), each (n, 6)."""
    phi, th = eta[:, 3], eta[:, 4]
    dphi, dth, dpsi = deta[:, 3], deta[:, 4], deta[:, 5]
    R_n_b = euler_zyx_to_matrix(eta[:, 3:6])  # R_b^n, Fossen eq. (2.18)
    Rt = np.swapaxes(R_n_b, 1, 2)  # R_n^b
    sf, cf, st, ct = np.sin(phi), np.cos(phi), np.sin(th), np.cos(th)
    # ω = T⁻¹(Θ) Θ̇ for the zyx convention
    p = dphi - st * dpsi
    q = cf * dth + ct * sf * dpsi
    r = -sf * dth + ct * cf * dpsi
    w_b = np.stack([p, q, r], axis=1)
    v_b = np.einsum("nij,nj->ni", Rt, deta[:, :3])
    # ν̇₁ = Rᵀ p̈ + (d/dt Rᵀ) ṗ, d/dt Rᵀ = −S(ω_b) Rᵀ
    a_b = np.einsum("nij,nj->ni", Rt, ddeta[:, :3]) - np.cross(w_b, v_b)
    ddphi, ddth, ddpsi = ddeta[:, 3], ddeta[:, 4], ddeta[:, 5]
    dp = ddphi - st * ddpsi - ct * dth * dpsi
    dq = cf * ddth - sf * dphi * dth + ct * sf * ddpsi + (-st * dth * sf + ct * cf * dphi) * dpsi
    dr = -sf * ddth - cf * dphi * dth + ct * cf * ddpsi + (-st * dth * cf - ct * sf * dphi) * dpsi
    nu = np.concatenate([v_b, w_b], axis=1)
    nu_dot = np.concatenate([a_b, np.stack([dp, dq, dr], axis=1)], axis=1)
    return nu, nu_dot


@dataclass
class MRU:
    """Motion reference unit: the true η, ν, ν̇ plus a constant bias and white noise per DOF.

    ``noise_eta``/``noise_nu``/``noise_nu_dot`` are standard deviations (6 values each, SI units);
    ``bias_*`` constant offsets.  The generator makes every run reproducible.
    """

    rng: np.random.Generator
    noise_eta: ArrayLike = (0.0,) * 6
    noise_nu: ArrayLike = (0.0,) * 6
    noise_nu_dot: ArrayLike = (0.0,) * 6
    bias_eta: ArrayLike = (0.0,) * 6
    bias_nu: ArrayLike = (0.0,) * 6
    bias_nu_dot: ArrayLike = (0.0,) * 6

    def __post_init__(self) -> None:
        for name in ("noise_eta", "noise_nu", "noise_nu_dot", "bias_eta", "bias_nu", "bias_nu_dot"):
            v = np.asarray(getattr(self, name), dtype=float)
            if v.shape != (6,) or not np.all(np.isfinite(v)):
                raise VesselError(f"MRU {name} must be 6 finite numbers")
            if name.startswith("noise") and np.any(v < 0):
                raise VesselError(f"MRU {name} must not be negative")
            setattr(self, name, v)

    def measure(self, s: VesselState) -> VesselState:
        n = s.t.size

        def noisy(x, sd, bias):
            return x + bias + self.rng.standard_normal((n, 6)) * sd

        return VesselState(
            s.t,
            noisy(s.eta, self.noise_eta, self.bias_eta),
            noisy(s.nu, self.noise_nu, self.bias_nu),
            noisy(s.nu_dot, self.noise_nu_dot, self.bias_nu_dot),
        )
