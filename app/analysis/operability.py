"""Operability (workability) of crane-head compensation over a wave scatter diagram, on Dask (issue 17, item 3).

One simulation (:func:`app.scenarios.tac.simulate`) per scatter-diagram cell (Hs × Tp) × heading × seed, run
as tasks on a Dask cluster — a local one by default, any scheduler given by its address — each result kept
in ``OUT/cells/KEY.json`` as soon as it arrives, so an interrupted study resumes with what is missing.  Per
cell and heading the seeds are averaged (rms e_c, the saturated share) or maximised (max e_c); a cell is
*workable* when its mean rms(e_c) of eq. (61) is at most the criterion.  The operability of a heading is the
probability-weighted share of workable cells, Σ p(Hs, Tp) · workable / Σ p (DNV-RP-H103's and DNV-ST-N001's
workability: the share of time a limiting criterion is met).

Scatter diagram CSV (``load_scatter``): a header row ``hs\\tp,TP1,TP2,…`` (peak periods [s]) or
``hs\\tz,TZ1,TZ2,…`` (zero up-crossing periods [s]) and one row per significant wave height ``HS,p1,p2,…``
(probabilities or counts of occurrence; normalised here; empty = 0), ``#`` lines are comments.  A Tz
diagram's cells are simulated at the peak period whose spectrum has that Tz
(:func:`app.marine.waves.tp_from_tz`); a cell whose sea would break (DNV-RP-C205 §3.5.5.4) cannot be simulated
and counts as not workable, its probability reported (``unsimulated``).

Shipped diagrams, by name (``SCATTERS``): ``north-atlantic`` — IACS Recommendation No. 34 (Rev. 1, 2001),
Table 1, the North Atlantic (Global Wave Statistics areas 8, 9, 15, 16), Hs × Tz, per 100 000 observations
(``app/marine/data/scatter_north_atlantic.csv``; Rec. 34 pairs it with the Pierson–Moskowitz spectrum).
"""

from __future__ import annotations

import contextlib
import csv
import hashlib
import itertools
import json
import logging
import math
import multiprocessing
import os
import time
import warnings
from collections.abc import Callable, Iterator
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from app.analysis.figures import pyplot, save_figure
from app.csvtext import cells, content_lines
from app.errors import BosunError, one_line, shown

CELL_VERSION = 1  # bump when a cell's simulation changes: older cached cells are not used

# Bounds of a study, checked before any work (issue 27, item 4: a 3 000 × 800 diagram drove a study to 8.7 GB).
#: simulations (cells with a probability × headings × seeds) a study runs unless told more (``--max-runs``):
#: 4× the 2 534 of the README's seven-heading North Atlantic study
MAX_RUNS = 10_000
#: the most ``--max-runs`` allows: the table and the cells' results are held in memory (≈ 2 kB a simulation)
RUNS_CEILING = 100_000
#: a scatter diagram file, checked before it is read (a 100 × 100 diagram of 8-digit numbers is 90 kB)
MAX_SCATTER_BYTES = 1_000_000
MAX_HEADING = 360.0  # |heading| [deg]
MAX_SEEDS = 1000
MAX_DURATION = 10_800.0  # s: a simulated sea state is at most 3 h (DNV-RP-C205 §3.3.1: short-term stationary seas)
MAX_WORKERS = 64  # worker processes of a local cluster
#: tasks queued on the cluster beyond one a worker: results arrive as they finish, memory stays bounded
QUEUE_PER_WORKER = 4
#: s: a scheduler address must answer Dask's handshake and say it is a scheduler within this (then the client
#: connects with the rest of the 10 s a bad scheduler may take to be refused)
PROBE_TIMEOUT = 4.0
CLIENT_TIMEOUT = 4.0
SCHEDULER_SCHEMES = ("tcp", "tls", "ws", "wss")


class OperabilityError(BosunError):
    """A study that cannot be made (one line)."""


@dataclass(frozen=True, eq=False)
class Scatter:
    hs: NDArray[np.float64]  # (n_hs,) [m]
    t: NDArray[np.float64]  # (n_t,) [s]: peak periods Tp, or zero up-crossing periods Tz (``period``)
    prob: NDArray[np.float64]  # (n_hs, n_t), sums to 1
    source: str = "scatter"
    period: str = "tp"  # "tp" or "tz"

    @property
    def period_label(self) -> str:
        return "Tp" if self.period == "tp" else "Tz"


#: shipped scatter diagrams (module docstring): name → file in app/marine/data
SCATTERS = {"north-atlantic": "scatter_north_atlantic.csv"}


def scatter_path(name_or_file: str | Path) -> Path:
    """A shipped diagram's file by name, else the path given."""
    if str(name_or_file) in SCATTERS:
        from app.resources import marine_data

        return marine_data() / SCATTERS[str(name_or_file)]
    return Path(name_or_file)


