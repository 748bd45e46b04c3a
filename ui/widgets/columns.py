"""A column of controls that scrolls on its own, so the plots and views beside it keep the page's height.

A page's minimum height is its tallest column's: a form of twenty rows made a Motion-Lab page 890 px
tall, so on a 1280×800 screen (the status panel below) the whole page scrolled and the plots and the 3D
view beside the form were cut at the bottom.  In a scroll area of its own the column scrolls instead.
"""

from __future__ import annotations

from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QFrame, QScrollArea, QWidget


def scroll_column(column: QWidget, max_width: int | None = None) -> QScrollArea:
    """``column`` in a vertical scroll area as wide as the column needs (never a horizontal scroll bar)."""
    area = QScrollArea()
    area.setWidget(column)
    area.setWidgetResizable(True)
    area.setFrameShape(QFrame.NoFrame)
    area.setHorizontalScrollBarPolicy(Qt.ScrollBarAlwaysOff)
    bar = area.verticalScrollBar().sizeHint().width()
    area.setMinimumWidth(column.minimumSizeHint().width() + bar + 4)
    if max_width is not None:
        column.setMaximumWidth(max_width)
        area.setMaximumWidth(max_width + bar + 4)
    return area
