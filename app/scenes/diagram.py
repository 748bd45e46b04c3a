"""Scenes as diagrams (issue 29, item 3): the blocks of a scene and the wires between them, as data.

A :class:`Diagram` lists its nodes in the order a step runs them and its wires, each from one node's output
ports to one input port of another.  A node is a block (:class:`app.models.block.Block`: its ports are the
block's inputs and outputs) or a part of the scene that is not (yet) one, declared with its ports: the
operator's input, a sensor, a solver.  :meth:`Diagram.check` holds the data to the blocks: every port a wire
names exists, and every input of every node is fed by exactly one wire.

The same data gives ``bosun describe --scene NAME --diagram`` (:meth:`Diagram.text`), a JSON form and the
documentation's figures (:meth:`Diagram.svg`, ``docs/figures/diagram-NAME.svg``; a test keeps them equal).

Floors: ``operator`` (what a person commands), ``controller`` (app.control, app.teleop, app.ik), ``plant``
(app.sim, app.marine: what moves) and ``sensor`` (what measures it: an MRU, a tracker, the kinematics that
give a tool point from joints).  A wire that runs against the step order is feedback: its value is the one
of the previous step.
"""

from __future__ import annotations

import html
from dataclasses import dataclass, field

from app.control.antisway import SWING_CONTROL
from app.control.lab import COMAU_GUARD, COMAU_LAW, WINCH_GUARD, WINCH_LAW
from app.control.tac import CRANE_AHC, CRANE_LAW, HEAD_PID
from app.errors import BosunError
from app.models.block import Block
from app.sim.actuators import JOINT_ACTUATORS
from app.sim.head import CRANE_JOINTS, HEAD_MOTORS
from app.sim.motionlab import COMAU_DRIVES, PENDULUM, WINCH_DRUM

FLOORS = ("operator", "controller", "plant", "sensor")


class DiagramError(BosunError):
    """A diagram whose wires do not match its nodes' ports (one line)."""


@dataclass(frozen=True)
class Node:
    """One node of a diagram: ``name`` (its id in wires), ``floor`` (:data:`FLOORS`), ``where`` (the module
    that implements it), ``block`` (if it is one) or its declared ``inputs`` and ``outputs``."""

    name: str
    floor: str
    where: str
    block: Block | None = None
    inputs: tuple[str, ...] = ()
    outputs: tuple[str, ...] = ()
    note: str = ""

    def __post_init__(self) -> None:
        if self.floor not in FLOORS:
            raise DiagramError(f"node {self.name}: floor must be one of {', '.join(FLOORS)}, got {self.floor!r}")
        if self.block is not None:
            object.__setattr__(self, "inputs", self.block.inputs)
            object.__setattr__(self, "outputs", self.block.outputs)

    @property
    def title(self) -> str:
        return self.note or (self.block.name if self.block is not None else self.name)


@dataclass(frozen=True)
class Wire:
    """Outputs ``ports`` of node ``source`` into input ``port`` of node ``target`` (several outputs make one
    record input, e.g. the load's (α, β) into the winch law's ``swing``), or one record output into the several
    inputs ``port`` (comma-separated) it holds, in order (a guard's ``command`` into the drives' five inputs)."""

    source: str
    ports: tuple[str, ...]
    target: str
    port: str

    @property
    def targets(self) -> tuple[str, ...]:
        """The input ports this wire feeds."""
        return tuple(p.strip() for p in self.port.split(","))

    def label(self) -> str:
        src = self.ports[0] if len(self.ports) == 1 else "(" + ", ".join(self.ports) + ")"
        dst = self.port if len(self.targets) == 1 else "(" + ", ".join(self.targets) + ")"
        return f"{self.source}.{src} -> {self.target}.{dst}"


def wire(text: str) -> Wire:
    """``"source.a,b -> target.port"`` (or ``"source.record -> target.a,b"``) as a :class:`Wire`."""
    left, right = (s.strip() for s in text.split("->"))
    source, ports = left.split(".", 1)
    target, port = right.split(".", 1)
    if "," in ports and "," in port:
        raise DiagramError(f"wire {text}: several outputs into several inputs (one side must be one port)")
    return Wire(
        source, tuple(p.strip() for p in ports.split(",")), target, ",".join(p.strip() for p in port.split(","))
    )


def part(name: str, floor: str, where: str, ports: str, note: str = "") -> Node:
    """A node that is not a block, its ports declared as ``"in, … -> out, …"`` (either side may be empty)."""
    left, right = (tuple(p.strip() for p in side.split(",") if p.strip()) for side in ports.split("->"))
    return Node(name, floor, where, inputs=left, outputs=right, note=note)


