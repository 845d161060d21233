#!/usr/bin/env python3
"""A statue as it is often delivered, for ctest
campaign_runs.scene_from_scan.statue (tests/statue_file.sh).

  statue_file.py IN.ply OUT.ply [--air FRACTION]

IN is `synth.scan` preset `sculpture`'s points.ply (binary PLY: x y z in
meters, z up, colors, a station per point and the stations in comments).
OUT is the same scan as a photogrammetry or fused RGB-D export brings it:
one file without scanner stations (neither the comments nor the per-point
property), in millimetres, y up (x, y, z -> x, z, -y), and cropped to 1 m
around the plinth's axis (the carved blob, its box and a disk of paving).
Normals, if IN has them, are turned with the points.

  statue_file.py --check-sides GLB...

--check-sides reads each model.glb the workflows exported from OUT and
asserts that its faces' fronts (counter-clockwise, as glTF draws and culls
them) face out: of the area of the faces within 60 degrees of level (the
plinth's and the blob's sides) at least 90 % faces away from the vertical
axis through the model's middle, and of the rest (the ground, the plinth's
top; the blob's overhangs rightly face down) at least 75 % faces up. A
viewer culls back faces: with points.normals 3 the plinth and the ground
faced in and down (38 % and 10-21 %; now 97-100 % and 89-91 % on the
full-size stand-in), and a headset would have shown the blob floating
over nothing. Up is the file's
+y, which the glTF's z-up-to-y-up node turns to -z.

--air FRACTION moves that fraction of the kept points (a fixed pseudo-random
choice) into the air: each along the line to the station that scanned it,
5 to 60 % of the way (dust, mixed returns; IN must have its stations). It
prints how many, for the test to check that the workflows left them out
(docs/real-scans.md, "Points in the air").
"""
import random
import struct
import sys

TYPES = {'char': 'b', 'uchar': 'B', 'short': 'h', 'ushort': 'H', 'int': 'i', 'uint': 'I',
         'float': 'f', 'double': 'd'}


def read_header(data, path):
    end = data.find(b'end_header\n')
    if not data.startswith(b'ply\n') or end < 0:
        sys.exit(f'{path}: not a PLY file (no ply / end_header lines)')
    lines = data[:end].decode('ascii').splitlines()
    if 'format binary_little_endian 1.0' not in lines:
        sys.exit(f'{path}: only binary little-endian PLY is read here')
    count, names, fmt = None, [], '<'
    for line in lines:
        words = line.split()
        if words[:2] == ['element', 'vertex']:
            count = int(words[2])
        elif words[:1] == ['element'] and count is not None:
            sys.exit(f'{path}: an element after the vertices ({line}) is not read here')
        elif words[:1] == ['property']:
            if words[1] == 'list' or words[1] not in TYPES:
                sys.exit(f'{path}: property {line!r} is not read here')
            fmt += TYPES[words[1]]
            names.append(words[2])
    if count is None:
        sys.exit(f'{path}: no vertex element')
    return end + len(b'end_header\n'), count, names, struct.Struct(fmt)


def read_colored_points(path):
    """PATH's bytes and header (read_header), checked to hold every vertex
    it announces and x, y, z, red, green and blue."""
    with open(path, 'rb') as f:
        data = f.read()
    start, count, names, record = read_header(data, path)
    if len(data) < start + count * record.size:
        sys.exit(f'{path}: {count} vertices announced, the file ends before them')
    for name in ('x', 'y', 'z', 'red', 'green', 'blue'):
        if name not in names:
            sys.exit(f'{path}: no {name} property')
    return data, start, count, names, record


def stations_of(data, path):
    """The `comment station I X Y Z` lines of IN's header, by I."""
    header = data[:data.find(b'end_header\n')].decode('ascii')
    stations = {}
    for line in header.splitlines():
        words = line.split()
        if words[:2] == ['comment', 'station'] and len(words) == 6:
            stations[int(words[2])] = tuple(float(w) for w in words[3:])
    if not stations:
        sys.exit(f'{path}: --air needs the scanner stations (comment station lines)')
    return stations


