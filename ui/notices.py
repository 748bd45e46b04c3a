"""The banner, the message bar and the keys overlay: shown without moving a single control.

Issue 26, item 2: the E-STOP banner and each message bar were inserted above the tabs, so every control
moved 33 px down when one appeared and back up when it went; an operator who pressed Space, clicked
*Reset E-STOP* and then clicked where *Open XML…* had been opened the solver drop-down instead.  Here
both live in the empty room to the right of the tab bar (:class:`NoticeStrip`, the tab widget's corner
widget), which has the tab bar's height whatever it shows: nothing below it ever moves.  Each half keeps
its room when empty, so the banner appearing does not shift the message's dismiss button either.

Item 7: a message is tied to its condition.  :meth:`NoticeStrip.post` takes a key (one message per
key: a newer one replaces it) and optionally ``gone``, a predicate; :meth:`NoticeStrip.sweep` clears
every message whose condition is gone ("Engine connection lost" once the engine is back, a refusal
"E-STOP is latched" once the reset is confirmed), :meth:`NoticeStrip.clear` one by its key.

The keys overlay (F1) floats over the top of the pages; F1 or its × closes it.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

from PyQt5.QtCore import QSize, Qt, pyqtSignal
from PyQt5.QtGui import QFont
from PyQt5.QtWidgets import QFrame, QHBoxLayout, QLabel, QPushButton, QSizePolicy, QTabWidget, QVBoxLayout, QWidget

from ui.widgets.labels import ElidedLabel

MESSAGE_COLORS = {"error": "#7a2421", "warning": "#7a5a00", "info": "#1f4e79"}


@dataclass
class Notice:
    key: str
    title: str
    message: str
    level: str
    stamp: str  # local time it was posted, hh:mm:ss
    gone: Callable[[], bool] | None = None

    @property
    def line(self) -> str:
        first = self.message.strip().splitlines()[0] if self.message.strip() else ""
        return f"{self.stamp}  {self.title}: {first}" if first else f"{self.stamp}  {self.title}"


def _keep_room(w: QWidget) -> None:
    """Hidden, ``w`` keeps its place in the layout (its neighbours never move)."""
    pol = w.sizePolicy()
    pol.setRetainSizeWhenHidden(True)
    w.setSizePolicy(pol)


class MessageBar(QFrame):
    """The newest message whose condition still holds: one line, ``+n`` more, × dismisses it."""

    dismissed = pyqtSignal()

    def __init__(self) -> None:
        super().__init__()
        self.setObjectName("message-bar")
        lay = QHBoxLayout(self)
        lay.setContentsMargins(8, 0, 2, 0)
        lay.setSpacing(4)
        self.text = ElidedLabel("")
        lay.addWidget(self.text, 1)
        self.more = QLabel("")
        self.more.setToolTip("")
        lay.addWidget(self.more)
        self.close_button = QPushButton("×")
        self.close_button.setFocusPolicy(Qt.NoFocus)  # Space stays STOP
        self.close_button.setFixedWidth(26)
        self.close_button.setToolTip("dismiss this message (it stays in the log)")
        self.close_button.clicked.connect(self.dismissed)
        lay.addWidget(self.close_button)
        self.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Preferred)
        _keep_room(self)
        self.hide()

    def show_notice(self, notice: Notice, others: list[Notice]) -> None:
        self.setStyleSheet(
            f"#message-bar {{ background: {MESSAGE_COLORS.get(notice.level, MESSAGE_COLORS['error'])};"
            " border-radius: 4px; } QLabel { color: white; }"
        )
        self.text.setText(notice.line)
        self.text.setToolTip(f"{notice.title}\n{notice.message}")
        self.more.setText(f"+{len(others)}" if others else "")
        self.more.setToolTip("\n".join(n.line for n in others))
        self.show()


class NoticeStrip(QWidget):
    """Banner (left half) and message bar (right half) in the tab bar's row; see the module doc."""

    def __init__(self, tabs: QTabWidget) -> None:
        super().__init__()
        self.tabs = tabs
        lay = QHBoxLayout(self)
        lay.setContentsMargins(8, 1, 2, 1)
        lay.setSpacing(6)
        self.banner = ElidedLabel("")
        self.banner.setAlignment(Qt.AlignCenter)
        f = QFont(self.banner.font())
        f.setBold(True)
        f.setPointSizeF(f.pointSizeF() * 1.15)
        self.banner.setFont(f)
        _keep_room(self.banner)
        self.banner.hide()
        lay.addWidget(self.banner, 1)
        self.message_bar = MessageBar()
        self.message_bar.dismissed.connect(self.dismiss)
        lay.addWidget(self.message_bar, 1)
        self.notices: list[Notice] = []  # oldest first
        self._banner_shown = None

    def sizeHint(self) -> QSize:
        """All the room beside the tabs: the tab bar keeps its own width (a wider hint squeezed the tabs away),
        the strip the tab bar's height; both depend only on the window's width, never on a text."""
        bar = self.tabs.tabBar().sizeHint()
        return QSize(max(0, self.tabs.width() - bar.width() - 6), bar.height())

    def minimumSizeHint(self) -> QSize:
        return QSize(0, self.tabs.tabBar().sizeHint().height())

    # ------------------------------------------------------------------ banner
    def set_banner(self, text: str, color: str = "") -> None:
        if (text, color) == self._banner_shown:
            return
        self._banner_shown = (text, color)
        self.banner.setText(text)
        self.banner.setToolTip(text)
        self.banner.setStyleSheet(f"background: {color}; color: white; border-radius: 4px; padding: 0 6px;")
        self.banner.setVisible(bool(text))

    # ------------------------------------------------------------------ messages
    def post(
        self, key: str, title: str, message: str, level: str = "error", gone: Callable[[], bool] | None = None
    ) -> Notice:
        """Show a message for ``key`` (replacing the one it had); ``gone()`` true clears it on :meth:`sweep`."""
        self.notices = [n for n in self.notices if n.key != key]
        n = Notice(key, title, message, level, time.strftime("%H:%M:%S"), gone)
        self.notices.append(n)
        self._show()
        return n

    def clear(self, key: str) -> None:
        if any(n.key == key for n in self.notices):
            self.notices = [n for n in self.notices if n.key != key]
            self._show()

    def sweep(self) -> None:
        """Clear every message whose condition is gone."""
        keep = [n for n in self.notices if n.gone is None or not n.gone()]
        if len(keep) != len(self.notices):
            self.notices = keep
            self._show()

    def dismiss(self) -> None:
        """× : the shown (newest) message goes; the next one shows."""
        if self.notices:
            self.notices.pop()
        self._show()

    def _show(self) -> None:
        if self.notices:
            self.message_bar.show_notice(self.notices[-1], self.notices[-2::-1])
        else:
            self.message_bar.hide()


