"""URDF import (issue 32, items 1 and 3): chains of any shape against pytransform3d's URDF kinematics, the two
reference arms against their DH files, ``bosun import urdf`` and direct loading, and the refusals."""

from __future__ import annotations

import math

import numpy as np
import pytest

from app.cli import main
from app.errors import BosunError
from app.models.registry import build_model, load_robot
from app.models.xml import parse_robot_xml
from app.resources import robot_library

pytest.importorskip("yourdfpy", reason="yourdfpy (bosun[urdf])")
UrdfTransformManager = pytest.importorskip(
    "pytransform3d.urdf", reason="pytransform3d (bosun[urdf])"
).UrdfTransformManager

URDF_DIR = robot_library() / "urdf"


def _reference(text: str):
    tm = UrdfTransformManager()
    tm.load_urdf(text)
    return tm


def _fk_gap(robot, text: str, base: str, tip: str, n: int = 1000, seed: int = 32) -> float:
    """The largest difference between the robot's FK and pytransform3d's over ``n`` seeded configurations."""
    tm = _reference(text)
    Q = np.random.default_rng(seed).uniform(robot.lower, robot.upper, (n, robot.n_joints))
    worst = 0.0
    for q in Q:
        for name, v in zip(robot.joint_names, q, strict=True):
            tm.set_joint(name, float(v))
        worst = max(worst, float(np.abs(robot.fk(q) - tm.get_transform(tip, base)).max()))
    return worst


@pytest.mark.parametrize(("name", "base", "tip"), [("franka_panda", "panda_link0", "panda_hand_tcp"),
                                                   ("ur5", "base_link", "tool0")])  # fmt: skip
def test_the_reference_urdfs_are_pytransform3d_s_and_their_dh_files_to_1e12(name, base, tip):
    """The UR5 and Panda URDFs (written from the makers' tables) load directly: FK equals pytransform3d's for the
    URDF and the library's DH file (modified DH for the Panda) to 1e-12 over 1,000 seeded configurations."""
    path = URDF_DIR / f"{name}.urdf"
    text = path.read_text(encoding="utf-8")
    robot, dh = load_robot(str(path)), load_robot(name)
    assert robot.n_joints == dh.n_joints and np.array_equal(robot.lower, dh.lower)
    for kernels in (False, True):
        robot.use_kernels = kernels
        assert _fk_gap(robot, text, base, tip) < 1e-12
    Q = np.random.default_rng(1).uniform(dh.lower, dh.upper, (1000, dh.n_joints))
    assert float(np.abs(robot.fk(Q) - dh.fk(Q)).max()) < 1e-12


def _random_urdf(rng, n: int, kinds=None) -> str:
    """A chain of n movable joints with fixed links between some, every origin and axis random, with the special
    cases a DH table must handle: parallel, meeting and coincident axes, a prismatic joint, a continuous one."""
    kinds = kinds or ["revolute"] * n
    parts, parent, k = ['<robot name="random"><link name="l0"/>'], "l0", 0
    special = {1: "parallel", 2: "meeting", 4: "coincident"}
    last_axis = None
    for i in range(n):
        kind = kinds[i]
        axis = rng.normal(size=3)
        xyz, rpy = rng.uniform(-0.4, 0.4, 3), rng.uniform(-math.pi, math.pi, 3)
        case = special.get(i)
        if case and last_axis is not None:  # expressed in the new joint's frame: set after the origin's rotation
            axis = _in_frame(last_axis, rpy)
            if case in ("meeting", "coincident"):
                xyz = np.zeros(3)
            if case == "meeting":
                axis = axis + _in_frame(np.array([0.3, -0.2, 0.5]), rpy)
        o = f'<origin xyz="{_v(xyz)}" rpy="{_v(rpy)}"/>'
        a = f'<axis xyz="{_v(axis)}"/>'
        lim = '<limit lower="-2.5" upper="2.5" velocity="1.5" effort="1"/>'
        if kind == "prismatic":
            lim = '<limit lower="-0.3" upper="0.3" velocity="0.5" effort="1"/>'
        elif kind == "continuous":
            lim = '<limit velocity="2" effort="1"/>'
        child = f"l{k + 1}"
        parts.append(f'<link name="{child}"/><joint name="j{i}" type="{kind}"><parent link="{parent}"/>'
                     f'<child link="{child}"/>{o}{a}{lim}</joint>')  # fmt: skip
        parent, k = child, k + 1
        last_axis = np.asarray(axis, dtype=float)  # a joint's axis is in its child link's frame
        if i + 1 not in special and rng.random() < 0.4:  # a fixed link between movable ones
            child = f"l{k + 1}"
            xyz, rpy = rng.uniform(-0.3, 0.3, 3), rng.uniform(-math.pi, math.pi, 3)
            parts.append(f'<link name="{child}"/><joint name="f{i}" type="fixed"><parent link="{parent}"/>'
                         f'<child link="{child}"/><origin xyz="{_v(xyz)}" '
                         f'rpy="{_v(rpy)}"/></joint>')  # fmt: skip
            parent, k = child, k + 1
            last_axis = _in_frame(last_axis, rpy)
    parts.append("</robot>")
    return "".join(parts)


