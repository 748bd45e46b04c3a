"""Non-modal file choosers: while one is open, STOP and the rest of the window stay live."""

from __future__ import annotations

from collections.abc import Callable

from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QFileDialog, QWidget


def choose_file(
    parent: QWidget, title: str, directory: str, filters: str, on_chosen: Callable[[str], None], save: bool = False
) -> QFileDialog:
    """Open a Qt (not native) file dialog that blocks nothing; ``on_chosen(path)`` runs when one is picked."""
    dlg = QFileDialog(parent, title, directory, filters)
    dlg.setOption(QFileDialog.DontUseNativeDialog, True)
    if save:
        dlg.setAcceptMode(QFileDialog.AcceptSave)
        dlg.setFileMode(QFileDialog.AnyFile)
    else:
        dlg.setFileMode(QFileDialog.ExistingFile)
    dlg.setModal(False)
    dlg.setWindowModality(Qt.NonModal)
    dlg.setAttribute(Qt.WA_DeleteOnClose)
    dlg.fileSelected.connect(on_chosen)
    dlg.show()
    return dlg