class KeysOverlay(QFrame):
    """The shortcut overlay (F1): floats over the top of the pages, moves nothing, takes no keyboard."""

    def __init__(self, parent: QWidget, html: str) -> None:
        super().__init__(parent)
        self.setObjectName("keys-overlay")
        self.setStyleSheet(
            "#keys-overlay { background: rgba(22, 32, 48, 240); border: 1px solid #6a8ab0; border-radius: 6px; }"
            " QLabel { color: white; }"
        )
        lay = QVBoxLayout(self)
        lay.setContentsMargins(12, 8, 8, 10)
        top = QHBoxLayout()
        title = QLabel("<b>Keys and STOP</b> (F1 closes)")
        top.addWidget(title, 1)
        close = QPushButton("×")
        close.setFocusPolicy(Qt.NoFocus)
        close.setFixedWidth(26)
        close.clicked.connect(self.hide)
        top.addWidget(close)
        lay.addLayout(top)
        self.text = QLabel(html)
        self.text.setWordWrap(True)
        self.text.setTextFormat(Qt.RichText)
        lay.addWidget(self.text)
        self.setFocusPolicy(Qt.NoFocus)
        self.hide()

    def place(self, top: int) -> None:
        """Right-aligned over the parent, ``top`` px below its top edge."""
        p = self.parentWidget()
        w = min(760, max(300, p.width() - 24))
        self.setFixedWidth(w)
        h = self.heightForWidth(w)  # the wrapped text's height at this width (adjustSize guessed another width)
        if h > 0:
            self.setFixedHeight(h)
        else:
            self.adjustSize()
        self.move(p.width() - w - 12, top)
        self.raise_()

    def toggle(self, top: int) -> None:
        if self.isVisible():
            self.hide()
        else:
            self.place(top)
            self.show()
            self.raise_()
