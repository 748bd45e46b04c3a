"""Motion-Lab tab, modelled on the lab's own PyQt5 HMI (Motion-Lab paper §2.9, Figs. 10–11).

One sub-tab per Stewart platform (mode buttons, motion source with the sine generator and the
wave simulator, status fields, position and attitude plots, six actuator-stroke bars), one for
the Comau robot and the winch (modes, joint plots, utilisation bars, wire-length bar and the
spring-return speed slider, VVMC on/off) and one with the 3D scene of the lab and the pendulum
plots.  Everything goes through the lab engine (``bosun server --plant lab``).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtWidgets import QHBoxLayout, QSizePolicy, QTabWidget, QVBoxLayout, QWidget

from ui.lab.comau import ComauWinchPage
from ui.lab.common import HISTORY_S, LAB_COLUMNS, LAB_LIGHTS, SAMPLE_HZ, SWING_COLUMNS
from ui.lab.platform import PlatformPanel
from ui.lab.scene import ScenePage
from ui.lab.status import StatusStrip
from ui.lab.swing import SwingPage
from ui.scene_tab import SceneEngineMixin
from ui.widgets.buttons import button
from ui.widgets.labels import ElidedLabel
from ui.widgets.plots import Ring
from ui.widgets.status import SceneLights, lab_plc_light


class MotionLabTab(SceneEngineMixin, QWidget):
    """The Motion-Lab HMI; ``link_factory`` makes the link to the lab engine on first view.

    Its pages are widgets of their own (``ui/lab/``): ``platforms`` (one :class:`PlatformPanel` each),
    ``comau`` (Comau and winch), ``scene_page`` (the lab drawn, swing and error plots), ``swing`` (the load
    swing estimator) and ``status`` (machine lights and CSV logger, below every page).  This tab links them
    to the engine: commands out through :meth:`_send`, the engine's description and states in."""

    notice = pyqtSignal(str, str)
    plc_link = pyqtSignal(str, str)  # the plant's link as a status light: state (ok/warn/error/off), detail
    engine_label = "Motion-Lab"

    def __init__(self, link_factory: Callable[[], object] | None = None, use_gl: bool | None = None) -> None:
        super().__init__(link_factory, use_gl)  # state: the newest LabSnapshot, desc: the LabDescription
        self._t_last = -math.inf
        self.ring = Ring(int(HISTORY_S * SAMPLE_HZ), LAB_COLUMNS)
        self.swing_ring = Ring(int(HISTORY_S * SAMPLE_HZ), SWING_COLUMNS)
        self.tabs = QTabWidget()
        self.platforms = {n: PlatformPanel(n, t) for n, t in (("em8000", "E-Motion 8000"), ("em1500", "E-Motion 1500"))}
        for n, p in self.platforms.items():
            p.command.connect(self._on_panel)
            self.tabs.addTab(p, n.upper())
        self.comau = ComauWinchPage(self._send, self._draw)
        self.scene_page = ScenePage(use_gl, self._draw)
        self.swing = SwingPage(self._send, self._draw)
        self.stick = self.comau.stick  # the REMOTE stick: the main window routes keys and joysticks to it
        self.scene = self.scene_page.scene
        self.tabs.addTab(self.comau, "Comau && winch")
        self.tabs.addTab(self.scene_page, "Scene && load")
        self.tabs.addTab(self.swing, "Load swing")
        self.start = ElidedLabel("The Motion-Lab engine starts when this tab is first opened.")
        self.plc_bar = self._plc_bar()
        self.lights = SceneLights("Motion-Lab", LAB_LIGHTS, padding="1px 6px")  # its engine's lights (issue 26)
        self.status = StatusStrip()  # the lab HMI's bottom: machine and sensor states, CSV logger
        self.status.notice.connect(self.notice)
        lay = QVBoxLayout(self)
        lay.addWidget(self.lights)
        # the engine's start note and the PLC's error live in the room beside the sub-tabs (the tab widget's
        # corner, the tab bar's height whatever it shows): nothing moves when one comes or goes (issue 26,
        # item 2: a page that stays put; as the main window's notices)
        notes = QWidget()
        row = QHBoxLayout(notes)
        row.setContentsMargins(8, 0, 0, 0)
        row.setSpacing(0)
        row.addWidget(self.start, 1)
        row.addWidget(self.plc_bar, 1)
        notes.setFixedHeight(self.tabs.tabBar().sizeHint().height())
        notes.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Fixed)
        self.notes = notes
        self.tabs.setCornerWidget(notes, Qt.TopRightCorner)
        lay.addWidget(self.tabs)
        lay.addWidget(self.status)
        self._set_enabled(False)

    # ------------------------------------------------------------------ layout
    def _plc_bar(self) -> QWidget:
        """The PLC's error, as the lab HMI shows it, with Acknowledge; never a modal box (STOP stays live)."""
        bar = QWidget()
        bar.setStyleSheet("background: #5a1f1d; color: white;")
        bar.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Preferred)
        row = QHBoxLayout(bar)
        row.setContentsMargins(6, 0, 2, 0)
        self.plc_text = ElidedLabel("")  # one line in the row's kept room ("…" and the whole in the tool tip)
        row.addWidget(self.plc_text, 1)
        self.plc_ack = button(
            "Acknowledge",
            "writes MAIN.bReset; a platform in WARNING/ERROR: its bReset, then SETTLED",
            lambda: self._send("lab_plc_ack"),
            keyboard=False,
        )
        row.addWidget(self.plc_ack)
        bar.hide()
        return bar

    def _show_plant(self, state) -> None:
        """The plant backend's link: the PLC light (:func:`~ui.widgets.status.lab_plc_light`, on this page's
        row and as ``plc_link``) and, while the PLC reports an error, the bar above the tabs."""
        light = lab_plc_light(state)
        self.plc_link.emit(light.look, light.detail)
        pl = getattr(state, "plant", None)
        if pl is None or pl.backend != "plc":
            self.plc_bar.hide()
            return
        show = bool(pl.plc_error) and pl.connected
        if show:
            self.plc_text.setText(f"PLC error: {pl.plc_error}")  # one line: "…" and the whole in its tool tip
            self.plc_ack.setEnabled(not state.estop)  # the E-STOP's reset resets the PLC: acknowledge after it
            self.start.hide()
        self.plc_bar.setVisible(show)

    def _set_enabled(self, on: bool) -> None:
        for i in range(self.tabs.count()):  # the pages, not the tab widget: its corner (the notes) stays live
            self.tabs.widget(i).setEnabled(on)
        self.start.setVisible(not on and not self.plc_bar.isVisibleTo(self))

    # ------------------------------------------------------------------ engine
    def _connection(self, ok: bool, message: str) -> None:
        if not ok:  # the engine is gone: nothing more to log, nothing known about the machines
            self.status.stop_logger(f"stopped: engine lost ({message})" if message else "stopped: engine lost")
            self.status.show_machines(None)
            self.lights.show_lost()

    def _linked(self, make) -> bool:
        done = super()._linked(make)
        if done:
            for signal, slot in (("states", self.status.log_states), ("connection", self._connection)):
                if hasattr(self.link, signal):
                    getattr(self.link, signal).connect(slot)
        return done

    def close_link(self) -> None:
        self.status.stop_logger("stopped: the Motion-Lab tab closed")
        self.comau.jog_release()
        super().close_link()

    def _engine_failed(self, err: Exception) -> None:
        self.start.setText(f"engine not started: {err}")

    def _on_panel(self, mtype: str, fields: dict) -> None:
        if mtype == "_error":
            self.notice.emit("error", f"Motion-Lab: refused: {fields['text']}")
            return
        self._send(mtype, **fields)

    def on_reply(self, re: str, ok: bool, error: str) -> None:
        if not ok and "no longer the operator" in error:
            self.notice.emit("error", f"Motion-Lab: operator role lost: {error}")
        if not ok and re == "lab_comau_jog" and not self.comau.jog_refused():  # resent while held: said once
            return
        if not ok and (re.startswith("lab_") or re in ("reset", "set_vessel", "set_lab_delay", "set_frame")):
            self.notice.emit("error", f"Motion-Lab: {re} refused: {error}")

    # ------------------------------------------------------------------ state
    def on_description(self, desc) -> None:
        """The lab's static data: platform leg ranges and seas, Comau limits, winch range."""
        if getattr(desc, "kind", None) != "lab":
            return
        self.desc = desc
        for info in desc.platforms:
            if info.name in self.platforms:
                self.platforms[info.name].set_info(info)
        for panel in self.platforms.values():  # the wave simulator's vessel (none over the PLC)
            panel.vessel.setVisible(bool(desc.vessels))
            if desc.vessels:
                panel.vessel.set_engine(desc.vessel, list(desc.vessels))
        self.scene.set_description(desc)
        self.comau.set_description(desc)

    def on_state(self, state) -> None:
        if getattr(state, "kind", None) != "lab":
            return
        self.state = state
        self.lights.show_state(state)
        self._show_plant(state)
        self.status.show_machines(state)
        self.swing.show_state(state)
        self.comau.show_state(state)
        t = state.t
        for p in state.platforms:
            self.platforms[p.name].update_state(p, t, state.estop)
        if t - self._t_last >= 1.0 / SAMPLE_HZ - 1e-9:
            self._t_last = t
            c, w, pend = state.comau, state.winch, state.pendulum
            self.ring.push([t, *np.degrees(c.q), *c.qd, pend.alpha, pend.beta, *state.tool_error_b2, w.length])
            sw = getattr(state, "swing", None)
            if sw is not None:
                err = sw.error if sw.error is not None else [math.nan] * 4
                self.swing_ring.push(
                    [t, *np.degrees([pend.alpha, pend.beta, *sw.estimate[:2], *err[:2], *sw.sigma[:2]]),
                     *(1000 * np.asarray(sw.offset[:2]))]
                )  # fmt: skip
            if state.scene is not None:
                self.scene.update_scene(state.scene)
            self._draw()

    def _draw(self) -> None:
        """Every page's plots from the newest data (a page coming on screen calls it too)."""
        for p in self.platforms.values():
            p.draw()
        if self.ring.n < 2 or not self.isVisible():
            return
        self.comau.draw(self.ring)
        self.scene_page.draw(self.ring)
        self.swing.draw(self.swing_ring)
