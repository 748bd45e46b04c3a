"""Who may talk to an engine: CURVE keys, the launch secret, and throttled authentication.

* **CURVE** (ZeroMQ's own CurveZMQ: Curve25519 key exchange, every frame encrypted and
  authenticated).  ``bosun keys NAME`` writes a key pair in ZeroMQ's certificate format
  (``NAME.key`` public, ``NAME.key_secret`` secret).  The engine holds its secret key and a folder
  of allowed client public keys; a client holds its own secret key and the engine's public key.
  Required for any non-loopback bind.  Handshakes with a key not in the folder are refused by
  the ZAP handler below (the key is always looked at first) and counted per peer address and key.
* **Launch secret**: an engine a GUI starts gets a random secret in its environment
  (``BOSUN_OPERATOR_SECRET``, never on the command line, where other users could read it); only a
  hello carrying it is granted the operator role.  Anyone else on the host may watch.
* **Token**: the old shared secret, for loopback testing only; failed checks are throttled per
  client connection, never for everybody (:class:`AuthThrottle`).
"""

from __future__ import annotations

import collections
import logging
import math
import os
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Self

import zmq
import zmq.auth
from zmq.auth.thread import ThreadAuthenticator
from zmq.utils import z85

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
class _OwnPair:
    """The CURVE pair a socket speaks with (a client's or the engine's) and what it knows of its peers."""

    public: bytes
    secret: bytes

    @classmethod
    def from_files(cls, secret_file: str, peers: str) -> Self:
        """The pair of the secret certificate ``secret_file``; the peers' keys from ``peers`` (read by
        :meth:`_peers`)."""
        public, secret = load_pair(secret_file)
        return cls(public, secret, cls._peers(peers))

    @staticmethod
    def _peers(peers: str) -> Any:
        raise NotImplementedError  # each kind of pair reads its peers' keys its own way

    def _apply_pair(self, sock: zmq.Socket) -> None:
        sock.curve_publickey = self.public
        sock.curve_secretkey = self.secret


@dataclass(frozen=True)
class ClientCurve(_OwnPair):
    """A client's CURVE keys: its own pair and the engine's public key (``from_files``: the engine's
    public key file)."""

    server_public: bytes

    _peers = staticmethod(load_public)

    def apply(self, sock: zmq.Socket) -> None:
        self._apply_pair(sock)
        sock.curve_serverkey = self.server_public


@dataclass(frozen=True)
class ServerCurve(_OwnPair):
    """The engine's CURVE pair and the folder of allowed client public keys (``from_files``: that folder)."""

    clients_dir: Path

    @staticmethod
    def _peers(clients_dir: str) -> Path:
        folder = Path(clients_dir)
        if not folder.is_dir():
            raise KeyFileError(f"{clients_dir}: not a folder of client public keys")
        if not list(folder.glob("*.key")):
            raise KeyFileError(f"{clients_dir}: no client public keys (*.key) in it")
        return folder

    def apply(self, sock: zmq.Socket) -> None:
        sock.curve_server = True
        self._apply_pair(sock)


