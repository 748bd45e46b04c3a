"""The one input pipeline: deadman, zero-position arming, stale halt from receive time, stop button."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from app.teleop.devices import InputSample
from app.teleop.pipeline import InputPipeline
from app.teleop.profiles import ProfileError, parse_profile

PAD = parse_profile("name='pad'\nenable_button=0\nstop_button=2\nmode_button=1\n[axes.x]\nindex=0\n[axes.w]\nindex=3\n")


def s(x=0.0, enable=False, stop=False, mode=False, w=0.0):
    return InputSample((x, 0.0, 0.0, w), (enable, mode, stop), "pad")


def feed_step(p, sample, t):
    p.feed(sample, t)
    return p.step(t)


def test_starts_disarmed_a_deflected_stick_with_enable_held_does_nothing():
    p = InputPipeline()
    p.set_profile(PAD)
    for k in range(50):
        out = feed_step(p, s(x=1.0, enable=True), 0.01 * k)
        assert not out.enabled and not np.any(out.signal)
    assert "centre the stick" in out.reason


def test_arms_only_after_neutral_released_then_enable_pressed_at_neutral():
    p = InputPipeline()
    p.set_profile(PAD)
    assert not feed_step(p, s(enable=True), 0.00).enabled  # enable held from before: no
    assert not feed_step(p, s(enable=False), 0.01).enabled  # released at neutral: ready
    assert not feed_step(p, s(x=0.5, enable=True), 0.02).enabled  # pressed while deflected: no
    assert not feed_step(p, s(x=0.0, enable=True), 0.03).enabled  # still held, no new press: no
    feed_step(p, s(enable=False), 0.04)
    assert feed_step(p, s(enable=True), 0.05).enabled  # pressed at neutral: armed
    out = feed_step(p, s(x=0.5, enable=True), 0.06)
    assert out.enabled and out.signal[0] == pytest.approx((0.5 - 0.08) / 0.92) and out.signal[3] == 0.0
    out = feed_step(p, s(x=0.5, enable=False), 0.07)  # deadman released: holds, disarms
    assert not out.enabled and not out.armed
    assert not feed_step(p, s(x=0.5, enable=True), 0.08).enabled  # re-press while deflected: no


def arm(p, t=0.0):
    feed_step(p, s(), t)
    assert feed_step(p, s(enable=True), t + 0.01).enabled
    return t + 0.01


def test_stale_counts_from_receive_time_and_disarms():
    p = InputPipeline(stale_timeout=0.2)
    p.set_profile(PAD)
    t = arm(p)
    # a sample stamped long ago by the sender but received now is fresh: the engine's clock counts
    old = InputSample((0.5, 0, 0, 0), (True, False, False), "pad", t=-1000.0)
    assert feed_step(p, old, t + 0.01).enabled
    assert p.step(t + 0.2).enabled
    out = p.step(t + 0.22)
    assert out.stale and not out.enabled and not out.armed and p.stale_count == 1
    assert not feed_step(p, s(x=0.5, enable=True), t + 0.3).enabled  # back, but needs re-arming


def test_steady_hold_at_30_hz_is_never_stale():
    p = InputPipeline()
    p.set_profile(PAD)
    t = arm(p)
    for k in range(1, 3001):  # 1 kHz engine, 30 Hz sender, 3 s
        now = t + k * 1e-3
        if k % 33 == 0:
            p.feed(s(x=0.7, enable=True), now)
        assert not p.step(now).stale
    assert p.stale_count == 0


def test_unplug_holds_and_disarms():
    p = InputPipeline()
    p.set_profile(PAD)
    t = arm(p)
    p.feed(None, t + 0.01)
    out = p.step(t + 0.01)
    assert not out.enabled and not out.connected and "unplugged" in out.reason
    assert not feed_step(p, s(x=0.0, enable=True), t + 0.02).enabled


def test_stop_button_is_a_rising_edge_even_when_disarmed():
    p = InputPipeline()
    p.set_profile(PAD)
    assert feed_step(p, s(stop=True), 0.0).stop
    assert not feed_step(p, s(stop=True), 0.01).stop
    assert not feed_step(p, s(), 0.02).stop
    assert feed_step(p, s(stop=True), 0.03).stop


def test_profile_without_enable_never_drives():
    """No deadman, no driving: a profile must name an enable button to move anything."""
    p = InputPipeline()
    p.set_profile(parse_profile("name='free'\nstop_button=1\n[axes.x]\nindex=0\n"))
    for k, x in enumerate((0.0, 0.9, 0.0, 0.9)):
        out = feed_step(p, InputSample((x,), (False, False), "free"), 0.01 * k)
        assert not out.enabled and not np.any(out.signal)
    assert "no enable (deadman) button" in out.reason
    assert feed_step(p, InputSample((0.0,), (False, True), "free"), 0.1).stop  # its stop button still stops


def test_mode_button_held_through_a_stale_gap_does_not_toggle_again():
    p = InputPipeline()
    p.set_profile(PAD)
    assert feed_step(p, s(mode=True), 0.0).mode_toggle
    assert p.step(0.5).stale  # silence
    assert not feed_step(p, s(mode=True), 0.6).mode_toggle  # still the same press


def test_unused_axes_need_not_be_centred_to_arm():
    """A throttle (w) left off centre does not block arming an arm that drives x, y, z only."""
    p = InputPipeline(axes=3)
    p.set_profile(PAD)
    feed_step(p, s(w=0.7), 0.0)
    out = feed_step(p, s(w=0.7, enable=True), 0.01)
    assert out.enabled and out.signal[3] == 0.0
    lab = InputPipeline(axes=4)
    lab.set_profile(PAD)
    feed_step(lab, s(w=0.7), 0.0)
    assert not feed_step(lab, s(w=0.7, enable=True), 0.01).enabled  # the lab drives w: it must be centred


def test_profile_buttons_must_differ():
    with pytest.raises(ProfileError, match="must be different buttons"):
        parse_profile("name='x'\nenable_button=1\nstop_button=1\n")


_ev = st.tuples(
    st.floats(-1, 1, allow_nan=False), st.booleans(), st.sampled_from(["feed", "silence", "unplug", "disarm"])
)


@settings(max_examples=80, deadline=None, derandomize=True)
@given(st.lists(_ev, min_size=1, max_size=40))
def test_property_enabled_only_after_a_fresh_arming_gesture(events):
    """Whatever happens, an enabled output needs fresh input and, since the last disarming event
    (unplug, disarm, silence), a neutral sample with enable released, later a neutral sample with
    enable pressed, and enable held on every sample since that press."""
    p = InputPipeline(stale_timeout=0.2)
    p.set_profile(PAD)
    t, last_feed = 0.0, None
    history: list[tuple[bool, bool]] = []  # (neutral, enable) since the last disarming event
    for x, en, what in events:
        t += 0.05 if what != "silence" else 0.3
        if what == "feed":
            p.feed(s(x=x, enable=en), t)
            last_feed = t
            history.append((abs(x) <= PAD.deadzone, en))
        elif what == "unplug":
            p.feed(None, t)
            last_feed, history = None, []
        elif what == "disarm":
            p.disarm("test")
            history = []
        fresh = last_feed is not None and t - last_feed <= 0.2
        out = p.step(t)
        if not fresh:
            history = []
        if out.enabled:
            assert fresh
            press = max(j for j, (n, e) in enumerate(history) if n and e and (j == 0 or not history[j - 1][1]))
            assert any(n and not e for n, e in history[:press])
            assert all(e for _, e in history[press:])
        else:
            assert not np.any(out.signal)


def test_gesture_and_stop_edges_survive_several_samples_in_one_tick():
    """A loaded engine drains many samples before one control tick: no edge may be lost."""
    p = InputPipeline()
    p.set_profile(PAD)
    p.feed(s(), 0.001)  # neutral, released
    p.feed(s(enable=True), 0.002)  # pressed at neutral
    p.feed(s(x=0.6, enable=True), 0.003)
    out = p.step(0.004)
    assert out.enabled and out.signal[0] > 0.5
    p.feed(s(x=0.6, enable=True, stop=True), 0.005)  # the stop button pressed and released between ticks
    p.feed(s(x=0.6, enable=True, stop=False), 0.006)
    assert p.step(0.007).stop
    assert not p.step(0.008).stop