def load_scatter(path: str | Path) -> Scatter:
    """A scatter diagram from CSV or by name (module docstring); one-line errors with file, line and field."""
    name = str(path) if str(path) in SCATTERS else None
    path = scatter_path(path)
    if not path.is_file():
        names = ", ".join(SCATTERS)
        raise OperabilityError(f"{path}: no such scatter diagram (a CSV file, or a shipped one: {names})")
    try:
        size = path.stat().st_size
        if size > MAX_SCATTER_BYTES:
            raise OperabilityError(
                f"{path}: {size:,} bytes; a scatter diagram is at most {MAX_SCATTER_BYTES:,} bytes "
                "(a 100 × 100 diagram is 90 kB)"
            )
        text = path.read_text(encoding="utf-8-sig")  # a spreadsheet's "CSV UTF-8" starts with a BOM
    except UnicodeDecodeError as err:
        raise OperabilityError(f"{path}: not UTF-8 text (byte {err.start}): save it as CSV UTF-8") from None
    except OSError as err:
        raise OperabilityError(f"{path}: cannot be read: {err.strerror or err}") from None
    lines = list(zip(*content_lines(text), strict=True))
    if len(lines) < 2:
        raise OperabilityError(f"{path}: a header row of periods and at least one row of Hs are needed")

    def number(text: str, n: int, what: str, empty: float | None = None) -> float:
        text = text.strip()
        if not text and empty is not None:
            return empty
        try:
            v = float(text)
        except ValueError:
            raise OperabilityError(f"{path}:{n}: {what}: {shown(text)} is not a number") from None
        if not math.isfinite(v) or v < 0:
            raise OperabilityError(f"{path}:{n}: {what}: {text} must be a finite number ≥ 0")
        return v

    n0, head = lines[0]
    heads = cells(head)
    corner = heads[0].strip().lower().replace(" ", "").replace("/", "\\")
    if corner not in ("hs\\tp", "hs\\tz"):
        raise OperabilityError(
            f"{path}:{n0}: the first field names the periods: hs\\tp (peak) or hs\\tz (zero up-crossing), "
            f"with a backslash, got {shown(heads[0])}"
        )
    period = corner[-2:]
    what = "peak period" if period == "tp" else "zero up-crossing period"
    periods = np.array([number(c, n0, f"{what} (column {k + 2})") for k, c in enumerate(heads[1:])])
    if periods.size == 0 or np.any(periods <= 0) or np.any(np.diff(periods) <= 0):
        raise OperabilityError(f"{path}:{n0}: {what}s must be positive and increasing")
    hs, rows = [], []
    for n, line in lines[1:]:
        row = cells(line)
        if len(row) != periods.size + 1:
            raise OperabilityError(f"{path}:{n}: expected {periods.size + 1} fields, got {len(row)}")
        hs.append(number(row[0], n, "Hs"))
        rows.append(
            [number(c, n, f"{period.capitalize()} {t:g} s", empty=0.0) for c, t in zip(row[1:], periods, strict=True)]
        )
    h = np.array(hs)
    if np.any(h <= 0) or np.any(np.diff(h) <= 0):
        raise OperabilityError(f"{path}: significant wave heights must be positive and increasing")
    p = np.array(rows)
    if p.sum() <= 0:
        raise OperabilityError(f"{path}: no cell has a probability above zero")
    return Scatter(h, periods, p / p.sum(), source=name or str(path), period=period)


def cell_periods(scatter: Scatter, spectrum: str) -> tuple[NDArray[np.float64], dict[tuple[int, int], str]]:
    """The peak period each cell is simulated at; NaN where the sea would break (the reason in the dict: such a
    cell is not simulated and counts as not workable).  A cell out of the simulated range (Hs, Tp) refuses the
    study in one line: it is a wrong diagram, not a sea that breaks."""
    from app.marine.waves import BreakingSeaError, SeaStateError, check_sea, tp_from_tz

    tp = np.full(scatter.prob.shape, np.nan)
    why: dict[tuple[int, int], str] = {}
    for i, hs in enumerate(scatter.hs):
        for j, t in enumerate(scatter.t):
            if scatter.prob[i, j] <= 0:
                continue
            try:
                if scatter.period == "tz":
                    tp[i, j] = round(tp_from_tz(spectrum, float(hs), float(t)), 4)
                else:
                    check_sea(float(hs), float(t))
                    tp[i, j] = float(t)
            except BreakingSeaError as err:
                why[(i, j)] = str(err)
            except SeaStateError as err:
                raise OperabilityError(
                    f"{scatter.source}: cell Hs {hs:g} m, {scatter.period_label} {t:g} s: {err}"
                ) from None
    return tp, why


