"""The one reader of the CSV files an operator hands Bosun (RAO tables, platform motion time series, wave
scatter diagrams): the lines that hold data, each with its line number for a one-line error.

A leading byte-order mark (a spreadsheet's "CSV UTF-8") is skipped; blank lines, a spreadsheet's empty rows
(commas only) and comments (``#`` as the first character that is not a space) are not data.  What each
format's fields mean and how they are checked stays with the format (:func:`app.marine.vessel.load_rao_csv`,
:func:`app.sim.stewart.parse_timeseries_csv`, :func:`app.analysis.operability.load_scatter`).
"""

from __future__ import annotations

import csv
import io
import math
from collections.abc import Callable

LINES_BLOCK = 1 << 16  # characters split into lines at a time (a 4 MB text in one call held the lock 20-30 ms)


def content_lines(text: str, pace: Callable[[], None] | None = None) -> tuple[list[int], list[str]]:
    """The numbers (from 1) and text of the lines of ``text`` that are neither blank nor comments.

    Split a block at a time, cut after a newline (the same lines as ``text.splitlines()``), with ``pace``
    called between blocks (an engine's parse off its control loop waits there for the loop's idle time).
    Two flat lists, not a list of pairs: 56,000 tuples kept alive set off full garbage collections (70 ms in
    a test process)."""
    text = text.removeprefix("\ufeff")
    numbers: list[int] = []
    lines: list[str] = []
    n, start = 0, 0
    while start < len(text):
        cut = text.find("\n", start + LINES_BLOCK)
        end = len(text) if cut < 0 else cut + 1
        for line in text[start:end].splitlines():
            n += 1
            content = line.strip()
            if content.strip(",") and not content.startswith("#"):  # a spreadsheet's empty row is commas
                numbers.append(n)
                lines.append(line)
        start = end
        if pace is not None:
            pace()
    return numbers, lines


def cells(line: str) -> list[str]:
    """The fields of one CSV line (quoted fields as CSV has them)."""
    return next(csv.reader(io.StringIO(line)), [])


def finite_number(text: str) -> float:
    """The finite number in one cell; ValueError ``not a number`` or ``not a finite number`` (the format puts
    its line, field and the cell's text before it)."""
    try:
        value = float(text)
    except ValueError:
        raise ValueError("not a number") from None
    if not math.isfinite(value):
        raise ValueError("not a finite number")
    return value
