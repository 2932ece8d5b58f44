#!/usr/bin/env python3
"""Converts an OpenVDB FloatGrid (a .vdb file's density) into prt's raw density grid
(docs/FORMAT.md "Density grid files") for a scene's "volumes": {"file": "OUT.grid", ...}.

prt reads no .vdb itself: Debian's libopenvdb-dev (10.0.1) has a C++ API only and no NanoVDB C
header. This script needs python3-openvdb (apt install python3-openvdb), which `make deps` does
not install.

    scripts/vdb_to_grid.py smoke.vdb smoke.grid [--grid density] [--max-dim 128]

The grid's active bounding box is sampled at voxel centres (its own voxels, or fewer when a side
exceeds --max-dim: then by the nearest voxel), negative values clamped to zero. It prints the
world box of the result, to give as the volume's "min" and "max".
"""
import argparse
import struct
import sys
import zlib


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("vdb")
    ap.add_argument("out")
    ap.add_argument("--grid", default=None, help="name of the FloatGrid (default: 'density', else the first)")
    ap.add_argument("--max-dim", type=int, default=128, help="largest side of the result in voxels (1..512, default 128)")
    a = ap.parse_args()
    if not 1 <= a.max_dim <= 512:
        sys.exit("vdb_to_grid: --max-dim must lie in 1..512")
    try:
        import pyopenvdb as vdb
    except ImportError:
        try:
            import openvdb as vdb
        except ImportError:
            sys.exit("vdb_to_grid: needs python3-openvdb (apt install python3-openvdb)")
    grids = vdb.readAllGridMetadata(a.vdb)
    names = [g.name for g in grids]
    name = a.grid or ("density" if "density" in names else (names[0] if names else None))
    if name is None or name not in names:
        sys.exit("vdb_to_grid: '%s' holds no grid %s (it has: %s)" % (a.vdb, name, ", ".join(names) or "none"))
    grid = vdb.read(a.vdb, name)
    (x0, y0, z0), (x1, y1, z1) = grid.evalActiveVoxelBoundingBox()
    size = [x1 - x0 + 1, y1 - y0 + 1, z1 - z0 + 1]
    if min(size) < 1:
        sys.exit("vdb_to_grid: grid '%s' has no active voxels" % name)
    dims = [min(s, a.max_dim) for s in size]
    acc = grid.getConstAccessor()
    values = []
    for k in range(dims[2]):
        for j in range(dims[1]):
            for i in range(dims[0]):
                ijk = (x0 + (i * size[0]) // dims[0], y0 + (j * size[1]) // dims[1], z0 + (k * size[2]) // dims[2])
                v = float(acc.getValue(ijk))
                values.append(v if v > 0 and v == v and v != float("inf") else 0.0)
    body = b"PRTGRID\0" + struct.pack("<I3II", 1, dims[0], dims[1], dims[2], 0) + struct.pack("<%df" % len(values), *values)
    with open(a.out, "wb") as f:
        f.write(body + struct.pack("<I", zlib.crc32(body) & 0xFFFFFFFF))
    lo = grid.transform.indexToWorld((x0 - 0.5, y0 - 0.5, z0 - 0.5))
    hi = grid.transform.indexToWorld((x1 + 0.5, y1 + 0.5, z1 + 0.5))
    print("%s: %d x %d x %d voxels; \"min\": [%g, %g, %g], \"max\": [%g, %g, %g]" % (a.out, dims[0], dims[1], dims[2], lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]))


if __name__ == "__main__":
    main()
