#!/usr/bin/env python3
"""Writes the bomb files of issue 23 (small files that ask for huge work) into this folder.

Each must be refused within a second by `cell`, naming the file, the entity or field and the
limit (tests/bombs.rs). Run from anywhere: python3 tests/data/bombs/make_bombs.py
"""
import pathlib
import struct

HERE = pathlib.Path(__file__).resolve().parent


def dxf(blocks, entities, version="AC1009"):
    """A minimal ASCII DXF (R12 groups unless `version` says) with BLOCKS and ENTITIES."""
    out = ["0", "SECTION", "2", "HEADER", "9", "$ACADVER", "1", version, "0", "ENDSEC"]
    out += ["0", "SECTION", "2", "BLOCKS"]
    for name, body in blocks:
        out += ["0", "BLOCK", "8", "0", "2", name, "70", "0", "10", "0", "20", "0", "30", "0",
                "3", name] + body + ["0", "ENDBLK", "8", "0"]
    out += ["0", "ENDSEC", "0", "SECTION", "2", "ENTITIES"] + entities
    out += ["0", "ENDSEC", "0", "EOF"]
    return "\n".join(out) + "\n"


def polyline(handle, layer, vertices, closed=True):
    """POLYLINE with VERTEXes (x, y, bulge)."""
    g = ["0", "POLYLINE", "5", handle, "8", layer, "66", "1", "10", "0", "20", "0", "30", "0",
         "70", "1" if closed else "0"]
    for x, y, b in vertices:
        g += ["0", "VERTEX", "8", layer, "10", repr(x), "20", repr(y), "30", "0", "42", repr(b)]
    return g + ["0", "SEQEND", "8", layer]


def insert(handle, layer, block, cols, rows, spacing):
    return ["0", "INSERT", "5", handle, "8", layer, "2", block, "10", "0", "20", "0", "30", "0",
            "70", str(cols), "71", str(rows), "44", repr(spacing), "45", repr(spacing)]


def circle(handle, layer, x, y, r):
    return ["0", "CIRCLE", "5", handle, "8", layer, "10", repr(x), "20", repr(y), "30", "0",
            "40", repr(r)]


# 8 nested 10 × 10 INSERT arrays of a triangle: 10^16 placed entities.
blocks = [("L0", polyline("10", "0", [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)]))]
for k in range(1, 9):
    blocks.append((f"L{k}", insert(f"{k + 10:X}", "0", f"L{k - 1}", 10, 10, 2.0 * 10 ** (k - 1))))
(HERE / "nested-inserts.dxf").write_text(dxf(blocks, insert("2A", "PARTS", "L8", 1, 1, 0.0)))

# A closed polyline of two bulge-1 arcs: a circle of radius 1e14 mm (~10^8 points at 0.005 mm).
(HERE / "huge-bulge.dxf").write_text(
    dxf([], polyline("2B", "PARTS", [(0.0, 0.0, 1.0), (2e14, 0.0, 1.0)])))

# Twelve circles of radius 9e6 mm, each ~94 000 points at 0.005 mm: over 10^6 together.
ents = []
for i in range(12):
    ents += circle(f"{0x30 + i:X}", "PARTS", 0.0, 0.0, 9e6 - i)
(HERE / "many-points.dxf").write_text(dxf([], ents))

# A full ELLIPSE of major radius 1e12 mm (R2000: ELLIPSE is R13 on); the reader used to
# flatten it to 10^5 points, silently coarser than the drawing's tolerance.
(HERE / "huge-ellipse.dxf").write_text(dxf([], [
    "0", "ELLIPSE", "5", "2C", "8", "PARTS", "10", "0.0", "20", "0.0", "30", "0.0",
    "11", "1e12", "21", "0.0", "31", "0.0", "40", "0.5", "41", "0.0", "42", "6.283185307179586",
], version="AC1015"))

# A JSON layout on a sheet of 10^12 x 10^12 mm: a thermal raster of 6e22 cells at 4 mm.
(HERE / "huge-sheet.json").write_text(
    '{"sheet": [1e12, 1e12],\n "parts": [{"outer": {"points": [[10, 10], [60, 10], [60, 60]]}}]}\n')

# Wing specs: the Table 2 wing with 200 000 lifting-line stations, or 1e-9 mm layers.
table2 = (HERE / "../../../config/wings/gwing-table2.yaml").read_text()
table2 = table2.replace("airfoil: ../airfoils/ag24.dat", "airfoil: ../../../config/airfoils/ag24.dat")
assert "stations: 400 " in table2 and "layer_height_mm: 0.2\n" in table2
(HERE / "wing-stations.yaml").write_text(table2.replace("stations: 400 ", "stations: 200000 "))
(HERE / "wing-layer-height.yaml").write_text(
    table2.replace("\n  layer_height_mm: 0.2\n", "\n  layer_height_mm: 1.0e-9\n"))

# WAAM process profiles (every key optional).
(HERE / "waam-layer-height.yaml").write_text("# issue 23 bomb: 1e-9 mm layers\nlayer_height_mm: 1.0e-9\n")
(HERE / "waam-perimeters.yaml").write_text("# issue 23 bomb: 10^12 perimeter loops\nperimeters: 1000000000000\n")

# A binary STL whose header announces 2^32 − 1 triangles and holds one.
tri = struct.pack("<12fH", 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0)
(HERE / "huge-count.stl").write_bytes(b"\0" * 80 + struct.pack("<I", 0xFFFFFFFF) + tri)
