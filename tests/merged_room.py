#!/usr/bin/env python3
"""A room registered and exported as one cloud, without its scanner stations,
for ctest campaign_runs.scene_from_scan.merged_room (tests/merged_room.sh).

  merged_room.py make OUT.ply [corridor]   writes the room (binary PLY: x y z, colors)
  merged_room.py check GLB...              asserts each glTF model faces into the room

The room is 5 x 4 x 2.8 m, its faces sampled on a jittered 2.5 cm grid with
1.5 mm of noise across them (about 140,000 points), with a door 0.9 m wide
and 2 m high and a window 1.2 x 1 m left open (no points beyond them, as a
scan's), a table (top and sides) standing in it, and dark and light 20 cm
squares in a hue per face, with 2 % color noise. Deterministic (a fixed
seed).

`corridor` writes a corridor instead, 9 x 1.8 x 2.6 m, open at both ends (no
end walls: the scan stops there), with a window 1.2 x 1 m in one wall and a
bench (top and sides) against the other, about 130,000 points: the free
space it encloses reaches the cloud's box through its ends, so the enclosure
test closes nothing in, and until points.normals 7 it was meshed inside-out
and viewed from outside.

`check` reads each model.glb (positions and triangles of its meshes, node
transforms being rotations and translations, which keep the sides) and
measures the share of the triangles' area whose front (counter-clockwise, as
glTF draws it) faces the center of the model's bounding box, the room's
middle. A room meshed inside-out has about none; one facing in, nearly all
(the table's sides facing away from the middle are a few percent).
"""
import json
import math
import random
import struct
import sys

WIDTH, DEPTH, HEIGHT = 5.0, 4.0, 2.8
SPACING, NOISE = 0.025, 0.0015


HUES = [(1.0, 0.85, 0.7), (0.8, 0.9, 1.0), (1.0, 0.75, 0.75), (0.85, 1.0, 0.8), (0.95, 0.95, 0.95),
        (0.9, 0.8, 1.0), (0.7, 0.55, 0.4)]


def opening(x, y, z):
    door = y < 0.01 and 1.0 < x < 1.9 and z < 2.0
    window = x > WIDTH - 0.01 and 1.4 < y < 2.6 and 0.9 < z < 1.9
    return door or window


def box_faces(points, lo, hi, rng, skip, tint):
    for axis in range(3):
        u, v = (axis + 1) % 3, (axis + 2) % 3
        nu = int((hi[u] - lo[u]) / SPACING)
        nv = int((hi[v] - lo[v]) / SPACING)
        for side, plane in enumerate((lo[axis], hi[axis])):
            face = 2 * axis + side
            for i in range(nu):
                for j in range(nv):
                    p = [0.0, 0.0, 0.0]
                    p[axis] = plane + rng.gauss(0.0, NOISE)
                    p[u] = lo[u] + (i + 0.5 + rng.uniform(-0.3, 0.3)) * SPACING
                    p[v] = lo[v] + (j + 0.5 + rng.uniform(-0.3, 0.3)) * SPACING
                    if skip(*p):
                        continue
                    # Dark and light squares (texture a person sees in
                    # luma too), a hue per face, 2 % sensor noise.
                    square = (int(p[u] / 0.2) + int(p[v] / 0.2)) % 2
                    light = 0.35 + 0.5 * square
                    hue = HUES[(face + tint) % len(HUES)]
                    color = tuple(max(0, min(255, round(255 * (light * h + rng.gauss(0.0, 0.02)))))
                                  for h in hue)
                    points.append((p, color))


CORRIDOR = (9.0, 1.8, 2.6)


def corridor_opening(x, y, z):
    ends = x < 0.01 or x > CORRIDOR[0] - 0.01
    window = y > CORRIDOR[1] - 0.01 and 3.0 < x < 4.2 and 0.9 < z < 1.9
    return ends or window


def make(path, kind="room"):
    rng = random.Random(15)
    points = []
    if kind == "corridor":
        box_faces(points, (0, 0, 0), CORRIDOR, rng, corridor_opening, 0)
        # A bench against the wall y = 0: its top and its other sides.
        box_faces(points, (5.0, 0.0, 0.0), (6.5, 0.45, 0.45), rng, lambda x, y, z: z < 0.01 or y < 0.01, 6)
    else:
        box_faces(points, (0, 0, 0), (WIDTH, DEPTH, HEIGHT), rng, opening, 0)
        # A table: its top and sides, not its bottom on the floor.
        box_faces(points, (1.5, 1.8, 0.0), (2.7, 2.6, 0.75), rng, lambda x, y, z: z < 0.01, 6)
    with open(path, "wb") as out:
        out.write((
            "ply\nformat binary_little_endian 1.0\nelement vertex %d\n"
            "property float x\nproperty float y\nproperty float z\n"
            "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n"
            % len(points)).encode())
        for p, c in points:
            out.write(struct.pack("<fffBBB", p[0], p[1], p[2], *c))
    print("%s: %d points" % (path, len(points)))


