"""Issue 30, item 3: a suspended load on the offshore crane: the wire over a winch with its limits, the hook and
payload as a pendulum driven by the head TCP's acceleration, and the winch's active heave compensation (AHC)."""

import numpy as np
import pytest

from app.scenarios.tac import TacScenario, TacSimulator
from app.scenes.crane_load import CraneLoad, WinchSpec

DT = 0.01


def _run(mode: str, seconds: float, ahc: bool, speed: float = 0.0, hs: float = 3.0, seed: int = 1):
    sim = TacSimulator(TacScenario(duration=seconds + 1.0, hs=hs, mode=mode, seed=seed))
    load = CraneLoad(ahc=ahc, speed_command=speed)
    hooks, tcps, lengths, rates, swings = [], [], [], [], []
    while not sim.done:
        c = sim.advance(50)
        for p in c.p_c_n:
            load.step(p, DT)
            tcps.append(p)
            hooks.append(load.hook(p))
            lengths.append(load.length)
            rates.append(load.length_rate)
            swings.append(load.swing_angle())
    return load, *(np.array(a) for a in (hooks, tcps, lengths, rates, swings))


def test_the_winchs_heave_compensation_holds_the_hook_while_the_tcp_heaves():
    """The TCP heaving 1 m at 9 s (no sideways motion: no swing): the AHC winch keeps the hook's height in the
    world within a few centimetres; without it the hook heaves with the TCP."""
    t = np.arange(0.0, 60.0, DT)
    z = -20.0 + 1.0 * np.sin(2 * np.pi * t / 9.0)
    out = {}
    for ahc in (True, False):
        load = CraneLoad(ahc=ahc)
        hook = []
        for zk in z:
            p = np.array([0.0, 0.0, zk])
            load.step(p, DT)
            hook.append(load.hook(p)[2])
        out[ahc] = np.array(hook)[1000:]
    assert np.std(out[False]) > 0.65  # 1 m amplitude: 0.71 m rms
    assert np.max(np.abs(out[True] - np.mean(out[True]))) < 0.05, np.max(np.abs(out[True] - np.mean(out[True])))


@pytest.mark.parametrize("fade", [True, False])
def test_the_heave_compensation_switched_on_or_off_eases_in(fade):
    """H108: switched on under a hook that rides a heaving TCP, the AHC stepped the drum's rate from 0 to the TCP's
    heave rate (about 0.7 m/s here) in one step, a jerk the wire rings with; switched off it let go at once.  With
    ``ahc_ease`` it fades over seconds both ways: no step of the drum's rate over what its acceleration limit gives
    in a few steps, and once faded it holds the hook (on) or leaves the wire's length (off).  Without the fade
    (``ahc_ease`` 0, the old behaviour) the step is there: the test's own check."""
    t = np.arange(0.0, 40.0, DT)
    z = -20.0 + 1.0 * np.sin(2 * np.pi * t / 9.0)
    load = CraneLoad(spec=WinchSpec(ahc_ease=5.0 if fade else 0.0), ahc=False)
    hook = []
    for k, zk in enumerate(z):
        load.ahc = 1000 <= k < 2500  # on at 10 s, off at 25 s
        p = np.array([0.0, 0.0, zk])
        load.step(p, DT)
        hook.append((load.length_rate, load.hook(p)[2]))
    rate, hz = np.array(hook).T
    jump = max(np.max(np.abs(np.diff(rate[995:1010]))), np.max(np.abs(np.diff(rate[2495:2510]))))
    if fade:
        assert jump < 0.01, jump  # about 1 mm/s a step: the fade's own acceleration
        assert np.ptp(hz[2000:2500]) < 0.1  # eased in: the hook held in the world
        assert np.ptp(hz[3100:]) > 1.5  # eased out: riding the TCP's 2 m heave again
    else:
        assert jump >= 0.015, jump  # the drum's acceleration limit over one step: 2 m/s² × 0.01 s


def test_in_waves_the_winch_follows_its_compensation_and_stays_in_its_limits():
    """Mode off, Hs 3 m beam sea: the wire follows the AHC's length (the hook's height target minus the TCP's)
    to centimetres, within the winch's length and speed limits; what the hook still does vertically is its swing."""
    load, _, tcp, L, rates, swing = _run("off", 60.0, ahc=True)
    assert np.std(tcp[2000:, 2]) > 0.3  # the TCP heaves
    z_target = load.law[0]
    follow = L[2000:] - (z_target - tcp[2000:, 2])
    assert np.max(np.abs(follow)) < 0.1, np.max(np.abs(follow))
    assert np.all((L >= 3.0 - 1e-9) & (L <= 40.0 + 1e-9)) and np.max(np.abs(rates)) <= WinchSpec().speed + 1e-9
    assert np.max(swing) > 0.05  # the vessel's roll swings the load: the anti-swing law's job (item 3)


