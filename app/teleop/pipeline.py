"""One input pipeline in front of every engine scene: profile → deadzone/expo → deadman → arming → stale halt.

Sanfilippo et al. (§III-A) send a vector s with no semantics from any device; what turns raw
axes into s, and decides whether s may move a machine at all, is the same for the teleop arm,
the crane head and the Motion-Lab.  One :class:`InputPipeline` per engine does it:

1. **Profile.**  The device's TOML profile (by name, else the default) picks, inverts and
   scales axes into s = (x, y, z, w) ∈ [−1, 1]⁴ (w: an auxiliary axis, e.g. the lab winch).
2. **Deadzone and expo** (:func:`~app.teleop.mapping.shape_input`).
3. **Deadman.**  The profile's enable button must be held.
4. **Arming** (zero-position interlock).  After start-up, E-STOP reset, a new operator
   (reconnect), a mode, robot, solver, scaling or profile change, a stale or lost device, or a
   released deadman, the input is *disarmed*: a deflected stick or an enable still held does
   not count.  It arms again only when the stick has been seen at neutral with the enable
   released, and then the enable is pressed while the stick is still at neutral.  A profile
   without an enable button never drives (its stop button still works).
5. **Stale halt.**  A sample counts for ``stale_timeout`` seconds from the engine's *receive*
   time (never the sender's clock), measured on the receiver's clock: stale once the receiver found
   nothing new for that long (a receiver starved by its own engine's load does not make input stale,
   up to ``DEAF_LIMIT``); older, it commands nothing and disarms.
6. **Unplug.**  ``feed(None)`` (device lost) commands nothing and disarms.

The optional stop button of a profile is reported as a rising edge (``stop``): every scene
latches its E-STOP on it, armed or not.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from app.teleop.devices import InputSample
from app.teleop.mapping import shape_input
from app.teleop.profiles import DeviceProfile, default_profile, profile_for

STALE_TIMEOUT = 0.2  # s from the engine's receive time
DEAF_LIMIT = 0.5  # s: a receiver that has not looked for this long counts as hearing nothing


@dataclass(frozen=True)
class InputState:
    """What one pipeline step lets through.

    Attributes
    ----------
    signal : ndarray (4,)
        Shaped s = (x, y, z, w) in [−1, 1]; zero unless ``enabled``.
    raw_signal : ndarray (4,)
        Shaped s before the deadman/arming gate (for display).
    enabled : bool
        Deadman held, input armed, fresh and connected: the scene may move.
    armed : bool
    deadman : bool
        The enable button as read (True for a profile without one).
    stale, connected : bool
    stop, mode_toggle : bool
        Rising edges of the profile's stop and mode buttons in this step.
    reason : str
        Why the input does not move anything ("" when enabled).
    """

    signal: np.ndarray
    raw_signal: np.ndarray
    enabled: bool
    armed: bool
    deadman: bool
    stale: bool
    connected: bool
    stop: bool
    mode_toggle: bool
    reason: str


class InputPipeline:
    """The input chain of one engine (see the module docstring).

    Parameters
    ----------
    stale_timeout : float
        Seconds a sample stays valid after the engine received it (default 0.2).
    axes : int
        How many of s = (x, y, z, w) the scene uses (3 for an arm, 4 with the lab winch); the others
        are passed as zero and need not be at neutral to arm (a throttle lever does not centre).
    note : callable(level, text), optional
        Where device and arming events are logged.
    """

    def __init__(self, stale_timeout: float = STALE_TIMEOUT, note=None, axes: int = 3) -> None:
        self.stale_timeout = float(stale_timeout)
        self.axes = int(axes)  # the scene drives s[:axes]; only those must be at neutral to arm
        self._note = note or (lambda level, text: None)
        self.profile: DeviceProfile = default_profile()
        self.profile_locked = False
        self.sample: InputSample | None = None
        self.sample_time = -math.inf
        self.listened: float | None = None  # the engine's receiver last found nothing waiting (None: no server)
        self.connected = False
        self.armed = False
        self._seen_neutral_released = False
        self._deadman_prev = False
        self._stop_prev = False
        self._mode_prev = False
        self._stop_edge = self._mode_edge = False
        self._raw, self._deadman = np.zeros(4), False
        self.released = False
        self.disarm_reason = "start-up"
        self.stale_count = 0
        self.stale_while_driving = False  # the input went stale while armed (the alarm's condition)
        self._was_stale = True
        self.last: InputState = self._state(np.zeros(4), np.zeros(4), False, False, True, False, False, "no input")

    # ------------------------------------------------------------------ configuration
    def set_profile(self, profile: DeviceProfile | None) -> None:
        """Use this profile for every device (None: pick by device name again)."""
        self.profile_locked = profile is not None
        if profile is not None:
            self.profile = profile
        elif self.sample is not None:
            self.profile = profile_for(self.sample.device, len(self.sample.axes))
        self.disarm("profile changed")

    def disarm(self, reason: str) -> None:
        """Motion needs the stick at neutral and the enable pressed anew."""
        if self.armed:
            self._note("info", f"input disarmed ({reason}): centre the stick and press enable to drive")
        self.armed = False
        self._seen_neutral_released = False
        self.disarm_reason = reason

    # ------------------------------------------------------------------ input
    def feed(self, sample: InputSample | None, now: float, released: bool = False) -> None:
        """A reading of the device (None: unplugged), stamped with the engine's receive time.

        ``released`` with None: the operator turned to another machine (the GUI left this engine's
        tab); it holds and disarms like an unplug, without the device-lost alarm.  The arming
        gesture and the stop / mode button edges are evaluated here, sample by sample, so none is
        lost when several samples arrive within one control tick."""
        if sample is None:
            if self.connected and not released:
                self._note("warning", "input device disconnected: holding")
            self.connected = False
            self.released = released
            self.sample = None
            self.disarm("input released" if released else "device lost")
            return
        self.released = False
        if not self.connected or (self.sample is not None and self.sample.device != sample.device):
            self._note("info", f"input device {sample.device}")
            if not self.profile_locked:
                self.profile = profile_for(sample.device, len(sample.axes))
            self.disarm("new device")
        if self._was_stale:  # back after silence: enable must be pressed anew (buttons held through stay held)
            self.stale_while_driving = False
            self._deadman_prev = False
            self._was_stale = False
        self.connected = True
        self.sample, self.sample_time = sample, now
        self._gesture(sample)

    def _gesture(self, sample: InputSample) -> None:
        prof = self.profile
        raw = shape_input(prof.signal(sample.axes), prof.deadzone, prof.expo)
        raw[self.axes :] = 0.0
        neutral = not np.any(raw)
        has_enable = prof.enable_button is not None
        deadman = has_enable and prof.enabled(sample.buttons)  # no enable button: no deadman, never drives
        b = sample.buttons

        def held(index: int | None) -> bool:
            return index is not None and index < len(b) and bool(b[index])

        stop_btn, mode_btn = held(prof.stop_button), held(prof.mode_button)
        self._stop_edge |= stop_btn and not self._stop_prev
        self._mode_edge |= mode_btn and not self._mode_prev
        self._stop_prev, self._mode_prev = stop_btn, mode_btn
        if self.armed and not deadman:
            self.disarm("enable released")
        if not self.armed:
            if neutral and not deadman:
                self._seen_neutral_released = True
            pressed = deadman and not self._deadman_prev
            if self._seen_neutral_released and neutral and pressed:
                self.armed = True
                self._note("info", "input armed: the operator drives")
        self._deadman_prev = deadman
        self._raw, self._deadman = raw, deadman

    def _state(self, sig, raw, enabled, deadman, stale, stop, mode, reason) -> InputState:
        return InputState(sig, raw, enabled, self.armed, deadman, stale, self.connected, stop, mode, reason)

    def step(self, now: float) -> InputState:
        """Evaluate the chain at engine time ``now``; call once per control tick."""
        stop, mode_toggle = self._stop_edge, self._mode_edge
        self._stop_edge = self._mode_edge = False
        sample = self.sample
        stale = sample is None or (self._receive_clock(now) - self.sample_time) > self.stale_timeout
        if stale:
            if not self._was_stale and sample is not None:
                self.stale_count += 1
                self.stale_while_driving = self.armed  # stale input matters to an operator who was driving
                self._note("warning", f"input stale (nothing for {self.stale_timeout * 1e3:.0f} ms): holding")
            self._was_stale = True
            if self.armed or self._seen_neutral_released:
                self.disarm("stale input" if sample is not None else "no input")
            why = "input device unplugged" if not self.connected and sample is None else "no fresh input"
            self.last = self._state(np.zeros(4), np.zeros(4), False, False, True, stop, False, why)
            return self.last
        raw, deadman = self._raw, self._deadman
        enabled = self.armed and deadman
        if enabled:
            reason = ""
        elif self.profile.enable_button is None:
            reason = f"profile {self.profile.name} has no enable (deadman) button: it cannot drive"
        elif not deadman:
            reason = "enable released"
        else:
            reason = f"{self.disarm_reason}: centre the stick and press enable again"
        sig = raw if enabled else np.zeros(4)
        self.last = self._state(sig, raw, enabled, deadman, False, stop, mode_toggle, reason)
        return self.last

    def _receive_clock(self, now: float) -> float:
        """The time the input's age is measured at: the receiver's, not the tick's (issue 26, item 9).

        The engine's I/O thread stamps :attr:`listened` whenever it finds the request socket empty.  A
        sample is stale when the receiver *looked* and nothing came for ``stale_timeout``; while the
        engine's own load keeps the I/O thread from reading, samples wait in the socket and are not old
        (a steady stick was flagged stale and the Comau stopped mid-move).  A receiver deaf for longer
        than :data:`DEAF_LIMIT` counts as silence: the input is stale then, whatever the reason."""
        if self.listened is None or now - self.listened > DEAF_LIMIT:
            return now
        return min(now, max(self.listened, self.sample_time))

    # ------------------------------------------------------------------ state
    @property
    def lost(self) -> bool:
        """A device that was sending is gone (unplugged or silent link), not deliberately released."""
        return not self.connected and self.sample_time > -math.inf and not self.released

    def flags(self, estop: bool = False) -> dict:
        """Input flags for a snapshot (the fields of ``app.net.snapshots.InputFlags``); ``estop``: the
        scene's latch (nothing is enabled while latched; the latch itself is the snapshot's ``estop``)."""
        s = self.last
        return {
            "stale_input": s.stale,
            "enabled": s.enabled and self.armed and not estop,
            "armed": self.armed,
            "deadman": s.deadman,
            "device": self.connected,
            "device_name": self.sample.device if self.sample is not None else "",
            "profile": self.profile.name,
            "input_reason": s.reason,
            "stale_count": self.stale_count,
        }
