"""Run by ``pvpython`` (tests/unit/pictures/test_paraview.py): open a vibrofeed ParaView export as a
user would and print, as JSON, what ParaView loads at every time step.

Usage: pvpython pvpython_probe.py RUN.pvd [RUN_outlet.vtp]
"""

import json
import sys

from paraview import servermanager
from paraview.simple import GetAnimationScene, GetTimeKeeper, OpenDataFile, Show, TensorGlyph


def leaves(data):
    """{block name: dataset} of a time step's multiblock (each block holds one piece); a
    collection of one part (parts only) loads as that part's dataset."""
    if not data.IsA("vtkMultiBlockDataSet"):
        return {"parts": data}
    found = {}
    for i in range(data.GetNumberOfBlocks()):
        block = data.GetBlock(i)
        while block is not None and block.IsA("vtkMultiBlockDataSet"):
            block = block.GetBlock(0)
        found[data.GetMetaData(i).Get(data.NAME())] = block
    return found


def describe(block):
    pd = block.GetPointData()
    active = {kind: (getattr(pd, f"Get{kind}")().GetName() if getattr(pd, f"Get{kind}")() else None)
              for kind in ("Scalars", "Vectors", "Tensors", "Normals")}
    return {"points": block.GetNumberOfPoints(),
            "arrays": [pd.GetArrayName(k) for k in range(pd.GetNumberOfArrays())], **active}


reader = OpenDataFile(sys.argv[1])
times = [float(t) for t in reader.TimestepValues]
steps = []
for t in times:
    reader.UpdatePipeline(t)
    steps.append({name: describe(block) for name, block in leaves(servermanager.Fetch(reader)).items()})
display = Show(reader)  # what the GUI's Apply does: colour by the active scalars, if any
out = {"times": times, "steps": steps, "colour": display.ColorArrayName[1],
       "tensor_glyph": TensorGlyph(Input=reader).Tensors[1]}
if len(sys.argv) > 2:
    events = OpenDataFile(sys.argv[2])
    events.UpdatePipeline()
    Show(events)
    out["outlet_times"] = [float(t) for t in events.TimestepValues]
    out["outlet"] = describe(servermanager.Fetch(events))
GetAnimationScene().UpdateAnimationUsingDataTimeSteps()
out["animation"] = [float(t) for t in GetTimeKeeper().TimestepValues]
print("PROBE " + json.dumps(out))