def test_the_operators_winch_speed_lowers_the_hook_in_the_world_within_the_winchs_limits():
    _, hook, _, L, rates, _ = _run("tac", 20.0, ahc=True, speed=0.5, hs=1.0)
    s = slice(500, None)
    fall = np.polyfit(np.arange(len(hook))[s] * DT, hook[s, 2], 1)[0]  # NED: lowering is +z
    assert fall == pytest.approx(0.5, abs=0.05)
    assert np.max(np.abs(rates)) <= WinchSpec().speed * (1 + 1e-9)
    assert np.all(np.diff(L) / DT <= WinchSpec().speed + 1e-9)


def test_the_load_swings_when_the_tcp_moves_and_hangs_still_when_it_is_held():
    """The pendulum is driven by the TCP: riding the vessel (off) the load swings; with the head holding the TCP
    still in the world (tac) it hangs almost still."""
    *_, swing_off = _run("off", 40.0, ahc=True)
    *_, swing_tac = _run("tac", 40.0, ahc=True)
    assert np.max(swing_off) > 5 * np.max(swing_tac[500:]), (np.max(swing_off), np.max(swing_tac[500:]))


def test_the_tension_of_a_still_hanging_load_is_its_weight():
    load = CraneLoad()
    for _ in range(100):
        load.step(np.array([0.0, 0.0, -20.0]), DT)
    assert load.tension == pytest.approx(load.static_tension(), rel=1e-9)


def test_the_crane_head_engine_carries_the_load_and_the_sticks_w_lowers_it():
    """Through the engine (issue 30, items 2 and 3): the snapshot reports the load; armed, the stick's w pays out and
    the hook goes down in the world with the AHC on (tac); an E-STOP holds the wire where it is."""
    from app.engine.tac_session import WINCH_SPEED, TacSession
    from app.teleop.devices import InputSample
    from tests.test_crane_stick import arm, run

    ses = TacSession(scenario=TacScenario(duration=1e5, hs=1.0, mode="tac"))
    t = run(ses, 2.0)
    load = ses.snapshot().load
    assert load is not None and load.ahc and load.wire_length == pytest.approx(10.0, abs=0.05)
    assert load.tension_factor == pytest.approx(1.0, abs=0.05)
    hook0 = np.array(load.hook)
    t = arm(ses, t)
    lower = InputSample((0.0, 0.0, 0.0, 0.5), (True, False), "test stick")
    t = run(ses, 2.0, lower, t)
    d = np.array(ses.snapshot().load.hook) - hook0
    w = (0.5 - 0.1) / 0.9  # the default profile's deadzone 0.1, rescaled
    assert d[2] == pytest.approx(w * WINCH_SPEED * 2.0, abs=0.05), d  # NED: down is +z
    assert np.array(ses.snapshot().scene.hook) == pytest.approx(np.array(ses.snapshot().load.hook), abs=1e-3)
    ses.estop()
    t = run(ses, 1.0, lower, t)
    L = ses.snapshot().load.wire_length
    run(ses, 1.0, lower, t)
    assert ses.snapshot().load.wire_length == pytest.approx(L, abs=1e-3) and not ses.snapshot().load.ahc


def test_heave_compensation_switched_back_on_holds_the_hook_where_it_is_then():
    """AHC off while the hook is lowered by hand, then on again: the winch holds the hook's new height; it does not
    haul it back to the height it had when AHC was last on (an unbidden move)."""
    load = CraneLoad()
    p = np.array([0.0, 0.0, -20.0])
    for _ in range(100):
        load.step(p, DT)
    load.ahc, load.speed_command = False, 0.5
    for _ in range(200):  # 2 s paying out by hand: the hook 1 m lower
        load.step(p, DT)
    load.speed_command = 0.0
    for _ in range(100):
        load.step(p, DT)
    L = load.length
    load.ahc = True
    rates = []
    for _ in range(200):
        load.step(p, DT)
        rates.append(abs(load.length_rate))
    assert max(rates) < 1e-6 and load.length == pytest.approx(L, abs=1e-6)
