"""Reading a recorded session (issue 32, item 6): the MCAP files ``bosun server --record`` writes
(:mod:`app.engine.record`), message by message in the order they were written; what runs a recording again
(:mod:`app.engine.replay`) and what scores one (:mod:`app.analysis.score`) read it here."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from app.errors import BosunError

__all__ = ["RecordingError", "read_recording"]


class RecordingError(BosunError):
    """A recording that cannot be read (one line)."""


def read_recording(path: str | Path) -> Iterator[tuple[str, Any]]:
    """(topic, message) of every message of the recording at ``path``, in the order written; a file that is no
    readable MCAP recording (cut, corrupt, foreign) is one :class:`RecordingError`."""
    try:
        from mcap.reader import make_reader
    except ImportError:  # pragma: no cover - mcap is a core dependency
        raise RecordingError("reading a recording needs the mcap package (pip install mcap)") from None
    try:
        f = open(path, "rb")  # noqa: SIM115 - closed below
    except OSError as err:
        raise RecordingError(f"{path}: cannot read: {err.strerror or err}") from None
    with f:
        try:
            reader = make_reader(f)
            for _, channel, message in reader.iter_messages(log_time_order=False):
                yield channel.topic, json.loads(message.data)
        except Exception as err:  # the reader's (a cut, corrupt or foreign file): one line
            raise RecordingError(f"{path}: not a readable MCAP recording ({type(err).__name__}: {err})") from None
