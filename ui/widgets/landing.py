"""The landing panel (issue 30, item 7): the load's clearance to the deck, its speed towards it, its swing and the
wire's tension, each a bar against its limits, as the crane-head engine reports them (``TacSnapshot.load``)."""

from __future__ import annotations

from PyQt5.QtCore import QRectF, Qt
from PyQt5.QtGui import QColor, QPainter, QPen
from PyQt5.QtWidgets import QGridLayout, QLabel, QSizePolicy, QWidget

from ui.widgets.status import LIGHT

GREY = QColor(110, 110, 120)
SWL_WARN = 90.0  # % of SWL shown amber (a load-moment indicator's pre-warning; the overload alarm is at 100 %)


class LimitBar(QWidget):
    """A horizontal bar from ``lo`` to ``hi`` (a signed one fills from zero), marks at its limits, the value as
    text on it; green, amber (``warn``) or red (``error``); grey with a dash when there is no value."""

    def __init__(self, lo: float, hi: float, marks: tuple[float, ...] = (), parent=None) -> None:
        super().__init__(parent)
        self.lo, self.hi, self.marks = lo, hi, marks
        self.value: float | None = None
        self.text = "—"
        self.state = "unknown"
        self.setMinimumSize(120, 16)
        self.setSizePolicy(QSizePolicy.Expanding, QSizePolicy.Fixed)

    def set(self, value: float | None, text: str, state: str = "ok") -> None:
        self.value, self.text, self.state = value, text, state if value is not None else "unknown"
        self.update()

    def _x(self, v: float, w: float) -> float:
        return w * (min(max(v, self.lo), self.hi) - self.lo) / (self.hi - self.lo)

    def paintEvent(self, _ev) -> None:
        p = QPainter(self)
        w, h = float(self.width()), float(self.height())
        p.fillRect(QRectF(0, 0, w, h), QColor(40, 40, 48))
        if self.value is not None:
            x0 = self._x(max(self.lo, 0.0), w)
            x1 = self._x(self.value, w)
            color = QColor(LIGHT[self.state]) if self.state in LIGHT and self.state != "unknown" else GREY
            p.fillRect(QRectF(min(x0, x1), 2, max(abs(x1 - x0), 2.0), h - 4), color)
        p.setPen(QPen(QColor(230, 230, 230), 1))
        for m in self.marks:
            x = self._x(m, w)
            p.drawLine(int(x), 0, int(x), int(h))
        p.setPen(QColor(250, 250, 250))
        p.drawText(QRectF(4, 0, w - 8, h), Qt.AlignVCenter | Qt.AlignLeft, self.text)
        p.end()