@dataclass(frozen=True)
class OperabilityStudy:
    mode: str = "tac"
    headings: tuple[float, ...] = (90.0, 135.0, 180.0)
    seeds: int = 2
    duration: float = 300.0
    criterion: float = 0.1  # rms(e_c) [m] a workable cell keeps to
    vessel: str | None = None  # a name or an RAO file (None: the default vessel)
    spectrum: str = "jonswap"
    dt: float = 0.01

    def __post_init__(self) -> None:
        if self.mode not in ("off", "tac", "cooperative"):
            raise OperabilityError(f"mode must be off, tac or cooperative, got {self.mode!r}")
        if not self.headings:
            raise OperabilityError("at least one heading is needed")
        for h in self.headings:
            if not (math.isfinite(h) and -MAX_HEADING <= h <= MAX_HEADING):
                raise OperabilityError(f"heading {h:g}° is outside ±{MAX_HEADING:g}°")
        if len(set(self.headings)) != len(self.headings):
            raise OperabilityError(f"headings repeated: {', '.join(f'{h:g}' for h in self.headings)}")
        if not 1 <= self.seeds <= MAX_SEEDS:
            raise OperabilityError(f"seeds must be 1 to {MAX_SEEDS}, got {self.seeds}")
        if not (math.isfinite(self.duration) and 0 < self.duration <= MAX_DURATION):
            raise OperabilityError(f"duration must be in (0, {MAX_DURATION:g}] s (3 h), got {self.duration:g}")
        if not (math.isfinite(self.criterion) and self.criterion > 0):
            raise OperabilityError(f"criterion must be a positive number, got {self.criterion:g}")


def vessel_id(vessel: str | None) -> str | None:
    """What the results depend on: a vessel's name, or a file's content (its hash; moving the file keeps the cache)."""
    if vessel is not None and Path(vessel).is_file():
        return f"file:{hashlib.sha256(Path(vessel).read_bytes()).hexdigest()[:16]}"
    return vessel


def cell_params(
    study: OperabilityStudy, hs: float, tp: float, heading: float, seed: int, vessel: str | None = None
) -> dict[str, Any]:
    """Everything one cell's simulation depends on (its cache key is the hash of this); ``vessel`` is
    :func:`vessel_id` of the study's vessel."""
    return {
        "v": CELL_VERSION, "mode": study.mode, "hs": float(hs), "tp": float(tp), "heading": float(heading),
        "seed": int(seed), "duration": float(study.duration), "dt": float(study.dt), "spectrum": study.spectrum,
        "vessel": vessel,
    }  # fmt: skip


def cell_key(params: dict[str, Any]) -> str:
    return hashlib.sha256(json.dumps(params, sort_keys=True).encode()).hexdigest()[:20]


def run_cell(params: dict[str, Any], vessel: str | None = None) -> dict[str, Any]:
    """One simulation (a Dask task: a module-level function of plain data); ``vessel`` the name or file."""
    from app.scenarios.tac import TacScenario, simulate

    sc = TacScenario(
        hs=params["hs"], tp=params["tp"], heading=params["heading"], duration=params["duration"], dt=params["dt"],
        seed=params["seed"], mode=params["mode"], spectrum=params["spectrum"], rao=vessel,
    )  # fmt: skip
    t0 = time.perf_counter()
    d = simulate(sc).summary
    return {
        **params,
        "rms_e_c_m": float(d["rms_e_c_m"]), "max_e_c_m": float(d["max_e_c_m"]), "rms_e_s_m": float(d["rms_e_s_m"]),
        "ratio": float(d["ratio_rms"]), "saturated_percent": float(d["saturated_pct"]),
        "wall_s": time.perf_counter() - t0, "pid": os.getpid(),
    }  # fmt: skip


@dataclass
class StudyResult:
    study: OperabilityStudy
    scatter: Scatter
    table: list[dict[str, Any]]  # per (hs, tp, heading) with p > 0
    operability: dict[float, float]  # per heading, 0…1
    computed: int = 0
    cached: int = 0
    wall_s: float = 0.0
    workers: int = 0
    scheduler: str = ""
    cells: list[dict[str, Any]] = field(default_factory=list)  # every simulation
    unsimulated: float = 0.0  # probability of the cells that cannot be simulated (breaking seas): not workable


def study_runs(study: OperabilityStudy, scatter: Scatter) -> int:
    """The simulations a study asks for: cells with a probability × headings × seeds."""
    return int(np.count_nonzero(scatter.prob > 0)) * len(study.headings) * study.seeds


