"""Write the robot-file fuzz corpus of tests/test_robot_fuzz.py into tests/data/robot_fuzz/.

Deterministic (seeded): running it again writes the same files.  Each file is a library robot
with one mutation from a class the issue-13 fuzzing campaign found to kill or fool the loader:

  entity   entity or character references, a DOCTYPE
  number   numbers the schema takes as xs:double and float() does not (1e, 1.e, INF, NaN, …)
  huge     values past the physical bounds (1e154, 1e308, 1e30)
  tiny     speeds and accelerations that underflow (5e-324 deg/s is 0 rad/s)
  joints   serial chains with 13–30 joints (22 stalled the loop 8.6 s; 26 exhausted memory)
  stewart  leg ranges that miss the neutral pose or a pose limit, non-finite or swapped legs
  coupling coupling factors of 1e3 … 1e308 (a non-finite Jacobian)
  bytes    truncations, flipped bytes, deleted attributes and elements
  valid    numbers scaled by a few percent: most of these must still load

Usage:  python scripts/make_robot_fuzz.py [OUT_DIR]
"""

from __future__ import annotations

import random
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SOURCES = ["scara", "kuka_youbot", "comau_smart5_6dof", "offshore_crane", "tac_delta_head", "em8000", "em1500"]
NUMBER_ATTR = re.compile(r'(\b[a-z_]+)="([-+0-9.eE ]+)"')

BAD_NUMBERS = ["1e", "1E", "1e+", "1.e", "INF", "-INF", "NaN", "0x10", "1_0", "--1", "1e999", "-1e999", ". ", "1,5"]
HUGE = ["1e154", "1e308", "-1e308", "1e30", "12000", "-5e5"]
TINY = ["5e-324", "1e-300", "1e-9", "4.9e-324"]


def numeric_spans(text: str) -> list[re.Match]:
    return [m for m in NUMBER_ATTR.finditer(text) if m.group(1) not in ("index", "version", "sign", "name")]


def replace_value(text: str, m: re.Match, value: str) -> str:
    return text[: m.start(2)] + value + text[m.end(2) :]


