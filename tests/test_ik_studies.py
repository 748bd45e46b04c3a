"""Error distribution (Fig. 5), trajectory tracking (Fig. 4), the IK benchmark and their CLI."""

import csv
import json

import numpy as np
import pytest

from app.analysis.ik_studies import bench_ik, error_distribution, track, tracking_path
from app.cli import main
from app.models import load_robot


def test_error_distribution_grid_and_outputs(tmp_path):
    robot = load_robot("offshore_crane")
    seen = []
    res = error_distribution(robot, "analytic", grid=4, progress=lambda d, t: seen.append((d, t)))
    assert res.complete and len(res.targets) == 64 and seen[-1] == (64, 64)
    # the grid spans the box, corners included
    np.testing.assert_allclose(res.targets.min(axis=0), res.box_lower)
    np.testing.assert_allclose(res.targets.max(axis=0), res.box_upper)
    assert np.all(res.success <= res.reachable)  # solved implies reachable
    assert np.all(res.error[res.success] < 1e-6)
    s = res.summary()
    assert s["targets"] == 64 and s["reachable"] == int(res.reachable.sum()) and 0 < s["reachable"] < 64
    assert s["success"] == s["reachable"]  # the closed form solves every reachable target
    res.write_csv(tmp_path / "e.csv")
    with open(tmp_path / "e.csv", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    assert len(rows) == 65 and rows[0][:3] == ["target_x", "target_y", "target_z"]


def test_error_distribution_cancel_keeps_done_rows():
    robot = load_robot("scara")
    done = []
    res = error_distribution(
        robot,
        "jacobian",
        grid=3,
        solver_options={"time_budget": 0.01},
        progress=lambda d, t: done.append(d),
        cancelled=lambda: len(done) >= 5,
    )
    assert not res.complete and len(res.targets) == 5 and len(res.reachable) == 5


def test_grid_size_checked():
    with pytest.raises(ValueError, match="grid must be between 2 and 40"):
        error_distribution(load_robot("scara"), "jacobian", grid=1)


def test_tracking_path_is_reachable_and_tracked_exactly_by_analytic():
    robot = load_robot("comau_smart5_3dof")
    t, path = tracking_path(robot, duration=5.0, dt=0.1)
    assert len(t) == 51 and path.shape == (51, 3)
    res = track(robot, "analytic", duration=5.0, dt=0.1)
    assert res.success.all() and res.error.max() < 1e-9
    assert np.all(robot.within_limits(res.q))


def test_tracking_with_jacobian_warm_start():
    robot = load_robot("kuka_youbot")
    res = track(robot, "jacobian", duration=4.0, dt=0.1, solver_options={"time_budget": None})
    assert res.success.all() and res.summary()["rms_error_m"] < 1e-4


def test_bench_ik_rows():
    rows = bench_ik([load_robot("offshore_crane")], targets=5)
    assert [(r["solver"], r["start"]) for r in rows] == [
        (s, m) for s in ("ga", "ga-restart", "jacobian", "analytic") for m in ("cold", "warm")
    ]
    for r in rows:
        assert r["targets"] == 5 and 0 <= r["success_rate"] <= 1 and r["p99_ms"] >= r["p95_ms"] >= r["median_ms"] > 0
    assert rows[6]["success_rate"] == rows[7]["success_rate"] == 1.0  # analytic: exact, inside the limits


def test_warm_targets_are_one_centimetre_apart_and_reachable():
    from app.analysis.ik_studies import warm_path

    robot = load_robot("kuka_youbot")
    X = warm_path(robot, 200, np.random.default_rng(1))
    gaps = np.linalg.norm(np.diff(X, axis=0), axis=1)
    assert X.shape == (200, 3) and np.median(gaps) == pytest.approx(0.01, rel=0.05) and gaps.max() < 0.03


# ------------------------------------------------------------------ CLI
def test_cli_ik_solved_and_not_solved(capsys):
    assert main(["ik", "comau_smart5_3dof", "--target", "2", "0.5", "1.5", "--solver", "analytic", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["success"] and data["error_m"] < 1e-9 and len(data["q"]) == 3
    assert main(["ik", "scara", "--target", "5", "5", "5", "--solver", "jacobian", "--time-budget", "0.02"]) == 1
    out = capsys.readouterr().out
    assert "NOT solved" in out and "error = 7.95 m" in out


def test_cli_ik_q0_in_degrees(capsys):
    code = main(
        [
            "ik",
            "comau_smart5_3dof",
            "--solver",
            "jacobian",
            "--target",
            "2",
            "0.5",
            "1.5",
            "--q0",
            "0",
            "0",
            "-90",
            "--deg",
            "--json",
        ]
    )
    assert code == 0 and json.loads(capsys.readouterr().out)["success"]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["ik", "scara", "--target", "1", "2", "3", "--solver", "ga", "--elbow", "up"], "--elbow applies to"),
        (["ik", "kuka_youbot", "--target", "0.2", "0", "0.3", "--solver", "analytic"], "no closed-form solution"),
        (["ik", "scara", "--target", "1", "2"], "argument --target: expected 3 arguments"),
        (["ik", "scara", "--target", "1", "2", "3", "--solver", "magic"], "invalid choice: 'magic'"),
        (["ik", "scara", "--target", "1", "2", "3", "--time-budget", "0"], "'0' must be positive"),
        (["ik", "scara", "--target", "1", "2", "3", "--q0", "1"], "scara has 4 joints"),
        (["analyze", "scara", "--grid", "1"], "argument --grid: invalid choice"),
    ],
)
def test_cli_ik_errors(capsys, argv, message):
    try:
        code = main(argv)
    except SystemExit as exc:
        code = exc.code
    assert code == 2
    err = capsys.readouterr().err
    assert message in err and err.count("\n") == 1


def test_cli_analyze_and_track_write_files(capsys, tmp_path):
    out = tmp_path / "a"
    assert main(["analyze", "offshore_crane", "--solver", "analytic", "--grid", "2", "--out", str(out), "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["targets"] == 8
    for f in ("error_distribution.csv", "error_distribution.png", "summary.json"):
        assert (out / f).stat().st_size > 0
    assert (out / "error_distribution.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    out = tmp_path / "t"
    assert main(["track", "scara", "--solver", "jacobian", "--duration", "2", "--out", str(out)]) == 0
    assert "rms error" in capsys.readouterr().out
    with open(out / "tracking.csv", encoding="utf-8") as f:
        assert len(list(csv.reader(f))) == 22
    assert (out / "tracking.png").read_bytes()[:4] == b"\x89PNG"


def test_cli_bench_ik_json(capsys):
    assert main(["bench", "ik", "--targets", "2", "--robots", "scara", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["benchmark"] == "ik" and {r["solver"] for r in data["results"]} == {"ga", "ga-restart", "jacobian"}
    assert "cores" in data["machine"]
