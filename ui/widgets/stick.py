"""On-screen virtual stick and keyboard control, for when no joystick is present."""

from __future__ import annotations

from typing import ClassVar

from PyQt5.QtCore import QPointF, Qt, pyqtSignal
from PyQt5.QtGui import QBrush, QColor, QFont, QFontMetrics, QPainter, QPen
from PyQt5.QtWidgets import QHBoxLayout, QLabel, QPushButton, QSlider, QVBoxLayout, QWidget

# ENABLE's look per engine state (flags of the engine's newest snapshot): text, style
ENABLE_LOOK = {
    "none": ("ENABLE\nno engine", "color: #777;"),
    "idle": ("ENABLE\n(hold)", ""),
    "not_armed": ("NOT ARMED\nre-press", "background: #e0a020; color: black; font-weight: bold;"),
    "armed": ("ARMED\nnot driving", "background: #f3d58a; color: black; font-weight: bold;"),
    "enabled": ("ENABLED\nlive", "background: #3c9d3c; color: white; font-weight: bold;"),
    "estop": ("E-STOP\nlatched", "background: #5a1f1d; color: #ffb0a8; font-weight: bold;"),
}


class StickSlider(QSlider):
    """A stick axis: a deflection only while the handle is held (or the stick's keys); a wheel notch is no
    deflection (the page scrolls instead)."""

    def wheelEvent(self, ev) -> None:
        ev.ignore()


class StickPad(QWidget):
    """Drag the knob: x to the right, y up, each in [−1, 1]; it springs back when released."""

    moved = pyqtSignal(float, float, bool)  # x, y, held

    def __init__(self, parent=None, size: int = 140) -> None:
        super().__init__(parent)
        self.setMinimumSize(size, size)
        self.setToolTip(
            "virtual stick: drag to move the tool in x (right) and y (up); release to let go. "
            "Full deflection = k_p [m] (position mode) or k_v [m/s] (velocity mode)"
        )
        self.x = self.y = 0.0
        self.held = False

    def _radius(self) -> float:
        return min(self.width(), self.height()) / 2 - 12

    def _set_from(self, pos) -> None:
        r = self._radius()
        cx, cy = self.width() / 2, self.height() / 2
        x, y = (pos.x() - cx) / r, -(pos.y() - cy) / r
        n = (x * x + y * y) ** 0.5
        if n > 1:
            x, y = x / n, y / n
        self.x, self.y = x, y
        self.update()
        self.moved.emit(self.x, self.y, self.held)

    def mousePressEvent(self, ev) -> None:
        self.held = True
        self._set_from(ev.pos())

    def mouseMoveEvent(self, ev) -> None:
        if self.held:
            self._set_from(ev.pos())

    def mouseReleaseEvent(self, ev) -> None:
        self.held = False
        self.x = self.y = 0.0
        self.update()
        self.moved.emit(0.0, 0.0, False)

    def set_position(self, x: float, y: float, held: bool) -> None:
        """Programmatic deflection (keyboard, tests)."""
        self.x, self.y, self.held = x, y, held
        self.update()
        self.moved.emit(x, y, held)

    def paintEvent(self, ev) -> None:
        p = QPainter(self)
        p.setRenderHint(QPainter.Antialiasing)
        r = self._radius()
        c = QPointF(self.width() / 2, self.height() / 2)
        p.setPen(QPen(QColor(120, 120, 120), 2))
        p.setBrush(QBrush(QColor(40, 44, 52)))
        p.drawEllipse(c, r, r)
        p.drawLine(QPointF(c.x() - r, c.y()), QPointF(c.x() + r, c.y()))
        p.drawLine(QPointF(c.x(), c.y() - r), QPointF(c.x(), c.y() + r))
        knob = QPointF(c.x() + self.x * r, c.y() - self.y * r)
        p.setBrush(QBrush(QColor(230, 140, 40) if self.held else QColor(150, 150, 150)))
        p.drawEllipse(knob, 12, 12)


