"""The robot file format: every library file validates; every bad input is one clear error."""

from pathlib import Path

import numpy as np
import pytest

from app.errors import RobotNotFoundError, RobotXmlError
from app.models import list_robots, load_robot, load_spec, robots_dir
from app.models.xml import parse_robot_file, parse_robot_xml

LIBRARY = sorted(robots_dir().glob("*.xml"))

GOOD = """<?xml version="1.0"?>
<robot name="two_link" type="serial" angle_unit="deg">
  <description>test arm</description>
  <source>test</source>
  <serial>
    <base xyz="0 0 1" rpy="0 0 90"/>
    <link joint="revolute">
      <dh d="0.5" a="1.0" alpha="0"/>
      <joint name="q1"><limits min="-90" max="90" speed="45" accel="90"/></joint>
    </link>
    <link joint="prismatic">
      <dh theta="0" a="0" alpha="0"/>
      <joint name="q2" offset="0.2"><limits min="0" max="0.5" speed="0.1"/>
        <coupling joint="q1" factor="0.5"/></joint>
    </link>
    <tool xyz="0 0 0.1"/>
  </serial>
</robot>
"""


def test_library_has_the_required_robots():
    assert {
        "offshore_crane",
        "comau_smart5_3dof",
        "comau_smart5_6dof",
        "knuckle_boom_crane",
        "scara",
        "kuka_youbot",
        "tac_delta_head",
        "em8000",
        "em1500",
    } <= set(list_robots())


@pytest.mark.parametrize("path", LIBRARY, ids=lambda p: p.stem)
def test_every_library_file_loads_and_validates(path: Path):
    spec = parse_robot_file(path)
    assert spec.name == path.stem, "file name and robot name must agree"
    assert spec.description and spec.source
    if spec.type == "serial":
        robot = load_robot(path.stem)
        assert np.all(robot.lower < robot.upper) and np.all(robot.speed > 0)
        q_mid = 0.5 * (robot.lower + robot.upper)
        assert np.all(np.isfinite(robot.fk(q_mid)))
    elif spec.type == "delta":
        d = spec.delta
        assert d.alpha_min < d.alpha_max and d.l_r > 0
    else:
        s = spec.stewart
        assert s.base_joints_n.shape == (6, 3) and s.platform_joints_b.shape == (6, 3)
        assert np.all(s.pose_min < 0) and np.all(s.pose_max > 0)


def test_units_are_converted():
    spec = parse_robot_xml(GOOD)
    j1, j2 = spec.serial.joints
    assert j1.lower == pytest.approx(-np.pi / 2) and j1.speed == pytest.approx(np.pi / 4)
    assert j1.accel == pytest.approx(np.pi / 2)
    assert j2.kind == "prismatic" and j2.upper == 0.5 and j2.accel is None and j2.offset == 0.2
    assert j2.coupling == ((0, 0.5),)
    np.testing.assert_allclose(spec.serial.T_world_base[:3, :3], [[0, -1, 0], [1, 0, 0], [0, 0, 1]], atol=1e-15)


def test_tac_delta_table4_values():
    d = load_spec("tac_delta_head").delta
    assert (d.l_k, d.l_a, d.l_r, d.l_p) == (2.00, 3.25, 7.00, 1.25)
    np.testing.assert_allclose(d.arm_rotations, [5 * np.pi / 6, 3 * np.pi / 2, np.pi / 6])  # TAC eq. (1)
    np.testing.assert_allclose([d.alpha_min, d.alpha_max], np.deg2rad([-40, 70]))
    assert (d.motor_time_constant, d.motor_gain, d.pid) == (0.2, 1.0, (10.0, 60.0, 1.0))


def test_stewart_table8_values():
    s = load_spec("em8000").stewart
    np.testing.assert_allclose(s.pose_min[:3], [-1.110, -1.149, -0.955])
    np.testing.assert_allclose(np.rad2deg(s.pose_max[3:]), [26.10, 33.40, 31.10])
    np.testing.assert_allclose(np.rad2deg(load_spec("em1500").stewart.speed_max[3:]), [40, 40, 50])


def _bad(old: str, new: str) -> str:
    assert old in GOOD
    return GOOD.replace(old, new, 1)


