"""Universal input: mapping (eqs. 1, 2, 7), device profiles, and the real pygame joystick path."""

import numpy as np
import pytest

from app.models import load_robot
from app.models.workspace import workspace_box
from app.teleop.devices import ManualInput, PygameJoysticks
from app.teleop.mapping import (
    Scaling,
    apply_deadzone,
    apply_expo,
    default_scaling,
    position_target,
    shape_input,
    velocity_command,
    velocity_target,
)
from app.teleop.profiles import ProfileError, default_profile, parse_profile, profile_for, shipped_profiles
from app.teleop.virtual import VirtualJoystick


def test_eq1_position_mapping():
    s = np.array([0.5, -1.0, 0.2])
    np.testing.assert_allclose(position_target(s, [2.0, 2.0, 1.0], [1.0, 0.0, 3.0]), [2.0, -2.0, 3.2])
    np.testing.assert_allclose(position_target(np.zeros(3), 5.0, [1, 2, 3]), [1, 2, 3])  # released: back to x_w


def test_eq2_eq7_velocity_mapping():
    xdot = velocity_command([1.0, 0.0, -0.5], 0.4)
    np.testing.assert_allclose(xdot, [0.4, 0.0, -0.2])
    np.testing.assert_allclose(velocity_target([1, 1, 1], xdot, 0.01), [1.004, 1.0, 0.998])
    np.testing.assert_allclose(velocity_target([1, 1, 1], velocity_command(np.zeros(3), 0.4), 0.01), [1, 1, 1])


def test_deadzone_rescales_continuously():
    np.testing.assert_allclose(apply_deadzone([0.05, -0.1, 0.55, -1.0, 1.0], 0.1), [0, 0, 0.5, -1.0, 1.0])
    s = np.linspace(-1, 1, 2001)
    out = apply_deadzone(s, 0.2)
    assert np.all(np.diff(out) >= 0) and np.max(np.abs(np.diff(out))) < 2e-3  # monotone, no jump
    with pytest.raises(ValueError, match="deadzone"):
        apply_deadzone([0.0], 1.0)


def test_expo_keeps_end_points_and_softens_centre():
    np.testing.assert_allclose(apply_expo([-1, 0, 1], 0.7), [-1, 0, 1])
    assert apply_expo(0.3, 0.7) < 0.3
    with pytest.raises(ValueError, match="expo"):
        apply_expo(0.1, 1.5)


def test_shape_input_neutralises_bad_values():
    np.testing.assert_allclose(shape_input([np.nan, np.inf, 2.0], 0.0, 0.0), [0.0, 0.0, 1.0])


def test_default_scaling_from_workspace_for_every_robot():
    for name in ("comau_smart5_3dof", "kuka_youbot", "offshore_crane"):
        robot = load_robot(name)
        box = workspace_box(robot)
        start = robot.position(0.5 * (robot.lower + robot.upper))
        sc = default_scaling(box, start)
        assert sc.k_p[0] == pytest.approx(0.25 * box.extent.min()) and sc.k_v[0] == pytest.approx(0.05 * box.diagonal)
        np.testing.assert_allclose(sc.x_w, start)
    with pytest.raises(ValueError, match="k_p must be 3 finite"):
        Scaling((1.0, np.nan, 1.0), (0, 0, 0), (1, 1, 1)).validate()


# ------------------------------------------------------------------ profiles
def test_shipped_profiles_load_and_match():
    names = {p.name for p in shipped_profiles()}
    assert {"Logitech Extreme 3D Pro", "Xbox-style gamepad"} <= names
    assert profile_for("Logitech Extreme 3D pro", 4).name == "Logitech Extreme 3D Pro"
    assert profile_for("Xbox 360 Wireless Receiver", 6).enable_button == 4
    unknown = profile_for("Some Cheap Stick", 2)
    assert unknown.name == "default" and unknown.axes[2] is None and unknown.enable_button == 0


def test_profile_signal_inverts_and_picks_axes():
    prof = profile_for("Logitech Extreme 3D Pro", 4)
    # x, y (inverted), z; no w: the throttle does not spring back, so it commands nothing
    np.testing.assert_allclose(prof.signal((0.5, -0.25, 0.8, 0.9)), [0.5, 0.25, 0.8, 0.0])
    np.testing.assert_allclose(default_profile(2).signal((0.3, 0.6)), [0.3, -0.6, 0.0, 0.0])
    assert prof.enabled((True, False)) and not prof.enabled((False, True)) and not prof.enabled(())


@pytest.mark.parametrize(
    "text, message",
    [
        ("name = 'x'\n[axes.q]\nindex = 0\n", r"\[axes\] may only have x, y, z"),
        ("name = 'x'\ndeadzone = 2\n", "field 'deadzone' must be a number in"),
        ("name = 'x'\nenable_button = -1\n", "field 'enable_button' must be a button index"),
        ("name = 'x'\n[axes.x]\nindex = 'a'\n", "axes.x.index must be an axis index"),
        ("name = 'x'\ncolour = 'red'\n", "unknown field"),
        ("name = \n", "TOML syntax error"),
        ("deadzone = 0.1\n", "field 'name' must be a non-empty string"),
    ],
)
def test_bad_profiles(text, message):
    with pytest.raises(ProfileError, match=message) as info:
        parse_profile(text, "my.toml")
    assert str(info.value).startswith("my.toml: ")


# ------------------------------------------------------------------ devices
def test_manual_input():
    src = ManualInput("keys")
    src.set([0.1, 0.2, 0.3], [True])
    s = src.poll()
    assert s.axes == (0.1, 0.2, 0.3) and s.buttons == (True,) and s.device == "keys"
    src.disconnect()
    assert src.poll() is None


@pytest.fixture
def joysticks():
    pytest.importorskip("pygame", reason="pygame (bosun[joystick])")
    src = PygameJoysticks()
    yield src
    src.close()


def test_real_pygame_path_with_virtual_joystick(joysticks):
    """SDL's virtual joystick: values set here arrive through pygame, then through the profile."""
    joysticks.poll()
    joysticks.take_events()
    vj = VirtualJoystick(n_axes=4, n_buttons=8)
    try:
        sample = joysticks.poll()
        assert [e.kind for e in joysticks.take_events()] == ["added"]
        assert sample is not None and len(sample.axes) == 4 and len(sample.buttons) == 8
        vj.set_axis(0, 0.5)
        vj.set_axis(1, -1.0)
        vj.set_button(0, True)
        sample = joysticks.poll()
        assert sample.axes[0] == pytest.approx(0.5, abs=1e-4) and sample.axes[1] == pytest.approx(-1.0, abs=1e-4)
        assert sample.buttons[0]
        prof = profile_for(sample.device, len(sample.axes))
        s = shape_input(prof.signal(sample.axes), prof.deadzone, prof.expo)
        assert s[0] > 0.4 and s[1] == pytest.approx(1.0, abs=1e-4) and prof.enabled(sample.buttons)
    finally:
        vj.detach()
    # unplugged: the source reports it and stops producing samples
    assert joysticks.poll() is None
    assert [e.kind for e in joysticks.take_events()] == ["removed"]


def test_hot_plug_second_device_selected_by_name(joysticks):
    joysticks.poll()
    joysticks.take_events()
    a = VirtualJoystick(n_axes=2, n_buttons=2)
    b = VirtualJoystick(n_axes=6, n_buttons=10)
    try:
        joysticks.poll()
        assert len(joysticks.devices()) == 2
        assert [e.kind for e in joysticks.take_events()] == ["added", "added"]
    finally:
        b.detach()
        a.detach()
    joysticks.poll()
    assert joysticks.devices() == []
