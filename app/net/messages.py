"""The Bosun protocol, version 3: message types and their fields (see docs/protocol.md).

Version 2 (typed state): every snapshot has ``kind`` and the E-STOP latch at ``estop`` (version 1
nested it under ``flags`` for the teleop scene); static data (robot file, limits, joint names,
the workspace box, the lab's geometry) moved from the state into the ``description`` a client asks
for with ``describe``; server fields moved under ``engine``.  The classes are in
:mod:`app.net.snapshots`.

Every message is a msgpack map with ``v`` (protocol version), ``type`` and the fields
below.  A field spec is (kind, required, limit):

* ``str``: UTF-8 text of at most ``limit`` characters;
* ``int``: integer in [0, limit];
* ``float``: finite number with |x| ≤ limit;
* ``bool``;
* ``floats``: list of at most ``limit`` finite numbers; ``unit_floats``: same, each in [−1, 1];
* ``bools``: list of at most ``limit`` booleans;
* ``vec3``: three finite numbers with |x| ≤ limit;
* ``enum``: one of the strings in ``limit``;
* ``map``: a map (state snapshots from the engine; not accepted from clients).
"""

from __future__ import annotations

PROTOCOL_VERSION = 3
MAX_MESSAGE_BYTES = 65_536  # a client's message
MAX_ENGINE_MESSAGE_BYTES = 16 * 2**20  # an engine's (a study's result, a description with robot files)
MAX_ROBOT_TEXT = 60_000  # robot XML sent by a client in set_robot (larger files go in a robot folder)

ROLES = ("operator", "viewer")
MODES = ("position", "velocity")

# ------------------------------------------------------------------ client -> engine
CLIENT_MESSAGES: dict[str, dict[str, tuple]] = {
    "hello": {
        "role": ("enum", True, ROLES),
        "name": ("str", True, 64),
        "token": ("str", False, 256),
        "secret": ("str", False, 256),
    },
    "bye": {},
    "ping": {"seq": ("int", False, 2**62)},
    "input": {
        "seq": ("int", True, 2**62),
        "t_send": ("float", False, 1e12),
        "axes": ("unit_floats", True, 16),
        "buttons": ("bools", True, 64),
        "device": ("str", True, 128),
    },
    "device_lost": {"device": ("str", False, 128), "released": ("bool", False, None)},
    "set_robot": {"robot": ("str", True, 1024), "xml": ("str", False, MAX_ROBOT_TEXT)},
    "set_solver": {"solver": ("str", True, 64)},
    "set_mode": {"mode": ("enum", True, MODES)},
    "set_scaling": {"k_p": ("vec3", False, 1e4), "x_w": ("vec3", False, 1e5), "k_v": ("vec3", False, 1e3)},
    "estop": {"reason": ("str", False, 256), "token": ("str", False, 256)},
    "ack_alarm": {"key": ("str", False, 64)},
    # shelve one alarm for ``minutes`` (ISA-18.2 §12.3; at most 60, default 10; 0 unshelves it now)
    "shelve_alarm": {"key": ("str", True, 64), "minutes": ("float", False, 60.0)},
    "reset": {},
    "release_operator": {},
    "describe": {},  # answered by ``description`` on the request socket
    "pause": {"on": ("bool", True, None)},  # no client shows the scene: time stands still (operator)
    # teleop scene: IK studies in a worker process the engine owns
    "study_start": {
        "study": ("enum", True, ("distribution", "tracking")),
        "solver": ("str", False, 64),
        "grid": ("int", False, 40),
    },
    "study_cancel": {},
    # crane-head scene (``bosun server --plant tac``)
    # the crane-head scene's vessel (issue 17, item 2): a name (``bosun vessel list``) or an RAO table in Bosun's CSV,
    # sent in parts of ≤ 60 000 characters (``part`` 0 … ``parts`` − 1, in order; a part 0 starts anew)
    "set_vessel": {
        "vessel": ("str", False, 64),
        "csv": ("str", False, 60_000),
        "part": ("int", False, 63),
        "parts": ("int", False, 64),
        "label": ("str", False, 256),
    },
    "set_sea": {
        "spectrum": ("enum", True, ("jonswap", "pm", "torsethaugen")),
        "hs": ("float", True, 30.0),
        "tp": ("float", True, 40.0),
        "heading": ("float", True, 720.0),
    },
    "set_tac_mode": {"mode": ("enum", True, ("off", "tac", "cooperative"))},
    # Motion-Lab (``bosun server --plant lab``)
    "lab_platform": {
        "platform": ("str", True, 32),
        "action": ("enum", True, ("neutral", "settle", "engage", "disengage")),
    },
    "lab_source": {
        "platform": ("str", True, 32),
        "source": ("enum", True, ("simulation", "generator", "remote", "timeseries")),
        "amplitude": ("floats", False, 6),
        "frequency": ("floats", False, 6),
        "phase": ("floats", False, 6),
        "spectrum": ("enum", False, ("jonswap", "pm", "torsethaugen")),
        "hs": ("float", False, 30.0),
        "tp": ("float", False, 40.0),
        "heading": ("float", False, 720.0),
        "seed": ("int", False, 2**31),
        "scale": ("floats", False, 6),
        "csv": ("str", False, 60_000),
        "name": ("str", False, 256),
    },
    "lab_remote_pose": {"platform": ("str", True, 32), "eta": ("floats", True, 6)},
    "lab_comau_mode": {"mode": ("enum", True, ("settled", "remote", "motion_comp"))},
    "lab_winch": {"mode": ("enum", False, ("local", "remote", "motion_comp")), "speed": ("float", False, 10.0)},
    "lab_vvmc": {"on": ("bool", True, None)},
    # the real lab's PLC (``--plc``): acknowledge its error as the lab HMI does (``platform``: only that one)
    "lab_plc_ack": {"platform": ("str", False, 32)},
    # the Comau's joint jog (issue 16, item 5): ``joint`` 1–3 (q1–q3), ``speed`` a fraction of the profile's
    # joint speed; resent while held, zero when let go (a speed not refreshed for 0.3 s returns to zero)
    "lab_comau_jog": {"joint": ("int", True, 3), "speed": ("float", True, 1.0)},
    # the load-swing estimator and anti-swing law (issue 16, item 4; the lab HMI's "Pendel Estimator" buttons)
    "lab_antisway": {"action": ("enum", True, ("activate", "deactivate", "reset"))},
}

