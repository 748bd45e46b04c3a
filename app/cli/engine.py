"""``bosun server``, ``replay``, ``joystick``, ``keys``: the engine headless (and its recordings run again), the
input client, CURVE keys."""

from __future__ import annotations

import argparse
import os
import threading
import time
from pathlib import Path

from app.cli.args import command
from app.cli.common import (
    _positive_float,
    _rt_priority,
)
from app.errors import BosunError, require


def _make_session(args: argparse.Namespace):
    if getattr(args, "comau_limits", None) is not None and getattr(args, "plant", "teleop") != "lab":
        raise BosunError("--comau-limits is for the Motion-Lab's Comau: add --plant lab")
    if getattr(args, "plant", "teleop") == "tac":
        from app.engine.tac_session import TacSession

        return TacSession()
    if getattr(args, "plant", "teleop") == "lab":
        from app.engine.lab_session import LabSession

        return LabSession(plc=_plc_target(args), comau_profile=getattr(args, "comau_limits", None))
    from app.engine.session import Session

    folders = list(getattr(args, "robots_dir", None) or [])
    if args.robot.endswith(".xml") or "/" in args.robot:  # the start-up robot's folder is allowed too
        folders.append(str(Path(args.robot).expanduser().resolve().parent))
    for folder in folders:
        if not Path(folder).is_dir():
            raise BosunError(f"--robots-dir {folder}: not a folder")
    return Session(robot_name=args.robot, solver_name=args.solver, mode=args.mode, seed=0, robots_dirs=tuple(folders))


def _plc_target(args: argparse.Namespace):
    """The PLC of ``--plc`` (None without it); pyads must be there (the extra ``plc``)."""
    if getattr(args, "plc", None) is None:
        if getattr(args, "plc_host", None) or getattr(args, "plc_local_id", None):
            raise BosunError("--plc-host and --plc-local-id go with --plc AMS_NET_ID[:PORT]")
        return None
    if getattr(args, "plant", "teleop") != "lab":
        raise BosunError("--plc drives the Motion-Lab's PLC: use it with --plant lab")
    require("pyads", "plc", "bosun server --plc")
    from app.plc.bridge import PlcTarget

    return PlcTarget.parse(args.plc, args.plc_host, args.plc_local_id)


def _run_until_stopped(server, duration: float | None) -> None:
    """Run an engine's loop until SIGTERM, Ctrl+C or ``duration``; its sockets closed after."""
    import signal

    signal.signal(signal.SIGTERM, lambda *_: server.stop())
    try:
        server.run(duration=duration)
    except KeyboardInterrupt:
        pass
    finally:
        server.close()


