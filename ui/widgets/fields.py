"""Fields that show an engine value and keep the operator's unapplied edit.

A field follows the engine's value (from each state) until the operator edits it.  From then on
the edit stays, whatever states come in, until

* the engine's value equals it (the operator applied it and the engine took it), or
* the operator presses Esc in the field (back to the engine's value), or :meth:`EngineFields.revert`.

While the field differs from the engine's value it is highlighted (``DIRTY_STYLE``) and its tool
tip says what the engine has.  A refused Apply leaves the edit and its highlight in place.
"""

from __future__ import annotations

from PyQt5.QtCore import QEvent, QObject, Qt, pyqtSignal
from PyQt5.QtWidgets import QAbstractSpinBox, QComboBox, QWidget

DIRTY_COLOR = "#fff1a8"
DIRTY_STYLE = f"background: {DIRTY_COLOR}; color: black;"


class _Field:
    __slots__ = ("edited", "engine", "tip", "widget")

    def __init__(self, widget: QWidget) -> None:
        self.widget = widget
        self.engine = None  # the engine's value, None until a state gave one
        self.edited = False
        self.tip = widget.toolTip()


class EngineFields(QObject):
    """A group of spin boxes and combo boxes showing engine values; see the module doc."""

    dirty_changed = pyqtSignal(bool)  # any field of the group edited and not yet the engine's

    def __init__(self, parent: QObject | None = None) -> None:
        super().__init__(parent)
        self.fields: dict[QWidget, _Field] = {}
        self._setting = False
        self._any_dirty = False

    # ------------------------------------------------------------------ set-up
    def add(self, widget: QWidget) -> QWidget:
        f = _Field(widget)
        self.fields[widget] = f
        if isinstance(widget, QAbstractSpinBox):
            widget.valueChanged.connect(lambda _v, w=widget: self._edited(w))
        elif isinstance(widget, QComboBox):
            widget.currentIndexChanged.connect(lambda _i, w=widget: self._edited(w))
        else:
            raise TypeError(f"{type(widget).__name__}: a spin box or a combo box")
        widget.installEventFilter(self)
        return widget

    # ------------------------------------------------------------------ values
    @staticmethod
    def _value(w: QWidget):
        return w.currentText() if isinstance(w, QComboBox) else w.value()

    @staticmethod
    def _same(w: QWidget, a, b) -> bool:
        if a is None or b is None:
            return a is b
        if isinstance(w, QComboBox):
            return a == b
        return round(float(a), w.decimals()) == round(float(b), w.decimals())

    def _show(self, w: QWidget, value) -> None:
        self._setting = True
        try:
            if isinstance(w, QComboBox):
                if w.findText(value) < 0:
                    w.addItem(value)
                w.setCurrentText(value)
            else:
                w.setValue(value)
        finally:
            self._setting = False

    def engine_value(self, w: QWidget, value) -> None:
        """The engine's value of this field (from a state): shown unless the operator's edit waits."""
        f = self.fields[w]
        f.engine = value
        if f.edited and self._same(w, self._value(w), value):
            f.edited = False  # applied and taken (or typed back to the engine's value)
        if not f.edited and not self._same(w, self._value(w), value):
            self._show(w, value)
        self._style(f)

    def _edited(self, w: QWidget) -> None:
        if self._setting:
            return
        f = self.fields[w]
        f.edited = not self._same(w, self._value(w), f.engine) if f.engine is not None else True
        self._style(f)

    # ------------------------------------------------------------------ state
    def dirty(self, w: QWidget) -> bool:
        """The field holds an edit that differs from the engine's value."""
        f = self.fields[w]
        return f.edited and (f.engine is None or not self._same(w, self._value(w), f.engine))

    def any_dirty(self) -> bool:
        return any(self.dirty(w) for w in self.fields)

    def revert(self, w: QWidget | None = None) -> None:
        """Back to the engine's value (every field of the group when ``w`` is None)."""
        for f in [self.fields[w]] if w is not None else list(self.fields.values()):
            f.edited = False
            if f.engine is not None:
                self._show(f.widget, f.engine)
            self._style(f)

    def _style(self, f: _Field) -> None:
        w = f.widget
        dirty = self.dirty(w)
        if bool(w.property("dirty")) != dirty:  # restyling relayouts: only on change
            w.setProperty("dirty", dirty)
            w.setStyleSheet(DIRTY_STYLE if dirty else "")
        if dirty:
            shown = f.engine if f.engine is not None else "unknown"
            if not isinstance(w, QComboBox) and f.engine is not None:
                shown = f"{w.prefix()}{float(f.engine):.{w.decimals()}f}{w.suffix()}"
            tip = f"edited, not applied (the engine has {shown}): Apply sends it, Esc reverts"
            w.setToolTip(f"{f.tip}\n{tip}" if f.tip else tip)
        elif w.toolTip() != f.tip:
            w.setToolTip(f.tip)
        any_dirty = dirty or self.any_dirty()
        if any_dirty != self._any_dirty:
            self._any_dirty = any_dirty
            self.dirty_changed.emit(any_dirty)

    def eventFilter(self, obj, ev) -> bool:
        if ev.type() == QEvent.KeyPress and ev.key() == Qt.Key_Escape and obj in self.fields:
            if isinstance(obj, QComboBox) and obj.view().isVisible():
                return False  # Esc closes an open list first
            if self.fields[obj].edited:
                self.revert(obj)
                return True
        return False
