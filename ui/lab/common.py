"""What the Motion-Lab pages share: the lab's names, colours and looks, and the bar every page uses."""

from __future__ import annotations

from PyQt5.QtWidgets import (
    QProgressBar,
)

HISTORY_S = 60.0
SAMPLE_HZ = 25
DOFS = ("surge", "sway", "heave", "roll", "pitch", "yaw")
SOURCES = ("generator", "simulation", "remote", "timeseries")
COMAU_MODES = ("settled", "remote", "motion_comp", "hold")
PLATFORM_COLUMNS = ("t", *DOFS)  # position [m], attitude [deg]
# engine time, Comau q [deg] and q̇ [rad/s], swing α β [rad], tool − work point in {b2} [m], wire length [m]
LAB_COLUMNS = ("t", "q1", "q2", "q3", "qd1", "qd2", "qd3", "alpha", "beta", "err_x", "err_y", "err_z", "wire")
# issue 16, item 4: the swing estimator's estimate α̂ β̂, its error (estimate − true) and 1-σ [deg], the law's offset [mm]
SWING_COLUMNS = ("t", "alpha", "beta", "alpha_hat", "beta_hat", "err_a", "err_b", "sig_a", "sig_b", "off_x", "off_y")
# issue 16, item 5: the lab HMI's "Machine and Sensor States" lights (engine name, shown name) and their colours
MACHINES = (
    ("em8000", "EM8000"),
    ("em1500", "EM1500"),
    ("comau", "Comau"),
    ("mru1", "MRU1"),
    ("mru2", "MRU2"),
    ("tracker", "tracker"),
    ("remote", "remote"),
)
MACHINE_LIGHT = {
    "active": ("ok", "on"),
    "inactive": ("error", "OFF"),
    "absent": ("off", "n/c"),
    "stale": ("warn", "old"),  # issue 27: the PLC sent invalid data for it; the last valid value is held
    "unknown": ("unknown", "?"),
}
MOTION_COLOR = {"SYSTEM_OK": "#3c9", "WARNING": "#fa3", "ERROR": "#e33"}
# a platform's mode as its page shows it; red only for a latched E-STOP (issue 26, item 5)
STATUS_COLOR = {"ENGAGED": "#3c9", "NEUTRAL": "#39f", "SETTLED": "#999", "HOLDING": "#fa3"}
STOP_COLOR = "#e33"
# the Motion-Lab engine's lights on its page (issue 26, item 6): key, shown name, tool tip
LAB_LIGHTS = (
    ("engine", "engine", "the Motion-Lab engine: connection and loop"),
    ("input", "input", "the input that drives a lab machine now: a joint jog, the stick (REMOTE) or none"),
    ("plant", "plant", "the lab's machines as the engine reports them: moving, compensating, holding, at rest, E-STOP"),
    ("plc", "PLC", "the lab's PLC link (bosun server --plant lab --plc): none (simulated plant), ok, lost, error"),
)
# the stick's ENABLE as the engine takes it: (text, style sheet) for enabled, held but refused, armed, not armed
ENABLE_LOOK = {
    "enabled": ("ENABLED", "QPushButton { background: #3c9d3c; color: white; font-weight: bold; }"),
    "refused": (
        "NOT ARMED\n(release)",
        "QPushButton, QPushButton:pressed { background: #e0a020; color: black; font-weight: bold; }",
    ),
    "armed": ("ENABLE\n(armed)", "QPushButton { border: 2px solid #3c9d3c; }"),
    "idle": ("ENABLE\n(hold)", ""),
}
JOG_RESEND_MS = 100  # a held jog button resends its speed this often (the engine stops a jog after 0.3 s)


def progress_bar(fmt: str = "%p %") -> QProgressBar:
    b = QProgressBar()
    b.setRange(0, 1000)
    b.setFormat(fmt)
    b.setTextVisible(True)
    return b


def set_bar(bar: QProgressBar, fraction: float, text: str) -> None:
    bar.setValue(int(1000 * min(1.0, max(0.0, fraction))))
    bar.setFormat(text)
