"""Deck files: tunables with units, commands with their file and line (includes
followed), lookup by name, files that are not decks refused."""

import pytest

from helpers import DECKS, vibrofeed
from vibrofeed.decks import Deck, DeckError, available, split_commands, strip_comment
from vibrofeed.errors import InputError

# (the part's size is deck-specific: single_part's radius, bulk_feeder's part_size)
VOCABULARY = ["density", "youngs", "poisson", "restitution", "t_end", "output_dt", "dt", "seed"]
# ... and every deck with a vibrating surface (all but the pull-off test) also:
VIBRATION = ["freq", "amp_t", "amp_n", "phase", "incline", "mu"]
# ... where the bowl's track climbs at its helix angle instead of an incline
SLOPE = {"bowl_feeder": "helix_angle"}


def test_every_deck_declares_the_shared_vocabulary_with_units():
    assert {"single_part", "bulk_feeder", "bowl_feeder", "pulloff"} <= set(available())
    for name in available():
        deck = Deck.find(name)
        wanted = VOCABULARY + ([SLOPE.get(name, v) if v == "incline" else v for v in VIBRATION]
                               if name != "pulloff" else [])
        for var in wanted:
            assert var in deck.variables, f"{name} lacks {var}"
            assert deck.variables[var].unit, f"{name}: {var} has no [unit]"
            assert deck.variables[var].description, f"{name}: {var} has no description"


def test_every_deck_starts_with_a_header_and_says_how_to_run():
    for name in available():
        deck = Deck.find(name)
        assert deck.header, name
        assert "liggghts -in decks/" in deck.header, f"{name}: header must show how to run by hand"
        assert "Units" in deck.header, f"{name}: header must state units"


def test_single_part_variables_parsed(tmp_path):
    deck = Deck(DECKS / "single_part.liggghts")
    freq = deck.variables["freq"]
    assert (freq.unit, freq.default) == ("Hz", "50")
    assert "vibration frequency" in freq.description
    assert deck.variables["rolling"].default == "0"
    for name in ("n_steps", "dt_used", "t_contact", "ss_x0"):
        assert name in deck.constants
    for name in ("sin_x", "tx", "ss_x", "cp_vx"):  # follow `time`, directly or not
        assert name in deck.formulas and name not in deck.constants


def test_constants_follow_references(tmp_path):
    p = tmp_path / "c.liggghts"
    p.write_text("variable a index 1 # [m] a\n"
                 "variable b equal 2*v_a\n"
                 "variable c equal v_b+time\n"
                 "variable d equal v_c*2\n"
                 "variable e equal v_b*3  # time in a comment is not a reference\n")
    assert Deck(p).constants == ["b", "e"]


def test_split_commands_joins_continuations_and_strips_comments():
    text = 'a 1 # c\n\n# only comment\nb 2 &\n   3 &\n 4\nprint "x # not a comment"\n'
    cmds = split_commands(text)
    assert [(c.line, c.text) for c in cmds] == [(1, "a 1"), (4, "b 2 3 4"),
                                                (7, 'print "x # not a comment"')]
    assert strip_comment("x 'a#b' # c") == "x 'a#b' "


def test_continuation_joins_as_liggghts_does():
    # No space is added: a formula wrapped with '&' and an unindented next line
    # stays one word, as LIGGGHTS reads it.
    cmds = split_commands("variable x equal &\n(1+2)&\n*3   # c\nvariable y equal 1\n")
    assert [(c.line, c.text) for c in cmds] == [(1, "variable x equal (1+2)*3"), (4, "variable y equal 1")]


def write_deck_with_include(tmp_path, include="${deck_dir}/include/block.liggghts"):
    (tmp_path / "include").mkdir()
    (tmp_path / "include" / "block.liggghts").write_text(
        "# a shared block\n"                              # 1
        "variable b equal &\n"                            # 2
        "2*v_a\n"
        "variable c equal v_b+time\n"                     # 4
        "fix bad all nope\n")                             # 5
    deck = tmp_path / "d.liggghts"
    deck.write_text("# header\n"                          # 1
                    "variable a index 1 # [m] a\n"         # 2
                    f"include {include}\n"                 # 3
                    "variable e equal v_b*3\n"             # 4
                    "run 1\n")                             # 5
    return deck


def test_includes_are_followed(tmp_path):
    deck = Deck(write_deck_with_include(tmp_path))
    block = (tmp_path / "include" / "block.liggghts").resolve()
    where = [(c.file.name, c.line, c.text) for c in deck.commands]
    assert where == [("d.liggghts", 2, "variable a index 1"),
                     ("d.liggghts", 3, "include ${deck_dir}/include/block.liggghts"),
                     ("block.liggghts", 2, "variable b equal 2*v_a"),
                     ("block.liggghts", 4, "variable c equal v_b+time"),
                     ("block.liggghts", 5, "fix bad all nope"),
                     ("d.liggghts", 4, "variable e equal v_b*3"),
                     ("d.liggghts", 5, "run 1")]
    assert deck.commands[2].file == block
    assert list(deck.sources) == ["d.liggghts", "include/block.liggghts"]
    assert deck.sources["include/block.liggghts"] == block.read_text()
    # formulas of an included file count: b is constant, c follows time
    assert deck.constants == ["b", "e"]
    assert deck.command_at(5, "include/block.liggghts").text == "fix bad all nope"
    assert deck.command_at(5).text == "run 1"
    assert list(deck.tunables) == ["a"]


