"""Issue 30, item 5 in the lab engine: the simulated Motion-Lab's load rides the crane's elastic wire and lands on
EM1500's deck (app/scenes/lab_load.py wired into LabSession); the engine reports the landing in its snapshot
(``LabSnapshot.load``) and raises the landing alarms (slack wire, snap load, re-hit, sideways contact)."""

import numpy as np

from app.engine.lab_session import LabSession
from app.teleop.devices import InputSample

DT = 0.02


class Rig:
    def __init__(self) -> None:
        self.s = LabSession()
        self.t = 0.0

    def run(self, seconds: float, axes=(0.0, 0.0, 0.0, 0.0), enable: bool = False) -> None:
        for _ in range(round(seconds / DT)):
            self.t += DT
            self.s.feed(InputSample(tuple(axes), (enable, False), "test"), self.t)
            self.s.tick(self.t, DT)

    def raised(self) -> "Rig":
        for p in self.s.names:
            self.s.lab_platform(p, "neutral")
        self.run(16.0)
        return self

    def arm(self) -> None:
        """Centred, the deadman released and pressed again: the pipeline arms on the press."""
        self.run(0.1, enable=False)
        self.run(0.4, enable=True)

    def alarms(self) -> set[str]:
        return {a.key for a in self.s.snapshot().alarms if a.active}


def test_the_operator_lowers_the_load_onto_em1500_and_the_engine_reports_the_landing():
    rig = Rig().raised()
    s = rig.s
    snap = s.snapshot()
    assert snap.load is not None and snap.load.clearance is not None and snap.load.clearance > 0.3
    assert not snap.load.landed and snap.load.tension_factor == np.float64(snap.load.tension_factor)
    s.lab_vvmc(True)
    rig.arm()
    seen_clearance = []
    for _ in range(100):  # w pays out: the winch lowers the load relative to EM1500's deck (0.2 m/s at full stick)
        rig.run(0.2, axes=(0.0, 0.0, 0.0, 0.5), enable=True)
        ld = s.snapshot().load
        seen_clearance.append(ld.clearance)
        if ld.contact:
            break
    ld = s.snapshot().load
    assert ld.contact and ld.landed and ld.rehits == 0, ld
    assert ld.clearance is not None and -0.003 < ld.clearance <= 0.0  # on the deck, about a millimetre in
    assert max(c for c in seen_clearance if c is not None) > 0.05  # it came down from above
    rig.run(2.0, enable=True)  # centred: the load rests there, the wire taking part of it
    ld = s.snapshot().load
    assert ld.landed and ld.contact
    active = rig.alarms()
    assert not active & {"payload_below_deck", "snap_load", "slack_wire", "rehit"}, active
    # hauled in, the load lifts off and, half a metre clear, a new landing begins
    rig.run(5.0, axes=(0.0, 0.0, 0.0, -1.0), enable=True)
    ld = s.snapshot().load
    assert not ld.contact and not ld.landed and ld.clearance > 0.5


def test_a_load_left_on_a_heaving_deck_without_compensation_is_re_hit_and_the_alarm_says_so():
    """VVMC off, the winch holding: EM1500 in waves lifts the landed load and drops away under it, and the deck
    strikes it again: the engine counts the re-hits and raises the re-hit alarm (H102)."""
    rig = Rig().raised()
    s = rig.s
    s.lab_winch(mode="remote")
    rig.arm()
    for _ in range(100):
        rig.run(0.2, axes=(0.0, 0.0, 0.0, 0.5), enable=True)
        if s.snapshot().load.contact:
            break
    rig.run(0.1, enable=True)  # stop paying out the moment it lands: the wire nearly taut over a heaving deck
    assert s.snapshot().load.landed
    s.lab_source("em1500", "simulation", hs=2.0, tp=8.0, heading=90.0, seed=3)
    s.lab_platform("em1500", "engage")
    raised = set()
    for _ in range(60):
        rig.run(0.5)
        raised |= rig.alarms()
    ld = s.snapshot().load
    assert ld.rehits >= 1 and "rehit" in raised, (ld, raised)
    assert "payload_below_deck" not in raised


def test_vvmc_engages_without_snatching_the_load():
    """H106: EM8000 in waves (Hs 2.5 m) carries the Comau's tool off the work point and sets it moving; VVMC
    switched on stepped the tool onto the point at once and the load's stiff wire rang to 1.6–1.9× the load's
    weight, slack between (Snap load, critical).  Now it engages from where the tool is, at the speed it has: the
    wire stays under the snap limit and never slack, no landing alarm is raised, and the tool is on the work point
    once the engagement is over."""
    rig = Rig().raised()
    s = rig.s
    s.lab_source("em8000", "simulation", hs=2.5, tp=8.0, heading=150.0, seed=1)
    s.lab_platform("em8000", "engage")
    s.lab_platform("em1500", "engage")
    rig.run(3.0)
    off = np.linalg.norm(s.lab.last.e_t_b2)
    assert off > 0.02, off  # the tool is off the work point before VVMC
    tension, raised = [], set()
    after = s._after_step

    def watch(dt):
        after(dt)
        tension.append(s.load.tension / s.load.static_tension())

    s.plant.after_step = watch
    s.lab_vvmc(True)
    for _ in range(20):
        rig.run(0.5)
        raised |= rig.alarms()
    assert max(tension) < 1.5 and min(tension) > 0.1, (max(tension), min(tension))
    assert not raised & {"snap_load", "slack_wire"}, raised
    assert not s.lab.engagement()[0].any()  # engaged
    assert np.linalg.norm(s.lab.last.e_t_b2) < 0.005


def test_in_the_lab_s_world_frame_vvmc_holds_the_tool_still_in_the_lab():
    """Item 1 in the lab: under VVMC the frame ``world`` holds the Comau's tool still in the lab's world while
    both platforms move (only EM8000's motion compensated: the lab's TAC), where ``target`` holds it on EM1500's
    moving work point; the switch disarms the stick and the tool does not jump."""
    rig = Rig().raised()
    s = rig.s
    for k, p in enumerate(s.names):
        s.lab_source(p, "simulation", hs=2.5, tp=8.0, heading=150.0 - 60.0 * k, seed=1 + k)
        s.lab_platform(p, "engage")
    rig.run(5.0)
    s.lab_vvmc(True)
    rig.run(12.0)  # engaged
    sweep = {}
    for frame in ("target", "world"):
        s.set_frame(frame)
        assert s.snapshot().frame == frame and not s.snapshot().flags.armed
        before = s.lab.p_t_g.copy()
        rig.run(0.05)
        assert np.linalg.norm(s.lab.p_t_g - before) < 0.02  # no jump at the switch (EM1500 moves ≤ 0.3 m/s)
        rig.run(3.0)
        pts = []
        for _ in range(200):
            rig.run(0.05)
            pts.append(s.lab.p_t_g.copy())
        sweep[frame] = float(np.max(np.ptp(np.array(pts), axis=0)))
    assert sweep["world"] < 0.005 and sweep["target"] > 20 * sweep["world"], sweep
