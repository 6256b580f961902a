"""The documentation stays true to the code and stays a front door.

- Every command of ``vibrofeed.cli.COMMANDS`` has its section in docs/commands.md
  (a ``## `vibrofeed NAME` `` heading) and a row in the README's table of commands
  linking to that section; every option of its parser has its line in the section's
  option list (``- `-o DIR`, `--output DIR`: ...``).
- Every relative link and image in README.md and docs/*.md resolves to an existing
  file and, for ``#anchor``, to a heading of that page (GitHub's anchor rules).
- The README stays short (at most 260 lines) and its quick start has exactly the two
  bootstrap commands.

Each check is a function of a tree's root, so the tests also run it on a copy of the
documentation with a planted defect and see it fail.
"""

from __future__ import annotations

import argparse
import importlib
import re
import shutil
from pathlib import Path

import pytest

from helpers import REPO
from vibrofeed.cli import COMMANDS, build_parser

README_MAX_LINES = 260
QUICK_START = ["bash bootstrap.sh demo", "bash bootstrap.sh test"]
COMMANDS_PAGE = Path("docs") / "commands.md"


# -- reading Markdown ----------------------------------------------------------------------
def _outside_fences(text: str) -> list[tuple[str, bool]]:
    """Each line with whether it lies in a fenced code block (the fence lines count as in)."""
    out, fence = [], None
    for line in text.splitlines():
        marker = re.match(r"\s*(`{3,}|~{3,})", line)
        if fence is None and marker:
            fence = marker.group(1)
            out.append((line, True))
        elif fence is not None:
            out.append((line, True))
            if line.strip().startswith(fence) and not line.strip().strip(fence[0]):
                fence = None
        else:
            out.append((line, False))
    return out


def _prose(text: str) -> str:
    """The text without fenced blocks and inline code spans (no links live in them)."""
    lines = [line for line, fenced in _outside_fences(text) if not fenced]
    return re.sub(r"(`+)(?!`).*?(?<!`)\1(?!`)", "code", "\n".join(lines))


def slug(heading: str) -> str:
    """GitHub's anchor of a heading: its rendered text lower-cased, punctuation other than
    hyphens and underscores dropped, spaces turned into hyphens."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # a link renders as its text
    text = text.replace("`", "").strip().lower()
    return re.sub(r"[^\w\- ]", "", text).replace(" ", "-")


def headings(text: str) -> list[tuple[int, str]]:
    """(level, text) of every ATX heading outside code blocks."""
    out = []
    for line, fenced in _outside_fences(text):
        m = re.match(r"(#{1,6})\s+(.*?)\s*#*\s*$", line)
        if m and not fenced:
            out.append((len(m.group(1)), m.group(2)))
    return out


def anchors(text: str) -> set[str]:
    """Every heading's anchor; a repeated one gets -1, -2, ... as GitHub numbers them."""
    seen: dict[str, int] = {}
    out = set()
    for _, heading in headings(text):
        base = slug(heading)
        n = seen.get(base, 0)
        seen[base] = n + 1
        out.add(base if n == 0 else f"{base}-{n}")
    return out


def sections(text: str, level: int) -> dict[str, str]:
    """Heading text -> the text under it, up to the next heading of this level or higher."""
    out: dict[str, str] = {}
    current = None
    for line, fenced in _outside_fences(text):
        m = None if fenced else re.match(r"(#{1,6})\s+(.*?)\s*$", line)
        if m and len(m.group(1)) <= level:
            current = m.group(2) if len(m.group(1)) == level else None
            if current is not None:
                out[current] = ""
            continue
        if current is not None:
            out[current] += line + "\n"
    return out


def links(text: str) -> list[str]:
    """The targets of every link and image in the prose."""
    return re.findall(r"!?\[[^\]]*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)", _prose(text))


def mentions(text: str, option: str) -> bool:
    """Whether ``option`` appears as a whole word (``--gap`` is not in ``--gap-distance``)."""
    return re.search(rf"(?<![\w-]){re.escape(option)}(?![\w-])", text) is not None


# -- the checks ----------------------------------------------------------------------------
def pages(root: Path) -> list[Path]:
    return [root / "README.md", *sorted((root / "docs").glob("*.md"))]


