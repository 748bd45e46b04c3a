"""Issue 27 (items 1 and 7): the short version of ``bosun bench plc-soak``.

The lab engine against pyads' own ADS test server playing a misbehaving lab PLC: NaN, ±inf and out-of-range
values, a restart with ``MAIN.bStop`` (and one more symbol) of another size, the link gone, a slow server
and one slower than the ADS timeout — one phase of each.  Nothing unsafe may be seen: no non-finite number
in any snapshot, no command that could start motion taken while the link was not ``ok``, no write that
could start motion received by the PLC whose STOP Bosun could not use, every refusal one line.  The full
10-minute soak is ``bosun bench plc-soak`` (README, docs/safety.md H80).
"""

import pytest

from app.bench.plc_soak import count_numbers, is_rest_write


def test_the_soaks_checks_themselves():
    n, bad = count_numbers({"a": [1.0, float("nan"), True, {"b": float("-inf"), "c": "x"}], "d": 3})
    assert n == 4 and sorted(bad) == [".a[1]", ".a[3].b"]
    assert is_rest_write("MAIN.em8000.bStart", b"\x00") and not is_rest_write("MAIN.em8000.bStart", b"\x01")
    assert is_rest_write("MAIN.winch.u", b"\x00" * 4) and not is_rest_write("MAIN.winch.u", b"\xcd\xcc\xcc\x3d")
    assert not is_rest_write("MAIN.em8000.eModeCmd", b"\x01") and not is_rest_write("MAIN.em8000.eModeCmd", b"\x00")


@pytest.mark.slow
def test_a_short_soak_against_a_misbehaving_plc_sees_nothing_unsafe():
    pytest.importorskip("pyads")
    from app.bench.plc_soak import run
    from app.plc.testplc import TestPlcError

    try:
        rep = run(48.0, seed=1, phase_s=6.0)
    except TestPlcError as err:
        pytest.skip(str(err))
    assert rep.nonfinite_fields == 0, rep.nonfinite_paths
    assert rep.motion_accepted_while_not_ok == []
    assert rep.motion_writes_while_stop_unusable == []
    assert rep.multi_line_refusals == [] and rep.resets_taken_while_stop_unusable == 0
    assert rep.ok and rep.snapshots > 100 and rep.fields_checked > 100 * rep.snapshots
    inj = rep.injections
    assert inj["wrong_sizes"] == 2 and inj["link_gone"] == 1 and inj["slow"] == 1 and inj["slower_than_timeout"] == 1
    assert sum(v for k, v in inj.items() if k.startswith("values_")) > 10
    assert {"STOP unusable", "invalid data", "link down"} <= set(rep.refused_by) and rep.accepted > 0
    assert rep.estops == 1 and rep.resets_refused >= 1 and rep.stop_rewritten_after_fix == 1
    assert {"plc_invalid", "plc_link", "plc_symbols", "plc_error"} <= set(rep.alarms_raised)
