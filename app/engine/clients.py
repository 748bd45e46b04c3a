"""The engine's client book: who is connected, in which role, and the operator's silence watched.

The I/O thread keeps it (hello, bye, roles, lapses, forgetting silent clients); the loop only reads it
(whose input counts, who is named in the state).  Roles: the first client asking for ``operator`` gets it;
others are viewers.  The role lapses only after ``operator_timeout`` without any message from its holder,
with a warning to every client at ``lapse_warning``; the displaced holder is remembered, so that what it
sends next is refused with the reason.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from app.errors import printable


def clean_name(name: str) -> str:
    """A client's name as it may appear in every log: printable, one line, at most 64 characters."""
    return printable(name, 64) or "?"


@dataclass
class ClientInfo:
    name: str
    role: str
    last_seen: float
    refused_at: float = -math.inf  # last explicit refusal of its input (at most one a second)


class ClientBook:
    """The clients by ZeroMQ identity and the operator's; ``note(level, text)`` tells every client."""

    def __init__(
        self,
        note: Callable[[str, str], None],
        operator_timeout: float = 5.0,
        lapse_warning: float = 2.0,
        client_timeout: float = 60.0,
    ) -> None:
        self.clients: dict[bytes, ClientInfo] = {}
        self.operator: bytes | None = None
        self.operator_timeout = operator_timeout
        self.lapse_warning = min(lapse_warning, operator_timeout)
        self.client_timeout = client_timeout  # clients silent this long are forgotten (no ghosts pile up)
        self.displaced: dict[bytes, str] = {}  # former operators -> why they lost the role
        self._warned_silence = False
        self._note = note

    def holder(self) -> ClientInfo | None:
        """The operator's entry (None when the role is free)."""
        return self.clients.get(self.operator) if self.operator is not None else None

    def operator_alive(self, now: float) -> bool:
        if self.operator is None or self.operator not in self.clients:
            return False
        return now - self.clients[self.operator].last_seen <= self.operator_timeout

    def join(self, ident: bytes, name: str, wants_operator: bool, now: float) -> tuple[str, str]:
        """A client's hello (its credentials already checked): its role and, when it asked for more, why not.
        The caller announces it (after disarming the loop for a new operator: the order of the loop's inbox)."""
        role, note = "viewer", ""
        if wants_operator:
            if self.operator not in (None, ident) and not self.operator_alive(now):
                self.lapse(f"the role lapsed after {self.operator_timeout:g} s of silence")
            if self.operator in (None, ident):
                self.operator = ident
                self.displaced.pop(ident, None)
                self._warned_silence = False
                role = "operator"
            else:
                note = f"operator role is held by {self.clients[self.operator].name}; joined as viewer"
        self.clients[ident] = ClientInfo(name, role, now)
        return role, note

    def leave(self, ident: bytes) -> None:
        """A client's bye: forgotten, and its role free."""
        client = self.clients.pop(ident, None)
        if self.operator == ident:
            self.operator = None
            self._note("info", f"operator {client.name if client else '?'} left")

    def release(self, ident: bytes) -> None:
        """The operator gives up its role (anybody else's release changes nothing)."""
        if self.operator == ident:
            self.operator = None
            client = self.clients[ident]
            client.role = "viewer"
            self._note("info", f"operator {client.name} released the role")

    def lapse(self, why: str) -> None:
        ident = self.operator
        self.operator = None
        self._warned_silence = False
        if ident is None:
            return
        holder = self.clients.get(ident)
        if holder is not None:
            holder.role = "viewer"
        if len(self.displaced) > 1000:
            self.displaced.clear()
        self.displaced[ident] = why
        self._note("warning", f"operator role free: {why}")  # its input went stale long ago: holding

    def check_operator(self, now: float) -> None:
        """Warn every client when the operator falls silent; lapse the role after operator_timeout."""
        if self.operator is None:
            return
        holder = self.clients.get(self.operator)
        silent = now - holder.last_seen if holder is not None else math.inf
        if silent <= self.lapse_warning:
            self._warned_silence = False
            return
        name = holder.name if holder is not None else "?"
        if silent > self.operator_timeout:
            self.lapse(f"the role lapsed after {self.operator_timeout:g} s without a message from {name}")
        elif not self._warned_silence:
            self._warned_silence = True
            self._note(
                "warning",
                f"operator {name} silent for {self.lapse_warning:g} s: the role lapses at {self.operator_timeout:g} s",
            )

    def housekeeping(self, now: float) -> None:
        """The operator's silence (warning, lapse) and clients silent for ``client_timeout`` forgotten."""
        self.check_operator(now)
        for ident in [i for i, c in self.clients.items() if now - c.last_seen > self.client_timeout]:
            gone = self.clients.pop(ident)
            if self.operator == ident:
                self.operator = None
            self._note("info", f"{gone.name} silent for {self.client_timeout:g} s: forgotten")