def command_sections(root: Path) -> dict[str, str]:
    """Command name -> its section of docs/commands.md."""
    found = sections((root / COMMANDS_PAGE).read_text(), level=2)
    return {m.group(1): body for heading, body in found.items()
            if (m := re.fullmatch(r"`vibrofeed ([\w-]+)`", heading))}


def undocumented_commands(root: Path) -> list[str]:
    """Commands without a section in docs/commands.md or a row in the README's table."""
    documented = command_sections(root)
    readme = (root / "README.md").read_text()
    problems = []
    for name in COMMANDS:
        if name not in documented:
            problems.append(f"{name}: no section `vibrofeed {name}` in {COMMANDS_PAGE}")
        row = (rf"^\|\s*\[`vibrofeed {re.escape(name)}`\]\(docs/commands\.md"
               rf"#{re.escape(slug(f'`vibrofeed {name}`'))}\)\s*\|")
        if not re.search(row, readme, re.MULTILINE):
            problems.append(f"{name}: no row in the README's table of commands")
    return problems


def command_parsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()  # every command's arguments
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def option_list(section: str) -> str:
    """The heads of a section's option lines: ``- `-o DIR`, `--output DIR`: ...`` gives
    ``` `-o DIR`, `--output DIR` ```."""
    return "\n".join(m.group(1) for line in section.splitlines()
                     if (m := re.match(r"- (`[^`]+`(?:,\s*`[^`]+`)*)", line)))


def undocumented_options(root: Path) -> list[str]:
    """Options (and positional arguments) of each command without their line in its
    section's option list (a mention in the synopsis or the prose is not enough)."""
    documented = command_sections(root)
    problems = []
    for name, parser in command_parsers().items():
        body = option_list(documented.get(name, ""))
        for action in parser._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            words = action.option_strings or [action.metavar or action.dest]
            problems += [f"{name}: {word} is not in its section of {COMMANDS_PAGE}"
                         for word in words if not mentions(body, word)]
    return problems


def broken_links(root: Path) -> list[str]:
    """Relative links and images that point at no file, or at no heading of a page."""
    problems = []
    for page in pages(root):
        for target in links(page.read_text()):
            if re.match(r"[A-Za-z][A-Za-z0-9+.-]*:", target):  # https:, mailto:: not ours
                continue
            path, _, anchor = target.partition("#")
            dest = page.parent / path if path else page
            where = f"{page.relative_to(root)}: {target}"
            if not dest.exists():
                problems.append(f"{where}: no such file")
            elif anchor and (dest.suffix != ".md" or anchor not in anchors(dest.read_text())):
                problems.append(f"{where}: no heading with this anchor")
    return problems


def front_door_problems(root: Path) -> list[str]:
    """The README's length and its quick start's commands."""
    readme = (root / "README.md").read_text()
    problems = []
    n = len(readme.splitlines())
    if n > README_MAX_LINES:
        problems.append(f"README.md has {n} lines (at most {README_MAX_LINES})")
    quick = sections(readme, level=2).get("Quick start")
    if quick is None:
        return problems + ["README.md has no Quick start section"]
    commands = [line.split("#")[0].strip() for line, fenced in _outside_fences(quick)
                if fenced and not re.match(r"\s*(`{3,}|~{3,})", line)]
    commands = [c for c in commands if c]
    if commands != QUICK_START:
        problems.append(f"the quick start's commands are {commands}, not {QUICK_START}")
    return problems


# -- on the repository ---------------------------------------------------------------------
def test_every_command_module_has_the_command_shape():
    for name, (module_name, help_text) in COMMANDS.items():
        module = importlib.import_module(module_name)
        assert callable(module.add_arguments) and callable(module.run), name
        assert module.DESCRIPTION and help_text, name


def test_every_command_has_its_section_and_its_readme_row():
    assert not undocumented_commands(REPO)


def test_every_option_of_every_command_is_documented():
    assert set(command_parsers()) == set(COMMANDS)
    assert not undocumented_options(REPO)


def test_every_relative_link_and_image_resolves():
    assert not broken_links(REPO)


def test_the_readme_is_a_front_door():
    assert not front_door_problems(REPO)


