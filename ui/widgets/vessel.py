"""The vessel row of a scene's controls (issue 17, item 2): the vessel model the engine runs, the vessels it
knows by name, and an RAO file (MSS ``.mat`` or Bosun's CSV) read here and handed to the engine in parts."""

from __future__ import annotations

import os
from collections.abc import Callable

from PyQt5.QtCore import pyqtSignal
from PyQt5.QtWidgets import QComboBox, QHBoxLayout, QWidget

from ui.widgets.files import choose_file
from ui.widgets.labels import ElidedLabel

FILE_ITEM = "RAO file…"
PART_CHARS = 55_000  # a part of the table's CSV (ASCII): within a client message's 64 KiB


def rao_file_parts(path: str) -> tuple[list[str], str]:
    """An RAO file as Bosun's CSV in parts for ``set_vessel`` (comments left out), and its label; a file
    that does not load raises :class:`app.errors.BosunError` with its one-line reason."""
    from app.marine.vessel import load_rao, rao_to_csv

    table = load_rao(path)
    text = "".join(line + "\n" for line in rao_to_csv(table).splitlines() if not line.startswith("#"))
    parts = [text[i : i + PART_CHARS] for i in range(0, len(text), PART_CHARS)]
    if len(parts) > 64:
        from app.errors import BosunError

        raise BosunError(f"{path}: the table is too large to send ({len(text)} characters; at most {64 * PART_CHARS})")
    return parts, os.path.basename(path)


class VesselRow(QWidget):
    """A combo of the engine's named vessels and "RAO file…", and the model the engine runs.

    Both show the engine's vessel, from its description (issue 26, item 4): the label leads with the vessel's
    name (the named vessels' descriptions share their first words, so a label that began with them looked the
    same for every vessel in a narrow column), and a pick only asks the engine: the combo goes back to the
    engine's vessel at once and shows the new one when the engine describes it (a refused or cancelled pick
    never looks taken).  ``send(fields)`` sends one ``set_vessel`` message; ``error`` says in one line why a
    file was not sent."""

    error = pyqtSignal(str)

    def __init__(self, send: Callable[..., None], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self._send = send
        self.combo = QComboBox()
        self.combo.setToolTip(
            "the vessel whose motion RAOs drive the scene: a vessel the engine knows by name, or an RAO file "
            "(MSS .mat or Bosun's CSV, e.g. from bosun vessel rao)"
        )
        self.combo.activated.connect(self._chosen)
        self.label = ElidedLabel("–")  # the engine's vessel model, whole in the tool tip
        self.label.setStyleSheet("color: #555")
        row = QHBoxLayout(self)  # one row: the column must fit a 1280 × 800 screen
        row.setContentsMargins(0, 0, 0, 0)
        row.setSpacing(6)
        row.addWidget(self.combo)
        row.addWidget(self.label, 1)
        self._dialog = None
        self._engine_item: str | None = None  # the combo item of the engine's vessel (None: not described yet)

    def set_engine(self, current: str, names: list[str]) -> None:
        """The engine's vessel model and the vessels it knows by name (from its description)."""
        items = [*names, FILE_ITEM]
        if [self.combo.itemText(i) for i in range(self.combo.count())] != items:
            self.combo.blockSignals(True)
            self.combo.clear()
            self.combo.addItems(items)
            self.combo.blockSignals(False)
        name = current.split(":", 1)[0]
        self._engine_item = name if name in names else FILE_ITEM
        self._show_engine()
        self.label.setText(current)  # "supply-closed-form: MSS supply vessel, …" or "RAO file x.csv"
        self.label.setToolTip(f"the vessel the engine runs: {current}")

    def _show_engine(self) -> None:
        """The combo on the engine's vessel (not on a pick the engine has not taken)."""
        if self._engine_item is not None and self.combo.currentText() != self._engine_item:
            self.combo.blockSignals(True)
            self.combo.setCurrentText(self._engine_item)
            self.combo.blockSignals(False)

    def _chosen(self, index: int) -> None:
        text = self.combo.itemText(index)
        self._show_engine()  # until the engine describes the vessel it runs
        if text == FILE_ITEM:
            self._dialog = choose_file(self, "RAO file", os.getcwd(), "RAO tables (*.mat *.csv)", self.send_file)
        elif text:
            self._send(vessel=text)

    def send_file(self, path: str) -> bool:
        """Read ``path`` here and send it in parts; a file that does not load is said in one line, not sent."""
        from app.errors import BosunError

        try:
            parts, label = rao_file_parts(path)
        except BosunError as err:
            self.error.emit(str(err))
            return False
        for k, text in enumerate(parts):
            self._send(csv=text, part=k, parts=len(parts), label=label)
        return True
