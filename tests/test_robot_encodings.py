"""Issue 27, item 9: one reader for robot files.

A UTF-16 or Latin-1 robot file passed ``bosun check`` (lxml honoured its declaration) but not the
engine: ``bosun server --robot FILE`` died with a ``UnicodeDecodeError`` traceback and ``set_robot``
answered "internal error" (the engine read the file as UTF-8).  Now the checker, the engine's start,
``set_robot`` and the text the engine hands its clients go through one reader: what ``bosun check``
accepts, the engine loads; what it refuses, everybody refuses with the same line."""

import codecs
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from app.cli import main as cli_main
from app.engine.session import CommandError, Session
from app.errors import RobotXmlError
from app.models.registry import build_model
from app.models.xml import parse_robot_file, parse_robot_xml

ROOT = Path(__file__).resolve().parents[1]

# scara.xml with Latin-1 characters only (its α is not one): every encoding below can hold it
SCARA = (ROOT / "robots" / "scara.xml").read_text(encoding="utf-8").replace("α2", "alpha2").replace("–", "-")
DECLARED = '<?xml version="1.0" encoding="UTF-8"?>'
assert SCARA.startswith(DECLARED) and "±" in SCARA and "°" in SCARA

#: (declared encoding or None for no declaration, Python codec, byte-order mark)
ENCODINGS = [
    ("UTF-16", "utf-16-le", codecs.BOM_UTF16_LE),
    ("UTF-16", "utf-16-be", codecs.BOM_UTF16_BE),
    (None, "utf-16-le", codecs.BOM_UTF16_LE),  # a BOM and no declaration
    ("ISO-8859-1", "latin-1", b""),
    ("latin1", "latin-1", b""),
    ("windows-1252", "cp1252", b""),
    ("UTF-8", "utf-8", codecs.BOM_UTF8),
]
IDS = ["utf16le-bom", "utf16be-bom", "utf16-bom-only", "iso-8859-1", "latin1", "cp1252", "utf8-bom"]


def robot_file(folder: Path, declared: str | None, codec: str, bom: bytes, name: str = "arm.xml") -> Path:
    text = SCARA.replace(DECLARED, f'<?xml version="1.0" encoding="{declared}"?>' if declared else "", 1)
    path = folder / name
    path.write_bytes(bom + text.encode(codec))
    return path


def same_robot(model, reference) -> None:
    assert model.name == reference.name and model.joint_names == reference.joint_names
    np.testing.assert_array_equal(model.lower, reference.lower)
    np.testing.assert_array_equal(model.upper, reference.upper)
    q = np.random.default_rng(0).uniform(reference.lower, reference.upper, size=(8, reference.n_joints))
    np.testing.assert_allclose(model.position(q), reference.position(q))


@pytest.mark.parametrize("declared, codec, bom", ENCODINGS, ids=IDS)
def test_what_bosun_check_accepts_the_engine_loads(tmp_path, capsys, declared, codec, bom):
    path = robot_file(tmp_path, declared, codec, bom)
    assert cli_main(["check", str(path)]) == 0
    assert capsys.readouterr().out.startswith(f"ok       {path}: scara")
    reference = build_model(parse_robot_xml(SCARA, "scara"))
    # the engine's start (``bosun server --robot FILE``) and set_robot by path
    session = Session(robot_name=str(path), robots_dirs=(str(tmp_path),))
    assert session.robot_name == "scara"
    session.set_robot("scara")
    session.set_robot(str(path))
    assert session.robot_name == "scara" and session.robot.n_joints == 4
    # the text the engine keeps (the description sends it; studies and viewers parse it) is the same robot
    assert isinstance(session.robot_xml, str) and "±" in session.robot_xml and "°" in session.robot_xml
    same_robot(build_model(parse_robot_xml(session.robot_xml, "again")), reference)
    same_robot(session.robot, reference)
    # and a client that sends the file's text: as the reader gives it, and as bytes
    from app.models.xml import decode_robot_xml

    session.set_robot("arm.xml", xml=decode_robot_xml(path.read_bytes(), "arm.xml"))
    same_robot(build_model(parse_robot_xml(path.read_bytes(), "arm.xml")), reference)


def test_a_file_that_is_not_in_its_declared_encoding_is_refused_alike_by_checker_engine_and_set_robot(tmp_path, capsys):
    bad = tmp_path / "bad.xml"
    bad.write_bytes(SCARA.encode("latin-1"))  # says UTF-8, is Latin-1 ('±' at line 9)
    assert cli_main(["check", str(bad)]) == 2
    line = capsys.readouterr().out.strip()
    assert line.startswith(f"refused  {bad}:9: not valid UTF-8") and "\n" not in line, line
    with pytest.raises(RobotXmlError, match=r":9: not valid UTF-8 \(byte 0xb1\)"):
        parse_robot_file(bad)
    session = Session(robot_name="comau_smart5_3dof", robots_dirs=(str(tmp_path),))
    with pytest.raises(CommandError, match=rf"^{re.escape(tmp_path.name)}/bad\.xml:9: not valid UTF-8") as info:
        session.set_robot(str(bad))
    assert "internal" not in str(info.value) and "\n" not in str(info.value)
    assert session.robot_name == "comau_smart5_3dof"
    for text, words in [
        (SCARA.replace("UTF-8", "no-such-codec", 1), "unknown encoding 'no-such-codec'"),
        (SCARA.replace("UTF-8", "base64", 1), "unknown encoding 'base64'"),  # a Python codec, not a text encoding
        (SCARA.replace("UTF-8", "UTF-16", 1), "declares UTF-16 but"),  # a UTF-8 file labelled UTF-16
    ]:
        path = tmp_path / "x.xml"
        path.write_bytes(text.encode("utf-8"))
        with pytest.raises(RobotXmlError, match=words):
            parse_robot_file(path)
        with pytest.raises(CommandError, match=words):
            session.set_robot(str(path))


def test_load_robot_file_reads_once_and_returns_the_text_it_parsed(tmp_path):
    from app.models.registry import load_robot_file

    path = robot_file(tmp_path, "UTF-16", "utf-16-le", codecs.BOM_UTF16_LE)
    model, text = load_robot_file(str(path))
    assert model.name == "scara" and text.startswith('<?xml version="1.0" encoding="UTF-8"?>')
    assert text == SCARA  # decoded, the declaration now says what a str is sent as


@pytest.mark.slow
def test_bosun_server_starts_on_a_utf16_robot_file_and_refuses_a_broken_one_in_one_line(tmp_path):
    path = robot_file(tmp_path, "UTF-16", "utf-16-le", codecs.BOM_UTF16_LE)
    args = [sys.executable, "-m", "app", "server", "--bind", "tcp://127.0.0.1:0", "--rate", "100", "--duration", "0.5"]
    proc = subprocess.run([*args, "--robot", str(path)], capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert "Traceback" not in proc.stderr, proc.stderr
    assert proc.returncode == 0 and "bosun server: scara /" in proc.stdout, (proc.stdout, proc.stderr)
    bad = tmp_path / "bad.xml"
    bad.write_bytes(SCARA.encode("latin-1"))
    proc = subprocess.run([*args, "--robot", str(bad)], capture_output=True, text=True, timeout=300, cwd=ROOT)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr
    assert proc.stderr.count("\n") == 1 and "bad.xml:9: not valid UTF-8" in proc.stderr, proc.stderr