def check_study(study: OperabilityStudy, scatter: Scatter, max_runs: int = MAX_RUNS) -> None:
    """Everything a study is made of, checked before any work, file or process (one line each): its size
    against ``max_runs`` (at most ``RUNS_CEILING``), the vessel (loaded: the RAO bounds too), and one cell's
    scenario (spectrum, duration, time step)."""
    if not 1 <= max_runs <= RUNS_CEILING:
        raise OperabilityError(f"the run limit must be 1 to {RUNS_CEILING:,}, got {max_runs:,}")
    n_cells = int(np.count_nonzero(scatter.prob > 0))
    runs = study_runs(study, scatter)
    if runs > max_runs:
        raise OperabilityError(
            f"{scatter.source}: {n_cells:,} cells × {len(study.headings)} headings × {study.seeds} seeds = {runs:,} "
            f"simulations, more than the limit of {max_runs:,} (--max-runs N raises it, up to {RUNS_CEILING:,})"
        )
    from app.marine.vessels import vessel_rao
    from app.scenarios.tac import TacScenario

    try:
        vessel_rao(study.vessel)
        TacScenario(
            hs=float(scatter.hs[0]), tp=9.0, heading=study.headings[0], duration=study.duration, dt=study.dt,
            mode=study.mode, spectrum=study.spectrum, rao=study.vessel,
        )  # fmt: skip
    except BosunError as err:
        raise OperabilityError(str(err)) from None


@contextlib.contextmanager
def _quiet(*names: str) -> Iterator[None]:
    """Dask's loggers at CRITICAL meanwhile: a peer that is no scheduler is reported in one line of ours."""
    loggers = [logging.getLogger(n) for n in names]
    levels = [lg.level for lg in loggers]
    for lg in loggers:
        lg.setLevel(logging.CRITICAL)
    try:
        yield
    finally:
        for lg, level in zip(loggers, levels, strict=True):
            lg.setLevel(level)


def check_scheduler(address: str, timeout: float = PROBE_TIMEOUT) -> str:
    """The scheduler's address (``tcp://HOST:PORT``; ``HOST:PORT`` is taken as tcp) once its peer has answered
    Dask's handshake and an ``identity`` request as a scheduler, within ``timeout`` seconds; else one line.

    Issue 27, item 5: an HTTP server's reply was read as a frame length (Dask tried to allocate 3 EiB), a port
    that accepted and never spoke hung the client past 120 s, ``http://…`` was a traceback."""
    text = address.strip()
    scheme, sep, rest = text.partition("://")
    if not sep:
        scheme, rest = "tcp", text
    scheme = scheme.lower()
    if scheme in ("http", "https"):
        raise OperabilityError(
            f"--scheduler {shown(address)} is a web address: a Dask scheduler listens on tcp://HOST:PORT "
            "(8786 by default; the dashboard's http port is not it)"
        )
    if scheme not in SCHEDULER_SCHEMES:
        raise OperabilityError(
            f"--scheduler {shown(address)}: unknown scheme {shown(scheme)} "
            f"(tcp://HOST:PORT, or {', '.join(SCHEDULER_SCHEMES)})"
        )
    host, _, port = rest.rpartition(":")
    if not host or not port.isdigit() or not 1 <= int(port) <= 65535 or "/" in rest or any(c.isspace() for c in rest):
        raise OperabilityError(f"--scheduler {shown(address)}: expected {scheme}://HOST:PORT (port 1–65535)")
    url = f"{scheme}://{rest}"
    import asyncio

    try:
        from distributed.comm import connect
    except ImportError:
        raise OperabilityError("operability studies need Dask: pip install 'bosun[study]'") from None

    async def identity() -> Any:
        comm = await connect(url, timeout=timeout)
        try:
            await comm.write({"op": "identity", "reply": True})
            return await comm.read()
        finally:
            comm.abort()

    try:
        with _quiet("distributed", "tornado", "asyncio"):
            reply = asyncio.run(asyncio.wait_for(identity(), timeout))
    except TimeoutError:
        raise OperabilityError(
            f"--scheduler {url}: no Dask scheduler answered within {timeout:g} s (nothing there, or a peer that "
            "does not speak Dask's protocol)"
        ) from None
    except OSError as err:
        raise OperabilityError(f"--scheduler {url}: no Dask scheduler there: {one_line(str(err), 200)}") from None
    except Exception as err:  # garbage read as Dask frames: MemoryError, OverflowError, ValueError, msgpack's …
        raise OperabilityError(
            f"--scheduler {url}: the peer is not a Dask scheduler (its answer is not Dask's protocol: "
            f"{type(err).__name__})"
        ) from None
    kind = reply.get("type") if isinstance(reply, dict) else None
    if kind != "Scheduler":
        what = f"a Dask {kind}" if isinstance(kind, str) else "an unknown Dask peer"
        raise OperabilityError(f"--scheduler {url}: the peer is {what}, not a scheduler")
    return url


