#!/usr/bin/env python3
"""Writes the surface of a union of axis-aligned boxes as one closed ASCII STL (outward normals).

Inner structures of D Sect. 8.1.4 (crosses of 5 mm × 5 mm bars) are unions of bars. As separate
`box_outside` walls, the bars are separate meshes: where they overlap or touch, a sphere meets the
same surface through two meshes and feels it twice. One mesh of the union has each surface once,
and the mesh wall's face/edge/corner handling sees the flat seams between its triangles.

Method: the planes of all box faces cut space into a rectilinear grid of cells; a cell is solid if
its centre lies in any box; every face between a solid and an empty cell becomes two triangles
whose normal points into the empty cell. Neighbouring faces share whole edges (no T-junctions),
so the mesh is closed and consistently oriented.

    python3 scripts/box_union_stl.py single_cross OUT.stl   # D Fig. 8.11a
    python3 scripts/box_union_stl.py triple_cross OUT.stl   # D Fig. 8.11b
"""
import itertools
import sys

R_MM = 20.0      # inner radius of the baseline cylinder (D L3093)
L_MM = 52.4      # its inner length (examples/damper_cylinder_baseline.toml)
ARM_MM = 5.0     # every arm 5 mm × 5 mm (D L3310)


def cross(x_mm):
    """Two arms spanning the diameter, perpendicular to the axis x, centred at x_mm."""
    a, r = ARM_MM / 2, R_MM
    return [((x_mm - a, -r, -a), (x_mm + a, r, a)), ((x_mm - a, -a, -r), (x_mm + a, a, r))]


def structures():
    """The inner structures, boxes as ((x0, y0, z0), (x1, y1, z1)) in mm."""
    mid = L_MM / 2
    quarter = L_MM / 4
    a = ARM_MM / 2
    triple = cross(quarter) + cross(mid) + cross(3 * quarter)
    # "three evenly distributed crosses connected to each other" (D L3310): one bar along the
    # axis from the first cross to the third
    triple.append(((quarter, -a, -a), (3 * quarter, a, a)))
    return {"single_cross": cross(mid), "triple_cross": triple}


def union_surface(boxes):
    """Triangles (normal, v0, v1, v2) of the boundary of the union of `boxes`."""
    planes = [sorted({b[k][d] for b in boxes for k in (0, 1)}) for d in range(3)]
    shape = [len(p) - 1 for p in planes]

    def solid(i, j, k):
        if not (0 <= i < shape[0] and 0 <= j < shape[1] and 0 <= k < shape[2]):
            return False
        c = [(planes[d][n] + planes[d][n + 1]) / 2 for d, n in enumerate((i, j, k))]
        return any(all(lo[d] < c[d] < hi[d] for d in range(3)) for lo, hi in boxes)

    tris = []
    for cell in itertools.product(*(range(n) for n in shape)):
        if not solid(*cell):
            continue
        for d in range(3):
            for side in (0, 1):
                nb = list(cell)
                nb[d] += 1 if side else -1
                if solid(*nb):
                    continue
                # the face at planes[d][cell[d] + side], spanned by the two other axes
                u, v = (d + 1) % 3, (d + 2) % 3
                p = [0.0, 0.0, 0.0]
                p[d] = planes[d][cell[d] + side]
                corners = []
                for du, dv in ((0, 0), (1, 0), (1, 1), (0, 1)):
                    q = list(p)
                    q[u] = planes[u][cell[u] + du]
                    q[v] = planes[v][cell[v] + dv]
                    corners.append(tuple(q))
                # (u, v, d) is right-handed: counter-clockwise in (u, v) points along +d
                if not side:
                    corners.reverse()
                n = [0.0, 0.0, 0.0]
                n[d] = 1.0 if side else -1.0
                tris.append((n, corners[0], corners[1], corners[2]))
                tris.append((n, corners[0], corners[2], corners[3]))
    return tris


def write_stl(path, name, tris):
    with open(path, "w") as f:
        f.write(f"solid {name}\n")
        for n, *vs in tris:
            f.write("  facet normal {:.6e} {:.6e} {:.6e}\n    outer loop\n".format(*n))
            for v in vs:
                f.write("      vertex {:.6f} {:.6f} {:.6f}\n".format(*v))
            f.write("    endloop\n  endfacet\n")
        f.write(f"endsolid {name}\n")


def main():
    if len(sys.argv) != 3 or sys.argv[1] not in structures():
        sys.exit(f"usage: {sys.argv[0]} {{{'|'.join(structures())}}} OUT.stl")
    boxes = structures()[sys.argv[1]]
    tris = union_surface(boxes)
    write_stl(sys.argv[2], sys.argv[1], tris)
    print(f"{sys.argv[2]}: {len(boxes)} boxes, {len(tris)} triangles (mm)")


if __name__ == "__main__":
    main()