def cmd_server(args: argparse.Namespace) -> int:
    import signal

    from app.engine.server import DEFAULT_RATE, EngineServer
    from app.net.security import ENV_OPERATOR_SECRET, ServerCurve
    from app.net.transport import check_url, is_local

    running: list = []  # the server, once it exists
    if getattr(args, "exit_with_parent", False):
        # watched from the first moment, not after the kernels load: an engine whose GUI went while it was
        # still starting ran on for seconds on a busy machine (the GUI's SIGTERM test, 2026-11-28)
        parent = os.getppid()

        def watch_parent() -> None:
            while os.getppid() == parent:  # re-parented: the GUI is gone (killed, crashed)
                time.sleep(0.5)
            if running:
                running[0].stop()
            else:  # still starting: ended as SIGTERM ends it (one line, status 130)
                os.kill(os.getpid(), signal.SIGTERM)

        threading.Thread(target=watch_parent, daemon=True).start()
    check_url(args.bind)
    if (args.curve_secret is None) != (args.curve_clients is None):
        raise BosunError("--curve-secret and --curve-clients go together")
    curve = ServerCurve.from_files(args.curve_secret, args.curve_clients) if args.curve_secret else None
    if not is_local(args.bind) and curve is None:
        raise BosunError(
            f"binding to the non-local address {args.bind} needs CURVE keys (--curve-secret, --curve-clients); "
            "make them with 'bosun keys' (README: remote operation)"
        )
    plc = _plc_target(args)  # before the kernels compile: a missing extra or a bad address says so at once
    # the launch secret of a GUI's own engine comes in the environment, never on the command line
    operator_secret = os.environ.pop(ENV_OPERATOR_SECRET, None) or None
    from app.warmup import warm_up

    # compile (or load from the on-disk cache) before the first tick: never in the control loop
    compile_s = warm_up(
        progress=lambda k, n: print(f"bosun server: compiled kernels {k}/{n}", flush=True) if k == n else None
    )
    if compile_s > 1.0:
        print(f"bosun server: kernels compiled in {compile_s:.1f} s (cached for the next start)", flush=True)
    session = _make_session(args)
    rate = args.rate if args.rate is not None else (50.0 if args.plant in ("tac", "lab") else DEFAULT_RATE)
    pub = (
        min(args.publish_rate, rate)
        if args.publish_rate is not None
        else (25.0 if args.plant in ("tac", "lab") else 50.0)
    )
    server = EngineServer(
        session,
        bind=args.bind,
        rate=rate,
        publish_rate=pub,
        token=args.token,
        curve=curve,
        operator_secret=operator_secret,
        operator_timeout=args.operator_timeout,
        realtime=args.realtime,
    )
    if args.record:
        try:
            server.record(args.record, seed=getattr(session, "seed", 0))
        except BosunError:
            server.close()
            raise
    signal.signal(signal.SIGTERM, lambda *_: server.stop())
    running.append(server)  # from now on the parent watcher stops the loop
    print(f"bosun server: {session.robot_name} / {session.solver_name} / {session.mode} at {rate:g} Hz", flush=True)
    print(f"  requests on {server.url}, state on {server.state_url}", flush=True)
    if curve is not None:
        n_keys = len(list(curve.clients_dir.glob("*.key")))
        print(f"  CURVE: encrypted; {n_keys} allowed client key(s) in {curve.clients_dir}", flush=True)
    if operator_secret:
        print("  the operator role needs this engine's launch secret", flush=True)
    if plc is not None:
        print(f"  plant: the Motion-Lab's PLC at {plc} over ADS (pyads); STOP writes MAIN.bStop", flush=True)
    if server.recorder is not None:
        print(f"  recording to {server.recorder.path} (MCAP)", flush=True)
    _run_until_stopped(server, args.duration)
    st = server.stats.summary()
    print(f"bosun server: stopped after {st['ticks']} ticks, {st['missed_deadlines']} missed deadlines", flush=True)
    if server.recorder is not None:
        rec = server.recorder
        print(f"bosun server: recorded {rec.messages} messages to {rec.path} ({rec.path.stat().st_size} bytes)",
              flush=True)  # fmt: skip
    return 0


def cmd_keys(args: argparse.Namespace) -> int:
    from app.net.security import create_keys, load_public

    public, secret = create_keys(args.dir, args.name)
    print(f"public key  {public}  ({load_public(public).decode()}): give it to the other side")
    print(f"secret key  {secret}  (mode 0600): keep it on this machine")
    print("an engine uses its secret key and a folder of allowed client public keys:")
    print("  bosun server --bind tcp://0.0.0.0:5555 --curve-secret ENGINE.key_secret --curve-clients ALLOWED_DIR")
    print("a client uses its secret key and the engine's public key:")
    print("  bosun joystick --connect tcp://HOST:5555 --curve-secret CLIENT.key_secret --server-key ENGINE.key")
    return 0