def _client(scheduler: str | None, workers: int | None):
    """(client, cluster or None, the processes the cluster started); a remote scheduler is checked first."""
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise OperabilityError("operability studies need Dask: pip install 'bosun[study]'") from None
    if scheduler:
        url = check_scheduler(scheduler)
        try:
            with _quiet("distributed"):
                return Client(url, timeout=f"{CLIENT_TIMEOUT:g}s"), None, []
        except (OSError, TimeoutError, ValueError) as err:
            raise OperabilityError(f"--scheduler {url}: cannot connect: {one_line(str(err), 200)}") from None
    n = workers or max(1, (os.cpu_count() or 1))
    before = set(multiprocessing.active_children())
    cluster = None
    try:
        with _quiet_resource_tracker(), warnings.catch_warnings():
            # the scheduler's HTTP server (health routes, even without the dashboard) on a port another cluster
            # holds moves to a free one and says so on stderr: not a study's news (two studies at once, a notebook)
            warnings.filterwarnings("ignore", message="Port .* is already in use", category=UserWarning)
            cluster = LocalCluster(
                n_workers=n, threads_per_worker=1, processes=True,
                dashboard_address=None, silence_logs=logging.CRITICAL,  # a worker's heartbeat racing the shutdown
                # logged a traceback after a finished study; a task's own error still reaches fut.result()
            )  # fmt: skip
        procs = [p for p in multiprocessing.active_children() if p not in before]
        client = Client(cluster)
        from app.analysis.study_workers import IgnoreCtrlC

        client.register_plugin(IgnoreCtrlC())
        return client, cluster, procs
    except BaseException:
        # Ctrl-C or SIGTERM while the cluster starts: its worker processes end now, not at their next heartbeat
        _kill([p for p in multiprocessing.active_children() if p not in before], cluster)
        if cluster is not None:
            with contextlib.suppress(Exception):
                cluster.close(timeout=2)
        raise


@contextlib.contextmanager
def _quiet_resource_tracker() -> Iterator[None]:
    """The multiprocessing resource tracker started meanwhile (the cluster's first semaphore starts it) ignores
    its own "leaked semaphore objects" warning: a study interrupted while its cluster started left the
    nannies' queues to the tracker, which cleans them up, as it is there to, and said so in three lines
    after "bosun: interrupted".  Only that warning (its message starts "resource_tracker")."""
    old = os.environ.get("PYTHONWARNINGS")
    rule = "ignore:resource_tracker:UserWarning"
    os.environ["PYTHONWARNINGS"] = f"{old},{rule}" if old else rule
    try:
        yield
    finally:
        if old is None:
            os.environ.pop("PYTHONWARNINGS", None)
        else:
            os.environ["PYTHONWARNINGS"] = old


def _kill(procs: list, cluster=None) -> None:
    """End a local cluster's worker processes at once (a graceful close waits for running simulations: 4 s);
    its nannies are told first that the workers are going (else each starts a new one, and the close waits)."""
    for nanny in list(getattr(cluster, "workers", {}).values()):
        with contextlib.suppress(Exception):
            nanny.close_gracefully(reason="bosun: the study ended")
    for p in procs:
        with contextlib.suppress(Exception):
            p.kill()
    for p in procs:
        with contextlib.suppress(Exception):
            p.join(timeout=1)


def _make_dirs(path: Path) -> list[Path]:
    """``path`` and its missing parents made; the ones made, deepest first (a failed study removes them)."""
    made = []
    p = path
    while not p.exists():
        made.append(p)
        if p.parent == p:
            break
        p = p.parent
    path.mkdir(parents=True, exist_ok=True)
    return made


def _remove_if_empty(made: list[Path]) -> None:
    for p in made:  # deepest first; a folder that holds anything (a finished cell: the resume cache) stays
        with contextlib.suppress(OSError):
            p.rmdir()


