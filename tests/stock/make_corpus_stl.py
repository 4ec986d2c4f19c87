#!/usr/bin/env python3
"""make_corpus_stl.py: writes the seed corpus of fuzz_stl (tests/stock/corpus_stl/):
tiny valid meshes (a tetrahedron and a cube, binary and ASCII, a binary file whose
header starts with "solid") and malformed files (wrong triangle count, truncated,
NaN and huge coordinates, a quad facet, no endsolid, no triangles, a degenerate
triangle, a cube without its top face: an open surface, refused where its open edges are). Run from anywhere: python3 tests/stock/make_corpus_stl.py"""
import os
import struct

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "corpus_stl")

TETRA = [
    ((0, 0, 0), (0, 4, 0), (4, 0, 0)),
    ((0, 0, 0), (4, 0, 0), (0, 0, 4)),
    ((0, 0, 0), (0, 0, 4), (0, 4, 0)),
    ((4, 0, 0), (0, 4, 0), (0, 0, 4)),
]


def cube(lo, hi):
    c = [tuple(hi[k] if (i >> k) & 1 else lo[k] for k in range(3)) for i in range(8)]
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    tris = []
    for q in quads:
        tris.append((c[q[0]], c[q[1]], c[q[2]]))
        tris.append((c[q[0]], c[q[2]], c[q[3]]))
    return tris


CUBE = cube((1, 1, 1), (6, 6, 6))


def binary(tris, header=b"frepmill fuzz seed", count=None):
    out = header.ljust(80, b"\0")[:80] + struct.pack("<I", len(tris) if count is None else count)
    for t in tris:
        out += struct.pack("<3f", 0, 0, 0)
        for v in t:
            out += struct.pack("<3f", *v)
        out += b"\0\0"
    return out


def ascii(tris, name="seed"):
    s = "solid %s\n" % name
    for t in tris:
        s += " facet normal 0 0 0\n  outer loop\n"
        for v in t:
            s += "   vertex %g %g %g\n" % v
        s += "  endloop\n endfacet\n"
    return (s + "endsolid %s\n" % name).encode()


def main():
    os.makedirs(OUT, exist_ok=True)
    files = {
        "tetra_bin.stl": binary(TETRA),
        "tetra_ascii.stl": ascii(TETRA),
        "cube_bin.stl": binary(CUBE),
        "cube_ascii.stl": ascii(CUBE, "cube"),
        "cube_bin_solid_header.stl": binary(CUBE, header=b"solid cube, but binary"),
        "bad_count.stl": binary(TETRA, count=5),
        "truncated_bin.stl": binary(TETRA)[:-7],
        "nan_bin.stl": binary([((0, 0, 0), (float("nan"), 4, 0), (4, 0, 0))] + TETRA[1:]),
        "huge_bin.stl": binary([((0, 0, 0), (0, 4e7, 0), (4, 0, 0))] + TETRA[1:]),
        "empty_bin.stl": binary([]),
        "empty_ascii.stl": b"solid nothing\nendsolid nothing\n",
        "no_endsolid.stl": ascii(TETRA).rsplit(b"endsolid", 1)[0],
        "quad_facet.stl": ascii(TETRA[:1]).replace(b"  endloop", b"   vertex 1 1 0\n  endloop"),
        "bad_number.stl": ascii(TETRA[:1]).replace(b"vertex 0 4 0", b"vertex 0 4e 0x"),
        "degenerate.stl": ascii([((0, 0, 0), (5, 5, 5), (10, 10, 10))]),
        "open_cube_ascii.stl": ascii(CUBE[:2] + CUBE[4:], "open"),
        "open_cube_bin.stl": binary(CUBE[:2] + CUBE[4:]),
        "not_stl.txt": b"hello, this is not an STL file\n",
    }
    for name, data in files.items():
        with open(os.path.join(OUT, name), "wb") as f:
            f.write(data)
    print("wrote %d files to %s" % (len(files), OUT))


if __name__ == "__main__":
    main()
