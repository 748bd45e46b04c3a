"""Scenes as diagrams (issue 29, item 3): the data, its check against the blocks, the CLI and the figures."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from app.cli import main
from app.scenes.diagram import DIAGRAMS, LAB_DIAGRAM, Diagram, DiagramError, Node, wire
from app.sim.motionlab import COMAU_DRIVES, WINCH_DRUM

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_every_scene_has_a_diagram_whose_inputs_are_each_fed_once():
    assert set(DIAGRAMS) == {"lab", "tac", "teleop"}
    for d in DIAGRAMS.values():
        d.check()
        fed = [(w.target, p) for w in d.wires for p in w.targets]
        assert sorted(fed) == sorted((n.name, p) for n in d.nodes for p in n.inputs)


def test_the_lab_diagram_holds_its_blocks_ports_and_their_floors():
    drum = LAB_DIAGRAM.node("drum")
    assert drum.block is WINCH_DRUM and drum.inputs == ("L_ref", "L_dot_ref") and drum.floor == "plant"
    floors = {n.name: n.floor for n in LAB_DIAGRAM.nodes}
    assert floors["comau_law"] == floors["winch_law"] == "controller"
    assert floors["drives"] == floors["drum"] == floors["load"] == "plant"
    # controllers live in app.control, plants in app.sim (issue 29, item 2)
    for n in (n for d in DIAGRAMS.values() for n in d.nodes):
        if n.block is not None:
            assert n.where.startswith({"controller": "app.control.", "plant": "app.sim."}[n.floor]), n.name
    # the guards sit between each law and what it drives (H115, H117), each command through its guard only
    order = {n.name: k for k, n in enumerate(LAB_DIAGRAM.nodes)}
    assert order["comau_law"] < order["comau_guard"] < order["drives"]
    assert order["winch_law"] < order["winch_guard"] < order["drum"]
    into = {(w.target, p): w.source for w in LAB_DIAGRAM.wires for p in w.targets}
    assert {into[("drives", p)] for p in COMAU_DRIVES.inputs} == {"comau_guard"}
    assert {into[("drum", p)] for p in WINCH_DRUM.inputs} == {"winch_guard"}
    assert LAB_DIAGRAM.feedback(wire("drives.q -> comau_law.q"))
    assert not LAB_DIAGRAM.feedback(wire("comau_law.q_ref -> drives.q_ref"))


@pytest.mark.parametrize(
    "wires, message",
    [
        (["a.y -> b.u", "a.y -> b.u"], "input b.u is fed by 2 wires"),
        ([], "input b.u is fed by 0 wires"),
        (["a.z -> b.u"], "a has no output 'z'"),
        (["a.y -> b.v"], "b has no input 'v'"),
        (["a.y -> c.u"], "no node 'c'"),
    ],
)
def test_a_diagram_whose_wires_miss_the_ports_is_refused_in_one_line(wires, message):
    nodes = (Node("a", "operator", "x", outputs=("y",)), Node("b", "plant", "x", inputs=("u",)))
    with pytest.raises(DiagramError, match=message.replace("(", r"\(")) as err:
        Diagram("s", "test", nodes, tuple(wire(w) for w in wires))
    assert "\n" not in str(err.value)


def test_describe_prints_the_diagram_and_its_json(capsys):
    assert main(["describe", "--scene", "lab", "--diagram"]) == 0
    out = capsys.readouterr().out
    for n in LAB_DIAGRAM.nodes:
        assert n.name in out
    assert "winch_guard.wire_ref -> drum.(L_ref, L_dot_ref)" in out and "drives.q -> comau_law.q  [feedback]" in out
    assert main(["describe", "--scene", "lab"]) == 0
    assert "wires" not in capsys.readouterr().out
    assert main(["describe", "--scene", "tac", "--diagram", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert {n["name"] for n in data["nodes"]} >= {"vessel", "mru", "pid", "motors"}
    assert {n["name"]: n["where"] for n in data["nodes"] if n["block"]} == {
        "crane_law": "app.control.tac",
        "crane": "app.sim.head",
        "pid": "app.control.tac",
        "motors": "app.sim.head",
        "winch_law": "app.control.tac",  # the crane's winch and load (issue 30, item 3): the lab's blocks reused
        "drum": "app.sim.motionlab",
        "load": "app.sim.motionlab",
    }
    assert any(w["from"] == "pid" and w["to"] == "motors" for w in data["wires"])


def test_describe_refuses_an_unknown_scene_in_one_line(capsys):
    with pytest.raises(SystemExit) as stop:
        main(["describe", "--scene", "harbour", "--diagram"])
    assert stop.value.code == 2
    err = capsys.readouterr().err.strip()
    assert "invalid choice: 'harbour'" in err and len(err.splitlines()) == 1


@pytest.mark.parametrize("scene", sorted(DIAGRAMS))
def test_the_documentation_figures_are_the_diagrams_as_declared(scene):
    """docs/figures/diagram-SCENE.svg is `bosun describe --scene SCENE --svg`: regenerate it after a change."""
    page = (DOCS / "figures" / f"diagram-{scene}.svg").read_text(encoding="utf-8")
    assert page == DIAGRAMS[scene].svg(), (
        f"stale: bosun describe --scene {scene} --svg > docs/figures/diagram-{scene}.svg"
    )
    for n in DIAGRAMS[scene].nodes:
        assert f">{n.name}</text>" in page