def _v(values) -> str:
    return " ".join(repr(float(v)) for v in values)


def _rot(rpy):
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def _in_frame(v, rpy):
    """A direction given in the parent's frame, seen from a child frame turned by rpy."""
    return _rot(rpy).T @ v


@pytest.mark.parametrize("seed", range(6))
def test_any_chain_is_pytransform3d_s_to_1e12(seed):
    """Random chains (origins, axes off every coordinate axis, fixed links between, a prismatic and a continuous
    joint, parallel, meeting and coincident consecutive axes): the imported robot's FK equals pytransform3d's to
    1e-12, compiled and NumPy, and its Jacobian is the chain's own (central differences of pytransform3d's FK)."""
    rng = np.random.default_rng(seed)
    n = 6
    kinds = ["revolute"] * n
    kinds[3] = "prismatic"
    kinds[5] = "continuous"
    text = _random_urdf(rng, n, kinds)
    robot = build_model(parse_robot_xml(text, "random.urdf"))
    assert robot.n_joints == n and robot.joint_kinds[3] == "prismatic"
    from lxml import etree

    from app.models.urdf import urdf_chain

    J = urdf_chain(etree.fromstring(text.encode()), "random.urdf").joints  # the special cases are there
    assert abs(abs(J[0].axis @ J[1].axis) - 1) < 1e-12  # parallel
    w = J[2].point - J[1].point
    assert abs(abs(J[1].axis @ J[2].axis) - 1) > 1e-3 and abs(w @ np.cross(J[1].axis, J[2].axis)) < 1e-12  # meet
    assert abs(abs(J[3].axis @ J[4].axis) - 1) < 1e-12 and np.linalg.norm(np.cross(J[4].point - J[3].point,
                                                                                    J[3].axis)) < 1e-12  # fmt: skip
    assert robot.lower[5] == -2 * math.pi and robot.upper[5] == 2 * math.pi  # continuous: ±2π
    tip = max((f"l{k}" for k in range(40) if f'"l{k}"' in text), key=lambda s: int(s[1:]))
    for kernels in (False, True):
        robot.use_kernels = kernels
        assert _fk_gap(robot, text, "l0", tip, n=300, seed=seed) < 1e-12
    tm = _reference(text)
    q = np.random.default_rng(seed + 100).uniform(robot.lower, robot.upper)
    J, h = robot.jacobian(q), 1e-6

    def p(qq):
        for name, v in zip(robot.joint_names, qq, strict=True):
            tm.set_joint(name, float(v))
        return tm.get_transform(tip, "l0")[:3, 3]

    for j in range(n):
        dq = np.zeros(n)
        dq[j] = h
        np.testing.assert_allclose(J[:3, j], (p(q + dq) - p(q - dq)) / (2 * h), atol=1e-7)


def test_bosun_import_urdf_writes_a_robot_file_that_is_the_urdf(tmp_path, capsys):
    out = tmp_path / "arm.xml"
    assert main(["import", "urdf", str(URDF_DIR / "ur5.urdf"), "--out", str(out)]) == 0
    assert "wrote" in capsys.readouterr().out
    robot = load_robot(str(out))
    assert robot.name == "arm" and robot.joint_names[0] == "shoulder_pan_joint"
    text = (URDF_DIR / "ur5.urdf").read_text(encoding="utf-8")
    assert _fk_gap(robot, text, "base_link", "tool0", n=200) < 1e-12
    # a shorter chain: --base and --tip pick it
    assert main(["import", "urdf", str(URDF_DIR / "ur5.urdf"), "--base", "shoulder_lift_link", "--tip",
                 "wrist_2_link", "--out", str(tmp_path / "mid.xml")]) == 0  # fmt: skip
    mid = load_robot(str(tmp_path / "mid.xml"))
    assert mid.joint_names == ["elbow_joint", "wrist_1_joint", "wrist_2_joint"]
    assert _fk_gap(mid, text, "shoulder_lift_link", "wrist_2_link", n=200) < 1e-12