def test_absolute_include_path(tmp_path):
    deck = Deck(write_deck_with_include(tmp_path, include=tmp_path / "include" / "block.liggghts"))
    assert "variable c equal v_b+time" in [c.text for c in deck.commands]


@pytest.mark.parametrize("include, fragment", [
    ("${deck_dir}/include/missing.liggghts", "included file ${deck_dir}/include/missing.liggghts not found"),
    ("include/block.liggghts", "start the path with ${deck_dir}/"),
    ("${deck_dir}/include/${name}.liggghts", "only ${deck_dir} is resolved"),
])
def test_bad_include_is_a_deck_error_naming_it(tmp_path, include, fragment):
    with pytest.raises(DeckError, match="d.liggghts:3: ") as info:
        Deck(write_deck_with_include(tmp_path, include=include))
    assert fragment in str(info.value)


def test_include_cycle_is_refused(tmp_path):
    deck = write_deck_with_include(tmp_path)
    (tmp_path / "include" / "block.liggghts").write_text("include ${deck_dir}/d.liggghts\n")
    with pytest.raises(DeckError, match="includes itself"):
        Deck(deck)


def test_binary_deck_or_include_is_refused(tmp_path):
    binary = tmp_path / "b.liggghts"
    binary.write_bytes(b"\x7fELF\x02\x01\x01\x00\x00\xff\xfe")
    with pytest.raises(DeckError, match=r"b.liggghts is not a text deck"):
        Deck(binary)
    nul = tmp_path / "n.liggghts"
    nul.write_bytes(b"variable a index 1 # [m] a\n\x00\x00")
    with pytest.raises(DeckError, match="is not a text deck"):
        Deck(nul)
    (tmp_path / "inc").mkdir()
    deck = write_deck_with_include(tmp_path / "inc")
    (tmp_path / "inc" / "include" / "block.liggghts").write_bytes(b"\xff\xfe\x00binary")
    with pytest.raises(DeckError, match=r"block.liggghts is not a text file"):
        Deck(deck)


def test_binary_deck_is_one_line_on_the_command_line(tmp_path):
    proc = vibrofeed("run", "/bin/ls", "-o", tmp_path / "r.h5")
    assert proc.returncode == InputError.exit_code
    assert proc.stderr.startswith("vibrofeed: error: ") and "/bin/ls is not a text deck" in proc.stderr
    assert proc.stderr.count("\n") == 1 and "Traceback" not in proc.stderr
    assert list(tmp_path.iterdir()) == []


def test_shared_blocks_are_included_but_not_decks():
    deck = Deck.find("single_part")
    blocks = sorted(p.relative_to(DECKS).as_posix() for p in (DECKS / "include").glob("*.liggghts"))
    used = set(deck.sources) | set(Deck.find("bulk_feeder").sources)
    assert blocks and set(blocks) <= used  # every block is used by a deck
    assert not any(name.startswith("include") for name in available())
    for block in blocks:  # each says what it expects and defines
        text = (DECKS / block).read_text()
        assert text.startswith("# vibrofeed include:") and "Expects" in text and "Defines" in text
    # the contract variables and the run constants are seen through the includes
    for name in ("omega", "period", "lead", "cp_x0", "thermo_every"):
        assert name in deck.constants
    files = {c.file.name for c in deck.commands}
    assert {"single_part.liggghts", "surface_motion.liggghts", "contact.liggghts",
            "move_mesh.liggghts"} <= files


def test_no_deck_line_is_a_long_formula():
    # Long formulas are wrapped with '&' (see include/surface_motion.liggghts).
    for path in sorted(DECKS.rglob("*.liggghts")):
        for number, line in enumerate(path.read_text().splitlines(), start=1):
            assert len(line) <= 120, f"{path.name}:{number} is {len(line)} characters"


def test_header_drops_one_mark_and_one_space_and_title_is_the_description(tmp_path):
    p = tmp_path / "h.liggghts"
    p.write_text("# Deck h\n#\n# Moves a part. Then stops.\n#   indented\n#tight\n"
                 "variable a index 1 # [m] a\n")
    deck = Deck(p)
    # '#' and one space go; more indent and an unspaced first letter stay
    assert deck.header == "Deck h\n\nMoves a part. Then stops.\n  indented\ntight"
    assert deck.title == "Moves a part"  # the second paragraph's first sentence
    p.write_text("# Only a description. More.\nvariable a index 1 # [m] a\n")
    assert Deck(p).title == "Only a description"  # one paragraph: that one


def test_find_by_name_takes_a_bare_name_only(tmp_path):
    assert Deck.find("single_part").name == "single_part"
    assert Deck.find("single_part.liggghts").name == "single_part"
    with pytest.raises(DeckError, match=r"no deck no_such_deck \(not a file; decks available by name: .*"
                                        r"single_part"):
        Deck.find("no_such_deck")
    # a path in another folder is not a name: no fallback to the project's deck of that name
    elsewhere = tmp_path / "single_part"
    with pytest.raises(DeckError, match="no deck .*single_part"):
        Deck.find(elsewhere)
