"""Bytes ⇄ protocol messages: msgpack bodies validated against :mod:`app.net.messages`.

:func:`decode` validates a message once and returns an instance of its class (a typed
:class:`~app.net.messages.Message`); it never raises anything but :class:`ProtocolError` (with a one-line
reason), whatever the bytes: a server can log the reason and carry on.  :func:`encode_message` sends one.
"""

from __future__ import annotations

import math
from typing import Any

import msgpack

from app.errors import BosunError
from app.net.messages import (
    CLIENT,
    CLIENT_MESSAGES,
    ENGINE,
    ENGINE_MESSAGES,
    MAX_ENGINE_MESSAGE_BYTES,
    MAX_MESSAGE_BYTES,
    PROTOCOL_VERSION,
    Message,
)


class ProtocolError(BosunError):
    """A message that is not valid protocol; the reason says why."""


def _finite_number(x: Any) -> bool:
    return isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)


def _check_field(name: str, value: Any, kind: str, limit: Any) -> Any:
    def bad(why: str) -> ProtocolError:
        return ProtocolError(f"field '{name}' {why}")

    if kind == "str":
        if not isinstance(value, str):
            raise bad("must be text")
        if len(value) > limit:
            raise bad(f"is longer than {limit} characters")
        return value
    if kind == "int":
        if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= limit:
            raise bad(f"must be an integer in [0, {limit}]")
        return value
    if kind == "float":
        if not _finite_number(value) or abs(value) > limit:
            raise bad(f"must be a finite number with magnitude ≤ {limit:g}")
        return float(value)
    if kind == "bool":
        if not isinstance(value, bool):
            raise bad("must be true or false")
        return value
    if kind in ("floats", "unit_floats", "vec3"):
        if not isinstance(value, list | tuple):
            raise bad("must be a list of numbers")
        n = 3 if kind == "vec3" else limit
        if (kind == "vec3" and len(value) != 3) or len(value) > n:
            raise bad(f"must have {'exactly 3' if kind == 'vec3' else f'at most {n}'} values")
        if not all(_finite_number(v) for v in value):
            raise bad("must hold finite numbers only")
        if kind == "unit_floats" and any(abs(v) > 1.0 for v in value):
            raise bad("values must lie in [-1, 1]")
        if kind == "vec3" and any(abs(v) > limit for v in value):
            raise bad(f"values must have magnitude ≤ {limit:g}")
        return [float(v) for v in value]
    if kind == "bools":
        if not isinstance(value, list | tuple) or len(value) > limit or not all(isinstance(v, bool) for v in value):
            raise bad(f"must be a list of at most {limit} booleans")
        return list(value)
    if kind == "enum":
        if value not in limit:
            raise bad(f"must be one of {', '.join(limit)}")
        return value
    if kind == "map":
        if not isinstance(value, dict):
            raise bad("must be a map")
        return value
    raise AssertionError(f"unknown field kind {kind}")  # a bug in the schema, not in the input


def validate(msg: Any, schema: dict[str, dict[str, tuple]]) -> dict[str, Any]:
    """Check a decoded map against a schema; returns a clean dict (fields converted)."""
    if not isinstance(msg, dict):
        raise ProtocolError("message is not a map")
    if msg.get("v") != PROTOCOL_VERSION:
        raise ProtocolError(
            f"protocol version {msg.get('v')!r} is not supported (this engine speaks {PROTOCOL_VERSION})"
        )
    mtype = msg.get("type")
    if not isinstance(mtype, str) or mtype not in schema:
        raise ProtocolError(f"unknown message type {mtype!r}"[:200])
    fields = schema[mtype]
    extra = set(msg) - set(fields) - {"v", "type"}
    if extra:
        raise ProtocolError(f"{mtype}: unknown field(s) {', '.join(sorted(map(str, extra)))[:200]}")
    out: dict[str, Any] = {"type": mtype}
    for name, (kind, required, limit) in fields.items():
        if name not in msg:
            if required:
                raise ProtocolError(f"{mtype}: missing field '{name}'")
            continue
        try:
            out[name] = _check_field(name, msg[name], kind, limit)
        except ProtocolError as err:
            raise ProtocolError(f"{mtype}: {err}") from None
    return out


def encode(mtype: str, **fields: Any) -> bytes:
    """Encode one message by type and fields (not validated: the engine and clients build their own messages;
    :func:`encode_message` checks the fields against the message's class first)."""
    return msgpack.packb({"v": PROTOCOL_VERSION, "type": mtype, **fields}, use_bin_type=True)


def encode_message(msg: Message) -> bytes:
    """Encode a typed message (its set fields)."""
    return encode(msg.TYPE, **msg.fields())


def build(mtype: str, **fields: Any) -> Message:
    """The client message ``mtype`` with ``fields`` as its class (a TypeError names an unknown or missing field: a
    sender's bug, not the peer's)."""
    cls = CLIENT.get(mtype)
    if cls is None:
        raise TypeError(f"no client message {mtype!r}")
    return cls(**fields)


def _unpack(data: bytes, limit: int) -> Any:
    if not isinstance(data, bytes | bytearray | memoryview):
        raise ProtocolError("message is not bytes")
    if len(data) > limit:
        raise ProtocolError(f"message of {len(data)} bytes exceeds the limit of {limit}")
    try:
        return msgpack.unpackb(bytes(data), raw=False, strict_map_key=True)
    except Exception as err:  # msgpack raises many types on garbage; all mean "not msgpack"
        raise ProtocolError(f"not a msgpack message ({type(err).__name__})") from None


def decode(data: bytes, limit: int = MAX_MESSAGE_BYTES) -> Message:
    """Decode and validate a client's message: an instance of its class; any failure is a :class:`ProtocolError`."""
    fields = validate(_unpack(data, limit), CLIENT_MESSAGES)
    return CLIENT[fields.pop("type")](**fields)


def decode_engine(data: bytes) -> Message:
    """Decode and validate a message sent by the engine (client side): an instance of its class."""
    fields = validate(_unpack(data, MAX_ENGINE_MESSAGE_BYTES), ENGINE_MESSAGES)
    return ENGINE[fields.pop("type")](**fields)
