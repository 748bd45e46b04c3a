"""``bosun`` / ``bosun gui``: the operator HMI, with its own engine or attached to one."""

from __future__ import annotations

import os
import sys

from app.errors import BosunError, require


def has_display() -> bool:
    return bool(
        os.environ.get("DISPLAY")
        or os.environ.get("WAYLAND_DISPLAY")
        or os.environ.get("QT_QPA_PLATFORM") in ("offscreen", "minimal", "vnc")
    )


def require_gui(what: str) -> None:
    """:class:`~app.errors.MissingExtraError` (one line, exit 2) unless the ``gui`` extra is installed."""
    for module in ("PyQt5.QtWidgets", "pyqtgraph", "OpenGL"):
        require(module, "gui", what)


def stop_requests() -> list[str]:
    """SIGTERM and SIGINT from now on only record that a stop was asked for (the returned list).

    Once Qt runs, it calls Python for resize and paint events; an exception a signal handler raises
    inside such a call is printed and lost, so a handler that raised KeyboardInterrupt could leave the
    GUI running after SIGTERM (seen while the window was being built; H53)."""
    import signal

    asked: list[str] = []
    signal.signal(signal.SIGTERM, lambda *_: asked.append("SIGTERM"))
    signal.signal(signal.SIGINT, lambda *_: asked.append("SIGINT"))
    return asked


def close_when_asked(win, asked: list[str]) -> None:
    """Close ``win`` (engines stopped, links said bye) as soon as :func:`stop_requests` recorded a stop,
    also one asked for while the window was being built."""
    from PyQt5.QtCore import QTimer

    timer = QTimer(win)
    timer.setInterval(100)  # also lets Python run its signal handlers while Qt's loop runs in C

    def check() -> None:
        if asked:
            # once: a timer that went on calling close() every 100 ms fired while the closed window was being
            # destroyed (a test process died of SIGSEGV in the next test's event processing, CI 2026-11-28)
            timer.stop()
            win.close()

    timer.timeout.connect(check)
    timer.start()


def run_gui(
    connect: str | None = None,
    token: str | None = None,
    robot: str | None = None,
    solver: str | None = None,
    mode: str | None = None,
    quit_after: float | None = None,
    connect_tac: str | None = None,
    connect_lab: str | None = None,
    curve=None,
) -> int:
    """Open the main window; start a child engine unless ``connect`` names a running one."""
    require_gui("the GUI")
    if not has_display():
        raise BosunError(
            "no display to open the GUI on (DISPLAY is not set); run 'bosun server' headless, "
            "or start the GUI on a desktop or under xvfb-run"
        )
    from PyQt5.QtCore import QSettings, QTimer
    from PyQt5.QtWidgets import QApplication

    from app.net.transport import TransportError
    from ui.engine_process import EngineProcess
    from ui.glprobe import share_gl_contexts
    from ui.link import EngineLink
    from ui.main_window import MainWindow

    share_gl_contexts()  # before the QApplication: every GL view shares shaders
    app = QApplication.instance() or QApplication(sys.argv[:1])
    app.setApplicationName("Bosun")
    settings = QSettings("Bosun", "Bosun HMI")
    engine = None
    try:
        if connect is None:
            engine = EngineProcess(
                robot=robot or str(settings.value("robot", "comau_smart5_3dof")),
                solver=solver or str(settings.value("solver", "jacobian")),
                mode=mode or str(settings.value("mode", "velocity")),
            )
            connect = engine.url
        link = EngineLink(
            connect,
            role="operator",
            token=token,
            secret=engine.secret if engine is not None else None,  # only this GUI operates its own engine
            curve=curve if engine is None else None,
        )
    except TransportError as err:
        if engine is not None:
            engine.stop()
        raise BosunError(str(err)) from None
    except BaseException:  # Ctrl-C or SIGTERM while the engine starts: leave no engine behind
        if engine is not None:
            engine.stop()
        raise
    marine_engines: list = []

    class SceneStarter:
        """A scene (crane head, Motion-Lab) runs in its own engine process, started on first use: the
        process in a background thread (``start_process``), the link in the GUI thread (``link``)."""

        def __init__(self, plant: str, url: str | None) -> None:
            self.plant, self.url, self.proc = plant, url, None

        def start_process(self) -> str:
            if self.url is not None:
                return self.url
            self.proc = EngineProcess(plant=self.plant)
            return self.proc.url

        def link(self, url: str):
            name = f"bosun-gui-{self.plant}"
            try:
                link = EngineLink(
                    url,
                    role="operator",
                    token=token if self.url else None,
                    name=name,
                    secret=self.proc.secret if self.proc is not None else None,
                    curve=curve if self.url else None,
                )
            except TransportError:
                if self.proc is not None:
                    self.proc.stop()
                raise
            if self.proc is not None:
                marine_engines.append(self.proc)  # watched (restarted if it dies) only once its link is up
            return link

        def __call__(self):
            return self.link(self.start_process())

    asked = stop_requests()  # from here on Qt calls Python: a stop is asked for, never raised
    win = MainWindow(
        link,
        engine=engine,
        settings=settings,
        marine_link_factory=SceneStarter("tac", connect_tac),
        lab_link_factory=SceneStarter("lab", connect_lab),
    )
    app.aboutToQuit.connect(lambda: [p.stop() for p in marine_engines])
    win.child_engines = marine_engines  # restarted by the window's watchdog if they die
    close_when_asked(win, asked)
    win.show()  # sized by MainWindow.fit_to_screen: at most 1280×800, never past the screen
    if quit_after is not None:
        QTimer.singleShot(int(quit_after * 1000), win.close)
    return app.exec_()


