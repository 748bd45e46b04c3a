"""The vessels Bosun knows by name, and RAO files (issue 17, item 1).

``supply`` (the default) is the MSS supply vessel of the TAC paper (§9: Lpp 82.8 m, B 19.2 m, T 6.0 m,
C_B 0.651, GM_T 2.144 m, GM_L 103.6 m, r44/r55/r66 6.84/20.7/20.7 m, m 6.36e6 kg) with motion RAOs computed
from those particulars by ``bosun vessel rao`` (Capytaine, :mod:`app.marine.bem`) and shipped as package
data (``app/marine/data/supply_bem.csv``, its header names the command and inputs that made it);
``supply-closed-form`` is the same vessel through the closed-form model of :func:`parametric_rao`
(heave and pitch of Jensen, Mansour & Olsen 2004, a 1-DOF roll; no surge, sway, yaw).  Anything else is a
path to an RAO file (MSS ``.mat`` or Bosun's CSV, :func:`load_rao`).
"""

from __future__ import annotations

import functools
from pathlib import Path

from app.marine.vessel import RAOTable, VesselError, VesselParticulars, load_rao, load_rao_csv, parametric_rao
from app.resources import marine_data

DEFAULT_VESSEL = "supply"
VESSELS = {
    "supply": "MSS supply vessel, RAOs by boundary elements (Capytaine) from its particulars",
    "supply-closed-form": "MSS supply vessel, closed-form RAOs (Jensen, Mansour & Olsen 2004; 1-DOF roll)",
}
SHIPPED_TABLE = "supply_bem.csv"


def shipped_table_path() -> Path:
    """The shipped BEM table of the default vessel (package data of ``app.marine``)."""
    return marine_data() / SHIPPED_TABLE


@functools.lru_cache(maxsize=1)
def _shipped_table() -> RAOTable:
    """The shipped table, read once (an engine asks for it at every new sea); RAOTable is immutable."""
    path = shipped_table_path()
    if not path.is_file():
        raise VesselError(f"the shipped RAO table {path} is missing (reinstall Bosun)")
    table = load_rao_csv(path.read_text(encoding="utf-8-sig"), where=str(path))
    return RAOTable(table.w, table.headings, table.amp, table.phase, source=VESSELS["supply"])


def vessel_rao(spec: str | None = None, roll_damping: float = 0.15) -> RAOTable:
    """The RAO table of a named vessel (``supply``, ``supply-closed-form``) or of an RAO file; None is the
    default vessel.  ``roll_damping`` (ζ44) applies to the closed-form model only."""
    name = DEFAULT_VESSEL if spec is None else spec
    if name == "supply":
        return _shipped_table()
    if name == "supply-closed-form":
        return parametric_rao(VesselParticulars(roll_damping=roll_damping))
    looks_like_a_file = Path(name).suffix.lower() in (".mat", ".csv") or "/" in name or "\\" in name
    if not looks_like_a_file and not Path(name).is_file():
        known = ", ".join(VESSELS)
        raise VesselError(f"unknown vessel {name!r}: a vessel name ({known}) or an RAO file (.mat or .csv)")
    return load_rao(name)


def vessel_label(spec: str | None) -> str:
    """One line naming the vessel model (the GUI and the CLI show it)."""
    name = DEFAULT_VESSEL if spec is None else spec
    if name in VESSELS:
        return f"{name}: {VESSELS[name]}"
    return f"RAO file {Path(name).name}"
