"""LIGGGHTS error messages and the deck line they come from, read off logs."""

from vibrofeed.decks import Deck
from vibrofeed.engine.log import failed_command, find_error
from vibrofeed.errors import EngineError

MESH_ERROR = (  # as LIGGGHTS prints it, the trailing space of its first line included
    "Setting up run at Sun Nov 22 06:20:32 2026\n"
    "\n"
    "ERROR: Mesh (id plate): All 2 mesh elements have been lost / left the domain. \n"
    "Please use 'boundary m m m' or scale/translate/rotate the mesh or change its dynamics\n"
    "FYI: center of mass of mesh including scale/tranlate/rotate is 0.000000 / 0.000000 / 0.000000\n"
    "     simulation box x from -0.050000 to 0.050000 y  from -0.005000 to 0.005000 "
    "z from -0.002000 to 0.010000\n"
    "     (gives indication about changes in scale/tranlate/rotate necessary to make simulation run)\n"
    " (./src/multi_node_mesh_parallel_I.h:605)\n"
)


def test_single_line_error():
    err = find_error('thermo 10\nERROR: Invalid fix style: "gravityy" (./src/modify.cpp:850)\n')
    assert err.message == 'Invalid fix style: "gravityy"'
    assert err.proc is None and err.line_index == 1


def test_multi_line_error_is_joined_and_source_location_dropped():
    err = find_error(MESH_ERROR)
    assert err.message.startswith("Mesh (id plate): All 2 mesh elements have been lost")
    assert "boundary m m m" in err.message and "multi_node_mesh" not in err.message
    assert "\n" not in err.message


def test_error_on_one_proc():
    err = find_error("x\nERROR on proc 1: Particle lost (../src/fix_x.cpp:12)\n")
    assert err.proc == 1 and err.message == "Particle lost"


def test_no_error():
    assert find_error("LIGGGHTS (Version 3.8.0)\nLoop time of 1 on 1 procs\n") is None


def test_failed_command_is_the_last_deck_command_echoed(tmp_path):
    deck_path = tmp_path / "d.liggghts"
    deck_path.write_text(
        "# header\n"
        "variable freq index 50 # [Hz] f\n"             # 2
        "units si\n"                                    # 3
        "fix walls all wall/gran model hertz &\n"       # 4
        "    tangential history   # comment\n"
        "fix bad all nope ${freq}\n"                    # 6
        "run 10\n")                                     # 7
    log = ("LIGGGHTS (Version)\n"
           "variable freq index 50 # [Hz] f\n"
           "units si\n"
           "fix walls all wall/gran model hertz     tangential history   # comment\n"
           "fix bad all nope ${freq}\n"
           "fix bad all nope 50\n"  # LIGGGHTS echoes the substituted line too
           'ERROR: Invalid fix style: "nope" (./src/modify.cpp:850)\n')
    deck = Deck(deck_path)
    err = find_error(log)
    cmd = failed_command(log, deck, before=err.line_index)
    assert cmd.line == 6 and cmd.text == "fix bad all nope ${freq}"
    # the continuation line was matched too, so an error there points at line 4
    cmd = failed_command(log, deck, before=4)
    assert cmd.line == 4


def test_engine_error_reads_as_one_line():
    e = EngineError('Invalid fix style: "nope"', deck="d.liggghts", line=6,
                    command="fix bad all nope ${freq}", phase="deck")
    assert str(e) == 'LIGGGHTS error: Invalid fix style: "nope" at d.liggghts:6: fix bad all nope ${freq}'
    e = EngineError("Lost atoms", phase="run", step=100, time=1e-4)
    assert "during the run" in str(e) and "step 100" in str(e) and "\n" not in str(e)