def register(sub, helpers) -> None:
    """Add ``bosun gui`` and ``bosun view`` to the CLI (entry point ``bosun.commands``)."""
    import argparse

    p = sub.add_parser("gui", help="the operator HMI (the default command)")
    p.add_argument(
        "--connect",
        default=None,
        help="attach to a running 'bosun server' at this URL (default: start an engine process)",
    )
    p.add_argument("--token", default=None, help="shared token of that engine (loopback testing)")
    p.add_argument("--curve-secret", default=None, metavar="FILE", help="this GUI's CURVE secret key (bosun keys)")
    p.add_argument("--server-key", default=None, metavar="FILE", help="the remote engine's CURVE public key")
    p.add_argument(
        "--connect-tac",
        default=None,
        help="attach the Crane head tab to a running 'bosun server --plant tac' (default: start one on first use)",
    )
    p.add_argument(
        "--connect-lab",
        default=None,
        help="attach the Motion-Lab tab to a running 'bosun server --plant lab' (default: start one on first use)",
    )
    p.add_argument("--robot", default=None, help="robot for a new engine (default: the last one used)")
    p.add_argument("--solver", default=None, help="solver for a new engine")
    p.add_argument("--mode", choices=["position", "velocity"], default=None, help="mode for a new engine")
    p.add_argument("--quit-after", type=helpers["positive_float"], default=None, help=argparse.SUPPRESS)

    def curve_of(a):
        from app.net.security import ClientCurve

        if (a.curve_secret is None) != (a.server_key is None):
            raise BosunError("--curve-secret and --server-key go together")
        return ClientCurve.from_files(a.curve_secret, a.server_key) if a.curve_secret else None

    p.set_defaults(
        func=lambda a: run_gui(
            curve=curve_of(a),
            connect=a.connect,
            token=a.token,
            robot=a.robot,
            solver=a.solver,
            mode=a.mode,
            quit_after=a.quit_after,
            connect_tac=a.connect_tac,
            connect_lab=a.connect_lab,
        )
    )
    v = sub.add_parser("view", help="a standalone viewer of a running engine (3D view and plots; viewer role)")
    v.add_argument("--connect", required=True, help="URL of the engine ('bosun server', its --bind)")
    v.add_argument("--token", default=None, help="shared token of that engine (loopback testing)")
    v.add_argument("--curve-secret", default=None, metavar="FILE", help="this viewer's CURVE secret key")
    v.add_argument("--server-key", default=None, metavar="FILE", help="the engine's CURVE public key")
    v.add_argument("--quit-after", type=helpers["positive_float"], default=None, help=argparse.SUPPRESS)

    def view(a):
        require_gui("the viewer")
        from ui.viewer import run_viewer

        return run_viewer(a.connect, token=a.token, curve=curve_of(a), quit_after=a.quit_after)

    v.set_defaults(func=view)
