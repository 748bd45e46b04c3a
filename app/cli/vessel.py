"""``bosun vessel list|rao``: the vessels known by name, and RAOs from main particulars."""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from app.cli.args import command, group
from app.cli.common import _as_usage_error, _fields, _positive_float, _print_json, _progress_bar
from app.errors import BosunError


# ----------------------------------------------------------------------------- vessels (issue 17)
def cmd_vessel_list(args: argparse.Namespace) -> int:
    from app.marine.vessels import DEFAULT_VESSEL, VESSELS

    if args.json:
        _print_json({"default": DEFAULT_VESSEL, "vessels": VESSELS})
        return 0
    for name, text in VESSELS.items():
        print(f"{name:20s} {text}{'  (default)' if name == DEFAULT_VESSEL else ''}")
    print("or any RAO file: --vessel FILE.mat|FILE.csv")
    return 0


def cmd_vessel_rao(args: argparse.Namespace) -> int:
    """6-DOF motion RAOs of a monohull from its main particulars (Capytaine BEM + viscous roll damping)."""
    import dataclasses
    import shlex

    from app.marine.bem import BemError, BemInputs, compute_raos
    from app.marine.hull import HullError
    from app.marine.vessel import VesselError, VesselParticulars, rao_to_csv

    names = ("lpp", "beam", "draft", "cb", "gm_t", "gm_l", "r44", "r55", "r66", "mass")
    given = {n: v for n, v in _fields(args, *names).items() if v is not None}
    with _as_usage_error(BemError, HullError, VesselError):
        name = args.name or ("MSS supply vessel" if not given else "monohull")
        vessel = VesselParticulars(**given, name=name)
        bem = ("cwp", "nx", "nz", "w_min", "w_max", "n_w", "heading_step")
        viscous = "ikeda" if args.roll_damping == "ikeda" else "zeta"
        extra = {"viscous": viscous}
        if viscous == "zeta":
            try:
                extra["roll_damping"] = float(args.roll_damping)
            except ValueError:
                raise BemError(f"--roll-damping {args.roll_damping!r}: a ratio of critical (0.15) or 'ikeda'") from None
        inputs = BemInputs(vessel=vessel, **_fields(args, *bem), **extra)
        out = Path(args.out)
        if out.is_dir():
            raise BosunError(f"--out {out} is a folder; give a .csv file")
        result = compute_raos(inputs, progress=_progress_bar("vessel rao", unit="frequency"))
    argv = getattr(args, "argv", None) or []
    made_by = "bosun " + " ".join(shlex.quote(a) for a in argv) if argv else "bosun vessel rao"
    header = {
        "command": made_by,
        "inputs": inputs.to_dict(),
        "vessel": dataclasses.asdict(vessel),
        "info": result.info,
    }
    text = rao_to_csv(result.table)
    lines = text.splitlines(keepends=True)
    meta = "".join(f"# {line}\n" for line in json.dumps(header, indent=1, sort_keys=True).splitlines())
    body = lines[0] + "# made by: " + made_by + "\n" + meta + "".join(lines[1:])
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
        tmp = out.with_name(f".{out.name}.partial")
        tmp.write_text(body, encoding="utf-8")
        tmp.replace(out)
    except OSError as err:
        raise BosunError(f"cannot write {out}: {err.strerror or err}") from None
    info = result.info
    if args.json:
        _print_json({"out": str(out), **header})
        return 0
    t = result.table
    print(f"{vessel.name}: {t.w.size} frequencies × {t.headings.size} headings, {info['panels']} panels", end="")
    print(f" (+{info['lid_panels']} lid), {info['wall_s']:.0f} s")
    cwp, cm = info["waterplane_coefficient"], info["midship_section_coefficient"]
    origin = "given" if inputs.cwp is not None else "from GM_L − GM_T"
    print(f"  hull: C_WP {cwp:.3f} ({origin}), C_M {cm:.3f}, z_G {info['z_g_m']:+.2f} m above the waterline")
    ratio = 100 * info["roll_radiation_damping_ratio"]
    print(
        f"  roll: ω4 {info['roll_natural_frequency_rad_s']:.3f} rad/s, radiation damping {ratio:.2f} % of critical,",
        end="",
    )
    if inputs.viscous == "zeta":
        print(f" viscous added to {100 * inputs.roll_damping:g} %")
    else:
        ik = info["ikeda"]
        sea = ik["linearise_sea"]
        print(
            f" Ikeda's viscous damping {100 * info['roll_viscous_damping_ratio']:.2f} % at ω4 (linearised at "
            f"{ik['roll_amplitude_deg']:.1f}° in Hs {sea['hs']:g} m, Tp {sea['tp']:g} s, {sea['heading']:g}°)"
        )
        if ik["outside_the_method_s_range"]:
            print(f"  outside Ikeda's simplified method's range: {', '.join(ik['outside_the_method_s_range'])}")
    print(f"wrote {out}")
    return 0


