#!/usr/bin/env python3
# SPDX-License-Identifier: BSD-3-Clause
"""Writes bowl.obj: a closed bowl (a thick lower hemispherical shell with a flat rim), the
surface of revolution about y of a closed profile: outer sphere from its bottom pole up to
the rim, the rim, the inner sphere back down to its bottom pole. Triangles face outward.

    python3 models/bowl/makeBowl.py [--segments 48] [--rings 12] [--output models/bowl/bowl.obj]
"""
import argparse
import math


def profile(centre_y, inner, outer, rings):
    """(radius, height) points from the outer pole to the inner pole."""
    points = []
    for k in range(rings + 1):  # outer: angle from the bottom pole (0) to the rim (pi/2)
        a = 0.5 * math.pi * k / rings
        points.append((outer * math.sin(a), centre_y - outer * math.cos(a)))
    for k in range(rings, -1, -1):  # inner: back down
        a = 0.5 * math.pi * k / rings
        points.append((inner * math.sin(a), centre_y - inner * math.cos(a)))
    return points


def revolve(points, segments):
    vertices, rings = [], []
    for radius, height in points:
        if radius == 0.0:
            rings.append([len(vertices)])
            vertices.append((0.0, height, 0.0))
            continue
        ring = []
        for s in range(segments):
            t = 2.0 * math.pi * s / segments
            ring.append(len(vertices))
            vertices.append((radius * math.cos(t), height, radius * math.sin(t)))
        rings.append(ring)
    triangles = []
    for a, b in zip(rings, rings[1:]):
        for s in range(segments):
            a0, a1 = a[s % len(a)], a[(s + 1) % len(a)]
            b0, b1 = b[s % len(b)], b[(s + 1) % len(b)]
            if len(a) > 1:
                triangles.append((a0, a1, b0))
            if len(b) > 1:
                triangles.append((a1, b1, b0))
    return vertices, triangles


def signed_volume(vertices, triangles):
    volume = 0.0
    for i, j, k in triangles:
        (ax, ay, az), (bx, by, bz), (cx, cy, cz) = vertices[i], vertices[j], vertices[k]
        volume += (ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)) / 6.0
    return volume


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--segments", type=int, default=48, help="divisions around y")
    parser.add_argument("--rings", type=int, default=12, help="divisions of each quarter circle")
    parser.add_argument("--inner", type=float, default=0.35, help="inner radius")
    parser.add_argument("--outer", type=float, default=0.4, help="outer radius")
    parser.add_argument("--centre-height", type=float, default=0.4, help="height of the spheres' centre (the rim)")
    parser.add_argument("--output", default="models/bowl/bowl.obj")
    options = parser.parse_args()
    vertices, triangles = revolve(profile(options.centre_height, options.inner, options.outer, options.rings),
                                  options.segments)
    if signed_volume(vertices, triangles) < 0:
        triangles = [(i, k, j) for i, j, k in triangles]
    with open(options.output, "w") as out:
        out.write("# bowl: inner radius %g, outer radius %g, rim at y = %g; made by models/bowl/makeBowl.py\n"
                  % (options.inner, options.outer, options.centre_height))
        out.write("o bowl\n")
        for x, y, z in vertices:
            out.write("v %.9g %.9g %.9g\n" % (x, y, z))
        for i, j, k in triangles:
            out.write("f %d %d %d\n" % (i + 1, j + 1, k + 1))
    print("%s: %d vertices, %d triangles, volume %.6g" % (options.output, len(vertices), len(triangles),
                                                        abs(signed_volume(vertices, triangles))))


if __name__ == "__main__":
    main()
