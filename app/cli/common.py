"""What every command group shares: the one-line-error parser, argument types, tables, output folders."""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import shutil
import sys
import tempfile
from collections.abc import Sequence
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

from app.errors import BosunError

EXIT_USAGE = 2


class _Parser(argparse.ArgumentParser):
    """argparse that reports a usage error in one line (no usage dump) with exit 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USAGE, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def _finite_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a number") from None
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"'{text}' is not a finite number")
    return value


def _positive_float(text: str) -> float:
    value = _finite_float(text)
    if value <= 0:
        raise argparse.ArgumentTypeError(f"'{text}' must be positive")
    return value


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"'{text}' is not a whole number") from None
    if value <= 0:
        raise argparse.ArgumentTypeError(f"'{text}' must be positive")
    return value


def _rt_priority(text: str) -> int:
    """A SCHED_FIFO priority, 1 to 99 (``--realtime``)."""
    value = _positive_int(text)
    if value > 99:
        raise argparse.ArgumentTypeError(f"'{text}' must be a real-time priority from 1 to 99")
    return value


# ---------------------------------------------------------------------------- output
def _print_json(obj: Any) -> None:
    print(json.dumps(obj, indent=2, allow_nan=False))


def _fmt_row(cells: Sequence[str], widths: Sequence[int]) -> str:
    return "  ".join(c.ljust(w) for c, w in zip(cells, widths, strict=True)).rstrip()


def _table(header: Sequence[str], rows: Sequence[Sequence[str]], last_col_max: int | None = None) -> str:
    rows = [list(r) for r in rows]
    if last_col_max is not None:
        for r in rows:
            if len(r[-1]) > last_col_max:
                r[-1] = r[-1][: last_col_max - 1] + "…"
    widths = [max(len(h), *(len(r[i]) for r in rows)) if rows else len(h) for i, h in enumerate(header)]
    lines = [_fmt_row(header, widths), _fmt_row(["-" * w for w in widths], widths)]
    lines += [_fmt_row(r, widths) for r in rows]
    return "\n".join(lines)


def _progress_bar(desc: str, unit: str = "target"):
    """A tqdm bar on stderr (hidden when stderr is not a terminal) as a progress(done, total) callback."""
    from tqdm import tqdm

    bar = None

    def update(done: int, total: int) -> None:
        nonlocal bar
        if bar is None:
            bar = tqdm(total=total, desc=desc, unit=unit, file=sys.stderr, disable=None, leave=False)
        bar.n = done
        bar.refresh()
        if done >= total:
            bar.close()

    return update


def _solver_options(args: argparse.Namespace) -> dict[str, Any]:
    opts: dict[str, Any] = {}
    if getattr(args, "time_budget", None) is not None:
        opts["time_budget"] = args.time_budget
    if getattr(args, "elbow", None) is not None:
        if args.solver != "analytic":
            raise BosunError("--elbow applies to --solver analytic only")
        opts["elbow"] = args.elbow
    weights, axis, axis_weight = (getattr(args, k, None) for k in ("ga_weights", "ga_axis", "ga_axis_weight"))
    if weights is not None or axis is not None or axis_weight is not None:
        from app.ik import GaTask

        if not str(args.solver).startswith("ga"):
            raise BosunError("--ga-weights, --ga-axis and --ga-axis-weight apply to --solver ga or ga-restart only")
        if axis_weight is not None and axis is None:
            raise BosunError("--ga-axis-weight needs --ga-axis")
        try:
            opts["task"] = GaTask(
                tuple(weights) if weights is not None else (1.0, 1.0, 1.0),
                None if axis is None else tuple(axis),
                (1.0 if axis_weight is None else axis_weight) if axis is not None else 0.0,
            )
        except ValueError as err:
            raise BosunError(str(err)) from None
    return opts


def _out_dir(args: argparse.Namespace, kind: str) -> Path:
    return _make_out(args, f"{kind}_{args.robot_name}_{args.solver}")


def _make_out(args: argparse.Namespace, default: str) -> Path:
    """``--out`` (or out/DEFAULT): its parent created now, the folder itself only by :func:`_atomic_dir`
    when the study is complete; a folder that cannot be made is a one-line error."""
    out = Path(args.out) if args.out else Path("out") / default
    if out.exists() and not out.is_dir():
        raise BosunError(f"output folder {out} is a file")
    try:
        out.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise BosunError(f"cannot create output folder {out}: {err.strerror or err}") from None
    return out


@contextlib.contextmanager
def _atomic_dir(out: Path):
    """Write a study's files into a hidden ``.NAME.partial-XXXX`` folder beside ``out``; rename it to
    ``out`` only when every file is written.  An interrupted or failed run leaves ``out`` as it was
    (the previous complete run, or nothing) and removes its partial folder; only a SIGKILL can leave
    one, and its name says it is partial."""
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".{out.name}.partial-", dir=out.parent))
    except OSError as err:
        raise BosunError(f"cannot create output folder {out}: {err.strerror or err}") from None
    try:
        yield tmp
        old = None
        if out.exists():
            old = out.with_name(f".{out.name}.old-{os.getpid()}")
            out.rename(old)
        tmp.rename(out)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


def _write_run(args: argparse.Namespace, out: Path, save) -> dict[str, Any]:
    """Write a run's files into ``out`` as a whole (:func:`_atomic_dir`) with ``save(folder)``, which returns the
    run's summary; with ``--json`` print that summary and the folder.  Returns the summary."""
    with _atomic_dir(out) as tmp:
        doc = save(tmp)
    if args.json:
        _print_json({**doc, "out": str(out)})
    return doc


@contextlib.contextmanager
def _as_usage_error(*errors: type[Exception]):
    """A refusal of the model (a bad scenario, vessel or study: ``errors``) is the user's mistake: a
    BosunError, one line and exit 2."""
    try:
        yield
    except errors as err:
        raise BosunError(str(err)) from None


def _fields(args: argparse.Namespace, *names: str) -> dict[str, Any]:
    """The options ``names`` as keyword arguments, for a scenario whose fields are named as they are."""
    return {name: getattr(args, name) for name in names}


def _machine() -> str:
    import os
    import platform

    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            cpu = next((ln.split(":", 1)[1].strip() for ln in f if ln.startswith("model name")), cpu)
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}, numpy {np.__version__}"


def _kernels_on() -> bool:
    from app.models import kernels

    return kernels.ENABLED