@dataclass(frozen=True)
class Diagram:
    """A scene's nodes, in step order, and wires (see the module text)."""

    scene: str
    summary: str
    nodes: tuple[Node, ...]
    wires: tuple[Wire, ...]
    runs: str = ""  # what runs the diagram (the compiled step and its reference)
    index: dict[str, int] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "index", {n.name: k for k, n in enumerate(self.nodes)})
        self.check()

    def node(self, name: str) -> Node:
        return self.nodes[self.index[name]]

    def check(self) -> None:
        """Every wire joins existing ports, and every node input is fed by exactly one wire."""
        if len(self.index) != len(self.nodes):
            raise DiagramError(f"{self.scene}: two nodes share a name")
        fed: dict[tuple[str, str], int] = {}
        for w in self.wires:
            for end in (w.source, w.target):
                if end not in self.index:
                    raise DiagramError(f"{self.scene}: wire {w.label()}: no node {end!r}")
            missing = [p for p in w.ports if p not in self.node(w.source).outputs]
            if missing:
                raise DiagramError(f"{self.scene}: wire {w.label()}: {w.source} has no output {missing[0]!r}")
            for port in w.targets:
                if port not in self.node(w.target).inputs:
                    raise DiagramError(f"{self.scene}: wire {w.label()}: {w.target} has no input {port!r}")
                fed[(w.target, port)] = fed.get((w.target, port), 0) + 1
        for n in self.nodes:
            for port in n.inputs:
                count = fed.get((n.name, port), 0)
                if count != 1:
                    raise DiagramError(f"{self.scene}: input {n.name}.{port} is fed by {count} wires (one needed)")

    def feedback(self, w: Wire) -> bool:
        """Whether ``w`` runs against the step order (its value is the previous step's)."""
        return self.index[w.source] >= self.index[w.target]

    # ------------------------------------------------------------------ renderings
    def text(self) -> str:
        """The diagram for a terminal: the nodes in step order with their floor and module, then the wires."""
        lines = [f"scene {self.scene}: {self.summary}"]
        if self.runs:
            lines.append(f"runs: {self.runs}")
        lines += ["", "blocks, in step order:"]
        width = max(len(n.name) for n in self.nodes)
        for k, n in enumerate(self.nodes, 1):
            lines.append(f"  {k:2d}. {n.name:<{width}}  {n.floor:<10}  {n.title}  ({n.where})")
            if n.block is not None and n.block.state:
                lines.append(f"      {'':<{width}}  state: {', '.join(n.block.state)}")
        lines += ["", "wires ([feedback]: the previous step's value):"]
        for w in self.wires:
            lines.append(f"  {w.label()}{'  [feedback]' if self.feedback(w) else ''}")
        return "\n".join(lines) + "\n"

    def as_dict(self) -> dict:
        return {
            "scene": self.scene,
            "summary": self.summary,
            "runs": self.runs,
            "nodes": [
                {
                    "name": n.name,
                    "floor": n.floor,
                    "title": n.title,
                    "where": n.where,
                    "block": n.block is not None,
                    "state": list(n.block.state) if n.block is not None else [],
                    "inputs": list(n.inputs),
                    "outputs": list(n.outputs),
                    "params": list(n.block.params) if n.block is not None else [],
                }
                for n in self.nodes
            ],
            "wires": [
                {
                    "from": w.source,
                    "ports": list(w.ports),
                    "to": w.target,
                    "port": w.port,
                    "to_ports": list(w.targets),
                    "feedback": self.feedback(w),
                }
                for w in self.wires
            ],
        }

    def svg(self) -> str:
        """The diagram as an SVG figure: one lane per floor, the nodes left to right in step order, the wires
        as arrows (feedback dashed, below the boxes).  Plain text, the same bytes for the same data."""
        box_w, box_h, gap, lane_h, left, top = 150, 46, 24, 92, 96, 40
        lanes = [f for f in FLOORS if any(n.floor == f for n in self.nodes)]
        pos = {}
        for k, n in enumerate(self.nodes):
            pos[n.name] = (left + k * (box_w + gap), top + lanes.index(n.floor) * lane_h)
        width = left + len(self.nodes) * (box_w + gap) + 10
        height = top + len(lanes) * lane_h + 30
        colours = {"operator": "#fde9c8", "controller": "#d6e8fa", "plant": "#dff2d8", "sensor": "#efe1f5"}
        out = [
            f'<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{height}" '
            f'viewBox="0 0 {width} {height}" font-family="sans-serif" font-size="11">',
            '<defs><marker id="arrow" viewBox="0 0 10 10" refX="9" refY="5" markerWidth="7" markerHeight="7" '
            'orient="auto-start-reverse"><path d="M 0 0 L 10 5 L 0 10 z" fill="#444"/></marker></defs>',
            f'<text x="10" y="22" font-size="14" font-weight="bold">{html.escape(self.scene)}: '
            f"{html.escape(self.summary)}</text>",
        ]
        for i, lane in enumerate(lanes):
            y = top + i * lane_h
            out.append(f'<rect x="4" y="{y - 6}" width="{width - 8}" height="{lane_h - 12}" fill="none" '
                       'stroke="#ddd" stroke-dasharray="3,3"/>')  # fmt: skip
            out.append(f'<text x="10" y="{y + box_h / 2 + 4:.0f}" fill="#666">{lane}</text>')
        for w in self.wires:
            (x0, y0), (x1, y1) = pos[w.source], pos[w.target]
            if self.feedback(w):
                sx, sy, tx, ty = x0 + box_w / 2, y0 + box_h, x1 + box_w / 2, y1 + box_h
                drop = max(sy, ty) + 14 + 4 * (self.index[w.source] % 4)
                d = f"M {sx:.0f} {sy:.0f} C {sx:.0f} {drop:.0f} {tx:.0f} {drop:.0f} {tx:.0f} {ty:.0f}"
                style = 'stroke="#b55" stroke-dasharray="4,3"'
            elif y0 == y1 and self.index[w.target] - self.index[w.source] > 1:  # over the boxes between
                sx, sy, tx, ty = x0 + box_w / 2, y0, x1 + box_w / 2, y1
                rise = y0 - 12 - 4 * (self.index[w.source] % 3)
                d = f"M {sx:.0f} {sy:.0f} C {sx:.0f} {rise:.0f} {tx:.0f} {rise:.0f} {tx:.0f} {ty:.0f}"
                style = 'stroke="#444"'
            else:
                sx, sy, tx, ty = x0 + box_w, y0 + box_h / 2, x1, y1 + box_h / 2
                mid = (sx + tx) / 2
                d = f"M {sx:.0f} {sy:.0f} C {mid:.0f} {sy:.0f} {mid:.0f} {ty:.0f} {tx:.0f} {ty:.0f}"
                style = 'stroke="#444"'
            title = html.escape(w.label())
            out.append(f'<path d="{d}" fill="none" {style} marker-end="url(#arrow)"><title>{title}</title></path>')
        for n in self.nodes:
            x, y = pos[n.name]
            out.append(f'<rect x="{x}" y="{y}" width="{box_w}" height="{box_h}" rx="6" fill="{colours[n.floor]}" '
                       f'stroke="#333"><title>{html.escape(n.where)}</title></rect>')  # fmt: skip
            out.append(f'<text x="{x + box_w / 2:.0f}" y="{y + 18}" text-anchor="middle" font-weight="bold">'
                       f"{html.escape(n.name)}</text>")  # fmt: skip
            sub = n.title if len(n.title) <= 24 else n.title[:23] + "…"
            out.append(f'<text x="{x + box_w / 2:.0f}" y="{y + 34}" text-anchor="middle" fill="#333">'
                       f"{html.escape(sub)}</text>")  # fmt: skip
        out.append("</svg>")
        return "\n".join(out) + "\n"


