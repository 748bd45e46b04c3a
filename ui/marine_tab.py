"""Crane-head tab: supply vessel, offshore crane and Delta head in waves (TAC paper Figs. 7–12).

Talks to its own engine (``bosun server --plant tac``) through an :class:`~ui.link.EngineLink`;
the engine is started when the tab is first opened (or a link is given, e.g. by tests).
"""

from __future__ import annotations

import html
import math
from collections.abc import Callable

import numpy as np
import pyqtgraph as pg
from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import (
    QCheckBox,
    QComboBox,
    QDoubleSpinBox,
    QFormLayout,
    QGridLayout,
    QGroupBox,
    QHBoxLayout,
    QLabel,
    QPushButton,
    QSplitter,
    QVBoxLayout,
    QWidget,
)

from ui.scene_tab import SceneEngineMixin
from ui.widgets.fields import EngineFields
from ui.widgets.landing import LandingPanel
from ui.widgets.plots import Ring, TwinAxis, axis_label, blank_axis, legend, refit, refit_on_show
from ui.widgets.scene_view import DrawnScene, make_view
from ui.widgets.status import SceneLights
from ui.widgets.stick import VirtualStick
from ui.widgets.vessel import VesselRow

HISTORY_S = 60.0
SAMPLE_HZ = 25

# the live plots' ring: engine time, vessel pose η, p_ref^t, p_c^t, α, u_α, e_c, e_s
COLUMNS = (
    "t",
    *("north", "east", "heave", "roll", "pitch", "yaw"),
    *(f"p_ref_{a}" for a in "xyz"),
    *(f"p_c_{a}" for a in "xyz"),
    *(f"alpha{k}" for k in (1, 2, 3)),
    *(f"u{k}" for k in (1, 2, 3)),
    "e_c",
    "e_s",
)


def _up(p) -> np.ndarray:
    """{n} (NED, z down) → display coordinates (x north, y west, z up): a right-handed z-up frame."""
    p = np.asarray(p, dtype=float)
    return np.stack([p[..., 0], -p[..., 1], -p[..., 2]], axis=-1)


# the crane-head engine's lights on its page (issue 26, item 6): no PLC here, the scene is simulated
TAC_LIGHTS = (
    ("engine", "engine", "the crane-head engine: connection and loop"),
    ("input", "input", "no stick drives this scene: the head compensates by itself"),
    ("plant", "plant", "simulated plant: vessel, crane and Delta head: compensating, head locked, holding, E-STOP"),
)

SCENE_TIP = (
    "Vessel (red hull, grey deck) on the sea (blue), offshore crane (orange), Delta crane head (cyan, "
    "TCP red), desired point (green), the load (yellow crate) on its wire and the target platform (green slab) [m]; "
    "x north, y west, z up"
)


def _row(*items) -> QHBoxLayout:
    """A form row of widgets side by side, no margins; an item is a widget or (widget, stretch)."""
    row = QHBoxLayout()
    row.setContentsMargins(0, 0, 0, 0)
    for item in items:
        widget, stretch = item if isinstance(item, tuple) else (item, 0)
        row.addWidget(widget, stretch)
    return row


class TacDrawing:
    """The crane-head scene's solids from the engine's description (robot files, ship, waves) and a sample."""

    def __init__(self) -> None:
        self.crane = None  # SerialRobot of the offshore crane (frames in the vessel's {b})
        self.head = None  # DeltaSpec of the crane head
        self.ship = None
        self.waves = None

    def set_description(self, desc) -> None:
        from app.models.serial import SerialRobot
        from app.models.xml import parse_robot_xml

        self.ship, self.waves = desc.ship, desc.waves
        try:
            self.crane = SerialRobot(parse_robot_xml(desc.crane_xml, "crane"))
            self.head = parse_robot_xml(desc.head_xml, "head").delta
        except Exception:  # drawn from the scene points instead
            self.crane = self.head = None

    def meshes(self, scene, sample) -> list:
        from app.models.drawing import box, serial_links, tac_meshes

        if self.crane is not None and self.head is not None and sample is not None:
            F = self.crane.frames(np.asarray(sample.beta, dtype=float))
            hook = getattr(scene, "hook", None) or None  # the hanging load (issue 30, item 3)
            deck = getattr(scene, "deck", None) or None  # the target platform (issue 30, item 5)
            return tac_meshes(
                self.crane.links, F, self.head, sample.alpha, sample.p_c_t, sample.eta, self.ship, hook=hook, deck=deck
            )
        ship = _up(scene.ship)  # 8 corners: x, y, z each over (low, high)
        lo, hi = ship.min(axis=0), ship.max(axis=0)
        out = [box(0.5 * (lo + hi), np.eye(3), np.maximum(hi - lo, 1e-3), (0.6, 0.6, 0.6, 1.0), "ship")]
        return out + serial_links(_up(scene.crane), 0.8)  # no robot files: straight links between the joints

    def sea(self, sample, size: float):
        from app.models.drawing import sea_surface

        if self.waves is None or sample is None:
            return None
        return sea_surface(self.waves, sample.t, center=sample.eta[:2], size=size, n=41)


