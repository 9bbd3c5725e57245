#!/usr/bin/env python3
"""Opens pdamp's ParaView output with VTK's own XML readers (the library ParaView is built
on) and prints what it read as JSON: for a `.pvd` collection every frame and part, for a
`.vtp` file the file itself. Exit status 1 with a message when VTK reports an error or a file
is missing; used by crates/pdamp-cli/tests/paraview.rs (issue 32) and handy by hand:

    python3 scripts/check_vtk.py out/shaken_box/particles.pvd
"""
import json
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

from vtkmodules.vtkCommonCore import vtkCommand, vtkObject
from vtkmodules.vtkIOXML import vtkXMLPolyDataReader


class Errors:
    """Collects VTK's error and warning events (VTK prints them and carries on otherwise)."""

    def __init__(self):
        self.messages = []

    def __call__(self, obj, event, *args):
        self.messages.append(f"{event}")


def read_vtp(path: Path) -> dict:
    if not path.is_file():
        raise SystemExit(f"missing file: {path}")
    reader = vtkXMLPolyDataReader()
    errors = Errors()
    reader.AddObserver(vtkCommand.ErrorEvent, errors)
    reader.AddObserver(vtkCommand.WarningEvent, errors)
    reader.SetFileName(str(path))
    reader.Update()
    if errors.messages or reader.GetErrorCode() != 0:
        raise SystemExit(f"VTK could not read {path}: {errors.messages} code {reader.GetErrorCode()}")
    poly = reader.GetOutput()
    pd = poly.GetPointData()
    arrays = {}
    for k in range(pd.GetNumberOfArrays()):
        a = pd.GetArray(k)
        arrays[a.GetName()] = {
            "components": a.GetNumberOfComponents(),
            "range": list(a.GetRange(-1)) if a.GetNumberOfTuples() else None,
        }
    return {
        "file": str(path),
        "points": poly.GetNumberOfPoints(),
        "verts": poly.GetNumberOfVerts(),
        "polys": poly.GetNumberOfPolys(),
        "bounds": list(poly.GetBounds()) if poly.GetNumberOfPoints() else None,
        "point_data": arrays,
        "compressed": "vtkZLibDataCompressor" in path.read_bytes()[:400].decode("latin-1"),
    }


def read_pvd(path: Path) -> dict:
    root = ET.parse(path).getroot()
    if root.get("type") != "Collection":
        raise SystemExit(f"{path}: not a VTK collection")
    frames = {}
    for ds in root.iter("DataSet"):
        t = float(ds.get("timestep"))
        part = int(ds.get("part", "0"))
        info = read_vtp(path.parent / ds.get("file"))
        info["part"] = part
        frames.setdefault(t, []).append(info)
    return {
        "file": str(path),
        "frames": [{"time_s": t, "parts": parts} for t, parts in sorted(frames.items())],
    }


def main() -> None:
    vtkObject.GlobalWarningDisplayOff()
    out = []
    for arg in sys.argv[1:]:
        p = Path(arg)
        out.append(read_pvd(p) if p.suffix == ".pvd" else read_vtp(p))
    json.dump(out, sys.stdout, indent=1)
    print()


if __name__ == "__main__":
    main()