def check_sides(paths, least_sides=0.9, least_level=0.75):
    import os
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from merged_room import fronts
    up = (0.0, 0.0, -1.0)
    failed = 0
    for path in paths:
        faces, middle = fronts(path)
        side = side_out = level = level_up = 0.0
        for area, n, center in faces:
            if area == 0:
                continue
            vertical = sum(n[k] * up[k] for k in range(3)) / (2 * area)
            away = [center[k] - middle[k] for k in range(3)]
            height = sum(away[k] * up[k] for k in range(3))
            away = [away[k] - height * up[k] for k in range(3)]
            if abs(vertical) < 0.5:
                side += area
                side_out += area if sum(n[k] * away[k] for k in range(3)) > 0 else 0.0
            else:
                level += area
                level_up += area if vertical > 0 else 0.0
        shares = (side_out / side if side else 0.0, level_up / level if level else 0.0)
        ok = shares[0] >= least_sides and shares[1] >= least_level
        failed += not ok
        print('%s  %s: %.1f %% of the sides\' area faces out (>= %.0f %%), %.1f %% of the level '
              'faces\' up (>= %.0f %%)' % ('ok  ' if ok else 'FAIL', path, 100 * shares[0],
                                          100 * least_sides, 100 * shares[1], 100 * least_level))
    if not paths:
        print('FAIL  no models to check')
        return 1
    return 1 if failed else 0


def main():
    args = sys.argv[1:]
    if args[:1] == ['--check-sides']:
        sys.exit(check_sides(args[1:]))
    air = 0.0
    if len(args) == 4 and args[2] == '--air':
        air = float(args[3])
        args = args[:2]
    if len(args) != 2 or not 0 <= air < 1:
        sys.exit(__doc__)
    source, target = args
    data, start, count, names, record = read_colored_points(source)
    ix, iy, iz = (names.index(n) for n in ('x', 'y', 'z'))
    colors = [names.index(n) for n in ('red', 'green', 'blue')]
    normals = [names.index(n) for n in ('nx', 'ny', 'nz')] if 'nx' in names else None
    if air > 0:
        if 'station' not in names:
            sys.exit(f'{source}: --air needs the per-point station property')
        stations = stations_of(data, source)
        ist = names.index('station')
    rnd = random.Random(5)
    moved = 0
    out = struct.Struct('<fffBBB' + ('fff' if normals else ''))
    body = bytearray()
    kept = 0
    for r in record.iter_unpack(data[start:start + count * record.size]):
        x, y, z = r[ix], r[iy], r[iz]
        if x * x + y * y > 1.0:
            continue
        if air > 0 and rnd.random() < air:
            sx, sy, sz = stations[r[ist]]
            t = rnd.uniform(0.05, 0.6)
            x, y, z = x + t * (sx - x), y + t * (sy - y), z + t * (sz - z)
            moved += 1
        values = [1000 * x, 1000 * z, -1000 * y] + [r[i] for i in colors]
        if normals:
            values += [r[normals[0]], r[normals[2]], -r[normals[1]]]
        body += out.pack(*values)
        kept += 1
    header = ['ply', 'format binary_little_endian 1.0', 'comment a statue export: no stations, mm, y up',
              f'element vertex {kept}', 'property float x', 'property float y', 'property float z',
              'property uchar red', 'property uchar green', 'property uchar blue']
    if normals:
        header += ['property float nx', 'property float ny', 'property float nz']
    header.append('end_header')
    with open(target, 'wb') as f:
        f.write(('\n'.join(header) + '\n').encode('ascii'))
        f.write(body)
    print(f'{target}: {kept} of {count} points (mm, y up, no stations)')
    if air > 0:
        print(f'{target}: {moved} points moved into the air')


if __name__ == '__main__':
    main()
