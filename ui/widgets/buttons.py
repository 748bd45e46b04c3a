"""The push button as the HMI makes it: its text, tool tip and click in one call."""

from __future__ import annotations

from collections.abc import Callable

from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QPushButton


def button(text: str, tip: str = "", clicked: Callable | None = None, *, keyboard: bool = True) -> QPushButton:
    """A push button with its tool tip and what a click runs (``clicked``; None: the caller connects it).

    ``keyboard=False``: the button never takes the keyboard focus, so Space stays STOP (a focused button
    would swallow it as a click): the STOP column's buttons and those of panels shown beside every tab."""
    b = QPushButton(text)
    if not keyboard:
        b.setFocusPolicy(Qt.NoFocus)
    if tip:
        b.setToolTip(tip)
    if clicked is not None:
        b.clicked.connect(clicked)
    return b
