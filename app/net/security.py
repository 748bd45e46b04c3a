"""Who may talk to an engine: CURVE keys, the launch secret, and throttled authentication.

* **CURVE** (ZeroMQ's own CurveZMQ: Curve25519 key exchange, every frame encrypted and
  authenticated).  ``bosun keys NAME`` writes a key pair in ZeroMQ's certificate format
  (``NAME.key`` public, ``NAME.key_secret`` secret).  The engine holds its secret key and a folder
  of allowed client public keys; a client holds its own secret key and the engine's public key.
  Required for any non-loopback bind.  Handshakes with a key not in the folder are refused by
  the ZAP handler below, counted and throttled.
* **Launch secret**: an engine a GUI starts gets a random secret in its environment
  (``BOSUN_OPERATOR_SECRET``, never on the command line, where other users could read it); only a
  hello carrying it is granted the operator role.  Anyone else on the host may watch.
* **Token**: the old shared secret, for loopback testing only; failed checks are throttled.
"""

from __future__ import annotations

import asyncio
import collections
import os
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import zmq
import zmq.auth
from zmq.auth.thread import ThreadAuthenticator

from app.errors import BosunError

ENV_OPERATOR_SECRET = "BOSUN_OPERATOR_SECRET"


class KeyFileError(BosunError):
    """A key file that cannot be used."""


def create_keys(directory: str | os.PathLike[str], name: str) -> tuple[Path, Path]:
    """Write ``NAME.key`` (public) and ``NAME.key_secret`` (secret, mode 0600) into ``directory``."""
    if not name or not all(ch.isalnum() or ch in "-_." for ch in name):
        raise KeyFileError(f"key name {name!r}: use letters, digits, '-', '_' and '.'")
    folder = Path(directory)
    folder.mkdir(parents=True, exist_ok=True)
    public, secret = folder / f"{name}.key", folder / f"{name}.key_secret"
    for path in (public, secret):
        if path.exists():
            raise KeyFileError(f"{path} exists; remove it first or choose another name")
    pub, sec = zmq.auth.create_certificates(str(folder), name)
    os.chmod(sec, 0o600)
    return Path(pub), Path(sec)


def load_public(path: str | os.PathLike[str]) -> bytes:
    """The Z85 public key of a certificate file (public or secret)."""
    public, _ = _load(path)
    return public


def load_pair(path: str | os.PathLike[str]) -> tuple[bytes, bytes]:
    """(public, secret) of a secret certificate file (``NAME.key_secret``)."""
    public, secret = _load(path)
    if secret is None:
        raise KeyFileError(f"{path}: holds no secret key (give the .key_secret file)")
    return public, secret


def _load(path: str | os.PathLike[str]) -> tuple[bytes, bytes | None]:
    try:
        public, secret = zmq.auth.load_certificate(str(path))
    except (OSError, ValueError) as err:
        raise KeyFileError(f"{path}: not a key file ({err})") from None
    if public is None or len(public) != 40:
        raise KeyFileError(f"{path}: no CURVE public key in it")
    return public, secret


@dataclass(frozen=True)
class ClientCurve:
    """A client's CURVE keys: its own pair and the engine's public key."""

    public: bytes
    secret: bytes
    server_public: bytes

    @classmethod
    def from_files(cls, secret_file: str, server_key_file: str) -> ClientCurve:
        public, secret = load_pair(secret_file)
        return cls(public, secret, load_public(server_key_file))

    def apply(self, sock: zmq.Socket) -> None:
        sock.curve_publickey = self.public
        sock.curve_secretkey = self.secret
        sock.curve_serverkey = self.server_public


@dataclass(frozen=True)
class ServerCurve:
    """The engine's CURVE pair and the folder of allowed client public keys."""

    public: bytes
    secret: bytes
    clients_dir: Path

    @classmethod
    def from_files(cls, secret_file: str, clients_dir: str) -> ServerCurve:
        public, secret = load_pair(secret_file)
        folder = Path(clients_dir)
        if not folder.is_dir():
            raise KeyFileError(f"{clients_dir}: not a folder of client public keys")
        if not list(folder.glob("*.key")):
            raise KeyFileError(f"{clients_dir}: no client public keys (*.key) in it")
        return cls(public, secret, folder)

    def apply(self, sock: zmq.Socket) -> None:
        sock.curve_server = True
        sock.curve_publickey = self.public
        sock.curve_secretkey = self.secret


class AuthThrottle:
    """Failed authentications counted, and at most ``burst`` per ``window`` seconds checked.

    Past that, checks are refused unexamined until the window has room again, so guessing runs
    at ``burst / window`` per second at most (it ran at 9,710/s) and the loop never sleeps."""

    def __init__(self, burst: int = 10, window: float = 1.0) -> None:
        self.burst, self.window = burst, window
        self.failures = 0
        self.throttled = 0
        self._recent: collections.deque[float] = collections.deque()
        self._lock = threading.Lock()

    def allowed(self, now: float | None = None) -> bool:
        now = time.monotonic() if now is None else now
        with self._lock:
            while self._recent and now - self._recent[0] > self.window:
                self._recent.popleft()
            if len(self._recent) >= self.burst:
                self.throttled += 1
                return False
            return True

    def failed(self, now: float | None = None) -> None:
        with self._lock:
            self.failures += 1
            self._recent.append(time.monotonic() if now is None else now)


class CurveAuthenticator(ThreadAuthenticator):
    """pyzmq's ZAP handler thread allowing the client keys of one folder; failures counted and throttled."""

    def __init__(self, context: zmq.Context, clients_dir: Path, throttle: AuthThrottle) -> None:
        super().__init__(context)
        self.clients_dir = clients_dir
        self.throttle = throttle

    def start(self) -> None:
        super().start()
        self.configure_curve(domain="*", location=str(self.clients_dir))

    async def _authenticate_curve(self, domain: str, client_key: bytes) -> tuple[bool, bytes]:
        if not self.throttle.allowed():
            await asyncio.sleep(0.05)  # this thread only: failed handshakes slow down, the engine loop does not
            return False, b"too many failed authentications"
        ok, reason = await super()._authenticate_curve(domain, client_key)
        if not ok:
            self.throttle.failed()
        return ok, reason
