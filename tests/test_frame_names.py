"""One frame-naming rule in app/ (app/geometry.py): ``R_a_b`` maps vectors in frame b into frame a.

The papers write the same rotation R_b^a, so a name copied from the superscript order (``R_b_n`` for
Fossen's R_b^n) is the inverted one.  What is checked, by parsing every ``app/**/*.py``:

1. every assignment from ``euler_zyx_to_matrix(...)`` (R_b^n from the roll, pitch, yaw of η) goes to a
   name starting with ``R_n_b`` (or into ``T_n_b[...]``/``R_n_b[...]``);
2. every compiled ``_rot_zyx(φ, θ, ψ, out)`` (the same matrix into ``out``) fills a name starting with
   ``R_n_b``;
3. every ``R_a_b = R_c_d @ R_e_f`` (or ``T_``/``H_``) between frame-named matrices, names or attributes,
   chains: c = a, d = e, f = b (``R_n_t = R_n_b @ R_b_t``).  Names with a suffix after the two frames
   (``R_t_n_dot``, ``R_n_b_true``) are not checked by 3; {world} and the Motion-Lab paper's {g} are one frame.
"""

from __future__ import annotations

import ast
import re
from pathlib import Path

from tests.helpers import needs_source

ROOT = Path(__file__).resolve().parents[1] / "app"
pytestmark = needs_source  # a check of the source tree itself
FRAME_NAME = re.compile(r"^([RTH])_([A-Za-z0-9]+)_([A-Za-z0-9]+)$")
SAME_FRAME = {"world": "g"}


def _name(node: ast.AST) -> str | None:
    """The identifier of a Name, of an Attribute's last part, or of the base of a subscript."""
    while isinstance(node, ast.Subscript):
        node = node.value
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return node.attr
    return None


def _frames(name: str | None) -> tuple[str, str, str] | None:
    m = FRAME_NAME.match(name or "")
    if m is None:
        return None
    kind, a, b = m.groups()
    a, b = a.lower(), b.lower()
    return kind, SAME_FRAME.get(a, a), SAME_FRAME.get(b, b)


def _called(node: ast.AST) -> str | None:
    return _name(node.func) if isinstance(node, ast.Call) else None


def violations(source: str, where: str = "<source>") -> list[str]:
    """Every break of rules 1–3 of the module docstring in ``source``."""
    out: list[str] = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, (ast.Assign, ast.AnnAssign)) and node.value is not None:
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            if _called(node.value) == "euler_zyx_to_matrix":  # rule 1
                for t in targets:
                    name = _name(t) or ""
                    ok = name.startswith("R_n_b") or (isinstance(t, ast.Subscript) and name.startswith("T_n_b"))
                    if not ok:
                        out.append(f"{where}:{node.lineno}: {name or ast.unparse(t)} = euler_zyx_to_matrix(...)")
            v = node.value
            if isinstance(v, ast.BinOp) and isinstance(v.op, ast.MatMult):  # rule 3
                left, right = _frames(_name(v.left)), _frames(_name(v.right))
                for t in targets:
                    goal = _frames(_name(t)) if isinstance(t, (ast.Name, ast.Attribute)) else None
                    same_kind = goal and left and right and goal[0] == left[0] == right[0]
                    if same_kind and not (left[1] == goal[1] and left[2] == right[1] and right[2] == goal[2]):
                        out.append(f"{where}:{node.lineno}: {ast.unparse(node)} does not chain")
        if _called(node) == "_rot_zyx" and len(node.args) == 4:  # rule 2
            name = _name(node.args[3]) or ""
            if not name.startswith("R_n_b"):
                out.append(f"{where}:{node.lineno}: _rot_zyx(..., {name or ast.unparse(node.args[3])})")
    return out


def test_app_follows_the_frame_naming_rule() -> None:
    files = sorted(ROOT.rglob("*.py"))
    assert len(files) > 20
    found = [v for f in files for v in violations(f.read_text(encoding="utf-8"), str(f.relative_to(ROOT.parent)))]
    assert found == []


def test_the_check_catches_the_paper_order() -> None:
    # the names app/models/crane_head.py and its kernels used before the rule was applied
    old = """
R_b_n = euler_zyx_to_matrix(eta[:, 3:6])
R_t_n = R_b_n @ R_t_b
_rot_zyx(eta[k, 3], eta[k, 4], eta[k, 5], R_b_n)
"""
    assert len(violations(old)) == 3
    new = """
R_n_b = euler_zyx_to_matrix(eta[:, 3:6])
R_n_t = R_n_b @ R_b_t
_rot_zyx(eta[k, 3], eta[k, 4], eta[k, 5], R_n_b)
T_n_b[:3, :3] = euler_zyx_to_matrix(eta[3:6])
T_n1_n2 = self.T_n1_g @ self.layout.T_world_n2
"""
    assert violations(new) == []
    assert len(violations("R = euler_zyx_to_matrix(eta[3:6])")) == 1
