"""The ctypes binding, exercised in a child process (one engine per process)."""

import json
import subprocess
import sys

from helpers import DECKS

SCRIPT = r"""
import json, sys
from vibrofeed.engine.library import Liggghts
out = {}
lmp = Liggghts(["-log", sys.argv[1] + "/log", "-screen", sys.argv[1] + "/screen", "-nocite",
                "-var", "driver", "1", "-var", "deck_dir", sys.argv[2], "-var", "freq", "40"])
lmp.file(sys.argv[2] + "/single_part.liggghts")
out["freq"] = lmp.variable("omega") / (2 * 3.141592653589793)
out["dt_used"] = lmp.variable("dt_used")
out["dt"] = lmp.dt
out["natoms"] = lmp.natoms
lmp.command("run 10")
atoms = lmp.local_atoms(["id", "type", "radius", "x", "v", "omega"])
out["shapes"] = {k: list(v.shape) for k, v in atoms.items()}
out["id"] = atoms["id"].tolist()
out["radius"] = atoms["radius"].tolist()
for bad in ("no_such_variable", "radius"):  # radius is an index variable, not equal-style
    try:
        lmp.variable(bad)
    except KeyError:
        out.setdefault("missing", []).append(bad)
try:
    lmp.local_atoms(["q"])
except KeyError:
    out["bad_atom_name"] = True
lmp.close()
print(json.dumps(out))
"""


def test_binding_reads_variables_and_atoms(tmp_path):
    proc = subprocess.run([sys.executable, "-c", SCRIPT, str(tmp_path), str(DECKS)],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    assert abs(out["freq"] - 40) < 1e-12  # -var override reached the engine
    assert out["dt"] == out["dt_used"] > 0
    assert out["natoms"] == 1
    assert out["shapes"] == {"id": [1], "type": [1], "radius": [1], "x": [1, 3], "v": [1, 3],
                             "omega": [1, 3]}
    assert out["id"] == [1] and abs(out["radius"][0] - 5e-4) < 1e-15
    assert out["missing"] == ["no_such_variable", "radius"]
    assert out["bad_atom_name"] is True