class VirtualStick(QWidget):
    """Pad for x/y, a z slider, an optional auxiliary slider (w) and a separate ENABLE (deadman).

    Deflection and enable are separate, as on a joystick: the pad and sliders spring back to
    neutral when released, the enable is held with the ENABLE button or the Shift key.  So in
    position mode releasing the pad while enable is held returns the tool to x_w, and releasing
    enable holds the machine where it is.  Emits ``changed(x, y, z, w, enabled)`` on every change.
    """

    changed = pyqtSignal(float, float, float, float, bool)

    def __init__(self, parent=None, aux_axis: str | None = None, pad_size: int = 140) -> None:
        super().__init__(parent)
        lay = QHBoxLayout(self)
        self.pad = StickPad(size=pad_size)
        lay.addWidget(self.pad, 1)
        self.z = self._slider(lay, "z", "z deflection in [−1, 1] (Page Up/Down); springs back to 0 when released")
        self.w = (
            self._slider(lay, aux_axis, f"{aux_axis} in [−1, 1]; springs back to 0 when released") if aux_axis else None
        )
        self.enable = QPushButton()
        self.enable.setFocusPolicy(Qt.NoFocus)  # Space stays STOP; Shift stays the stick's
        bold = QFont(self.enable.font())
        bold.setBold(True)
        fm = QFontMetrics(bold)
        widest = max(fm.horizontalAdvance(line) for text, _ in ENABLE_LOOK.values() for line in text.split("\n"))
        self.enable.setFixedSize(widest + 18, 2 * fm.height() + 16)  # the same size in every state: nothing moves
        self.engine_state = ""
        self.show_engine(None)
        self.enable.pressed.connect(self._changed)
        self.enable.released.connect(self._changed)
        lay.addWidget(self.enable)
        self.pad.moved.connect(lambda *_: self._changed())
        self.keys: dict[int, bool] = {}

    def _slider(self, lay, label: str, tip: str) -> QSlider:
        col = QVBoxLayout()
        col.addWidget(QLabel(label.split()[0]))
        sl = StickSlider(Qt.Vertical)
        sl.setRange(-100, 100)
        sl.setToolTip(tip)
        sl.sliderReleased.connect(lambda: sl.setValue(0))
        sl.setFocusPolicy(Qt.NoFocus)  # a deflection: only the held handle (or the stick's keys) moves it
        sl.valueChanged.connect(lambda _v: self._changed())
        col.addWidget(sl, 1)
        lay.addLayout(col)
        return sl

    def show_engine(self, state) -> None:
        """ENABLE shows what the engine's newest snapshot says of the input (``flags.enabled``, ``armed``,
        ``deadman``, the E-STOP latch), never only that the button is held: held while the engine is latched
        or not armed, it says so.  ``state`` None: no engine (lost, not started)."""
        if state is None:
            key, why = "none", "no engine state: the machine holds"
        else:
            f = state.flags
            if state.estop:
                key, why = "estop", "the E-STOP is latched: Reset first, then neutral and a fresh press of enable"
            elif f.enabled:
                key, why = "enabled", "the engine takes this input: the stick moves the machine"
            elif f.armed:
                key, why = "armed", f.input_reason or "armed; hold enable to drive"
            elif f.deadman:
                key, why = "not_armed", f.input_reason or "not armed: stick to neutral, release enable, press again"
            else:
                key, why = "idle", f.input_reason or "hold to drive (or hold Shift)"
        if key == self.engine_state:
            return
        self.engine_state = key
        text, style = ENABLE_LOOK[key]
        self.enable.setText(text)
        self.enable.setStyleSheet(f"QPushButton {{ {style} }} QPushButton:pressed {{ border: 3px solid #9fd89f; }}")
        self.enable.setToolTip(
            f"engine: {why}.\nDeadman: motion only while held (or hold Shift). After a reset, a mode or robot "
            "change the engine waits for the stick at neutral and a fresh press of enable"
        )

    @property
    def enabled(self) -> bool:
        return self.enable.isDown() or self.keys.get(Qt.Key_Shift, False)

    def values(self) -> tuple[float, float, float, float, bool]:
        z = self.z.value() / 100.0
        w = self.w.value() / 100.0 if self.w is not None else 0.0
        return self.pad.x, self.pad.y, z, w, self.enabled

    def _changed(self) -> None:
        self.changed.emit(*self.values())

    # keyboard: arrows for x/y, Page Up/Down for z, Shift = enable, while held
    KEYMAP: ClassVar[dict[int, tuple[int, int]]] = {
        Qt.Key_Left: (0, -1),
        Qt.Key_Right: (0, 1),
        Qt.Key_Down: (1, -1),
        Qt.Key_Up: (1, 1),
        Qt.Key_PageDown: (2, -1),
        Qt.Key_PageUp: (2, 1),
    }
    KEYS = frozenset({*KEYMAP, Qt.Key_Shift})

    def key(self, key: int, pressed: bool) -> bool:
        """A key press or release; True when it belongs to the stick (arrows, Page Up/Down, Shift)."""
        if key not in self.KEYS:
            return False
        if self.keys.get(key, False) == pressed:
            return True  # auto-repeat or a repeated release: nothing changes
        self.keys[key] = pressed
        self._apply_keys()
        return True

    def _apply_keys(self) -> None:
        v = [0.0, 0.0, 0.0]
        for k, down in self.keys.items():
            if down and k in self.KEYMAP:
                axis, sign = self.KEYMAP[k]
                v[axis] += sign
        if any(self.keys.get(k) for k in self.KEYMAP) or not self.pad.held:
            self.pad.x, self.pad.y = v[0], v[1]
            self.pad.update()
        self.z.blockSignals(True)
        self.z.setValue(int(100 * v[2]) if not self.z.isSliderDown() else self.z.value())
        self.z.blockSignals(False)
        self._changed()

    def release_all(self) -> None:
        """Every key, the pad and the sliders back to neutral, enable released (focus loss, tab change)."""
        self.keys.clear()
        self.pad.held = False
        self.pad.x = self.pad.y = 0.0
        self.pad.update()
        for sl in (self.z, self.w):
            if sl is not None:
                sl.blockSignals(True)
                sl.setSliderDown(False)
                sl.setValue(0)
                sl.blockSignals(False)
        self.enable.setDown(False)
        self._changed()
