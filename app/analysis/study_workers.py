"""The worker side of a local operability study's Dask cluster (imports Dask: loaded only when a study runs)."""

from __future__ import annotations

import signal
import threading

from distributed.diagnostics.plugin import WorkerPlugin


class IgnoreCtrlC(WorkerPlugin):
    """A local worker process ignores SIGINT: Ctrl-C in a terminal reaches the whole process group, and each
    worker printed its own KeyboardInterrupt traceback after "bosun: interrupted" (issue 27, item 10).  The
    study's process answers the interrupt and ends its workers itself."""

    name = "bosun-ignore-ctrl-c"

    def setup(self, worker) -> None:
        if threading.current_thread() is threading.main_thread():
            signal.signal(signal.SIGINT, signal.SIG_IGN)