# ============================================================================= the scenes
LAB_DIAGRAM = Diagram(
    scene="lab",
    summary="the Motion-Lab: two Stewart platforms, the Comau on EM8000, its winch and the hanging load",
    runs="app.scenes.lab.MotionLab.step: the platforms, then app.scenes.lab_kernels.lab_step (one compiled call), "
    "or each block's NumPy reference",
    nodes=(
        part(
            "operator",
            "operator",
            "app.engine.lab_session",
            "-> comau_mode, v_cmd, winch_mode, winch_speed, antisway",
            "HMI",
        ),
        part("waves", "plant", "app.sim.stewart", "-> eta8000, eta1500", "vessel motion / generator"),
        part("em8000", "plant", "app.sim.stewart", "source -> eta", "EM8000 platform"),
        part("em1500", "plant", "app.sim.stewart", "source -> eta", "EM1500 platform"),
        part("sensors", "sensor", "app.marine.sensors", "eta1, eta2 -> view, view2", "MRU / tracker or true"),
        part("obstacles", "sensor", "app.scenes.lab", "view, view2 -> world", "the guards' world in {r}"),
        Node("antisway", "controller", "app.control.antisway", SWING_CONTROL, note="EKF + LQR anti-swing"),
        Node("comau_law", "controller", "app.control.lab", COMAU_LAW, note="REMOTE / MOTION_COMP"),
        Node("comau_guard", "controller", "app.control.lab", COMAU_GUARD, note="hazard guard (H115, H117)"),
        Node("drives", "plant", "app.sim.motionlab", COMAU_DRIVES, note="Comau joint drives"),
        part("tool", "sensor", "app.models.comau", "q, eta1 -> tool, a_t_d", "tool point, eqs. 54-57"),
        Node("winch_law", "controller", "app.control.lab", WINCH_LAW, note="heave compensation"),
        Node("winch_guard", "controller", "app.control.lab", WINCH_GUARD, note="pay-out guard (H117)"),
        Node("drum", "plant", "app.sim.motionlab", WINCH_DRUM),
        Node("load", "plant", "app.sim.motionlab", PENDULUM, note="load, eqs. 29-30"),
    ),
    wires=tuple(
        wire(w)
        for w in (
            "waves.eta8000 -> em8000.source",
            "waves.eta1500 -> em1500.source",
            "em8000.eta -> sensors.eta1",
            "em1500.eta -> sensors.eta2",
            "tool.a_t_d -> antisway.a_t_d",
            "load.alpha,beta -> antisway.z",
            "drum.L_w -> antisway.L",
            "drum.L_w_dot -> antisway.L_dot",
            "operator.antisway -> antisway.active",
            "operator.comau_mode -> comau_law.mode",
            "drives.q -> comau_law.q",
            "operator.v_cmd -> comau_law.v_cmd",
            "antisway.p_d,v_d -> comau_law.offset",
            "sensors.view -> comau_law.view",
            "sensors.view -> obstacles.view",
            "sensors.view2 -> obstacles.view2",
            "comau_law.brake,q_ref,q_dot_ref,use_q_dot_ref,speed_scale -> comau_guard.command",
            "drives.q -> comau_guard.q",
            "drives.q_dot -> comau_guard.q_dot",
            "obstacles.world -> comau_guard.world",
            "comau_guard.command -> drives.brake,q_ref,q_dot_ref,use_q_dot_ref,speed_scale",
            "drives.q -> tool.q",
            "em8000.eta -> tool.eta1",
            "operator.winch_mode -> winch_law.track",
            "operator.winch_speed -> winch_law.speed_cmd",
            "drum.L_w -> winch_law.L_w",
            "load.alpha,beta -> winch_law.swing",
            "tool.tool -> winch_law.tool",
            "sensors.view2 -> winch_law.view2",
            "winch_law.L_ref,L_dot_ref -> winch_guard.wire_ref",
            "drum.L_w,L_w_dot -> winch_guard.wire",
            "drives.q,q_dot -> winch_guard.arm",
            "obstacles.world -> winch_guard.world",
            "sensors.view -> winch_guard.frames",
            "load.alpha,beta,alpha_dot,beta_dot -> winch_guard.swing",
            "winch_guard.wire_ref -> drum.L_ref,L_dot_ref",
            "tool.a_t_d -> load.a_t_d",
            "drum.L_w -> load.L",
            "drum.L_w_dot -> load.L_dot",
        )
    ),
)