def cmd_joystick(args: argparse.Namespace) -> int:
    from app.net.transport import TransportError, check_url
    from app.teleop.client import run_joystick_client

    check_url(args.connect)
    virtual = None
    if args.virtual:
        from app.teleop.devices import PygameJoysticks
        from app.teleop.virtual import VirtualJoystick

        PygameJoysticks()  # initialise SDL's joystick subsystem before attaching
        virtual = VirtualJoystick(n_axes=4, n_buttons=8)

        def operator(vj=virtual) -> None:
            """The arming gesture an operator makes: stick centred, press the deadman, then deflect."""
            time.sleep(0.5)
            vj.set_button(0, True)
            time.sleep(0.3)
            vj.set_axis(0, 0.5)

        threading.Thread(target=operator, daemon=True).start()
        print(
            "bosun joystick: a virtual joystick stands in for hardware (centred, deadman pressed at 0.5 s, "
            "x = 0.5 from 0.8 s)",
            flush=True,
        )
    import signal

    from app.net.security import ClientCurve

    if (args.curve_secret is None) != (args.server_key is None):
        raise BosunError("--curve-secret and --server-key go together")
    curve = ClientCurve.from_files(args.curve_secret, args.server_key) if args.curve_secret else None
    stop = threading.Event()  # SIGTERM and Ctrl-C stop streaming cleanly: the client says bye, the engine holds
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    try:
        sent = run_joystick_client(
            args.connect,
            token=args.token,
            curve=curve,
            device=args.device,
            rate=args.rate,
            duration=args.duration,
            stop=stop,
            on_event=lambda t: print(f"bosun joystick: {t}", flush=True),
        )
    except TransportError as err:
        raise BosunError(str(err)) from None
    except RuntimeError as err:
        raise BosunError(str(err)) from None
    except KeyboardInterrupt:
        sent = 0
    finally:
        if virtual is not None:
            virtual.detach()
    print(f"bosun joystick: sent {sent} input messages", flush=True)
    return 0


def cmd_replay(args: argparse.Namespace) -> int:
    """Run a recorded session again (app/engine/replay.py); with --check, every published state compared."""
    import json as _json

    from app.engine.replay import replay

    if args.serve:
        return _serve_replay(args)
    report = replay(args.file, check=args.check, tolerance=args.tolerance)
    if args.json:
        print(_json.dumps(report.to_dict(), indent=2))
    else:
        print(f"bosun replay: {report.path}: the {report.kind} engine, {report.ticks} ticks, {report.inputs} inputs, "
              f"{report.commands} commands, {report.estops} E-STOPs")  # fmt: skip
        if args.check:
            if report.equal:
                print(f"  every one of {report.states} published states equal to the recording (to {args.tolerance:g})")
            else:
                print(f"  {report.differing} of {report.states} states differ; the first: {report.first}")
    return 1 if args.check and not report.equal else 0


def _serve_replay(args: argparse.Namespace) -> int:
    """``bosun replay FILE --serve``: the recording played back in an engine loop at its own rate, for viewers."""
    from app.engine.replay import Replayer, ReplayScene
    from app.engine.server import EngineServer
    from app.net.transport import check_url, is_local

    if args.check:
        raise BosunError("--serve plays the recording back for viewers; --check compares it: one or the other")
    check_url(args.bind)
    if not is_local(args.bind):
        raise BosunError(f"--bind {args.bind}: a replay serves this machine only (tcp://127.0.0.1:PORT)")
    replayer = Replayer(args.file, check=False)
    scene = ReplayScene(replayer)
    server = EngineServer(scene, bind=args.bind, rate=replayer.rate, publish_rate=replayer.publish_rate)
    print(
        f"bosun replay: {args.file}: the {replayer.report.kind} engine played back at {replayer.rate:g} Hz", flush=True
    )
    print(f"  requests on {server.url}, state on {server.state_url}; watch it: bosun view --connect {server.url}",
          flush=True)  # fmt: skip
    try:
        _run_until_stopped(server, args.duration)
    finally:
        replayer.close()
    print(f"bosun replay: played {replayer.report.ticks} ticks{' (the whole recording)' if replayer.done else ''}",
          flush=True)  # fmt: skip
    return 0


def cmd_score(args: argparse.Namespace) -> int:
    """The training score sheet of a recorded crane-head or Motion-Lab session (app/analysis/score.py)."""
    import json as _json

    from app.analysis.score import score_recording, write_score

    sheet = score_recording(args.file)
    out = Path(args.out) if args.out else Path(args.file).with_suffix("")
    j, png = write_score(sheet, out)
    if args.json:
        print(_json.dumps(sheet.to_dict(), indent=2))
        return 0
    d = sheet.to_dict()
    print(f"bosun score: {sheet.path} ({sheet.kind}, {sheet.duration_s:.0f} s)")
    for key in ("peak_tension_factor", "peak_psi", "peak_swing_deg", "rms_swing_deg", "time_over_swl_s", "estops",
                "saturations", "saturated_s", "max_landing_speed_mps", "rehits"):  # fmt: skip
        v = d[key]
        print(f"  {key:24s} {'—' if v is None else (f'{v:.3g}' if isinstance(v, float) else v)}")
    print(f"  landings: {len(sheet.landing_speeds_mps)}; wrote {j} and {png}")
    return 0