def _urdf(body: str) -> str:
    return f'<robot name="bad">\n<link name="a"/>\n<link name="b"/>\n<link name="c"/>\n{body}\n</robot>\n'


_REV = '<limit lower="-1" upper="1" velocity="1" effort="1"/><axis xyz="0 0 1"/>'
_J_AB = f'<joint name="ab" type="revolute"><parent link="a"/><child link="b"/>{_REV}</joint>'


@pytest.mark.parametrize(
    ("body", "line", "message"),
    [
        (_J_AB + f'\n<joint name="bc" type="revolute"><parent link="b"/><child link="c"/>{_REV}'
         '<mimic joint="ab"/></joint>', 6, r"joint 'bc': <mimic> is not supported"),
        (_J_AB + '\n<joint name="bc" type="floating"><parent link="b"/><child link="c"/></joint>', 6,
         r"joint 'bc': type 'floating' is not supported"),
        (_J_AB + '\n<joint name="bc" type="planar"><parent link="b"/><child link="c"/><axis xyz="0 0 1"/></joint>',
         6, r"joint 'bc': type 'planar' is not supported"),
        (_J_AB + f'\n<joint name="bc" type="revolute"><parent link="b"/><child link="c"/>{_REV}</joint>'
         f'\n<joint name="ac" type="revolute"><parent link="a"/><child link="c"/>{_REV}</joint>', 7,
         r"joint 'ac': link 'c' is already the child of joint 'bc': a closed loop"),
        (_J_AB + f'\n<joint name="ac" type="revolute"><parent link="a"/><child link="c"/>{_REV}</joint>', None,
         r"branches below 'a' into 2 tips \(b, c\): give the tip link \(--tip\)"),
        ('<joint name="ab" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>'
         '<limit lower="-1" upper="1" effort="1"/></joint>\n'
         '<joint name="bc" type="fixed"><parent link="b"/><child link="c"/></joint>', 5,
         r"joint 'ab': no positive <limit velocity=>"),
    ],
)  # fmt: skip
def test_what_a_serial_chain_cannot_be_is_refused_in_one_line(tmp_path, capsys, body, line, message):
    """<mimic>, floating and planar joints, a closed loop, an unchosen branch and a joint without a speed limit:
    refused in one line naming the file, the element's line and the element — loading directly and by ``bosun
    import urdf`` (exit 2, nothing written)."""
    text = _urdf(body)
    with pytest.raises(BosunError, match=message) as info:
        parse_robot_xml(text, "bad.urdf")
    msg = str(info.value)
    assert "\n" not in msg and msg.startswith(f"bad.urdf:{line}:" if line else "bad.urdf: "), msg
    src, out = tmp_path / "bad.urdf", tmp_path / "bad.xml"
    src.write_text(text, encoding="utf-8")
    assert main(["import", "urdf", str(src), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "bad.urdf" in err and not out.exists(), err


def test_a_urdf_loads_wherever_a_robot_file_does(tmp_path, capsys):
    """``bosun fk`` and ``bosun check`` take a .urdf path; so does the engine's teleop session; a file that is no
    URDF given to ``import urdf`` is refused in one line."""
    path = str(URDF_DIR / "franka_panda.urdf")
    assert main(["check", path]) == 0
    assert "franka_panda" in capsys.readouterr().out
    assert main(["fk", path, "--q", "0", "0", "0", "-1.5", "0", "1.5", "0", "--json"]) == 0
    capsys.readouterr()
    from app.engine.session import Session

    ses = Session(robot_name=path)
    assert ses.snapshot().robot.endswith("franka_panda.urdf") or "franka" in ses.snapshot().robot
    assert main(["import", "urdf", str(robot_library() / "scara.xml"), "--out", str(tmp_path / "x.xml")]) == 2
    assert "not a URDF" in capsys.readouterr().err