def matrix_of(node):
    if "matrix" in node:
        m = node["matrix"]  # column-major
        return [[m[c * 4 + r] for c in range(4)] for r in range(4)]
    x, y, z, w = node.get("rotation", [0, 0, 0, 1])
    s = node.get("scale", [1, 1, 1])
    t = node.get("translation", [0, 0, 0])
    r = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
         [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
         [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
    return [[r[i][0] * s[0], r[i][1] * s[1], r[i][2] * s[2], t[i]] for i in range(3)] + [[0, 0, 0, 1]]


def multiply(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def triangles(path):
    data = open(path, "rb").read()
    magic, _, _ = struct.unpack_from("<III", data, 0)
    if magic != 0x46546C67:
        raise SystemExit("%s: not a binary glTF" % path)
    length, _ = struct.unpack_from("<II", data, 12)
    gltf = json.loads(data[20:20 + length])
    binary_at = 20 + length + 8
    binary = data[binary_at:]

    def accessor(index):
        a = gltf["accessors"][index]
        view = gltf["bufferViews"][a["bufferView"]]
        start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
        width = {"SCALAR": 1, "VEC3": 3}[a["type"]]
        code = {5126: "f", 5125: "I", 5123: "H"}[a["componentType"]]
        size = struct.calcsize(code)
        stride = view.get("byteStride", size * width)
        return [struct.unpack_from("<" + code * width, binary, start + k * stride) for k in range(a["count"])]

    out = []

    def walk(index, parent):
        node = gltf["nodes"][index]
        m = multiply(parent, matrix_of(node))
        if "mesh" in node:
            for primitive in gltf["meshes"][node["mesh"]]["primitives"]:
                if primitive.get("mode", 4) != 4:
                    continue
                positions = [tuple(sum(m[r][c] * p[c] for c in range(3)) + m[r][3] for r in range(3))
                             for p in accessor(primitive["attributes"]["POSITION"])]
                indices = [i[0] for i in accessor(primitive["indices"])]
                for k in range(0, len(indices), 3):
                    out.append(tuple(positions[i] for i in indices[k:k + 3]))
        for child in node.get("children", []):
            walk(child, m)

    identity = [[float(i == j) for j in range(4)] for i in range(4)]
    for root in gltf["scenes"][gltf.get("scene", 0)]["nodes"]:
        walk(root, identity)
    return out


def fronts(path):
    """The triangles of a model.glb as (area, front normal of length 2 * area,
    center), and the middle of their bounding box."""
    faces = triangles(path)
    lo = [min(p[a] for f in faces for p in f) for a in range(3)]
    hi = [max(p[a] for f in faces for p in f) for a in range(3)]
    out = []
    for a, b, c in faces:
        u = [b[k] - a[k] for k in range(3)]
        v = [c[k] - a[k] for k in range(3)]
        n = (u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0])
        area = math.sqrt(n[0] ** 2 + n[1] ** 2 + n[2] ** 2) / 2
        out.append((area, n, [(a[k] + b[k] + c[k]) / 3 for k in range(3)]))
    return out, [(lo[a] + hi[a]) / 2 for a in range(3)]


def facing_in(path):
    faces, middle = fronts(path)
    inward = total = 0.0
    for area, n, center in faces:
        toward = sum(n[k] * (middle[k] - center[k]) for k in range(3))
        total += area
        inward += area if toward > 0 else 0.0
    return len(faces), inward / total if total > 0 else 0.0


def check(paths, least=0.9):
    failed = 0
    for path in paths:
        count, share = facing_in(path)
        ok = share >= least
        failed += not ok
        print("%s  %s: %.1f %% of %d triangles' area faces into the room (>= %.0f %%)"
              % ("ok  " if ok else "FAIL", path, 100 * share, count, 100 * least))
    if not paths:
        print("FAIL  no models to check")
        return 1
    return 1 if failed else 0


if __name__ == "__main__":
    if len(sys.argv) in (3, 4) and sys.argv[1] == "make" and sys.argv[3:] in ([], ["corridor"]):
        make(sys.argv[2], *sys.argv[3:])
    elif len(sys.argv) >= 2 and sys.argv[1] == "check":
        sys.exit(check(sys.argv[2:]))
    else:
        sys.exit(__doc__)