def _run_cells(
    study: OperabilityStudy,
    todo: list[tuple[str, dict[str, Any]]],
    done: list[dict[str, Any]],
    total: int,
    cache: Path,
    scheduler: str | None,
    workers: int | None,
    progress: Callable[[int, int], None] | None,
    task: Callable[..., dict[str, Any]] = run_cell,
) -> tuple[int, str]:
    """Run ``todo`` on a cluster (``task(params, vessel=study.vessel)`` a cell: :func:`run_cell`, or the load
    chart's), each result appended to ``done`` and written to ``cache`` as it arrives;
    (workers, scheduler address).  The cluster holds a few tasks a worker at a time (memory stays bounded
    whatever the study's size).  On failure or interrupt the local workers end at once and the folders made
    here are removed unless a finished cell is in them."""
    from distributed import as_completed

    client, cluster, procs = _client(scheduler, workers)
    finished = False
    made: list[Path] = []
    try:
        try:
            made = _make_dirs(cache)
        except OSError as err:
            raise OperabilityError(f"cannot create {cache}: {err.strerror or err}") from None
        if progress is not None:
            progress(len(done), total)
        n_workers = len(client.scheduler_info().get("workers", {}))
        address = client.scheduler.address
        pending = iter(todo)
        keys: dict[str, str] = {}
        running = as_completed()

        def submit(k: int) -> None:
            for key, p in itertools.islice(pending, k):
                fut = client.submit(task, p, vessel=study.vessel, pure=False)
                keys[fut.key] = key
                running.add(fut)

        submit(QUEUE_PER_WORKER * max(n_workers, 2))
        for fut in running:
            res = fut.result()
            key = keys.pop(fut.key)
            tmp = cache / f".{key}.partial"
            tmp.write_text(json.dumps(res), encoding="utf-8")
            tmp.replace(cache / f"{key}.json")
            done.append(res)
            submit(1)
            if progress is not None:
                progress(len(done), total)
        finished = True
    finally:
        if not finished:
            _kill(procs, cluster)
        try:
            # after a failure the close must not hide it (nor wait on the workers just ended)
            with contextlib.nullcontext() if finished else contextlib.suppress(Exception):
                client.close(timeout=CLIENT_TIMEOUT)
                if cluster is not None:
                    cluster.close(timeout=10)
        except BaseException:  # interrupted while a finished study's cluster closes gracefully: end it now
            _kill(procs, cluster)
            raise
        if not finished:
            _remove_if_empty(made)
    return n_workers, address


def take_cell(cache: Path, key: str, params: dict[str, Any], done: list, todo: list) -> None:
    """A cell's cached result into ``done`` when ``cache/KEY.json`` holds one, else (key, params) into ``todo``."""
    f = cache / f"{key}.json"
    if f.is_file():
        try:
            done.append(json.loads(f.read_text(encoding="utf-8")))
            return
        except (OSError, ValueError):
            pass  # a torn file: run the cell again
    todo.append((key, params))


def run_missing(
    study: Any,
    todo: list[tuple[str, dict[str, Any]]],
    done: list[dict[str, Any]],
    cache: Path,
    scheduler: str | None,
    workers: int | None,
    progress: Callable[[int, int], None] | None,
    task: Callable[..., dict[str, Any]] = run_cell,
) -> tuple[int, str, float]:
    """Run a study's missing cells (``todo``) on a cluster, Dask's own log lines quieted; (workers, scheduler
    address, wall seconds).  With nothing missing, the progress is told so and nothing starts."""
    total = len(todo) + len(done)
    t0 = time.perf_counter()
    n_workers, address = 0, "cache"
    if todo:
        # an interrupted cluster start leaves tasks whose failure asyncio reports at garbage collection
        # ("Task exception was never retrieved", a traceback after "bosun: interrupted"): not a study's news; nor is
        # the client's batched comm to workers just ended on Ctrl-C ("distributed.batched - INFO - Batched Comm
        # Closed" with a CommClosedError traceback before "bosun: interrupted": the CI's failure, 2026-11-29)
        with contextlib.suppress(ImportError):  # Dask's import sets its loggers' levels: quieted after it
            import distributed  # noqa: F401
        with _quiet("asyncio", "distributed") if scheduler is None else _quiet("distributed.batched"):
            n_workers, address = _run_cells(study, todo, done, total, cache, scheduler, workers, progress, task)
    elif progress is not None:
        progress(len(done), total)
    return n_workers, address, time.perf_counter() - t0


def run_study(
    study: OperabilityStudy,
    scatter: Scatter,
    out: str | Path,
    scheduler: str | None = None,
    workers: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    max_runs: int = MAX_RUNS,
) -> StudyResult:
    """Run (or resume) the study; every finished cell is in ``out/cells`` at once.

    Everything is checked before any file or process is made (:func:`check_study`, the cells' seas, the
    scheduler); a study that fails or is interrupted removes the folders it made unless a finished cell is in
    them (the resume cache), and ends a local cluster's workers at once."""
    check_study(study, scatter, max_runs)
    if workers is not None and not 1 <= workers <= MAX_WORKERS:
        raise OperabilityError(f"workers must be 1 to {MAX_WORKERS}, got {workers}")
    tps, why = cell_periods(scatter, study.spectrum)  # a study that cannot be made is refused before any file
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise OperabilityError(f"output folder {out} is a file")
    cache = out / "cells"
    todo, done = [], []
    seen: set[str] = set()
    vid = vessel_id(study.vessel)  # the file read and hashed once
    for i, hs in enumerate(scatter.hs):
        for j in range(scatter.t.size):
            tp = tps[i, j]
            if scatter.prob[i, j] <= 0 or (i, j) in why:
                continue
            for heading in study.headings:
                for seed in range(1, study.seeds + 1):
                    p = cell_params(study, hs, tp, heading, seed, vid)
                    key = cell_key(p)
                    if key in seen:  # two columns of one Hs that give the same Tp: one simulation
                        continue
                    seen.add(key)
                    take_cell(cache, key, p, done, todo)
    cached = len(done)
    n_workers, address, wall = run_missing(study, todo, done, cache, scheduler, workers, progress)
    table, oper = aggregate(study, scatter, done, tps, why)
    unsim = float(sum(scatter.prob[ij] for ij in why))
    return StudyResult(study, scatter, table, oper, len(todo), cached, wall, n_workers, address, done, unsim)


