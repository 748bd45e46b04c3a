"""Issue 17, item 3: operability studies on Dask — a 2×2 scatter diagram on a local cluster and through a
scheduler started separately on loopback give identical tables; an interrupted study resumes."""

from __future__ import annotations

import json
import shutil
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from app.analysis.operability import OperabilityError, OperabilityStudy, load_scatter, run_study, save

pytest.importorskip("distributed")

STUDY = OperabilityStudy(mode="tac", headings=(90.0,), seeds=1, duration=20.0, criterion=0.004)


@pytest.fixture
def scatter(tmp_path):
    path = tmp_path / "scatter.csv"
    path.write_text("# a 2 x 2 test diagram\nhs\\tp,7,9\n1.5,30,20\n3.0,30,\n", encoding="utf-8")
    return load_scatter(path)


def _rows(out: Path) -> list[str]:
    return (out / "table.csv").read_text(encoding="utf-8").splitlines()


def test_scatter_loader_normalises_and_refuses_bad_files_in_one_line(tmp_path, scatter):
    assert scatter.hs.tolist() == [1.5, 3.0] and scatter.t.tolist() == [7.0, 9.0] and scatter.period == "tp"
    assert scatter.prob.sum() == pytest.approx(1.0) and scatter.prob[1, 1] == 0.0  # an empty field is 0
    bad = tmp_path / "bad.csv"
    bad.write_text("hs\\tp,7,9\n1.5,0.1,x\n", encoding="utf-8")
    with pytest.raises(OperabilityError, match=r"bad.csv:2: Tp 9 s: 'x' is not a number"):
        load_scatter(bad)
    bad.write_text("hs\\tp,9,7\n1.5,0.1,0.2\n", encoding="utf-8")
    with pytest.raises(OperabilityError, match="peak periods must be positive and increasing"):
        load_scatter(bad)
    with pytest.raises(OperabilityError, match="no such scatter diagram"):
        load_scatter(tmp_path / "none.csv")
    with pytest.raises(OperabilityError, match="headings repeated: 90, 90"):
        OperabilityStudy(headings=(90.0, 90.0))


@pytest.mark.slow
def test_local_cluster_and_loopback_scheduler_give_the_same_table_and_a_study_resumes(tmp_path, scatter):
    local = tmp_path / "local"
    a = run_study(STUDY, scatter, local, workers=2)
    doc = save(a, local)
    assert a.computed == 3 and a.cached == 0 and a.workers == 2  # the cell of probability 0 is not run
    assert {p.name for p in local.iterdir()} >= {"table.csv", "summary.json", "operability_polar.png", "heatmap.png"}
    assert len(_rows(local)) == 4 and doc["simulations"] == 3
    # rms(e_c) ≤ 4 mm is met in some cells and not in others: the operability is a weighted share, not 0 or 1
    ok = [row["workable"] for row in a.table]
    expected = sum(row["probability"] for row in a.table if row["workable"])
    assert any(ok) and not all(ok) and a.operability[90.0] == pytest.approx(expected)
    # the same study through a scheduler and a worker started as their own processes on loopback
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    dask = Path(sys.executable).with_name("dask")
    sched = subprocess.Popen([str(dask), "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    worker = None
    try:
        worker = subprocess.Popen(
            [str(dask), "worker", f"tcp://127.0.0.1:{port}", "--nworkers", "1", "--nthreads", "1", "--no-dashboard"],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )  # fmt: skip
        from distributed import Client

        end = time.monotonic() + 60
        while True:  # the worker has joined the scheduler
            try:
                with Client(f"tcp://127.0.0.1:{port}", timeout="5s") as c:
                    if c.scheduler_info()["workers"]:
                        break
            except OSError:
                pass
            assert time.monotonic() < end, "the loopback scheduler and worker did not start"
            time.sleep(0.5)
        remote = tmp_path / "remote"
        b = run_study(STUDY, scatter, remote, scheduler=f"tcp://127.0.0.1:{port}")
        save(b, remote)
        assert b.computed == 3 and b.scheduler == f"tcp://127.0.0.1:{port}" and b.workers == 1
        assert _rows(remote) == _rows(local)  # identical tables
        assert {c["pid"] for c in b.cells} != {c["pid"] for c in a.cells}  # really other processes
    finally:
        for p in (worker, sched):
            if p is not None:
                p.terminate()
                p.wait(timeout=30)
    # interrupted: one cell lost, one torn mid-write; the study runs those two again and only those
    cells = sorted((local / "cells").glob("*.json"))
    cells[0].unlink()
    cells[1].write_text('{"hs": 1.5, "tp"', encoding="utf-8")
    shutil.rmtree(local / "heatmap.png", ignore_errors=True)
    c = run_study(STUDY, scatter, local, workers=1)
    save(c, local)
    assert c.computed == 2 and c.cached == 1 and _rows(local) == _rows(remote)
    json.loads(cells[1].read_text(encoding="utf-8"))  # rewritten whole


def test_cli_study_refuses_a_missing_scatter_in_one_line(tmp_path):
    res = subprocess.run(
        [sys.executable, "-m", "app", "study", "operability", "--scatter", str(tmp_path / "x.csv"), "--out",
         str(tmp_path / "o")],
        capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert res.returncode == 2 and res.stderr.count("\n") == 1 and "no such scatter diagram" in res.stderr


@pytest.mark.slow
def test_two_columns_that_name_the_same_sea_run_it_once(tmp_path):
    """Review finding: Tz columns closer than the 0.1 ms Tp rounding gave one cache key twice; the study queued
    the simulation twice and its table refused "2 of 1 runs"."""
    path = tmp_path / "tz.csv"
    path.write_text("hs\\tz,7.5,7.500001\n2,1,1\n", encoding="utf-8")
    st = OperabilityStudy(mode="tac", headings=(180.0,), seeds=1, duration=2.0, spectrum="pm")
    res = run_study(st, load_scatter(path), tmp_path / "out", workers=1)
    assert res.computed == 1 and len(res.table) == 2 and res.table[0]["tp"] == res.table[1]["tp"]
    assert res.table[0]["rms_e_c_m"] == res.table[1]["rms_e_c_m"]