class AuthThrottle:
    """Failed authentications counted per source; a source past ``burst`` failures in ``window`` seconds
    is refused unexamined until its window has room again.

    A *source* is what a failure can be pinned on: a CURVE handshake's peer address, or a client
    connection (peer address, CURVE key, identity) for tokens and the launch secret.  One source's
    failures never hold another back: the operator's allowed key or right token is looked at and
    admitted while someone else guesses (issue 27, item 3: one throttle for everybody locked the
    operator out).  Guessing from one connection runs at ``burst / window`` a second at most (it ran
    at 9,710/s before there was a throttle).  At most ``sources`` are remembered (identities are
    cheap to invent): past that the quiet ones are forgotten, then all."""

    def __init__(self, burst: int = 10, window: float = 1.0, sources: int = 4096) -> None:
        self.burst, self.window, self.max_sources = burst, window, sources
        self.failures = 0  # every failure since the start (``auth_failures`` in the state)
        self.throttled = 0  # checks refused unexamined
        self._recent: dict[str, collections.deque[float]] = {}
        self._lock = threading.Lock()

    def _trim(self, source: str, now: float) -> collections.deque[float] | None:
        times = self._recent.get(source)
        while times and now - times[0] > self.window:
            times.popleft()
        return times

    def recent(self, source: str, now: float | None = None) -> int:
        """Failures of ``source`` within the last window."""
        now = time.monotonic() if now is None else now
        with self._lock:
            times = self._trim(source, now)
            return len(times) if times else 0

    def allowed(self, source: str, now: float | None = None) -> bool:
        """Whether ``source`` may be examined now (False: it failed ``burst`` times within the window)."""
        now = time.monotonic() if now is None else now
        with self._lock:
            times = self._trim(source, now)
            if times is not None and len(times) >= self.burst:
                self.throttled += 1
                return False
            return True

    def failed(self, source: str, now: float | None = None, count: bool = True) -> int:
        """Record a failure of ``source`` (``count``: in :attr:`failures` too; False for a second view of
        one failure); returns the failures of ``source`` within the last window."""
        now = time.monotonic() if now is None else now
        with self._lock:
            self.failures += count
            times = self._trim(source, now)
            if times is None:
                if len(self._recent) >= self.max_sources:
                    for key in [k for k, v in self._recent.items() if not v or now - v[-1] > self.window]:
                        del self._recent[key]
                    if len(self._recent) >= self.max_sources:
                        self._recent.clear()
                times = self._recent[source] = collections.deque(maxlen=self.burst + 1)  # enough to decide
            times.append(now)
            return len(times)

    def recent_by_source(self, now: float | None = None) -> dict[str, int]:
        """Sources with failures within the last window, and how many (for logs and tests)."""
        now = time.monotonic() if now is None else now
        with self._lock:
            return {k: len(t) for k in list(self._recent) if (t := self._trim(k, now))}


class CurveAuthenticator(ThreadAuthenticator):
    """pyzmq's ZAP handler thread allowing the client keys of one folder.

    The key is always looked at first: an allowed key is admitted whatever else knocks.  A key not in
    the folder is refused with the reason in the ZAP status text and the log; failures are counted per
    peer address (the ZAP request's ``address``) and per key, and logged at most once per address and
    5 s with their count.  The handler never sleeps: one thread answers every handshake in turn, and a
    pause for one address would hold up the others (issue 27, item 3)."""

    LOG_EVERY = 5.0

    def __init__(self, context: zmq.Context, clients_dir: Path, throttle: AuthThrottle) -> None:
        super().__init__(context, log=logging.getLogger("bosun.auth"))
        self.clients_dir = clients_dir
        self.throttle = throttle
        self._address = ""  # of the ZAP request in hand (one thread, one request at a time)
        self._logged: dict[str, float] = {}
        self.refusals: collections.deque[str] = collections.deque(maxlen=100)  # the latest reasons

    def start(self) -> None:
        super().start()
        self.configure_curve(domain="*", location=str(self.clients_dir))

    async def handle_zap_message(self, msg: list[bytes]) -> None:
        # the request's fields: version, request id, domain, address, identity, mechanism, credentials
        self._address = msg[3].decode("utf-8", "replace")[:64] if len(msg) > 3 else "?"
        await super().handle_zap_message(msg)

    async def _authenticate_curve(self, domain: str, client_key: bytes) -> tuple[bool, bytes]:
        ok, reason = await super()._authenticate_curve(domain, client_key)
        if ok:
            return ok, reason
        address = self._address or "?"
        key = z85.encode(client_key).decode("ascii", "replace") if len(client_key) == 32 else "?"
        source = f"handshake from {address}"
        n = self.throttle.failed(source)
        self.throttle.failed(f"handshake with key {key}", count=False)  # per key too: one stranger, many addresses
        why = f"client key {key[:8]}… from {address} is not in the allowed folder"
        if reason and reason != b"Unknown key":
            why += f" ({reason.decode('utf-8', 'replace')})"
        if n > self.throttle.burst:
            why += f"; more than {self.throttle.burst} refused from {address} within {self.throttle.window:g} s"
        self.refusals.append(why)
        now = time.monotonic()
        if now - self._logged.get(address, -math.inf) >= self.LOG_EVERY:
            if len(self._logged) > 1000:
                self._logged.clear()
            self._logged[address] = now
            self.log.warning(
                "CURVE handshake refused: %s (authentication failures so far: %d)", why, self.throttle.failures
            )
        return False, why.encode("utf-8")[:255]