TAC_DIAGRAM = Diagram(
    scene="tac",
    summary="the crane-head compensation: a supply vessel, its crane and the Delta head (TAC paper)",
    runs="app.scenarios.tac.TacSimulator.advance: the vessel motion, then app.scenes.tac_kernels.tac_chunk "
    "(one compiled call per chunk), or the NumPy reference",
    nodes=(
        part("operator", "operator", "app.engine.tac_session", "-> mode, p_d, winch_speed", "HMI: mode, stick"),
        part("vessel", "plant", "app.marine.vessel", "-> eta, nu", "vessel in irregular seas"),
        part("mru", "sensor", "app.marine.sensors", "eta, nu -> eta_m, nu_m", "motion reference unit"),
        part(
            "crane_ref",
            "controller",
            "app.models.crane_head",
            "mode, p_d, eta_m -> beta_d, beta_c, beta_c_dot",
            "crane targets, IK",
        ),
        Node("crane_law", "controller", "app.control.tac", CRANE_LAW, note="cooperative crane law"),
        Node("crane", "plant", "app.sim.head", CRANE_JOINTS, note="crane joints"),
        part(
            "head_ref",
            "controller",
            "app.models.crane_head",
            "p_d, eta_m, nu_m, beta, beta_dot -> alpha_ref, alpha_dot_ref",
            "references, eqs. 49-56 (mode changes faded, H108)",
        ),
        Node("pid", "controller", "app.control.tac", HEAD_PID, note="joint PID, eq. 57"),
        Node("motors", "plant", "app.sim.head", HEAD_MOTORS, note="DC motors, eq. 58"),
        part("windup", "controller", "app.scenes.tac_kernels", "trial, limited, saturated -> integral", "anti-windup"),
        part("head_fk", "sensor", "app.models.crane_head", "alpha, beta, eta -> p_c", "Delta FK, eqs. 17-25"),
        part("tcp", "sensor", "app.scenes.crane_load", "p_c -> tcp_z, a_tcp", "TCP height, rate, acceleration"),
        part("fade", "controller", "app.scenes.crane_load", "mode -> ease", "mode changes faded in (H108)"),
        Node("winch_law", "controller", "app.control.tac", CRANE_AHC, note="heave compensation (AHC)"),
        Node("drum", "plant", "app.sim.motionlab", WINCH_DRUM, note="crane winch"),
        Node("load", "plant", "app.sim.motionlab", PENDULUM, note="hook and payload, eqs. 29-30"),
    ),
    wires=tuple(
        wire(w)
        for w in (
            "vessel.eta -> mru.eta",
            "vessel.nu -> mru.nu",
            "operator.mode -> crane_ref.mode",
            "operator.p_d -> crane_ref.p_d",
            "mru.eta_m -> crane_ref.eta_m",
            "crane_ref.beta_d -> crane_law.beta_d",
            "crane_ref.beta_c -> crane_law.beta_c",
            "crane_ref.beta_c_dot -> crane_law.beta_c_dot",
            "crane.beta -> crane_law.beta",
            "crane_law.beta_dot_cmd -> crane.beta_dot_cmd",
            "operator.p_d -> head_ref.p_d",
            "mru.eta_m -> head_ref.eta_m",
            "mru.nu_m -> head_ref.nu_m",
            "crane.beta -> head_ref.beta",
            "crane.beta_dot -> head_ref.beta_dot",
            "head_ref.alpha_ref -> pid.alpha_ref",
            "head_ref.alpha_dot_ref -> pid.alpha_dot_ref",
            "motors.alpha -> pid.alpha",
            "pid.u -> motors.u",
            "pid.trial -> windup.trial",
            "pid.limited -> windup.limited",
            "motors.saturated -> windup.saturated",
            "motors.alpha -> head_fk.alpha",
            "crane.beta -> head_fk.beta",
            "vessel.eta -> head_fk.eta",
            "head_fk.p_c -> tcp.p_c",
            "operator.mode -> winch_law.track",
            "operator.mode -> fade.mode",
            "fade.ease -> winch_law.ease",
            "operator.winch_speed -> winch_law.speed_cmd",
            "drum.L_w -> winch_law.L",
            "tcp.tcp_z -> winch_law.tcp_z",
            "winch_law.L_ref -> drum.L_ref",
            "winch_law.L_dot_ref -> drum.L_dot_ref",
            "tcp.a_tcp -> load.a_t_d",
            "drum.L_w -> load.L",
            "drum.L_w_dot -> load.L_dot",
        )
    ),
)