#: scene commands the server hands to the scene's command table (fields as keywords)
SCENE_MESSAGES = frozenset(
    {
        "set_robot",
        "set_solver",
        "set_mode",
        "set_scaling",
        "study_start",
        "study_cancel",
        "set_sea",
        "set_tac_mode",
        "set_vessel",
        "lab_platform",
        "lab_source",
        "lab_remote_pose",
        "lab_comau_mode",
        "lab_winch",
        "lab_vvmc",
        "lab_plc_ack",
        "lab_comau_jog",
        "lab_antisway",
    }
)

# ------------------------------------------------------------------ engine -> client
ENGINE_MESSAGES: dict[str, dict[str, tuple]] = {
    "welcome": {
        "client_id": ("str", True, 64),
        "role": ("enum", True, ROLES),
        "state_url": ("str", True, 1024),
        "note": ("str", False, 256),
    },
    "reply": {"re": ("str", True, 32), "ok": ("bool", True, None), "error": ("str", False, 1024)},
    "state": {"state": ("map", True, None)},  # a snapshot (app.net.snapshots)
    "description": {"description": ("map", True, None)},  # the scene's static data, on join and on request
    "study": {"study": ("map", True, None)},  # an IK study's progress; its result in the last one
    "log": {
        "level": ("enum", True, ("info", "warning", "error")),
        "text": ("str", True, 1024),
        "t": ("float", True, 1e12),
    },
}

#: messages only the operator may send (a viewer gets an error reply); E-STOP is anyone's
OPERATOR_ONLY = frozenset({"input", "device_lost", "reset", "ack_alarm", "shelve_alarm", "pause"} | SCENE_MESSAGES)