def aggregate(
    study: OperabilityStudy,
    scatter: Scatter,
    cells: list[dict[str, Any]],
    tps: NDArray[np.float64] | None = None,
    why: dict[tuple[int, int], str] | None = None,
) -> tuple[list[dict[str, Any]], dict[float, float]]:
    """Per cell and heading the seeds' mean rms(e_c), max e_c, ratio and saturated share; the operability
    per heading.  A cell that cannot be simulated (``why``) is in the table, not workable, with its reason."""
    if tps is None or why is None:
        tps, why = cell_periods(scatter, study.spectrum)
    by: dict[tuple[float, float, float], list[dict[str, Any]]] = {}
    for c in cells:
        by.setdefault((c["hs"], c["tp"], c["heading"]), []).append(c)
    table = []
    oper: dict[float, float] = {}
    for heading in study.headings:
        good = 0.0
        for i, hs in enumerate(scatter.hs):
            for j, t in enumerate(scatter.t):
                p = float(scatter.prob[i, j])
                if p <= 0:
                    continue
                row: dict[str, Any] = {"hs": float(hs)}
                if scatter.period == "tz":
                    row["tz"] = float(t)
                if (i, j) in why:
                    row.update({
                        "tp": float(t) if scatter.period == "tp" else None, "heading": float(heading),
                        "probability": p, "rms_e_c_m": None, "max_e_c_m": None, "ratio": None,
                        "saturated_percent": None, "workable": False, "note": why[(i, j)],
                    })  # fmt: skip
                    table.append(row)
                    continue
                tp = float(tps[i, j])
                runs = sorted(by.get((float(hs), tp, float(heading)), []), key=lambda c: c["seed"])
                if len(runs) != study.seeds:
                    raise OperabilityError(
                        f"cell Hs {hs:g} m, {scatter.period_label} {t:g} s, {heading:g}°: {len(runs)} of "
                        f"{study.seeds} runs"
                    )
                rms = float(np.mean([r["rms_e_c_m"] for r in runs]))
                ok = rms <= study.criterion
                good += p * ok
                row.update({
                    "tp": tp, "heading": float(heading), "probability": p,
                    "rms_e_c_m": rms, "max_e_c_m": float(max(r["max_e_c_m"] for r in runs)),
                    "ratio": float(np.mean([r["ratio"] for r in runs])),
                    "saturated_percent": float(np.mean([r["saturated_percent"] for r in runs])),
                    "workable": bool(ok), "note": "",
                })  # fmt: skip
                table.append(row)
        oper[float(heading)] = good
    return table, oper


