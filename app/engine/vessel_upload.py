"""``set_vessel`` of the scenes with a vessel (issue 17, item 2): a vessel by name, or an RAO table in Bosun's
CSV sent in parts (a client message is at most 64 KiB).  :class:`VesselChoice` checks the message and puts
the parts together; the scene applies what it returns.  A whole table comes back as a :class:`TableText`
unparsed: a table of megabytes takes a second to parse, which an engine does off its control loop
(:mod:`app.engine.jobs`, issue 27 item 2) and a scene on its own in the command."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from app.engine.scene import CommandError
from app.errors import BosunError
from app.marine.vessel import RAOTable, load_rao_csv
from app.marine.vessels import VESSELS, vessel_label, vessel_rao

MAX_PARTS = 64


@dataclass(frozen=True)
class TableText:
    """The parts of a whole RAO table as sent, and its label (the file's name); :meth:`parse` makes the table."""

    parts: tuple[str, ...]
    label: str = ""

    @property
    def where(self) -> str:
        return self.label or "RAO table"

    def parse(self, pace: Callable[[], None] | None = None) -> RAOTable:
        """The table (:func:`~app.marine.vessel.load_rao_csv`, ``pace`` between small steps);
        :class:`CommandError` with its file, line and field when it does not parse."""
        try:
            return load_rao_csv("".join(self.parts), where=self.where, pace=pace)
        except BosunError as err:
            raise CommandError(str(err)) from None


@dataclass
class VesselChoice:
    """The scene's vessel: ``table`` (None: ``name`` is a named vessel) and ``label`` (one line, shown)."""

    name: str | None = None  # a named vessel (None: the default), or None with a table
    table: RAOTable | None = None
    label: str = field(default="")
    _parts: list[str] = field(default_factory=list)
    _upload: tuple[int, str] = (0, "")  # the upload in progress: its number of parts and label (fixed by part 0)

    def __post_init__(self) -> None:
        self.label = self.label or vessel_label(self.name)

    def rao(self, roll_damping: float = 0.15) -> RAOTable:
        return self.table if self.table is not None else vessel_rao(self.name, roll_damping)

    def take(
        self, vessel: str | None = None, csv: str | None = None, part: int = 0, parts: int = 1, label: str = ""
    ) -> bool | TableText:
        """One ``set_vessel`` message.  True when the vessel changed (a name); False while parts are still
        coming; the whole table (:class:`TableText`) with its last part: nothing changes until the scene has
        parsed it and calls :meth:`use`.  :class:`CommandError` (nothing changes) otherwise."""
        if (vessel is None) == (csv is None):
            raise CommandError("set_vessel: give a vessel name or an RAO table (csv), not both")
        if vessel is not None:
            if vessel not in VESSELS:
                raise CommandError(f"unknown vessel {vessel!r} (known: {', '.join(VESSELS)}; or send an RAO table)")
            try:
                vessel_rao(vessel)  # loads and checks before anything changes
            except BosunError as err:
                raise CommandError(str(err)) from None
            self.name, self.table, self.label, self._parts = vessel, None, vessel_label(vessel), []
            return True
        if not (1 <= parts <= MAX_PARTS and 0 <= part < parts):
            raise CommandError(f"set_vessel: part {part} of {parts} (1 to {MAX_PARTS} parts, numbered from 0)")
        if part == 0:
            self._parts, self._upload = [], (parts, label)
        if part != len(self._parts) or (parts, label) != self._upload:
            expected, self._parts = len(self._parts), []
            raise CommandError(
                f"set_vessel: part {part} of {parts} ({label or 'no label'}) is not the next of the table being sent "
                f"(expected part {expected} of {self._upload[0]}); send the table again"
            )
        self._parts.append(csv or "")
        if len(self._parts) < parts:
            return False
        whole, self._parts = TableText(tuple(self._parts), label), []
        return whole

    def use(self, table: RAOTable, text: TableText) -> None:
        """The table parsed from ``text`` is the vessel now."""
        self.name, self.table, self.label = None, table, f"RAO file {text.where}"
