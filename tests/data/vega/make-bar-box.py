#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Writes bar-box.obj and bar-box.interp: a box of 20 vertices and 36 triangles inside
bar.veg's 1 x 0.2 x 0.2 m bar, and for each box vertex the tetrahedron of bar.veg that
holds it with the vertex's barycentric coordinates there (Vega's .interp layout: index,
then four (0-based tet vertex, weight) pairs), nine significant digits.
Run in this folder: python3 make-bar-box.py"""


def read_bar():
    lines = [line.split() for line in open("bar.veg") if line.strip() and not line.startswith("#")]
    v = lines.index(["*VERTICES"])
    positions = [[float(x) for x in lines[v + 2 + k][1:4]] for k in range(int(lines[v + 1][0]))]
    e = lines.index(["*ELEMENTS"])
    tets = [[int(i) - 1 for i in lines[e + 3 + k][1:5]] for k in range(int(lines[e + 2][0]))]
    return positions, tets


def determinant(a, b, c):
    return a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])


def barycentric(point, tet, positions):
    origin = positions[tet[0]]
    edges = [[positions[tet[q]][i] - origin[i] for i in range(3)] for q in (1, 2, 3)]
    offset = [point[i] - origin[i] for i in range(3)]
    volume = determinant(*edges)
    weights = [determinant(offset, edges[1], edges[2]) / volume, determinant(edges[0], offset, edges[2]) / volume,
               determinant(edges[0], edges[1], offset) / volume]
    return [1 - sum(weights)] + weights


def main():
    positions, tets = read_bar()
    # Four sections of a box along x, its corners listed counter-clockwise around x.
    box = [(0.05 + 0.225 * s, y, z) for s in range(5) for (y, z) in [(0.03, 0.04), (0.17, 0.04), (0.17, 0.16),
                                                                       (0.03, 0.16)]]
    triangles = []
    for s in range(4):
        for c in range(4):
            a, b = 4 * s + c, 4 * s + (c + 1) % 4
            triangles += [(a, b, b + 4), (a, b + 4, a + 4)]
    triangles += [(0, 2, 1), (0, 3, 2), (16, 17, 18), (16, 18, 19)]
    with open("bar-box.obj", "w") as obj:
        obj.write("# a box embedded in bar.veg: 20 vertices, 36 triangles (weights: bar-box.interp)\n")
        for vertex in box:
            obj.write("v %.9g %.9g %.9g\n" % vertex)
        for triangle in triangles:
            obj.write("f %d %d %d\n" % tuple(i + 1 for i in triangle))
    with open("bar-box.interp", "w") as interp:
        for k, point in enumerate(box):
            tet, weights = next((t, w) for t in tets for w in [barycentric(point, t, positions)] if min(w) >= -1e-12)
            interp.write("%d" % k + "".join(" %d %.9g" % (tet[a], weights[a]) for a in range(4)) + "\n")


if __name__ == "__main__":
    main()