def save(result: StudyResult, out: str | Path) -> dict[str, Any]:
    """table.csv, summary.json, operability_polar.png, heatmap.png (one panel a heading)."""
    plt = pyplot()
    from matplotlib.colors import TwoSlopeNorm
    from matplotlib.ticker import MaxNLocator

    out = Path(out)
    st, sc = result.study, result.scatter
    cols = ("hs",) + (("tz",) if sc.period == "tz" else ()) + (
        "tp", "heading", "probability", "rms_e_c_m", "max_e_c_m", "ratio", "saturated_percent", "workable", "note",
    )  # fmt: skip

    def field_text(v: Any) -> Any:
        return "" if v is None else f"{v:.6g}" if isinstance(v, float) else v

    with open(out / "table.csv", "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f)
        w.writerow(cols)
        for row in result.table:
            w.writerow([field_text(row[c]) for c in cols])
    doc = {
        "study": asdict(st), "vessel_id": vessel_id(st.vessel), "scatter": sc.source,
        "scatter_period": sc.period_label,
        "criterion_rms_e_c_m": st.criterion,
        "operability": {f"{h:g}": v for h, v in result.operability.items()},
        "unsimulated_probability": result.unsimulated,
        "cells": len(result.table) // max(1, len(st.headings)), "table_rows": len(result.table),
        "simulations": len(result.cells), "computed": result.computed,
        "cached": result.cached, "wall_s": result.wall_s, "workers": result.workers, "scheduler": result.scheduler,
        "cells_per_minute": 60.0 * result.computed / result.wall_s if result.computed and result.wall_s > 0 else None,
    }  # fmt: skip
    (out / "summary.json").write_text(json.dumps(doc, indent=2), encoding="utf-8")
    heads = list(result.operability)
    fig = plt.figure(figsize=(5, 5))
    ax = fig.add_subplot(projection="polar")
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)
    order = sorted(heads, key=lambda h: h % 360)
    r = [100 * result.operability[h] for h in order]
    th = list(np.radians(order))
    # a closed polygon only when the headings go round (no gap over 90°); else a chord would cross headings
    # that were not computed
    gaps = np.diff([h % 360 for h in order] + [order[0] % 360 + 360]) if len(order) > 1 else [360.0]
    if max(gaps) <= 90.0:
        th, r = th + th[:1], r + r[:1]
    ax.plot(th, r, "o-", color="tab:blue")
    for h in order:
        ax.annotate(f"{100 * result.operability[h]:.0f} %", (np.radians(h), 100 * result.operability[h]),
                    textcoords="offset points", xytext=(0, 8), ha="center", fontsize=8)  # fmt: skip
    ax.set_ylim(0, 110)
    ax.set_yticks([20, 40, 60, 80, 100])
    ax.set_rlabel_position(247.5)  # the percent scale between 225° and 270°, off the usual 0–180° headings
    ax.set_title(
        f"operability [%], {st.mode}, rms(e_c) ≤ {st.criterion:g} m\n{sc.source}, {st.spectrum}"
        " (heading: 0 following, 180 head sea)",
        fontsize=9,
    )
    save_figure(plt, fig, out / "operability_polar.png", dpi=110)
    # only the rows and columns that hold probability (a published diagram has empty margins)
    rows_used = np.flatnonzero(sc.prob.sum(axis=1) > 0)
    cols_used = np.flatnonzero(sc.prob.sum(axis=0) > 0)
    hs_v, t_v = sc.hs[rows_used], sc.t[cols_used]
    big = hs_v.size * t_v.size > 120  # a full published diagram: a panel a row, values in cm
    scale, unit = (100.0, "cm") if big else (1.0, "m")
    if big:
        fig, axes = plt.subplots(len(heads), 1, figsize=(8.5, 4.6 * len(heads)), squeeze=False)
        panels = axes[:, 0]
    else:
        fig, axes = plt.subplots(1, len(heads), figsize=(4.2 * len(heads), 3.8), squeeze=False)
        panels = axes[0]
    key_t = "tz" if sc.period == "tz" else "tp"
    for ax, h in zip(panels, heads, strict=True):
        grid = np.full((hs_v.size, t_v.size), np.nan)
        broken = np.zeros_like(grid, dtype=bool)
        for row in result.table:
            if row["heading"] != h:
                continue
            i, j = np.searchsorted(hs_v, row["hs"]), np.searchsorted(t_v, row[key_t])
            if row["rms_e_c_m"] is None:
                broken[i, j] = True
            else:
                grid[i, j] = row["rms_e_c_m"] * scale
        # green up to the criterion, red beyond it: the workable region is seen at a glance
        crit = st.criterion * scale
        top = max(float(np.nanmax(grid)) if np.isfinite(grid).any() else crit, 1.01 * crit)
        norm = TwoSlopeNorm(vmin=0.0, vcenter=crit, vmax=top)
        im = ax.imshow(grid, origin="lower", aspect="auto", cmap="RdYlGn_r", norm=norm)
        for i in range(hs_v.size):
            for j in range(t_v.size):
                v = grid[i, j]
                if broken[i, j]:
                    ax.text(j, i, "×", ha="center", va="center", fontsize=7, color="0.3")
                elif np.isfinite(v):
                    text = f"{v:.0f}" if big and v >= 0.95 else f"{v:.1f}" if big else f"{v:.2f}"
                    ax.text(j, i, text, ha="center", va="center", fontsize=6.5 if big else 7)
        ax.set_xticks(range(t_v.size), [f"{t:g}" for t in t_v], fontsize=7 if big else None)
        ax.set_yticks(range(hs_v.size), [f"{v:g}" for v in hs_v], fontsize=7 if big else None)
        ax.set_xlabel(f"{sc.period_label} [s]")
        ax.set_ylabel("Hs [m]")
        ax.set_title(
            f"heading {h:g}°: {100 * result.operability[h]:.1f} % workable (probability-weighted)"
            + ("; × breaking sea" if broken.any() else ""),
            fontsize=9,
        )
        cb = fig.colorbar(im, ax=ax, label=f"rms e_c [{unit}], workable ≤ {crit:g}")
        above = [v for v in MaxNLocator(4).tick_values(crit, top) if crit * 1.5 < v <= top]
        cb.set_ticks([0.0, crit / 2, crit, *above])
    fig.suptitle(f"{st.mode}, {sc.source}, {st.spectrum}, rms(e_c) ≤ {st.criterion:g} m", fontsize=10)
    save_figure(plt, fig, out / "heatmap.png", dpi=110)
    return doc