def mutate(kind: str, name: str, text: str, rng: random.Random) -> str | None:
    spans = numeric_spans(text)
    if kind == "entity":
        choice = rng.randrange(5)
        if choice == 0:
            return text.replace("</description>", " &amp; more</description>", 1)
        if choice == 1:
            return text.replace("</source>", " &#65;&lt;</source>", 1)
        if choice == 2:
            return text.replace("</description>", " &undefined;</description>", 1)
        if choice == 3:
            head, sep, rest = text.partition("?>")
            return (
                head
                + sep
                + '\n<!DOCTYPE robot [<!ENTITY e "x">]>'
                + rest.replace("</description>", "&e;</description>", 1)
            )
        return text.replace(
            '<?xml version="1.0" encoding="UTF-8"?>', '<?xml version="1.0"?>\n<!DOCTYPE robot SYSTEM "/etc/passwd">', 1
        )
    if kind == "number":
        return replace_value(text, rng.choice(spans), rng.choice(BAD_NUMBERS))
    if kind == "huge":
        return replace_value(text, rng.choice(spans), rng.choice(HUGE))
    if kind == "tiny":
        hits = [m for m in spans if m.group(1) in ("speed", "accel", "time_constant", "gain")]
        return replace_value(text, rng.choice(hits), rng.choice(TINY)) if hits else None
    if kind == "joints":
        links = re.findall(r"    <link .*?</link>\n", text, flags=re.S)
        movers = [x for x in links if 'joint="fixed"' not in x]
        if not movers:
            return None
        n = rng.randrange(13, 31)
        extra = []
        for i in range(n - len(movers)):
            block = re.sub(r'<joint name="([^"]+)"', rf'<joint name="\1_x{i}"', rng.choice(movers))
            extra.append(re.sub(r"<coupling[^>]*/>", "", block))
        cut = text.rindex("</link>") + len("</link>\n")
        return text[:cut] + "".join(extra) + text[cut:]
    if kind == "stewart":
        if "<stewart>" not in text:
            return None
        legs = re.search(r'<legs min_length="([^"]+)" max_length="([^"]+)"', text)
        lo, hi = float(legs.group(1)), float(legs.group(2))
        choice = rng.randrange(6)
        if choice == 0:  # stroke above the neutral pose
            new = f'<legs min_length="{hi * 1.2:g}" max_length="{hi * 1.5:g}"'
        elif choice == 1:  # stroke too short for a pose limit
            new = f'<legs min_length="{lo:g}" max_length="{lo + 0.25 * (hi - lo):g}"'
        elif choice == 2:
            new = f'<legs min_length="{rng.choice(["NaN", "INF", "0", "-1"])}" max_length="{hi:g}"'
        elif choice == 3:
            new = f'<legs min_length="{hi:g}" max_length="{lo:g}"'
        elif choice == 4:  # a pose limit no leg reaches
            return re.sub(r'(<dof name="heave" min="[^"]+" max=")[^"]+"', r'\g<1>25"', text, count=1)
        else:  # a joint point moved far off
            return re.sub(r'<point xyz="[^"]+"', '<point xyz="40 0 0"', text, count=1)
        return text[: legs.start()] + new + text[legs.end() :]
    if kind == "coupling":
        if "<coupling" in text:
            return re.sub(r'factor="[^"]+"', f'factor="{rng.choice(["1e308", "1e3", "-1e200", "150"])}"', text, count=1)
        return _couple_second(text, rng) if "<serial>" in text else None
    if kind == "bytes":
        data = bytearray(text.encode())
        choice = rng.randrange(4)
        if choice == 0:
            return data[: rng.randrange(1, len(data))].decode(errors="ignore")
        if choice == 1:
            for _ in range(rng.randrange(1, 6)):
                i = rng.randrange(len(data))
                data[i] = rng.choice(b'<>&"=/ \n\x00\xff0123456789eE.-')
            return data.decode(errors="replace")
        if choice == 2:
            m = rng.choice(spans)
            return text[: m.start(1)] + text[m.end(2) + 1 :]
        elements = list(re.finditer(r"<(\w+)[^<>]*/>", text))
        m = rng.choice(elements)
        return text[: m.start()] + text[m.end() :]
    if kind == "valid":
        out = text
        for m in reversed(numeric_spans(text)):
            vals = m.group(2).split()
            if rng.random() < 0.3:
                scaled = " ".join(f"{float(v) * rng.uniform(0.97, 1.03):.6g}" for v in vals)
                out = out[: m.start(2)] + scaled + out[m.end(2) :]
        return out
    raise ValueError(kind)


def _couple_second(text: str, rng: random.Random) -> str | None:
    """Couple the second joint to the first with a huge factor."""
    names = re.findall(r'<joint name="([^"]+)"', text)
    if len(names) < 2:
        return None
    i = text.index(f'<joint name="{names[1]}"')
    j = text.index("</limits>", i) if "</limits>" in text[i:] else text.index("/>", text.index("<limits", i)) + 2
    factor = rng.choice(["1e308", "1e3", "-1e200", "150"])
    return text[:j] + f'<coupling joint="{names[0]}" factor="{factor}"/>' + text[j:]


PLAN = {
    "entity": 30,
    "number": 50,
    "huge": 40,
    "tiny": 25,
    "joints": 25,
    "stewart": 30,
    "coupling": 15,
    "bytes": 60,
    "valid": 40,
}


def main(out: Path) -> int:
    rng = random.Random(13)
    out.mkdir(parents=True, exist_ok=True)
    for old in out.glob("*.xml"):
        old.unlink()
    texts = {name: (ROOT / "robots" / f"{name}.xml").read_text(encoding="utf-8") for name in SOURCES}
    count = 0
    for kind, n in PLAN.items():
        made = 0
        tries = 0
        while made < n and tries < 50 * n:
            tries += 1
            name = rng.choice(SOURCES)
            text = mutate(kind, name, texts[name], rng)
            if text is None or text == texts[name]:
                continue
            (out / f"{kind}_{made:03d}_{name}.xml").write_text(text, encoding="utf-8", errors="replace")
            made += 1
        count += made
    print(f"{count} files in {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "tests" / "data" / "robot_fuzz"))