TELEOP_DIAGRAM = Diagram(
    scene="teleop",
    summary="any manipulator from a robot file, driven by any joystick through a pluggable solver",
    runs="app.engine.session.TeleopSession.tick: each block in turn at the engine's rate",
    nodes=(
        part("device", "operator", "app.teleop.devices", "-> axes, buttons", "joystick / keyboard"),
        part(
            "pipeline", "controller", "app.teleop.pipeline", "axes, buttons -> command", "deadzone, deadman, stale halt"
        ),
        part("mapping", "controller", "app.teleop.mapping", "command, q -> target", "position / velocity workspace"),
        part("solver", "controller", "app.ik", "target, q -> q_ref", "GA, Jacobian or analytic IK"),
        Node("actuators", "plant", "app.sim.actuators", JOINT_ACTUATORS, note="joint actuators"),
        part("fk", "sensor", "app.models.serial", "q -> tool", "forward kinematics"),
    ),
    wires=tuple(
        wire(w)
        for w in (
            "device.axes -> pipeline.axes",
            "device.buttons -> pipeline.buttons",
            "pipeline.command -> mapping.command",
            "actuators.q -> mapping.q",
            "mapping.target -> solver.target",
            "actuators.q -> solver.q",
            "solver.q_ref -> actuators.q_ref",
            "actuators.q -> fk.q",
        )
    ),
)

DIAGRAMS = {d.scene: d for d in (LAB_DIAGRAM, TAC_DIAGRAM, TELEOP_DIAGRAM)}