class LandingPanel(QWidget):
    """Four bars and a line of status: the landing as the engine reports it (issue 30, items 5 and 7)."""

    def __init__(
        self, parent=None, deck: str = "the target platform", fast: float = 0.3, ahc=("winch AHC on", "winch AHC off")
    ) -> None:
        """``deck``: what the clearance is measured to; ``fast``: a speed towards the deck, within 1 m of it, shown
        amber (assumed: the crane's 0.3 against its 0.2 m/s landing; the lab's 0.1 against 0.05 m/s); ``ahc``: the
        status line's words for the winch compensating or not."""
        super().__init__(parent)
        self.deck_name, self.fast, self.ahc_words = deck, fast, ahc
        grid = QGridLayout(self)
        grid.setContentsMargins(0, 0, 0, 0)
        grid.setVerticalSpacing(2)
        self.clearance = LimitBar(0.0, 5.0)
        self.speed = LimitBar(-0.5, 0.5, marks=(0.0,))
        self.swing = LimitBar(0.0, 10.0, marks=(5.0,))
        self.tension = LimitBar(0.0, 2.0, marks=(0.1, 1.0, 1.5))
        rows = (
            ("clearance", self.clearance, f"the load's underside above {deck}'s deck [m] (— not over it)"),
            ("to deck", self.speed, "the load's speed towards the deck [m/s]: positive closes in"),
            ("swing", self.swing, "the wire's angle from the vertical [°] against its limit (the mark)"),
            ("tension", self.tension, "the wire's tension over the load's weight; marks: slack 0.1, 1, snap 1.5"),
        )
        for i, (name, bar, tip) in enumerate(rows):
            label = QLabel(name)
            label.setToolTip(tip)
            bar.setToolTip(tip)
            grid.addWidget(label, i, 0)
            grid.addWidget(bar, i, 1)
        self.status = QLabel("—")
        self.status.setTextFormat(Qt.RichText)
        # its text asks no width of the page (a longer line widened the stick's box and pushed the plots past their
        # panel): what does not fit is cut at the right, where the least urgent words are
        self.status.setSizePolicy(QSizePolicy.Ignored, QSizePolicy.Preferred)
        grid.addWidget(self.status, len(rows), 0, 1, 2)
        grid.setColumnStretch(1, 1)

    def show_load(self, load) -> None:
        """Bars from a ``CraneLoadState`` (None: no load reported)."""
        if load is None:
            for bar in (self.clearance, self.speed, self.swing, self.tension):
                bar.set(None, "—")
            self.status.setText("—")
            return
        c = load.clearance
        if c is None:
            self.clearance.set(None, f"not over {self.deck_name}")
        else:
            state = "ok" if c > 1.0 or load.contact else "warn"
            self.clearance.set(max(c, 0.0), "on the deck" if load.contact else f"{c:.2f} m", state)
        near = c is not None and c < 1.0 and not load.contact
        v = load.rel_speed
        fast = near and v > self.fast  # closing in faster than a landing should
        self.speed.set(v, f"{v:+.2f} m/s", "warn" if fast else "ok")
        lim = load.swing_limit_deg
        self.swing.set(load.swing_deg, f"{load.swing_deg:.1f}°", "error" if load.swing_deg > lim else "ok")
        f = load.tension_factor
        bad = f > load.snap_factor or (f < load.slack_factor and not load.contact)
        text = f"{f:.2f}× static" + (" — slack" if f < load.slack_factor else "")
        self.tension.set(f, text, "error" if bad else "ok")
        parts = ["<b>landed</b>" if load.landed else "in the air"]
        if load.rehits:
            parts.append(f"<span style='color:{LIGHT['warn']}'><b>{load.rehits} re-hit(s)</b></span>")
        parts.append(self.ahc_words[0] if load.ahc else self.ahc_words[1])
        pct = getattr(load, "swl_percent", None)  # the load chart (issue 31, item 4): the crane's
        tip = ""
        if pct is not None:
            state = "error" if pct >= 100.0 else "warn" if pct >= SWL_WARN else "ok"
            parts.insert(0, f"<span style='color:{LIGHT[state]}'><b>SWL {pct:.0f} %</b></span>")  # first: seen
            tip = (
                f"this load in this sea against its safe working load: {load.payload_t:g} t × ψ {load.psi:.2f} (the "
                f"wire's peak tension over its weight in the last {load.psi_window:.0f} s) against the rated "
                f"{load.capacity_t:g} t at {load.radius:.1f} m; amber from {SWL_WARN:g} %, the overload alarm at 100 %"
            )
        elif getattr(load, "radius", None) is not None:  # the crane's, with no share to show: say why
            if load.rated and load.capacity_t is None:
                parts.insert(0, f"<span style='color:{LIGHT['error']}'><b>SWL —: beyond the chart</b></span>")
                tip = f"the load is at {load.radius:.1f} m, past the last rating of the crane's load chart: not rated"
            elif not load.rated:
                parts.insert(0, "<span style='color:#8a8aa0'>no load chart</span>")
                tip = "the crane's robot file has no <rated_capacity>: no share of its SWL can be shown"
        self.status.setToolTip(tip)
        self.status.setText(" · ".join(parts))
