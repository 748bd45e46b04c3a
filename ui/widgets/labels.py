"""Labels that never cut their text silently: too long for their room, they end in "…" and their
tool tip shows the whole text."""

from __future__ import annotations

from PyQt5.QtCore import QEvent, Qt
from PyQt5.QtGui import QPainter
from PyQt5.QtWidgets import QLabel, QSizePolicy, QStyle, QStyleOption, QToolTip


class ElidedLabel(QLabel):
    """A one-line plain-text label that elides (…) instead of cutting; it never widens its layout.

    ``text()`` is the whole text; :meth:`shown_text` what fits.  The tool tip adds the whole text
    whenever it is elided.
    """

    def __init__(self, text: str = "", parent=None, min_chars: int = 8) -> None:
        super().__init__(text, parent)
        self.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Preferred)
        self.setMinimumWidth(self.fontMetrics().averageCharWidth() * min_chars)
        self.setTextFormat(Qt.PlainText)

    def shown_text(self) -> str:
        return self.fontMetrics().elidedText(self.text(), Qt.ElideRight, max(0, self.contentsRect().width()))

    def elided(self) -> bool:
        return self.shown_text() != self.text()

    def paintEvent(self, ev) -> None:
        p = QPainter(self)
        opt = QStyleOption()
        opt.initFrom(self)
        self.style().drawPrimitive(QStyle.PE_Widget, opt, p, self)  # a style sheet's background
        align = self.alignment() or (Qt.AlignLeft | Qt.AlignVCenter)
        rect, text = self.contentsRect(), self.shown_text()
        self.style().drawItemText(p, rect, int(align), self.palette(), self.isEnabled(), text, self.foregroundRole())

    def event(self, ev) -> bool:
        if ev.type() == QEvent.ToolTip and self.elided():
            tip = self.toolTip()
            QToolTip.showText(ev.globalPos(), f"{self.text()}\n{tip}" if tip else self.text(), self)
            return True
        return super().event(ev)
