#!/usr/bin/env python3
"""Floaters in a multi-station scan, for ctest
campaign_runs.scene_from_scan.floaters (tests/floaters.sh).

  floaters.py IN.ply OUT.ply CLUMPS

IN is a `synth.scan` points.ply (binary PLY: x y z in meters, a station per
point and the stations in `comment station` lines). OUT is IN with CLUMPS
clumps of 150 points added (a Gaussian of 1 cm each, a cyan of its own: no
surface of the scene has such a colour, so a frame's cyan pixels are floaters),
each 5 to 40 cm in front of a scanned point towards the station that scanned
it, and recorded by that station only: a person or a bird one station saw
and the others did not (they were not there when the others scanned), or a
clump of dust returns. Every other property of an added point is its source
point's (normals, if any, point to the station). It prints how many points it
added, for the test to check that the workflows left them out
(docs/real-scans.md, "Floaters").

  floaters.py --check RUNS FRACTION

checks that every run's frames under RUNS (a campaign's out/runs) show a
floater's cyan on at most FRACTION of their drawn pixels.
"""
import math
import os
import random
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), '..', 'tools'))
from statue_file import read_header, stations_of  # noqa: E402

CLUMP_POINTS = 150


def check(runs, most):
    """Each run's frames show a floater's cyan on at most `most` of their
    drawn pixels; the scan's own render (which leaves out what the air stage
    left out, render.splats) is printed beside it."""
    import glob
    failed = 0
    paths = sorted(glob.glob(os.path.join(runs, '*', '*', 'frames')))
    for frames in paths:
        cyan = drawn = 0
        for path in sorted(glob.glob(os.path.join(frames, '*.png'))):
            c, d = floater_pixels(path)
            cyan, drawn = cyan + c, drawn + d
        scan = 0
        for path in sorted(glob.glob(os.path.join(os.path.dirname(frames), 'scan_frames', '*.png'))):
            if not path.endswith('.samples.png'):
                scan += floater_pixels(path)[0]
        share = cyan / drawn if drawn else 1.0
        ok = drawn > 0 and share <= most
        failed += not ok
        print('%s  %s: a floater\'s cyan on %d of %d drawn pixels (%.3f %%, at most %.3f %%); the scan\'s '
              'render: %d' % ('ok  ' if ok else 'FAIL', frames, cyan, drawn, 100 * share, 100 * most, scan))
    if not paths:
        print(f'FAIL  no frames under {runs}')
        return 1
    return 1 if failed else 0


def main():
    if len(sys.argv) == 4 and sys.argv[1] == '--check':
        sys.exit(check(sys.argv[2], float(sys.argv[3])))
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    source, target, clumps = sys.argv[1], sys.argv[2], int(sys.argv[3])
    with open(source, 'rb') as f:
        data = f.read()
    start, count, names, record = read_header(data, source)
    if len(data) < start + count * record.size:
        sys.exit(f'{source}: {count} vertices announced, the file ends before them')
    for name in ('x', 'y', 'z', 'red', 'green', 'blue', 'station'):
        if name not in names:
            sys.exit(f'{source}: no {name} property')
    stations = stations_of(data, source)
    ix, iy, iz = (names.index(n) for n in ('x', 'y', 'z'))
    colors = [names.index(n) for n in ('red', 'green', 'blue')]
    normals = [names.index(n) for n in ('nx', 'ny', 'nz')] if 'nx' in names else None
    ist = names.index('station')
    body = data[start:start + count * record.size]
    rnd = random.Random(11)
    added = bytearray()
    for _ in range(clumps):
        source_record = list(record.unpack_from(body, rnd.randrange(count) * record.size))
        p = [source_record[ix], source_record[iy], source_record[iz]]
        s = stations[source_record[ist]]
        way = [s[k] - p[k] for k in range(3)]
        length = math.sqrt(sum(w * w for w in way))
        way = [w / length for w in way]
        ahead = rnd.uniform(0.05, 0.40)
        center = [p[k] + ahead * way[k] for k in range(3)]
        color = [rnd.randrange(0, 40), rnd.randrange(170, 230), rnd.randrange(220, 256)]
        for _ in range(CLUMP_POINTS):
            values = list(source_record)
            values[ix], values[iy], values[iz] = (center[k] + rnd.gauss(0.0, 0.01) for k in range(3))
            for k in range(3):
                values[colors[k]] = color[k]
            if normals:
                for k in range(3):
                    values[normals[k]] = way[k]
            added += record.pack(*values)
    total = count + clumps * CLUMP_POINTS
    header = data[:start].decode('ascii').replace(f'element vertex {count}\n', f'element vertex {total}\n', 1)
    with open(target, 'wb') as f:
        f.write(header.encode('ascii'))
        f.write(body)
        f.write(added)
    print(f'{target}: {clumps * CLUMP_POINTS} points added in {clumps} clumps')


def floater_pixels(path):
    """(pixels of a floater's cyan, drawn pixels) of an RGB or RGBA PNG frame."""
    from check_real_campaign import read_png
    width, _, channels, rows = read_png(path)
    cyan = drawn = 0
    for row in rows:
        for x in range(0, width * channels, channels):
            if channels == 4 and row[x + 3] == 0:
                continue
            drawn += 1
            r, g, b = row[x], row[x + 1], row[x + 2]
            cyan += r <= 90 and g >= 140 and b >= 190 and b - r >= 130
    return cyan, drawn


if __name__ == '__main__':
    main()
