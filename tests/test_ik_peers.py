"""Issue 14, item 2: ``bosun bench ik --peers`` hands each library robot to robotics-toolbox-python and
ikpy as the same kinematic chain and judges their answers with Bosun's own forward kinematics."""

import json

import numpy as np
import pytest

from app.models.registry import list_robots, load_robot, load_spec

pytest.importorskip("roboticstoolbox")
pytest.importorskip("ikpy")

from app.analysis.ik_peers import LinkChain, Peer, ikpy_chain, rtb_model

SERIAL = [n for n in list_robots() if load_spec(n).type == "serial"]


@pytest.mark.parametrize("name", SERIAL)
def test_the_peers_models_are_the_library_robot(name):
    """The toolbox's ETS robot and ikpy's URDF chain put the tool where Bosun does (couplings, fixed
    links, prismatic joints, base and tool transforms included), at random poses inside the limits."""
    robot = load_robot(name)
    chain = LinkChain(robot)
    model, ik_chain = rtb_model(chain), ikpy_chain(chain)
    rng = np.random.default_rng(3)
    for q in rng.uniform(robot.lower, robot.upper, size=(20, robot.n_joints)):
        u = chain.u_of(q)
        np.testing.assert_allclose(chain.q_of(u), q, atol=1e-12)
        np.testing.assert_allclose(model.fkine(u).A[:3, 3], robot.position(q), atol=1e-9)
        np.testing.assert_allclose(ik_chain.forward_kinematics(np.r_[u, 0.0])[:3, 3], robot.position(q), atol=1e-9)


@pytest.mark.parametrize("name", ["comau_smart5_3dof", "kuka_youbot"])
def test_the_toolbox_cpp_solver_reaches_reachable_targets(name):
    robot = load_robot(name)
    peer = Peer("rtb ik_LM", robot)
    rng = np.random.default_rng(5)
    q0 = robot.clip(0.5 * (robot.lower + robot.upper))
    hits = 0
    for x in robot.position(rng.uniform(robot.lower, robot.upper, size=(10, robot.n_joints))):
        q = peer.solve(x, q0)
        hits += np.linalg.norm(robot.position(q) - x) < 1e-3 and bool(np.all(robot.within_limits(q, tol=1e-9)))
    assert hits >= 8


@pytest.mark.slow
def test_bench_ik_peers_reports_every_peer_with_its_ratio_to_the_toolbox(capsys):
    from app.cli import main

    assert main(["bench", "ik", "--peers", "--targets", "6", "--robots", "scara", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    solvers = {(r["solver"], r["start"]) for r in out["results"]}
    for peer in ("rtb ik_LM", "rtb ikine_LM", "ikpy"):
        assert {(peer, "cold"), (peer, "warm")} <= solvers
    assert all(r["ratio_to_rtb_cpp"] > 0 for r in out["results"])
    assert out["peers_missing"] == []
