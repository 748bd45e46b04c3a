"""The alarm list: every engine's alarms and the GUI's own, with acknowledge one / all and shelving.

Rows: first-out mark, time raised, priority, source (the engine), text, state (ACTIVE / cleared /
shelved), and whether acknowledged.  Active unacknowledged alarms come first (critical before warning),
then the rest, newest first; shelved alarms last, greyed.  An alarm leaves the list once it is both
cleared and acknowledged.  Each row's tool tip is its rationalisation (``docs/alarms.md``): cause,
consequence, what to do.
"""

from __future__ import annotations

import time

from PyQt5.QtCore import Qt, pyqtSignal
from PyQt5.QtGui import QBrush, QColor
from PyQt5.QtWidgets import (
    QAbstractItemView,
    QHBoxLayout,
    QHeaderView,
    QSizePolicy,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from app.engine.alarm_catalog import SHELVE_DEFAULT_S, definition
from ui.widgets.buttons import button
from ui.widgets.labels import ElidedLabel

COLUMNS = ("", "time (UTC)", "priority", "source", "alarm", "state")
SEVERITY_RANK = {"critical": 0, "warning": 1, "info": 2}
ROW_COLOR = {"critical": "#5a1d1b", "warning": "#5a4a12", "info": "#1f3a52"}


class AlarmPanel(QWidget):
    """Shows merged alarm lists; ``ack(origin, key)`` asks the owner to acknowledge (key "" = all of origin)."""

    ack = pyqtSignal(str, str)
    shelve = pyqtSignal(str, str, float)  # origin, key, minutes (0: unshelve)

    def __init__(self, parent=None) -> None:
        super().__init__(parent)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        head = QHBoxLayout()
        self.title = ElidedLabel("Alarms: none")  # "…" and the whole text in its tool tip when narrow
        self.title.setStyleSheet("font-weight: bold;")
        head.addWidget(self.title, 1)
        # the list stands beside every tab: its buttons never take the keyboard (Space is STOP)
        self.ack_one = button("Acknowledge", "acknowledge the selected alarm", self._ack_selected, keyboard=False)
        self.ack_all = button("Acknowledge all", clicked=self._ack_everything, keyboard=False)
        self.shelve_one = button(
            f"Shelve {SHELVE_DEFAULT_S / 60:g} min",
            "shelve the selected alarm: it stays tracked but quiet, and returns by itself when the time is up "
            "(critical and trip alarms cannot be shelved); again on a shelved alarm: unshelve it",
            self._shelve_selected,
            keyboard=False,
        )
        for b in (self.ack_one, self.ack_all, self.shelve_one):
            head.addWidget(b)
        lay.addLayout(head)
        self.table = QTableWidget(0, len(COLUMNS))
        self.table.setHorizontalHeaderLabels(COLUMNS)
        self.table.verticalHeader().setVisible(False)
        self.table.setSelectionBehavior(QAbstractItemView.SelectRows)
        self.table.setSelectionMode(QAbstractItemView.SingleSelection)
        self.table.setEditTriggers(QAbstractItemView.NoEditTriggers)
        self.table.setFocusPolicy(Qt.NoFocus)
        h = self.table.horizontalHeader()
        for k in range(len(COLUMNS)):
            h.setSectionResizeMode(k, QHeaderView.ResizeToContents)
        h.setSectionResizeMode(4, QHeaderView.Stretch)
        self.table.setMinimumHeight(60)
        self.table.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Expanding)  # long alarms never widen the window
        self.title.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Preferred)
        self.setMinimumWidth(300)
        lay.addWidget(self.table, 1)
        self.rows: list[dict] = []
        self._shown: tuple = ()

    @staticmethod
    def ordered(alarms: list[dict]) -> list[dict]:
        return sorted(
            alarms,
            key=lambda a: (
                bool(a.get("shelved_until")),
                not (a["active"] and not a["acked"]),
                SEVERITY_RANK.get(a["severity"], 3),
                -a["t_raised"],
            ),
        )

    def set_alarms(self, alarms: list[dict]) -> None:
        """Each alarm dict as published by an engine, plus ``origin`` (which engine or "gui")."""
        rows = self.ordered(alarms)
        # first-out across every engine: of the alarms their engines marked first, the earliest still shown
        firsts = [a for a in rows if a["first_out"] and not a.get("shelved_until")]
        first = min(firsts, key=lambda a: a["t_raised"]) if firsts else None
        rows = [{**a, "first_out": a is first} for a in rows]
        key = tuple(
            (a["origin"], a["key"], a["active"], a["acked"], a["text"], a["first_out"], a.get("shelved_until"))
            for a in rows
        )
        if key == self._shown:
            return
        self._shown = key
        self.rows = rows
        selected = self._selected_key()
        self.table.setRowCount(len(rows))
        for r, a in enumerate(rows):
            stamp = time.strftime("%H:%M:%S", time.gmtime(a["t_raised"]))
            shelved = a.get("shelved_until")
            state = ("ACTIVE" if a["active"] else "cleared") + ("" if a["acked"] else ", unacknowledged")
            if shelved:
                state = f"shelved until {time.strftime('%H:%M', time.gmtime(shelved))}, " + state.lower()
            cells = ("1st" if a["first_out"] else "", stamp, a["severity"].upper(), a["source"], a["text"], state)
            tip = _rationale(a["key"])
            for c, text in enumerate(cells):
                item = QTableWidgetItem(text)
                if tip:
                    item.setToolTip(tip)
                if shelved:
                    item.setForeground(QBrush(QColor("#888")))
                elif a["active"] and not a["acked"]:
                    item.setBackground(QBrush(QColor(ROW_COLOR.get(a["severity"], "#333"))))
                    item.setForeground(QBrush(QColor("white")))
                elif not a["active"]:
                    item.setForeground(QBrush(QColor("#888")))
                if c == 0:
                    item.setToolTip("first out: the first alarm raised while none was active")
                self.table.setItem(r, c, item)
            if (a["origin"], a["key"]) == selected:
                self.table.selectRow(r)
        shown = [a for a in rows if not a.get("shelved_until")]
        n_active = sum(a["active"] for a in shown)
        n_new = sum(not a["acked"] for a in shown)
        n_shelved = len(rows) - len(shown)
        text = f"Alarms: {n_active} active, {n_new} unacknowledged" if shown else "Alarms: none"
        self.title.setText(text + (f", {n_shelved} shelved" if n_shelved else ""))
        crit = any(a["active"] and not a["acked"] and a["severity"] == "critical" for a in shown)
        self.title.setStyleSheet(f"font-weight: bold; color: {'#d9534f' if crit else 'palette(text)'};")

    def _selected_key(self) -> tuple[str, str] | None:
        r = self.table.currentRow()
        if 0 <= r < len(self.rows) and self.table.selectionModel().isRowSelected(r, self.table.rootIndex()):
            return self.rows[r]["origin"], self.rows[r]["key"]
        return None

    def _ack_selected(self) -> None:
        sel = self._selected_key()
        if sel is None and self.rows:  # nothing selected: the top row (the newest most severe)
            sel = self.rows[0]["origin"], self.rows[0]["key"]
        if sel is not None:
            self.ack.emit(*sel)

    def _shelve_selected(self) -> None:
        sel = self._selected_key()
        if sel is None:
            return  # shelving is deliberate: only the alarm the operator selected
        row = next(a for a in self.rows if (a["origin"], a["key"]) == sel)
        self.shelve.emit(*sel, 0.0 if row.get("shelved_until") else SHELVE_DEFAULT_S / 60)

    def _ack_everything(self) -> None:
        for origin in sorted({a["origin"] for a in self.rows}):
            self.ack.emit(origin, "")


def _rationale(key: str) -> str:
    """The alarm's rationalisation as a tool tip: what it means and what to do."""
    d = definition(key)
    if d is None:
        return ""
    return f"{d.title}\nCause: {d.cause}\nIf nobody acts: {d.consequence}\nDo: {d.action}"