BAD_CASES = [
    ("syntax", _bad("</serial>", "</serail>"), r"bad\.xml:17: XML syntax error: Opening and ending tag mismatch"),
    (
        "unknown joint type",
        _bad('joint="prismatic"', 'joint="spherical"'),
        r"bad\.xml:11: schema: .*'spherical' is not an element of the set",
    ),
    (
        "schema: unknown element",
        _bad("<tool ", "<gripper "),
        r"bad\.xml:16: schema: Element 'gripper': This element is not expected",
    ),
    ("missing number", _bad('a="1.0" ', ""), r"bad\.xml:8: schema: .*attribute 'a' is required"),
    ("not a number", _bad('a="1.0"', 'a="one"'), r"bad\.xml:8: schema: .*'one' is not a valid value"),
    ("NaN", _bad('a="1.0"', 'a="NaN"'), r"bad\.xml:8: <dh> attribute 'a' is NaN; give a finite number"),
    ("infinite", _bad('speed="45"', 'speed="INF"'), r"bad\.xml:9: <limits> attribute 'speed' is INF"),
    (
        "min > max",
        _bad('min="-90" max="90"', 'min="90" max="-90"'),
        r"bad\.xml:9: joint q1 limits: min \(90\) must be less than max \(-90\)",
    ),
    ("bad angle unit", _bad('angle_unit="deg"', 'angle_unit="grad"'), r"bad\.xml:2: schema: .*angle_unit"),
    (
        "revolute with theta",
        _bad('<dh d="0.5"', '<dh theta="10" d="0.5"'),
        r"bad\.xml:8: link 1: a revolute joint drives 'theta'",
    ),
    (
        "link without joint",
        _bad('<joint name="q1"><limits min="-90" max="90" speed="45" accel="90"/></joint>', ""),
        r"bad\.xml:7: link 1: a revolute link needs a <joint>",
    ),
    (
        "coupling to unknown joint",
        _bad('joint="q1" factor', 'joint="q7" factor'),
        r"bad\.xml:14: joint q2: coupling names unknown joint 'q7'",
    ),
    ("duplicate joint", _bad('name="q2"', 'name="q1"'), r"joint name 'q1' is used more than once"),
    ("type mismatch", _bad('type="serial"', 'type="delta"'), r"bad\.xml:5: robot type is 'delta' but .*<serial>"),
    ("negative speed", _bad('speed="45"', 'speed="-45"'), r"bad\.xml:9: schema: .*speed"),
]


@pytest.mark.parametrize("text, pattern", [c[1:] for c in BAD_CASES], ids=[c[0] for c in BAD_CASES])
def test_bad_xml_raises_one_clear_error(text, pattern):
    with pytest.raises(RobotXmlError, match=pattern) as info:
        parse_robot_xml(text, "bad.xml")
    assert "\n" not in str(info.value)


def test_bad_delta_and_stewart():
    delta = Path(robots_dir(), "tac_delta_head.xml").read_text(encoding="utf-8")
    with pytest.raises(RobotXmlError, match=r"delta arm limits: min \(70\) must be less than max \(-40\)"):
        parse_robot_xml(delta.replace('min="-40" max="70"', 'min="70" max="-40"'), "d.xml")
    with pytest.raises(RobotXmlError, match="index 1, 2 and 3 once each"):
        parse_robot_xml(delta.replace('index="3"', 'index="2"'), "d.xml")
    stewart = Path(robots_dir(), "em8000.xml").read_text(encoding="utf-8")
    with pytest.raises(RobotXmlError, match="leg length: min"):
        parse_robot_xml(stewart.replace('min_length="1.6864"', 'min_length="3.5"'), "s.xml")
    with pytest.raises(RobotXmlError, match="pose limit for 'surge' is given twice"):
        parse_robot_xml(stewart.replace('name="sway"', 'name="surge"'), "s.xml")
    with pytest.raises(RobotXmlError, match=r"s\.xml:\d+: schema: .*point"):
        parse_robot_xml(stewart.replace('<point xyz="2.0284 0.5435 2.3000"/>', ""), "s.xml")


def test_unknown_robot_name_suggests():
    with pytest.raises(RobotNotFoundError, match="unknown robot 'scarra'; did you mean scara"):
        load_spec("scarra")


def test_missing_file(tmp_path):
    with pytest.raises(RobotNotFoundError, match="robot file not found"):
        load_spec(str(tmp_path / "nope.xml"))


def test_load_by_path_and_env_dir(tmp_path, monkeypatch):
    f = tmp_path / "two_link.xml"
    f.write_text(GOOD, encoding="utf-8")
    robot = load_robot(str(f))
    assert robot.name == "two_link" and robot.n_joints == 2
    # theta1 = q1 rotates a 1 m link after a base yaw of 90 deg; d2 = 0.2 + q2 + 0.5 q1; tool 0.1 m on z.
    np.testing.assert_allclose(robot.position([0, 0]), [0, 1, 1 + 0.5 + 0.2 + 0.1], atol=1e-12)
    monkeypatch.setenv("BOSUN_ROBOTS_DIR", str(tmp_path))
    assert list_robots() == ["two_link"]


def test_stewart_type_loads_its_platform_model():
    from app.models.stewart import StewartPlatform

    assert isinstance(load_robot("em8000"), StewartPlatform)
