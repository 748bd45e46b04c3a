"""The mouse wheel scrolls the page; it changes a set-point only in the field that has the keyboard.

Qt's spin boxes, combo boxes, sliders and tab bars take every wheel notch under the pointer, focused or
not: an operator scrolling the Motion-Lab's Comau & winch panel changed the jog speed from 25 to 17 %
without noticing (issue 26, item 3).  :class:`WheelGuard`, installed on the QApplication, keeps one rule
for every such widget of every window (also the ones a tab builds later):

* a widget that does not have the keyboard focus never changes on the wheel: the notch scrolls the
  nearest scroll area around it instead (the page the operator was scrolling), and a wheel notch never
  gives it the focus either (``Qt.WheelFocus`` becomes ``Qt.StrongFocus``);
* in the widget that has the focus (the operator clicked or tabbed into it) the wheel works as usual,
  and each change is written to the GUI log ("jog speed: 25 → 17 % of the joint speed (mouse wheel)"),
  one line per burst of notches.
"""

from __future__ import annotations

import re
from collections.abc import Callable

from PyQt5 import sip
from PyQt5.QtCore import QEvent, QObject, Qt, QTimer
from PyQt5.QtWidgets import (
    QAbstractScrollArea,
    QAbstractSlider,
    QAbstractSpinBox,
    QApplication,
    QComboBox,
    QFormLayout,
    QGridLayout,
    QLabel,
    QScrollBar,
    QTabBar,
    QWidget,
)

LOG_AFTER_MS = 600  # a burst of wheel notches is one log line, written this long after the last notch


def guarded(w) -> bool:
    """A widget whose value a wheel notch would change (scroll bars are the scrolling itself)."""
    return isinstance(w, QAbstractSpinBox | QComboBox | QTabBar) or (
        isinstance(w, QAbstractSlider) and not isinstance(w, QScrollBar)
    )


def shown_value(w) -> str:
    """What the operator reads in the widget (with its unit)."""
    if isinstance(w, QAbstractSpinBox):
        return w.text().strip()
    if isinstance(w, QComboBox):
        return w.currentText()
    if isinstance(w, QTabBar):
        return w.tabText(w.currentIndex())
    return str(w.value())


def _holds(item, w: QWidget) -> bool:
    if item is None:
        return False
    if item.widget() is not None:
        return item.widget() is w or item.widget().isAncestorOf(w)
    lay = item.layout()
    return lay is not None and any(_holds(lay.itemAt(i), w) for i in range(lay.count()))


def _plain(text: str) -> str:
    return re.sub(r"<[^>]+>", "", text).replace("&nbsp;", " ").strip()


def field_name(w: QWidget) -> str:
    """The name an operator sees next to ``w``: its form label, its grid row and column headers, else
    the first clause of its tool tip."""
    win = w.window()
    for form in win.findChildren(QFormLayout):
        for r in range(form.rowCount()):
            if _holds(form.itemAt(r, QFormLayout.FieldRole), w):
                label = form.itemAt(r, QFormLayout.LabelRole)
                if label is not None and isinstance(label.widget(), QLabel):
                    return _plain(label.widget().text())
    for grid in win.findChildren(QGridLayout):
        idx = grid.indexOf(w)
        if idx < 0:
            continue
        row, col, _, _ = grid.getItemPosition(idx)
        in_row = [grid.itemAtPosition(row, c) for c in range(grid.columnCount())]
        several = sum(1 for it in in_row if it is not None and guarded(it.widget())) > 1
        parts = []
        for r, c in ((row, 0), (0, col)) if several else ((row, 0),):  # the column header where a row has several
            item = grid.itemAtPosition(r, c)
            if item is not None and isinstance(item.widget(), QLabel) and item.widget() is not w:
                parts.append(_plain(item.widget().text()))
        if parts:
            return " ".join(dict.fromkeys(p for p in parts if p))
    tip = w.toolTip().split("\n")[0]
    if tip:
        return tip.split(":")[0][:40]
    return w.accessibleName() or w.objectName() or type(w).__name__


class WheelGuard(QObject):
    """The application-wide wheel rule of the module doc.  ``log(text)`` receives the change lines."""

    def __init__(self, log: Callable[[str], None], parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.log = log
        self._before: dict[QWidget, str] = {}  # widget -> its value before the current burst of notches
        self._timer = QTimer(self)
        self._timer.setSingleShot(True)
        self._timer.setInterval(LOG_AFTER_MS)
        self._timer.timeout.connect(self.flush)

    def install(self, app: QApplication | None = None) -> None:
        app = app or QApplication.instance()
        for w in app.allWidgets():
            # a widget of a window closed before may be gone by now (seen in CI: a QSpinBox deleted while
            # a second window was built in the same process)
            if not sip.isdeleted(w):
                self._no_wheel_focus(w)
        app.installEventFilter(self)

    def remove(self, app: QApplication | None = None) -> None:
        self.flush()
        (app or QApplication.instance()).removeEventFilter(self)

    @staticmethod
    def _no_wheel_focus(w) -> None:
        if guarded(w) and w.focusPolicy() == Qt.WheelFocus:
            w.setFocusPolicy(Qt.StrongFocus)  # a notch never gives the keyboard to it

    def eventFilter(self, obj, ev) -> bool:
        t = ev.type()
        if t == QEvent.Polish:  # every widget, also those a tab builds later, before it is first shown
            self._no_wheel_focus(obj)
        elif t == QEvent.Wheel and guarded(obj) and obj.isEnabled():
            if obj.hasFocus():
                if obj not in self._before:
                    self._before[obj] = shown_value(obj)
                    obj.destroyed.connect(lambda *_, o=obj: self._before.pop(o, None))
                self._timer.start()
                return False  # the focused field takes it (and the change is logged)
            self._scroll_instead(obj, ev)
            return True
        return False

    @staticmethod
    def _scroll_instead(w: QWidget, ev) -> None:
        """The notch goes to the nearest scroll area around ``w`` that can still scroll that way."""
        p = w.parentWidget()
        while p is not None:
            if isinstance(p, QAbstractScrollArea):
                ev.ignore()
                QApplication.sendEvent(p.viewport(), ev)
                if ev.isAccepted():
                    break
            if p.isWindow():
                break
            p = p.parentWidget()
        ev.accept()  # never handed on to the widget itself

    def flush(self) -> None:
        """Log every focused field the wheel changed (one line each) and forget the bursts."""
        before, self._before = self._before, {}
        for w, old in before.items():
            try:
                new = shown_value(w)
            except RuntimeError:  # deleted meanwhile
                continue
            if new != old:
                self.log(f"{field_name(w)}: {old} → {new} (mouse wheel, the field has the keyboard)")