def _machines_3d(parent: QWidget) -> QWidget:
    from ui.widgets.machines3d import MachineView3D

    return MachineView3D(parent, tooltip=SCENE_TIP)


def _machines_2d(parent: QWidget) -> QWidget:
    from ui.widgets.machines3d import MachineView2D

    views = [
        ("astern", "seen from astern: east [m] – up [m]", ((0, -1, 0), (0, 0, 1))),
        ("side", "seen from starboard: north [m] – up [m]", ((1, 0, 0), (0, 0, 1))),
    ]
    m = MachineView2D(parent, views=views, note="crane head, 2D views (no OpenGL here)", vertical=True)
    m.setToolTip(SCENE_TIP)
    return m


class SceneView3D(DrawnScene):
    """The vessel on a moving sea, the offshore crane on its deck and the Delta head, as solids."""

    kind = "3d"

    def __init__(self, parent=None) -> None:
        super().__init__(_machines_3d, TacDrawing(), parent)
        self.view = self.machines.view
        self.ride = False  # the camera rides with the target deck (issue 30, item 7)

    def set_ride(self, on: bool) -> None:
        """The camera rides with the target deck (on) or goes back to the fitted view (off)."""
        self.ride = bool(on)
        if not on:
            self.machines.set_preset(self.machines.preset)

    def draw_now(self, scene, p_d_n, sample=None) -> None:
        from app.models.drawing import merge

        meshes = self.draw.meshes(scene, sample)
        m = self.machines
        deck = getattr(scene, "deck", None)
        if self.ride and deck:
            m.follow(_up(deck).mean(axis=0))
        m.set_mesh("machines", merge(meshes))
        size = 3.0 * (self.draw.ship.length if self.draw.ship is not None else 80.0)
        m.set_mesh("sea", self.draw.sea(sample, size), translucent=True)
        m.set_points("goal", _up(p_d_n)[None], (0.2, 0.85, 0.3, 1), 12)

        def fit() -> None:
            lo = np.min([x.vertices.min(axis=0) for x in meshes], axis=0)
            hi = np.max([x.vertices.max(axis=0) for x in meshes], axis=0)
            m.set_extent(lo, hi, floor=float(lo[2]))

        self.fit_once(fit)


class SceneView2D(DrawnScene):
    """Without OpenGL: the scene's solids seen from astern (east–up, the plane a beam sea rolls the vessel
    in) and from starboard (north–up), with the sea's profile through the vessel."""

    kind = "2d"

    def __init__(self, parent=None) -> None:
        super().__init__(_machines_2d, TacDrawing(), parent)
        self.plot = self.machines.plots["astern"]["plot"]

    def set_ride(self, on: bool) -> None:
        """The 2D views are fixed to the world: there is no camera to ride with the deck."""

    def draw_now(self, scene, p_d_n, sample=None) -> None:
        from app.models.drawing import sea_profile

        meshes = self.draw.meshes(scene, sample)
        m = self.machines
        m.set_meshes(meshes)
        m.set_points("goal", _up(p_d_n)[None], (50, 220, 80), "+", 14)
        if self.draw.waves is not None and sample is not None:
            n0, e0 = sample.eta[0], sample.eta[1]
            half = 1.5 * (self.draw.ship.length if self.draw.ship is not None else 80.0)
            sea, water = (90, 150, 230), (40, 100, 170, 110)
            for key, p0, p1 in (
                ("astern", (n0, e0 - half), (n0, e0 + half)),
                ("side", (n0 - half, e0), (n0 + half, e0)),
            ):
                m.set_line("sea", sea_profile(self.draw.waves, sample.t, p0, p1), sea, 2, only=key, fill=water)
        self.fit_once(lambda: m.fit_meshes(meshes))


def make_scene_view(use_gl: bool | None = None) -> QWidget:
    return make_view(SceneView3D, SceneView2D, use_gl)