def register(sub) -> None:
    """Add this group's commands to ``bosun``'s subparsers."""
    with command(
        sub, "score", cmd_score, json=False,
        help="a training score sheet of a recorded crane-head or Motion-Lab session (JSON and a one-page figure)",
        description="Peak dynamic factor (the wire's tension over the load's weight, and the load chart's ψ), "
        "swing (peak, rms while the load hangs), time over SWL, STOPs, the head's saturations, touchdown speeds "
        "and re-hits, from the recording's published states; score.json and score.png in --out (default: the "
        "recording's name without .mcap).",
    ) as p:  # fmt: skip
        p.add_argument("file", metavar="FILE.mcap", help="the recording (bosun server --record)")
        p.add_argument("--out", default=None, metavar="DIR", help="where score.json and score.png go")
        p.add_argument("--json", action="store_true", help="the sheet as JSON on standard output")
    with command(
        sub, "replay", cmd_replay, help="run a recorded session (bosun server --record) again; --check compares it",
        description="Builds the recorded engine's scene, applies the recorded inputs, commands and E-STOPs through "
        "the loop's own command path and steps it with the recorded ticks. With --check every published state is "
        "compared with the recording (exit 1 when one differs: the first difference is named). A recording that "
        "holds work the loop did off its thread (a new sea, a study) is refused; a time-budgeted solver (the GA) "
        "may take other steps on another run, and the check says where.",
    ) as p:  # fmt: skip
        p.add_argument("file", metavar="FILE.mcap", help="the recording")
        p.add_argument("--check", action="store_true", help="compare every published state with the recording")
        p.add_argument("--tolerance", type=_positive_float, default=1e-12,
                       help="numbers equal to this, relative above 1 (default 1e-12)")  # fmt: skip
        p.add_argument("--serve", action="store_true",
                       help="play it back in an engine loop at its own rate for viewers (bosun view, the GUI); "
                       "live input is ignored, commands refused, STOP freezes it")  # fmt: skip
        p.add_argument("--bind", default="tcp://127.0.0.1:5555", help="with --serve: the request URL (this machine)")
        p.add_argument("--duration", type=_positive_float, default=None, help="with --serve: stop after this long [s]")

    def add_engine_args(p: argparse.ArgumentParser) -> None:
        p.add_argument("--robot", default="comau_smart5_3dof", help="robot to load (default comau_smart5_3dof)")
        p.add_argument("--solver", default="jacobian", help="solver (default jacobian)")
        p.add_argument("--mode", choices=["position", "velocity"], default="velocity", help="default velocity")
        p.add_argument(
            "--robots-dir",
            action="append",
            metavar="DIR",
            help="a folder whose robot files clients may load by path (repeatable; the library and "
            "$BOSUN_ROBOTS_DIR always are)",
        )

    p = sub.add_parser("server", help="run the engine headless (fixed-rate loop, ZeroMQ protocol)")
    p.add_argument(
        "--bind",
        default="tcp://127.0.0.1:5555",
        help="request URL: tcp://HOST:PORT or ipc://PATH (default tcp://127.0.0.1:5555); "
        "a non-local address needs CURVE keys (--curve-secret and --curve-clients)",
    )
    add_engine_args(p)
    p.add_argument(
        "--plant",
        choices=["teleop", "tac", "lab"],
        default="teleop",
        help="teleop (a library manipulator), tac (vessel, crane, Delta head), lab (Motion-Lab); default teleop",
    )
    p.add_argument(
        "--rate",
        type=_positive_float,
        default=None,
        help="control rate [Hz], up to 1000 (default 1000; tac and lab 50)",
    )
    p.add_argument(
        "--publish-rate", type=_positive_float, default=None, help="state messages per second (default 50; tac 25)"
    )
    p.add_argument("--token", default=None, help="shared token every client must present (loopback testing only)")
    p.add_argument(
        "--curve-secret", default=None, metavar="FILE", help="the engine's CURVE secret key file (bosun keys)"
    )
    p.add_argument(
        "--curve-clients", default=None, metavar="DIR", help="folder of the client public keys (*.key) allowed in"
    )
    p.add_argument(
        "--operator-timeout",
        type=_positive_float,
        default=5.0,
        help="seconds without a message before the operator role lapses (default 5; a warning at 2)",
    )
    p.add_argument(
        "--plc",
        default=None,
        metavar="AMS_NET_ID[:PORT]",
        help="with --plant lab: drive the real Motion-Lab through its TwinCAT PLC over ADS (needs the extra "
        "plc: pip install 'bosun[plc]'), e.g. 192.168.90.150.1.1:851 (port default 851)",
    )
    p.add_argument(
        "--plc-host", default=None, metavar="HOST", help="the PLC's IP or name (default: the Net ID's first 4 numbers)"
    )
    p.add_argument(
        "--plc-local-id",
        default=None,
        metavar="AMS_NET_ID",
        help="this machine's AMS Net ID, if the PLC's route to it names another (default: the ADS library's)",
    )
    p.add_argument(
        "--comau-limits", default=None, metavar="PROFILE",
        help="with --plant lab: the Comau's joint-limit profile, lab (the lab's program limits, the layout's default) "
        "or datasheet (the robot file's: the arm then reaches its platform and pedestal, guarded)",
    )  # fmt: skip
    p.add_argument(
        "--realtime", type=_rt_priority, nargs="?", const=50, default=0, metavar="PRIORITY",
        help="run the control loop's thread on the SCHED_FIFO scheduler at PRIORITY (1-99, default 50, as "
        "ros2_control does): programs on the normal scheduler (clients, viewers, the GUI) no longer preempt a tick "
        "(needs root or CAP_SYS_NICE; not granted, the loop runs as without it and says so)",
    )  # fmt: skip
    p.add_argument("--duration", type=_positive_float, default=None, help="stop after this many seconds")
    p.add_argument(
        "--record", default=None, metavar="FILE.mcap",
        help="record the session (inputs, commands, E-STOPs, ticks, description and every published state) to an "
        "MCAP file with JSON schemas, as Foxglove and PlotJuggler open it",
    )  # fmt: skip
    p.add_argument(
        "--exit-with-parent",
        action="store_true",
        help="stop when the process that started this engine ends (the GUI's own engines use it)",
    )
    p.set_defaults(func=cmd_server)

    p = sub.add_parser("joystick", help="stream a local joystick to an engine (the input client)")
    p.add_argument("--connect", required=True, help="the engine's request URL, e.g. tcp://127.0.0.1:5555")
    p.add_argument("--token", default=None, help="shared token of the engine (loopback testing)")
    p.add_argument("--curve-secret", default=None, metavar="FILE", help="this client's CURVE secret key (bosun keys)")
    p.add_argument("--server-key", default=None, metavar="FILE", help="the engine's CURVE public key")
    p.add_argument("--device", default=None, help="use the first joystick whose name contains this")
    p.add_argument("--rate", type=_positive_float, default=100.0, help="input messages per second (default 100)")
    p.add_argument(
        "--comau-limits", default=None, metavar="PROFILE",
        help="with --plant lab: the Comau's joint-limit profile, lab (the lab's program limits, the layout's default) "
        "or datasheet (the robot file's: the arm then reaches its platform and pedestal, guarded)",
    )  # fmt: skip
    p.add_argument("--duration", type=_positive_float, default=None, help="stop after this many seconds")
    p.add_argument("--virtual", action="store_true", help="attach an SDL virtual joystick (no hardware needed)")
    p.set_defaults(func=cmd_joystick)

    p = sub.add_parser(
        "keys",
        help="make a CURVE key pair for remote operation (NAME.key public, NAME.key_secret secret)",
        description="Writes NAME.key (public: give it to the other side) and NAME.key_secret (keep it; mode "
        "0600) in ZeroMQ's certificate format. The engine needs its own secret key and a folder with each "
        "allowed client's public key; a client needs its own secret key and the engine's public key.",
    )
    p.add_argument("name", help="name of the pair, e.g. engine or operator-laptop")
    p.add_argument("--dir", default="keys", help="folder to write into (default ./keys)")
    p.set_defaults(func=cmd_keys)