def test_failed_command_in_an_included_file(tmp_path):
    (tmp_path / "include").mkdir()
    block = tmp_path / "include" / "block.liggghts"
    block.write_text("# block\n"
                     "units si\n"                                  # 2: also in the deck
                     "variable y equal &\n"                        # 3
                     "1+2\n"
                     "fix bad all nope\n")                         # 5
    deck_path = tmp_path / "d.liggghts"
    deck_path.write_text("variable freq index 50 # [Hz] f\n"        # 1
                         "include ${deck_dir}/include/block.liggghts\n"  # 2
                         "units si\n"                              # 3
                         "run 10\n")                               # 4
    deck = Deck(deck_path)
    log = ("LIGGGHTS (Version)\n"
           "variable freq index 50 # [Hz] f\n"
           "include ${deck_dir}/include/block.liggghts\n"
           f"include {tmp_path}/include/block.liggghts\n"
           "units si\n"
           "variable y equal 1+2\n"
           "fix bad all nope\n"
           'ERROR: Invalid fix style: "nope" (./src/modify.cpp:850)\n')
    err = find_error(log)
    cmd = failed_command(log, deck, before=err.line_index)
    assert (cmd.file, cmd.line, cmd.text) == (block.resolve(), 5, "fix bad all nope")
    # "units si" echoed after the include is the block's line 2, not the deck's line 3
    cmd = failed_command(log, deck, before=5)
    assert (cmd.file.name, cmd.line) == ("block.liggghts", 2)
    # back in the deck after the include
    log2 = log.replace("fix bad all nope\nERROR", "fix bad all nope\nunits si\nERROR")
    cmd = failed_command(log2, deck, before=find_error(log2).line_index)
    assert (cmd.file, cmd.line) == (deck_path.resolve(), 3)


def test_engine_error_names_the_included_file():
    e = EngineError('Invalid fix style: "nope"', deck="decks/include/contact.liggghts", line=33,
                    command="fix m1 all nope", phase="deck")
    assert str(e).endswith("at decks/include/contact.liggghts:33: fix m1 all nope")


def test_a_multi_line_error_is_read_whole():
    assert find_error(MESH_ERROR).message == (
        "Mesh (id plate): All 2 mesh elements have been lost / left the domain. Please use "
        "'boundary m m m' or scale/translate/rotate the mesh or change its dynamics FYI: center of "
        "mass of mesh including scale/tranlate/rotate is 0.000000 / 0.000000 / 0.000000 simulation "
        "box x from -0.050000 to 0.050000 y from -0.005000 to 0.005000 z from -0.002000 to "
        "0.010000 (gives indication about changes in scale/tranlate/rotate necessary to make "
        "simulation run)")


def test_an_error_ends_at_its_source_location():
    err = find_error("ERROR: Cannot open mesh file\nmesh.stl (src/input_mesh_tri.cpp:98)\n"
                     "Last command: fix m all mesh/surface file mesh.stl\n")
    assert err.message == "Cannot open mesh file mesh.stl" and err.line_index == 0


def test_an_error_without_a_source_location_ends_with_the_text():
    err = find_error("x\nERROR: Lost atoms: original 10\ncurrent 9\n")
    assert err.message == "Lost atoms: original 10 current 9" and err.line_index == 1


def test_an_error_ends_at_a_blank_line_or_the_next_error():
    assert find_error("ERROR: first\nstill first\n\nnot it\n").message == "first still first"
    err = find_error("ERROR: first\nERROR on proc 2: second (src/a.cpp:1)\n")
    assert err.message == "first" and err.proc is None


def test_an_error_takes_at_most_twenty_more_lines():
    text = "\n".join(["x"] * 5 + ["ERROR: head"] + [f"l{k}" for k in range(1, 31)])
    err = find_error(text)
    assert err.line_index == 5
    assert err.message == "head " + " ".join(f"l{k}" for k in range(1, 21))


def test_the_first_command_and_a_command_written_twice(tmp_path):
    deck_path = tmp_path / "d.liggghts"
    deck_path.write_text("units si\n"                                  # 1
                         "variable freq index 50 # [Hz] f\n"           # 2
                         "units si\n"                                  # 3
                         "run 10\n"                                    # 4
                         "units si\n")                                 # 5
    deck = Deck(deck_path)
    # echoed once: the first place it is written, not a later one
    assert failed_command("LIGGGHTS (Version)\n\nunits si\nERROR: x\n", deck, before=3).line == 1
    # each further echo is the next place it is written
    assert failed_command("units si\nunits si\n", deck).line == 3
    log = "units si\nvariable freq index 50 # [Hz] f\nunits si\n\nrun 10\nunits si\n"
    assert failed_command(log, deck, before=3).line == 3
    assert failed_command(log, deck).line == 5              # before None: the whole log; the last command
    assert failed_command("LIGGGHTS (Version)\n", deck) is None
