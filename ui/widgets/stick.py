"""On-screen virtual stick and keyboard control, for when no joystick is present."""

from __future__ import annotations

from typing import ClassVar

from PyQt5.QtCore import QPointF, Qt, pyqtSignal
from PyQt5.QtGui import QBrush, QColor, QPainter, QPen
from PyQt5.QtWidgets import QHBoxLayout, QLabel, QSlider, QVBoxLayout, QWidget


class StickPad(QWidget):
    """Drag the knob: x to the right, y up, each in [−1, 1]; it springs back when released."""

    moved = pyqtSignal(float, float, bool)  # x, y, held

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        self.setMinimumSize(140, 140)
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
    """Pad for x/y plus a z slider; emits (x, y, z, held) whenever anything changes."""

    changed = pyqtSignal(float, float, float, bool)

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        lay = QHBoxLayout(self)
        self.pad = StickPad()
        lay.addWidget(self.pad, 1)
        col = QVBoxLayout()
        col.addWidget(QLabel("z"))
        self.z = QSlider(Qt.Vertical)
        self.z.setRange(-100, 100)
        self.z.setToolTip("z deflection in [−1, 1]; springs back to 0 when released")
        self.z.sliderReleased.connect(lambda: self.z.setValue(0))
        col.addWidget(self.z, 1)
        lay.addLayout(col)
        self.pad.moved.connect(self._emit)
        self.z.valueChanged.connect(lambda _v: self._emit(self.pad.x, self.pad.y, self.pad.held))
        self.keys: dict[int, bool] = {}

    def _emit(self, x: float, y: float, held: bool) -> None:
        z = self.z.value() / 100.0
        self.changed.emit(x, y, z, held or self.z.isSliderDown() or z != 0.0)

    # keyboard: arrows for x/y, Page Up/Down for z, while held
    KEYMAP: ClassVar[dict[int, tuple[int, int]]] = {
        Qt.Key_Left: (0, -1),
        Qt.Key_Right: (0, 1),
        Qt.Key_Down: (1, -1),
        Qt.Key_Up: (1, 1),
        Qt.Key_PageDown: (2, -1),
        Qt.Key_PageUp: (2, 1),
    }

    def key(self, key: int, pressed: bool) -> bool:
        if key not in self.KEYMAP:
            return False
        self.keys[key] = pressed
        v = [0.0, 0.0, 0.0]
        for k, down in self.keys.items():
            if down:
                axis, sign = self.KEYMAP[k]
                v[axis] += sign
        held = any(self.keys.values())
        self.pad.x, self.pad.y = v[0], v[1]
        self.pad.update()
        self.changed.emit(v[0], v[1], v[2], held)
        return True
