#!/usr/bin/env python3
"""One scan as users often export it, for ctest
campaign_runs.scene_from_scan.pump_ply (tests/pump_ply.sh).

  scan_without_station.py IN.ply OUT.ply

IN is a pointbake points PLY of one station (binary: x y z in meters, z up,
colors, the station per point and in a comment), e.g. io.read_points' output
for the pump E57. OUT is the same points as a binary PLY of x, y, z (double)
and colours only: no station, no grid, in millimetres, y up (x, y, z ->
x, z, -y) and georeferenced (plus 512,345 / 210 / 5,401,234 mm), as a
scanner's software writes one scan to hand it on. Prints where the station
lies in OUT's frame, for the test to compare with the one `pointbake scene`
finds (points/lost_station.h).
"""
import struct
import sys

sys.path.insert(0, __file__.rsplit('/', 1)[0])
from statue_file import read_colored_points, stations_of  # noqa: E402

OFFSET = (512345.0, 210.0, 5401234.0)  # mm


def to_out(x, y, z):
    return (1000 * x + OFFSET[0], 1000 * z + OFFSET[1], -1000 * y + OFFSET[2])


def main():
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    source, target = sys.argv[1:]
    data, start, count, names, record = read_colored_points(source)
    stations = stations_of(data, source)
    if len(stations) != 1:
        sys.exit(f'{source}: {len(stations)} stations; one scan has one')
    origin = (0.0, 0.0, 0.0)
    header = data[:start].decode('ascii')
    for line in header.splitlines():
        words = line.split()
        if words[:2] == ['comment', 'origin'] and len(words) == 5:
            origin = tuple(float(w) for w in words[2:])
    ix, iy, iz = (names.index(n) for n in ('x', 'y', 'z'))
    ir, ig, ib = (names.index(n) for n in ('red', 'green', 'blue'))
    out = struct.Struct('<dddBBB')
    rows = bytearray()
    for i in range(count):
        v = record.unpack_from(data, start + i * record.size)
        rows += out.pack(*to_out(v[ix] + origin[0], v[iy] + origin[1], v[iz] + origin[2]), v[ir], v[ig], v[ib])
    with open(target, 'wb') as f:
        f.write(('ply\nformat binary_little_endian 1.0\nelement vertex %d\n'
                 'property double x\nproperty double y\nproperty double z\n'
                 'property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n'
                 % count).encode('ascii'))
        f.write(rows)
    station = to_out(*next(iter(stations.values())))
    print('%s: %d points without their station, which lies at %.1f %.1f %.1f mm' % (target, count, *station))


if __name__ == '__main__':
    main()
