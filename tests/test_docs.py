"""The documentation site (issue 28, items 3-4): generated pages equal their generators, every command and
option is in the CLI reference, every schema element in the robot file reference, the nav lists every page,
and the README stays a front page.  CI builds the site itself with ``mkdocs build --strict`` (.ci/run)."""

from __future__ import annotations

import argparse
import re
from pathlib import Path

import pytest
from lxml import etree

from app.cli import _subparsers, build_parser, cli_reference_markdown
from app.models.schema_doc import XS, schema_markdown
from app.resources import robot_library

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _parser():
    parser = build_parser()
    if "gui" not in _subparsers(parser):
        pytest.skip("the GUI's plug-in commands are not registered here (bosun not installed with its entry points)")
    return parser


def _walk(parser: argparse.ArgumentParser):
    yield parser
    for child in _subparsers(parser).values():
        yield from _walk(child)


def test_cli_reference_page_is_current():
    page = (DOCS / "cli.md").read_text(encoding="utf-8")
    assert page == cli_reference_markdown(_parser()), "docs/cli.md is stale: bosun cli-reference > docs/cli.md"


def test_every_command_and_option_is_in_the_cli_reference():
    page = (DOCS / "cli.md").read_text(encoding="utf-8")
    headings = set(re.findall(r"^#+ `(bosun[^`]*)`$", page, flags=re.M))
    parsers = list(_walk(_parser()))
    assert len(parsers) > 30  # every command and subcommand, the GUI's too
    for p in parsers:
        assert p.prog in headings, f"{p.prog} has no section in docs/cli.md"
        section = page.split(f"`{p.prog}`\n", 1)[1].split("\n#", 1)[0]
        for action in p._actions:
            if action.help == argparse.SUPPRESS:  # hidden on purpose (test hooks such as gui --quit-after)
                continue
            for option in action.option_strings:
                assert re.search(rf"`[^`]*{re.escape(option)}\b", section), f"{p.prog} {option} missing in docs/cli.md"


def test_robot_file_reference_is_current():
    page = (DOCS / "robot-files.md").read_text(encoding="utf-8")
    assert page == schema_markdown(), (
        "docs/robot-files.md is stale: bosun robots --schema-markdown > docs/robot-files.md"
    )


def test_robot_file_reference_names_every_element_and_attribute_of_the_schema():
    page = (DOCS / "robot-files.md").read_text(encoding="utf-8")
    schema = etree.parse(str(robot_library() / "robot.xsd")).getroot()
    for el in schema.iter(f"{XS}element"):
        assert f"`<{el.get('name')}>`" in page, el.get("name")
    for attr in schema.iter(f"{XS}attribute"):
        assert f"| `{attr.get('name')}` |" in page, attr.get("name")


def test_the_generator_reads_a_changed_schema(tmp_path):
    xsd = (robot_library() / "robot.xsd").read_text(encoding="utf-8")
    changed = tmp_path / "robot.xsd"
    changed.write_text(xsd.replace('name="rot_x"', 'name="rot_y"'), encoding="utf-8")
    text = schema_markdown(changed)
    assert "| `rot_y` |" in text and "| `rot_x` |" not in text


def test_the_nav_lists_every_page_and_only_pages_that_exist():
    config = (ROOT / "mkdocs.yml").read_text(encoding="utf-8")
    nav = re.findall(r"^\s*- [^:]+: (\S+\.md)$", config, flags=re.M)
    pages = sorted(p.name for p in DOCS.glob("*.md"))
    assert sorted(nav) == pages
    assert "theme:\n  name: material" in config


def test_the_protocol_page_shows_the_version_the_engine_speaks():
    from app.net.messages import PROTOCOL_VERSION

    page = (DOCS / "protocol.md").read_text(encoding="utf-8")
    assert f'{{"v": {PROTOCOL_VERSION}, "type"' in page
    assert f"# Bosun engine protocol, version {PROTOCOL_VERSION}" in page


def test_the_readme_is_a_front_page_whose_links_resolve():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(readme.splitlines()) <= 150
    links = re.findall(r"\]\(([^)#\s]+)", readme)
    assert "docs/getting-started.md" in links and "docs/cli.md" in links
    for link in links:
        assert (ROOT / link).exists(), link