class CraneHeadTab(SceneEngineMixin, QWidget):
    """Sea-state controls, mode switch, 3D/2D scene, workspace hull and the live plots of Figs. 8–12.

    ``link_factory`` makes the :class:`~ui.link.EngineLink` to the crane-head engine on first use.
    """

    notice = pyqtSignal(str, str)  # level, text for the status log
    engine_label = "crane head"

    def __init__(self, link_factory: Callable[[], object] | None = None, use_gl: bool | None = None) -> None:
        super().__init__(link_factory, use_gl)  # state: the newest TacSnapshot, desc: the TacDescription
        self.hull = None
        self._sea_seq = -1
        self._t_last = -math.inf
        self._controls = False  # the operator's controls are on (a linked operator; a viewer never)
        self.ring = Ring(int(HISTORY_S * SAMPLE_HZ), COLUMNS)
        self._build()
        refit_on_show(self, self._shown)

    # ------------------------------------------------------------------ layout
    def _build(self) -> None:
        controls = QGroupBox("Sea state and compensation")
        form = QFormLayout(controls)
        self.spectrum = QComboBox()
        self.spectrum.addItems(["jonswap", "pm", "torsethaugen"])
        self.hs = QDoubleSpinBox(decimals=1, minimum=0.1, maximum=14.0, singleStep=0.5, value=3.0, suffix=" m")
        self.tp = QDoubleSpinBox(decimals=1, minimum=3.0, maximum=25.0, singleStep=0.5, value=9.0, suffix=" s")
        self.heading = QDoubleSpinBox(decimals=0, minimum=0, maximum=359, singleStep=15, value=90, suffix=" °")
        self.heading.setWrapping(True)
        self.heading.setToolTip("wave heading: 0 following sea, 90 beam sea (to starboard), 180 head sea")
        self.apply_sea = QPushButton("Apply sea")
        self.apply_sea.clicked.connect(self.send_sea)
        self.mode = QComboBox()
        self.mode.addItems(["off", "tac", "cooperative"])
        self.mode.setCurrentText("tac")
        self.mode.setToolTip(
            "off: head locked; tac: the head compensates (paper); cooperative: crane joins in. "
            "After an E-STOP reset the head and crane hold until a mode is chosen here again"
        )
        self.mode.activated.connect(lambda i: self._send("set_tac_mode", mode=self.mode.itemText(i)))
        self.start = QPushButton("Start crane-head engine")
        self.start.clicked.connect(self.connect_engine)
        form.addRow("spectrum", self.spectrum)
        # Hs and Tp side by side, heading beside Apply: the target and delay rows need the height
        form.addRow("Hs", _row((self.hs, 1), QLabel("Tp"), (self.tp, 1)))
        form.addRow("heading", _row((self.heading, 1), (self.apply_sea, 1)))
        self.vessel = VesselRow(lambda **f: self._send("set_vessel", **f))  # issue 17, item 2
        self.vessel.error.connect(lambda text: self.notice.emit("error", f"crane head: RAO file not sent: {text}"))
        form.addRow("vessel", self.vessel)
        self.antisway = QCheckBox("anti-swing")  # issue 30: the load's (the lab's estimator and law, reused)
        self.antisway.setToolTip(
            "the load's swing estimator and anti-swing law move the TCP's target against the swing while the head "
            "(and crane) compensate; off, their offset returns to zero"
        )
        self.antisway.clicked.connect(lambda on: self._send("set_crane_antisway", on=bool(on)))
        # issue 31: the measurement-to-actuation delay and the motion predicted that far ahead (set in off)
        self.delay = QDoubleSpinBox(decimals=2, minimum=0.0, maximum=2.0, singleStep=0.1, value=0.0, suffix=" s")
        self.delay.setToolTip(
            "the controller sees the motion sensor this late (real equipment's delay); set with the compensation off"
        )
        self.predict = QCheckBox("predict")
        self.predict.setToolTip("feed the motion predicted the delay ahead from the motion sensor (an online AR model)")
        self.delay.editingFinished.connect(self.send_delay)
        self.predict.clicked.connect(lambda _on: self.send_delay())
        form.addRow("mode", _row((self.mode, 1), self.antisway))  # one row: the 1280 × 800 page has no height to spare
        # issue 31, item 3: the lift window's threshold (the strip under the plots shows the prediction and verdict)
        self.lift_threshold = QDoubleSpinBox(decimals=2, minimum=0.05, maximum=10.0, singleStep=0.1, value=1.5)
        self.lift_threshold.setSuffix(" m")
        self.lift_threshold.setToolTip(
            "a lift window is open while the tip's heave (over the target deck with a vessel target) is predicted, "
            "with probability 0.95 or more, to stay within ± this of its mean for the next 10 s"
        )
        self.lift_threshold.editingFinished.connect(
            lambda: self._send("set_lift_window", threshold=float(self.lift_threshold.value()))
        )
        form.addRow("delay", _row((self.delay, 1), (self.predict, 1)))
        # the landing target, the stick's frame and the camera (issue 30, items 1, 5 and 7)
        self.target = QComboBox()
        self.target.addItems(["platform", "vessel"])
        self.target.setToolTip(
            "the deck the load is landed on: the fixed platform, or a second vessel's deck at its place in the same "
            "sea (the TCP then follows its deck); not while the load is over the present one"
        )
        self.target.activated.connect(lambda i: self._send("set_crane_target", target=self.target.itemText(i)))
        self.frame = QComboBox()
        self.frame.addItems(["world", "base", "target"])
        self.frame.setToolTip(
            "the stick's frame: world (a centred stick holds the TCP still in the world), base (it rides the crane's "
            "own vessel: a load picked up from its deck) or target (it holds the TCP over the target deck, following "
            "its surge, sway and heave); a change disarms the stick"
        )
        self.frame.activated.connect(lambda i: self._send("set_frame", frame=self.frame.itemText(i)))
        self.ride = QCheckBox("ride")
        self.ride.setToolTip("ride deck: the 3D camera rides with the target deck (looks at it wherever it moves)")
        self.ride.toggled.connect(lambda on: getattr(self.scene, "set_ride", lambda _on: None)(on))
        form.addRow("target", _row((self.target, 1), (self.frame, 1), self.ride))
        self.readout = QLabel("not connected")
        self.readout.setTextFormat(Qt.RichText)
        self.readout.setWordWrap(True)  # long lines wrap, never cut at the column's edge
        self.readout.setMinimumWidth(220)
        form.addRow(self.readout)
        form.addRow(self.start)  # last: when it goes (the engine started), no field or button moves (issue 26)
        # the sea fields show the engine's sea; an edit stays (highlighted) until Apply takes it or Esc
        self.sea_fields = EngineFields(self)
        for w in (self.spectrum, self.hs, self.tp, self.heading):
            self.sea_fields.add(w)

        self.scene = make_scene_view(self.use_gl)
        self.hull_plot = pg.PlotWidget(title="head workspace (x–z plane of {t})")
        self.hull_plot.setAspectLocked(True)
        self.hull_plot.setMinimumWidth(260)
        axis_label(self.hull_plot.getPlotItem(), "bottom", "x<sup>t</sup>", "m")  # x in {t}
        axis_label(self.hull_plot.getPlotItem(), "left", "z<sup>t</sup>", "m")
        self.hull_plot.showGrid(x=True, y=True, alpha=0.3)
        legend(self.hull_plot.getPlotItem(), cols=3)
        self.hull_plot.setToolTip("the head's workspace hull in its x–z plane, the reference p_ref and the TCP p_c")
        self.hull_curve = self.hull_plot.plot(pen=pg.mkPen((120, 140, 220), width=1.5), name="hull")
        self.ref_dot = self.hull_plot.plot(
            pen=None, symbol="o", symbolBrush=(160, 160, 160), symbolSize=10, name="p_ref"
        )
        self.pc_dot = self.hull_plot.plot(pen=None, symbol="o", symbolBrush=(240, 60, 50), symbolSize=7, name="p_c")

        plots = pg.GraphicsLayoutWidget()
        plots.ci.layout.setHorizontalSpacing(18)  # one column's right axis label apart from the next one's left
        self.p_eta = plots.addPlot(row=0, col=0, title="Fig. 8 vessel motion")
        self.p_tcp = plots.addPlot(row=0, col=1, title="Fig. 9 head TCP in {t}")
        self.p_err = plots.addPlot(row=1, col=0, title="Fig. 11 compensation error")
        self.p_ang = plots.addPlot(row=1, col=1, title="Fig. 12 Delta arm angles")
        # the lift-window strip under them, a plot widget of its own (in the grid, spanning both columns, it widened
        # the layout past a narrow panel)
        self.lift_plot = pg.PlotWidget(title="lift window")
        self.p_lift = self.lift_plot.getPlotItem()
        self._lift_items()
        colors = [(230, 90, 70), (90, 170, 230), (120, 210, 120)]
        for p in (self.p_eta, self.p_tcp, self.p_err, self.p_ang):
            p.showGrid(x=True, y=True, alpha=0.3)
            p.setDownsampling(auto=True, mode="peak")
            p.setClipToView(True)
            axis_label(p, "bottom", "t", "s")
        # one time axis a column: values and label under the lower plot only, the room goes to the curves
        for upper, lower in ((self.p_eta, self.p_err), (self.p_tcp, self.p_ang)):
            upper.setXLink(lower)
            upper.getAxis("bottom").setStyle(showValues=False)
            upper.getAxis("bottom").showLabel(False)
            for p in (upper, lower):
                p.getAxis("left").setWidth(54)
        # one unit per axis: heave [m] on the left, roll and pitch [deg] on a right axis of their own
        axis_label(self.p_eta, "left", "heave", "m")
        axis_label(self.p_tcp, "left", "position", "m")
        axis_label(self.p_err, "left", "error", "m")
        axis_label(self.p_ang, "left", "angle", "deg")
        legend(self.p_eta, cols=3)
        legend(self.p_tcp, cols=4)
        legend(self.p_err, cols=2)
        legend(self.p_ang, cols=4)
        self.eta_twin = TwinAxis(self.p_eta, "roll, pitch", "deg")
        self.eta_twin.axis.setWidth(50)
        blank_axis(self.p_err, "right", 50)  # the same width under the twin axis: the time axes line up
        self.c_eta = [
            self.p_eta.plot(pen=pg.mkPen(colors[0], width=1.2), name="heave [m]"),
            self.eta_twin.plot(pen=pg.mkPen(colors[1], width=1.2), name="roll [deg]"),
            self.eta_twin.plot(pen=pg.mkPen(colors[2], width=1.2), name="pitch [deg]"),
        ]
        self.c_pc = [self.p_tcp.plot(pen=pg.mkPen(colors[k], width=1.2), name=f"p_c {a}") for k, a in enumerate("xz")]
        self.c_ref = [
            self.p_tcp.plot(pen=pg.mkPen((*colors[k], 110), width=4), name=f"p_ref {a}") for k, a in enumerate("xz")
        ]
        for c in self.c_ref:
            c.setZValue(-1)  # the wide reference under the TCP's line
        self.c_es = self.p_err.plot(pen=pg.mkPen((230, 80, 70), width=1.2), name="e_s uncompensated")
        self.c_ec = self.p_err.plot(pen=pg.mkPen((90, 170, 230), width=1.5), name="e_c compensated")
        self.c_u = [self.p_ang.plot(pen=pg.mkPen((150, 150, 150), width=1)) for _ in range(3)]
        self.p_ang.legend.addItem(self.c_u[0], "u_α commands")
        self.c_al = [self.p_ang.plot(pen=pg.mkPen(c, width=1.2), name=f"α{k + 1}") for k, c in enumerate(colors)]
        self.p_tcp.setToolTip("head TCP p_c^t (thin) and its compensating reference p_ref^t (wide), x and z [m]")
        self.p_err.setToolTip("e_s: the crane tip's motion without compensation; e_c: the head TCP's error (eq. 61)")
        self.p_ang.setToolTip("Delta arm angles α and the servo commands u_α [deg]")

        # three columns the page's full height: controls over the workspace hull, the scene, the plots.  (The
        # views above the plots left the scene 130 px tall in a 1280×800 window.)
        controls.setMaximumWidth(340)
        self.hull_plot.setMinimumHeight(122)  # with the vessel row and the lights the page fits 1280 × 800
        # the operator's stick (issue 30, item 2): moves the TCP's target in the world in tac and cooperative
        self.stick_box = QGroupBox("Stick: TCP in the world (x, y; z up); w the winch — and the landing")
        sl = QHBoxLayout(self.stick_box)
        sl.setContentsMargins(4, 2, 4, 2)
        # compact: the scene above keeps its height on a 1280 × 800 screen; w: the winch (issue 30, item 3)
        self.stick = VirtualStick(aux_axis="w winch", pad_size=80)
        self.stick.setToolTip(
            "moves the head's TCP in the world (0.5 m/s at full stick) while the head (tac) or the crane and head "
            "(cooperative) cancel the sea; a centred stick holds it still; w pays the winch out (lowering the hook in "
            "the world, 1 m/s at full) or hauls in; hold Shift or the ENABLE button (deadman); a joystick works the "
            "same way; off and a stopped machine ignore the TCP axes"
        )
        sl.addWidget(self.stick)
        self.landing = LandingPanel()  # the landing on the target platform beside the stick (issue 30, item 7)
        sl.addWidget(self.landing, 1)
        self.stick_box.setMaximumHeight(118)
        left = QSplitter(Qt.Vertical)
        left.addWidget(controls)
        left.addWidget(self.hull_plot)
        left.setStretchFactor(1, 1)
        left.setChildrenCollapsible(False)
        middle = QSplitter(Qt.Vertical)  # the scene over the stick, as at a console
        middle.addWidget(self.scene)
        middle.addWidget(self.stick_box)
        middle.setStretchFactor(0, 1)
        middle.setStretchFactor(1, 0)
        middle.setSizes([1000, 100])  # the scene takes what the stick leaves
        middle.setChildrenCollapsible(False)
        main = QSplitter(Qt.Horizontal)
        main.addWidget(left)
        main.addWidget(middle)
        right = QWidget()
        rl = QVBoxLayout(right)
        rl.setContentsMargins(0, 0, 0, 0)
        rl.setSpacing(0)
        rl.addWidget(plots, 1)
        # the strip's threshold beside it (the controls' column has no width to spare at 1280 × 800)
        lift_row = QHBoxLayout()
        lift_row.setContentsMargins(6, 2, 6, 0)
        lift_row.addWidget(QLabel("lift window ±"))
        lift_row.addWidget(self.lift_threshold)
        lift_row.addWidget(QLabel("for 10 s — "))
        self.lift_verdict = QLabel("–")
        self.lift_verdict.setToolTip("open: the model gives the heave within the threshold for the next 10 s P ≥ 0.95")
        lift_row.addWidget(self.lift_verdict, 1)
        rl.addLayout(lift_row)
        rl.addWidget(self.lift_plot)
        main.addWidget(right)
        main.setChildrenCollapsible(False)
        self.scene.setMinimumWidth(240)
        right.setMinimumWidth(420)
        main.setStretchFactor(1, 2)
        main.setStretchFactor(2, 3)
        main.setSizes([320, 400, 560])
        self.splitter = main
        self.lights = SceneLights("Crane head (simulated plant)", TAC_LIGHTS, padding="1px 6px")
        lay = QGridLayout(self)
        lay.setContentsMargins(6, 2, 6, 0)  # with the lights' row the page still fits a 1280 × 800 window
        lay.setVerticalSpacing(2)
        lay.addWidget(self.lights, 0, 0)
        lay.addWidget(main, 1, 0)
        lay.setRowStretch(1, 1)
        self._set_enabled(False)

    def _set_enabled(self, on: bool) -> None:
        self._controls = on
        widgets = (self.spectrum, self.hs, self.tp, self.heading, self.apply_sea, self.mode, self.vessel, self.antisway)
        for w in (*widgets, self.target, self.frame):
            w.setEnabled(on)
        self.start.setVisible(not on)

    def _linked(self, make) -> bool:
        done = super()._linked(make)
        if done and hasattr(self.link, "connection"):
            self.link.connection.connect(self._connection)
        return done

    def _connection(self, ok: bool, message: str) -> None:
        if not ok:  # the engine is gone: nothing is known of its machines
            self.lights.show_lost()

    # ------------------------------------------------------------------ engine
    def _engine_failed(self, err: Exception) -> None:
        self.readout.setText(f"<b>engine not started</b>: {err}")

    def send_sea(self) -> None:
        self._send(
            "set_sea",
            spectrum=self.spectrum.currentText(),
            hs=float(self.hs.value()),
            tp=float(self.tp.value()),
            heading=float(self.heading.value()),
        )

    def _lift_items(self) -> None:
        """The lift-window strip (issue 31, item 3): the next 20 s of the tip's heave predicted, its ±2σ band, the
        threshold's lines, and the next 10 s shaded green when the window is open."""
        p = self.p_lift
        self.lift_plot.setMaximumHeight(150)
        self.lift_plot.setMinimumHeight(110)
        p.showGrid(x=True, y=True, alpha=0.3)
        axis_label(p, "bottom", "ahead", "s")
        axis_label(p, "left", "heave", "m")
        p.getAxis("left").setWidth(54)
        p.setXRange(0.0, 20.0, padding=0.0)
        p.setMouseEnabled(x=False, y=False)
        legend(p, cols=2, title="the heave predicted, the next 20 s")  # before the curves: they join it
        self.lift_open = pg.LinearRegionItem((0.0, 10.0), movable=False, brush=pg.mkBrush(60, 170, 80, 70))
        self.lift_open.setZValue(-10)
        self.lift_open.hide()
        p.addItem(self.lift_open)
        band = pg.mkPen((90, 170, 230, 90))
        self.lift_hi, self.lift_lo = p.plot(pen=band), p.plot(pen=band)
        p.addItem(pg.FillBetweenItem(self.lift_hi, self.lift_lo, brush=pg.mkBrush(90, 170, 230, 60)))
        self.lift_mean = p.plot(pen=pg.mkPen((90, 170, 230), width=1.8), name="predicted")
        dash = pg.mkPen((230, 90, 70), width=1, style=Qt.DashLine)
        self.lift_lines = [pg.InfiniteLine(angle=0, pen=dash) for _ in range(2)]
        for line in self.lift_lines:
            p.addItem(line)
        p.legend.addItem(self.lift_hi, "±2σ")
        p.setToolTip(
            "the tip's heave (over the target deck with a vessel target) predicted over the next 20 s from the motion "
            "alone (an online AR model), its ±2σ band and the threshold; green: a lift window open for the next 10 s "
            "(the model gives it probability 0.95 or more)"
        )

    def _show_lift(self, lift) -> None:
        if lift is None:
            return
        for line, sign in zip(self.lift_lines, (1, -1), strict=True):
            line.setValue(sign * lift.threshold)
        if not lift.mean:
            verdict = f"learning ({lift.learning_s:.0f} s)"
            for c in (self.lift_mean, self.lift_hi, self.lift_lo):
                c.setData([], [])
            self.lift_open.hide()
        else:
            x = np.arange(len(lift.mean)) * lift.step
            m, s = np.asarray(lift.mean), np.asarray(lift.sigma)
            self.lift_mean.setData(x, m)
            self.lift_hi.setData(x, m + 2 * s)
            self.lift_lo.setData(x, m - 2 * s)
            self.lift_open.setRegion((0.0, lift.length))
            self.lift_open.setVisible(lift.open)
            verdict = f"{'OPEN' if lift.open else 'closed'} (P {lift.probability:.2f})"
        what = "over the target deck, " if lift.signal != "heave" else ""
        text = f"{what}<b style='color:#2f8f3f'>{verdict}</b>" if lift.open else f"{what}{verdict}"
        if self.lift_verdict.text() != text:
            self.lift_verdict.setText(text)
        if not self.lift_threshold.hasFocus() and abs(self.lift_threshold.value() - lift.threshold) > 1e-9:
            self.lift_threshold.setValue(lift.threshold)

    def send_delay(self) -> None:
        self._send("set_tac_delay", delay=float(self.delay.value()), predict=bool(self.predict.isChecked()))

    def on_reply(self, re: str, ok: bool, error: str) -> None:
        if not ok and "no longer the operator" in error:
            self.notice.emit("error", f"crane head: operator role lost: {error}")
        refusable = (
            "set_sea", "set_tac_mode", "set_vessel", "set_crane_antisway", "set_crane_target", "set_frame",
            "set_tac_delay", "set_lift_window",
        )  # fmt: skip
        if not ok and re in (*refusable, "reset"):
            self.notice.emit("error", f"crane head: {re} refused: {error}")

    # ------------------------------------------------------------------ state
    def on_description(self, desc) -> None:
        """The scene's static data: workspace hull, arm limits, vessel, sea (on join and on change)."""
        if getattr(desc, "kind", None) != "tac":
            return
        self.desc = desc
        self.vessel.set_engine(desc.vessel, list(getattr(desc, "vessels", None) or []))
        self.scene.set_description(desc)
        if desc.hull is not None:
            self.hull = desc.hull
            self._draw_hull()

    def on_state(self, state) -> None:
        if getattr(state, "kind", None) != "tac":
            return
        self.state = state
        self.lights.show_state(state)
        # the engine refuses a mode under a latched E-STOP; after the reset a mode (also the same) resumes
        self.mode.setEnabled(self._controls and not state.estop)
        sea = state.sea
        if sea is not None:
            if sea.seq != self._sea_seq:
                self._sea_seq = sea.seq
            fields = (self.spectrum, self.hs, self.tp, self.heading)
            for w, v in zip(fields, (sea.spectrum, sea.hs, sea.tp, sea.heading_deg), strict=True):
                self.sea_fields.engine_value(w, v)
        if self.mode.currentText() != state.tac_mode and not self.mode.view().isVisible():
            self.mode.setCurrentText(state.tac_mode)  # the engine's mode (another console may change it)
        for box, value in ((self.target, getattr(state, "target", "platform")), (self.frame, state.frame)):
            if box.currentText() != value and not box.view().isVisible():
                box.setCurrentText(value)  # the engine's (a refused choice goes back)
        self.landing.deck_name = "the target platform" if self.target.currentText() == "platform" else "the vessel"
        where = {"world": "in the world", "base": "riding the vessel", "target": "over the target deck"}
        title = f"Stick: TCP {where.get(state.frame, state.frame)} (x, y; z up); w the winch — and the landing"
        if self.stick_box.title() != title:
            self.stick_box.setTitle(title)
        s = state.sample
        if s is None:
            return
        if s.t < self._t_last:  # a new sea record: keep plotting on one time axis
            self.ring = Ring(self.ring.size, COLUMNS)
        if s.t != self._t_last:  # a paused engine repeats its last sample: one row, not a flat history
            self.ring.push([s.t, *s.eta, *s.p_ref_t, *s.p_c_t, *s.alpha, *s.u, s.e_c, s.e_s])
        self._t_last = s.t
        if state.scene is not None:
            self.scene.update_scene(state.scene, state.p_d_n, s)
        load = getattr(state, "load", None)
        self.landing.show_load(load)
        self._show_lift(getattr(state, "lift", None))
        if load is not None and self.antisway.isChecked() != load.antisway:
            self.antisway.setChecked(load.antisway)  # the engine's (another console may switch it)
        if not self.delay.hasFocus() and abs(self.delay.value() - getattr(state, "delay", 0.0)) > 1e-9:
            self.delay.setValue(getattr(state, "delay", 0.0))  # what the engine has (a refusal leaves it)
        if self.predict.isChecked() != bool(getattr(state, "predict", False)):
            self.predict.setChecked(bool(getattr(state, "predict", False)))
        self.ref_dot.setData([s.p_ref_t[0]], [s.p_ref_t[2]])
        self.pc_dot.setData([s.p_c_t[0]], [s.p_c_t[2]])
        if self.isVisible():  # a hidden tab draws when shown again (_shown)
            self._draw_plots()
        r = self.ring
        rms_c = float(np.sqrt(np.nanmean(r["e_c"] ** 2)))
        rms_s = float(np.sqrt(np.nanmean(r["e_s"] ** 2)))
        ratio = f"{rms_c / rms_s:.1%}" if rms_s > 1e-9 else "—"
        flag = "<span style='color:#e08020'><b>SATURATED</b></span>" if s.saturated else "inside workspace"
        stop = (
            "<span style='color:#e03030'><b>E-STOP latched</b>: head and crane stopped</span><br>"
            if state.estop
            else ""
        )
        if state.holding and not state.estop:
            stop = "<span style='color:#e08020'><b>HOLDING</b>: choose a mode to resume</span><br>"
        paused = "<span style='color:#8a8aa0'><b>paused</b> (tab hidden)</span><br>" if state.engine.paused else ""
        sea_text = f"{sea.spectrum} Hs {sea.hs:g} m, Tp {sea.tp:g} s, {sea.heading_deg:g}°" if sea is not None else "—"
        self.readout.setText(
            f"{stop}{paused}t = {s.t:.1f} s — mode <b>{state.tac_mode}</b>, {flag}<br>"
            f"sea: {sea_text}<br>"
            f"e_c {s.e_c:.3f} m, e_s {s.e_s:.3f} m; last {HISTORY_S:g} s rms ratio {ratio}<br>"
            f"x_d = {state.x_d:.2f} m{self._hazard_line(state)}"
        )

    @staticmethod
    def _hazard_line(state) -> str:
        """The edge of the TCP target's range the stick's command was last scaled for (issue 32, item 5)."""
        hz = getattr(state, "hazard", None)
        if hz is None or not hz.text:
            return ""
        color = "#b06000" if hz.slowed else "inherit"
        return f"<br><span style='color:{color}'>{html.escape(hz.text)}{' — slowing' if hz.slowed else ''}</span>"

    def _shown(self) -> None:
        """The tab is on screen again: plots drawn from the newest data and refitted to it."""
        self._draw_plots()
        for p in (self.p_eta, self.p_tcp, self.p_err, self.p_ang):
            refit(p)

    def _draw_hull(self) -> None:
        """Outline of the hull's x–z projection (convex hull of the projected vertices)."""
        from scipy.spatial import ConvexHull

        pts = np.asarray(self.hull.points)[:, [0, 2]]
        h = ConvexHull(pts)
        loop = pts[np.append(h.vertices, h.vertices[0])]
        self.hull_curve.setData(loop[:, 0], loop[:, 1])
        lo, hi = pts.min(axis=0), pts.max(axis=0)
        self.hull_plot.setRange(xRange=(lo[0], hi[0]), yRange=(lo[1], hi[1]), padding=0.08)

    def _draw_plots(self) -> None:
        r = self.ring
        if r.n == 0:
            return
        t = r["t"]
        self.c_eta[0].setData(t, r["heave"])
        self.c_eta[1].setData(t, np.degrees(r["roll"]))
        self.c_eta[2].setData(t, np.degrees(r["pitch"]))
        for k, a in enumerate("xz"):
            self.c_ref[k].setData(t, r[f"p_ref_{a}"])
            self.c_pc[k].setData(t, r[f"p_c_{a}"])
        self.c_es.setData(t, r["e_s"])
        self.c_ec.setData(t, r["e_c"])
        for i in range(3):
            self.c_u[i].setData(t, np.degrees(r[f"u{i + 1}"]))
            self.c_al[i].setData(t, np.degrees(r[f"alpha{i + 1}"]))
