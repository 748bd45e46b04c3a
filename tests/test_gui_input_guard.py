"""The application-wide wheel rule (ui/input_guard.py) is installed over every widget the application has,
also when some of them belong to a window closed before and are already gone."""

import pytest

pytest.importorskip("PyQt5")
from PyQt5 import sip
from PyQt5.QtCore import Qt
from PyQt5.QtWidgets import QSpinBox

from ui.input_guard import WheelGuard

pytestmark = pytest.mark.gui


class _App:
    """The application's widget list as Qt handed it over in CI: one of them deleted meanwhile."""

    def __init__(self, widgets) -> None:
        self.widgets = widgets
        self.filters = []

    def allWidgets(self):
        return self.widgets

    def installEventFilter(self, f) -> None:
        self.filters.append(f)


def test_installing_the_wheel_rule_passes_over_a_widget_already_deleted(qtbot):
    gone, live = QSpinBox(), QSpinBox()
    qtbot.addWidget(live)
    live.setFocusPolicy(Qt.WheelFocus)
    sip.delete(gone)
    guard = WheelGuard(lambda text: None)
    app = _App([gone, live])
    guard.install(app)
    assert live.focusPolicy() == Qt.StrongFocus  # a notch never gives it the keyboard
    assert app.filters == [guard]