# -- the checks fail on planted defects ----------------------------------------------------
@pytest.fixture
def tree(tmp_path):
    """A copy of README.md and docs/ beside links to everything else of the repository."""
    for entry in REPO.iterdir():
        if entry.name not in ("README.md", "docs"):
            (tmp_path / entry.name).symlink_to(entry)
    shutil.copy(REPO / "README.md", tmp_path / "README.md")
    shutil.copytree(REPO / "docs", tmp_path / "docs")
    return tmp_path


def _edit(path: Path, old: str, new: str, count: int = 1) -> None:
    text = path.read_text()
    assert old in text, f"the planted defect needs {old!r} in {path.name}"
    path.write_text(text.replace(old, new, count))


def test_a_missing_section_or_readme_row_is_found(tree):
    assert not undocumented_commands(tree)
    _edit(tree / COMMANDS_PAGE, "## `vibrofeed export`", "## Exporting")
    _edit(tree / "README.md", "| [`vibrofeed sweep-report`]", "| [`sweep-report`]")
    assert undocumented_commands(tree) == [
        "sweep-report: no row in the README's table of commands",
        f"export: no section `vibrofeed export` in {COMMANDS_PAGE}"]


def test_a_missing_option_is_found(tree):
    _edit(tree / COMMANDS_PAGE, "- `--no-model`: skip the single-part model comparison.\n", "")
    assert undocumented_options(tree) == [f"feedrate: --no-model is not in its section of {COMMANDS_PAGE}"]
    # its synopsis in the section's code block still names it: that is not enough
    assert mentions(command_sections(tree)["feedrate"], "--no-model")
    _edit(tree / COMMANDS_PAGE, "- `--fps FPS`: movie: frames per second (default 25).\n", "")
    assert "render: --fps is not in its section" in " ".join(undocumented_options(tree))


def test_an_option_is_matched_as_a_whole_word():
    assert mentions("- `--gap S`: doubles", "--gap")
    assert not mentions("- `--gap-distance M`: doubles", "--gap")
    assert not mentions("`--every-other`", "--every")
    assert mentions("`-p NAME=VALUE`", "-p") and not mentions("`--plot DIR`", "-p")


def test_broken_links_images_and_anchors_are_found(tree):
    readme = tree / "README.md"
    readme.write_text(readme.read_text() + "\n[gone](docs/nowhere.md) ![lost](docs/lost.png) "
                      "[wrong](docs/commands.md#vibrofeed-teleport) [self](#no-such-section)\n"
                      "`[in code](docs/nowhere.md)`\n```\n[in a block](docs/nowhere.md)\n```\n")
    assert broken_links(tree) == [
        "README.md: docs/nowhere.md: no such file",
        "README.md: docs/lost.png: no such file",
        "README.md: docs/commands.md#vibrofeed-teleport: no heading with this anchor",
        "README.md: #no-such-section: no heading with this anchor",
    ]


def test_a_renamed_heading_breaks_the_links_to_it(tree):
    _edit(tree / "docs" / "validation.md", "## Measured trials", "## Trials measured")
    problems = broken_links(tree)
    assert problems and all("validation.md#measured-trials" in p for p in problems)


def test_anchors_follow_githubs_rules():
    text = ("# Studies: what the bulk feeder says\n## `vibrofeed sweep-report`\n"
            "## Mutation testing (2026-11-24, issue 13)\n## Run\n## Run\n"
            "## Shared blocks (`decks/include/`)\n"
            "```\n## not a heading\n```\n")
    assert anchors(text) == {"studies-what-the-bulk-feeder-says", "vibrofeed-sweep-report",
                             "mutation-testing-2026-11-24-issue-13", "run", "run-1",
                             "shared-blocks-decksinclude"}


def test_a_long_readme_or_another_quick_start_command_is_found(tree):
    readme = tree / "README.md"
    assert not front_door_problems(tree)
    _edit(readme, "bash bootstrap.sh test ", "bash bootstrap.sh validate ")
    assert "not ['bash bootstrap.sh demo', 'bash bootstrap.sh test']" in front_door_problems(tree)[0]
    _edit(readme, "bash bootstrap.sh validate ", "bash bootstrap.sh test \nbash bootstrap.sh validate ")
    assert len(front_door_problems(tree)) == 1
    _edit(readme, "\nbash bootstrap.sh validate ", " ")
    assert not front_door_problems(tree)
    readme.write_text(readme.read_text() + "line\n" * README_MAX_LINES)
    assert front_door_problems(tree)[0].startswith("README.md has ")