def register(sub) -> None:
    """Add this group's commands to ``bosun``'s subparsers."""
    ves = group(sub, "vessel", "vessels: vessel list, vessel rao (RAOs from main particulars, Capytaine)", "vessel_cmd")
    with command(ves, "list", cmd_vessel_list, help="the vessels known by name (the default first)"):
        pass  # --json only
    rao_help = "6-DOF motion RAOs of a monohull from its main particulars (boundary elements, extra 'marine')"
    with command(ves, "rao", cmd_vessel_rao, help=rao_help) as b:
        for flag, unit, what in (
            ("--lpp", "m", "length between perpendiculars"), ("--beam", "m", "beam"), ("--draft", "m", "draft"),
            ("--cb", "", "block coefficient"), ("--gm-t", "m", "transverse metacentric height"),
            ("--gm-l", "m", "longitudinal metacentric height"), ("--r44", "m", "roll radius of gyration"),
            ("--r55", "m", "pitch radius of gyration"), ("--r66", "m", "yaw radius of gyration"),
            ("--mass", "kg", "mass"),
        ):  # fmt: skip
            b.add_argument(
                flag, dest=flag[2:].replace("-", "_"), type=_positive_float, default=None,
                help=f"{what}{' [' + unit + ']' if unit else ''} (default: the MSS supply vessel's; "
                "physical range: README)",
            )  # fmt: skip
        b.add_argument("--name", default=None, help="the vessel's name (in the table's header)")
        b.add_argument(
            "--cwp", type=_positive_float, default=None, help="waterplane coefficient (default: from GM_L − GM_T)"
        )
        b.add_argument(
            "--roll-damping",
            default="0.15",
            metavar="ZETA|ikeda",
            help="total ζ44 at the roll natural frequency (0.15), or ikeda: Ikeda's components with the supply "
            "vessel's assumed bilge keels, linearised in Hs 3 m, Tp 9 s, beam",
        )
        b.add_argument("--nx", type=int, default=40, help="panels along the half hull, 4–200 (default 40)")
        b.add_argument("--nz", type=int, default=8, help="panels down its girth, 2–50; nx × nz ≤ 2000 (default 8)")
        b.add_argument("--w-min", type=_positive_float, default=0.1, help="lowest wave frequency [rad/s], ≥ 0.01 (0.1)")
        b.add_argument("--w-max", type=_positive_float, default=2.0, help="highest wave frequency [rad/s], ≤ 20 (2.0)")
        b.add_argument("--n-w", type=int, default=40, help="number of frequencies, 2–200 (default 40)")
        b.add_argument(
            "--heading-step", type=_positive_float, default=10.0, help="heading step [deg], 1–180, divides 360 (10)"
        )
        b.add_argument("--out", default="out/vessel_rao.csv", help="the RAO table (CSV; default out/vessel_rao.csv)")
