#!/usr/bin/env python3
"""Writes the starting corpus of every libFuzzer harness (tests/fuzz) into OUT/<harness>/: small
hand-made inputs of each format, and excerpts of the real files in the shared test data (the
first lines of the FARO and Leica scans, the PLY header of a real cloud, the meshes with their
materials). Used by tools/fuzz.sh; idempotent."""

from __future__ import annotations

import hashlib
import json
import os
import struct
import sys
import zlib


def tiny_png(width: int = 2, height: int = 2) -> bytes:
    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    rows = b"".join(b"\x00" + bytes([200, 100, 50] * width) for _ in range(height))
    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b"")


def head_lines(path: str, count: int) -> bytes:
    lines = []
    with open(path, "rb") as f:
        for _ in range(count):
            line = f.readline()
            if not line:
                break
            lines.append(line)
    return b"".join(lines)


def ply_header_and_body(path: str, vertices: int) -> bytes:
    """The header of a binary PLY and its first `vertices` records (x y z float, r g b uchar)."""
    with open(path, "rb") as f:
        data = f.read(1 << 16)
    end = data.index(b"end_header\n") + len(b"end_header\n")
    return data[:end] + data[end : end + 15 * vertices]


def seeds(shared: str) -> dict[str, list[bytes]]:
    scans = os.path.join(shared, "scans")
    meshes = os.path.join(shared, "meshes")
    out: dict[str, list[bytes]] = {}

    xyz = b"0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0.5 0 0 255\n"
    out["text_scan_fuzzer"] = [
        b"\x00" + xyz,
        b"\x00" + b"//X Y Z R G B\n" + xyz,
        b"\x01" + b"3\n" + b"0 0 0 -120 255 0 0\n1 0 0 5 0 255 0\n0 1 0 9 0 0 255\n",
        b"\x02" + b"# scanner 1 2 3\n" + xyz,
        b"\x03" + b"x,y,z,r,g,b\n0,0,0,1,2,3\n1e3,-2.5e-2,7,4,5,6\n",
        b"\x04" + b"0 0 0 0.5 10 20 30\n1 1 1 0.25 40 50 60\n",
        b"\x0c" + b"0 0 0 0 0 1 10 20 30\n1 1 1 0 1 0 40 50 60\n",
    ]
    if os.path.isfile(os.path.join(scans, "pumpA_xyzrgb.xyz")):
        out["text_scan_fuzzer"].append(b"\x00" + head_lines(os.path.join(scans, "pumpA_xyzrgb.xyz"), 40))
    if os.path.isfile(os.path.join(scans, "pumpA.pts")):
        out["text_scan_fuzzer"].append(b"\x01" + head_lines(os.path.join(scans, "pumpA.pts"), 40))
    if os.path.isfile(os.path.join(scans, "autzen_trim_xyzrgb.xyz")):
        out["text_scan_fuzzer"].append(b"\x00" + head_lines(os.path.join(scans, "autzen_trim_xyzrgb.xyz"), 40))

    ascii_ply = (
        b"ply\nformat ascii 1.0\ncomment scanner 0 0 1\nelement vertex 4\nproperty float x\nproperty float y\n"
        b"property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
        b"element face 2\nproperty list uchar int vertex_indices\nend_header\n"
        b"0 0 0 255 0 0\n1 0 0 0 255 0\n1 1 0 0 0 255\n0 1 0 9 9 9\n3 0 1 2\n3 0 2 3\n"
    )
    vertex = struct.pack("<fffBBB", 0, 0, 0, 1, 2, 3) + struct.pack("<fffBBB", 1, 0, 0, 4, 5, 6) + struct.pack(
        "<fffBBB", 0, 1, 0, 7, 8, 9
    )
    binary_le = (
        b"ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
        b"property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
        b"element face 1\nproperty list uchar uint vertex_indices\nend_header\n"
        + vertex
        + b"\x03"
        + struct.pack("<III", 0, 1, 2)
    )
    binary_be = (
        b"ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty double x\nproperty double y\n"
        b"property double z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float s\n"
        b"property float t\nend_header\n"
        + struct.pack(">dddfffff", 1, 2, 3, 0, 0, 1, 0.5, 0.5)
        + struct.pack(">dddfffff", 4, 5, 6, 0, 1, 0, 0.25, 0.75)
    )
    out["ply_fuzzer"] = [ascii_ply, binary_le, binary_be]
    if os.path.isfile(os.path.join(scans, "office1.ply")):
        out["ply_fuzzer"].append(ply_header_and_body(os.path.join(scans, "office1.ply"), 30))

    png = tiny_png()
    quad = (
        b"mtllib m.mtl\no quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
        b"vn 0 0 1\nusemtl tex\nf 1/1/1 2/2/1 3/3/1 4/4/1\ng back\nusemtl red\nf -1 -2 -3\n"
    )
    mtl = b"newmtl tex\nKd 1 1 1\nmap_Kd t.png\nnewmtl red\nKd 0.8 0.1 0.1\n"
    out["obj_mtl_fuzzer"] = [quad + b"\n--mtl--\n" + mtl + b"\n--tex--\n" + png, quad]
    for folder, obj, mtl_name in (
        ("cornell_box", "CornellBox-Original.obj", "CornellBox-Original.mtl"),
        ("crate", "crate.obj", "crate.mtl"),
    ):
        obj_path = os.path.join(meshes, folder, obj)
        if os.path.isfile(obj_path):
            text = open(obj_path, "rb").read()[:4096].replace(b"mtllib " + mtl_name.encode(), b"mtllib m.mtl")
            mtl_text = open(os.path.join(meshes, folder, mtl_name), "rb").read()
            out["obj_mtl_fuzzer"].append(text + b"\n--mtl--\n" + mtl_text + b"\n--tex--\n" + png)

    perspective = {
        "type": "PERSP",
        "matrix_world": [[0, 0, 1, 0], [1, 0, 0, 0], [0, 1, 0, 1.2], [0, 0, 0, 1]],
        "resolution": [16, 10],
        "lens": 24.0,
        "sensor_width": 36.0,
        "sensor_height": 24.0,
        "sensor_fit": "AUTO",
        "shift_x": 0.1,
        "shift_y": 0.0,
        "clip_start": 0.01,
        "clip_end": 100.0,
    }
    panorama = {
        "type": "PANO_EQUIRECT",
        "matrix_world": [[1, 0, 0, 0.2], [0, 1, 0, 0.1], [0, 0, 1, 1.0], [0, 0, 0, 1]],
        "resolution": [24, 12],
        "latitude_min": -1.2,
        "latitude_max": 1.2,
        "longitude_min": -3.0,
        "longitude_max": 3.0,
    }
    blender_pano = {"type": "PANO", "panorama_type": "EQUIRECTANGULAR", "resolution": [8, 4]}
    out["camera_fuzzer"] = [
        json.dumps(perspective).encode(),
        json.dumps(panorama).encode(),
        json.dumps(blender_pano).encode(),
        json.dumps({**perspective, "sensor_fit": "VERTICAL", "pixel_aspect_x": 2.0}).encode(),
        b"{}",
    ]

    probe = {
        "file": "probe_00000.exr",
        "position": [0.5, 0.5, 1.0],
        "resolution": 64,
        "coverage": {"empty": 0.0, "inferred": 0.0, "surface": 1.0, "unknown": 0.0},
        "memory_bytes": 73728,
    }
    grid = {
        "format": "lfprobe-probe-set",
        "format_version": 1,
        "world_offset": [0, 0, 0],
        "layout": "grid",
        "grid": {"counts": [2, 1, 1], "origin": [0.5, 0.5, 1.0], "spacing": [1.0, 1.0, 1.0]},
        "probes": [probe, {**probe, "file": "probe_00001.exr", "position": [1.5, 0.5, 1.0]}],
        "bake": {"resolution": 64, "source": "point cloud"},
        "sources": [],
    }
    positions = {**grid, "layout": "positions"}
    del positions["grid"]
    out["manifest_fuzzer"] = [json.dumps(grid).encode(), json.dumps(positions).encode()]

    # Cache entries in the harness's structured form (odd first byte): point count, flags (1:
    # colours), origin and scanner, positions, colours.
    points = [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)]
    arrays = b"".join(struct.pack("<fff", *p) for p in points) + b"".join(
        struct.pack("<fff", 0.5, 0.25, 0.125) for _ in points
    )
    structured = b"\x01" + struct.pack("<QI", 4, 1) + struct.pack("<6d", 0, 0, 0, 0, 0, 0) + arrays
    out["scan_cache_fuzzer"] = [structured, b"\x00LFPCACHE\x02\x00\x00\x00", b"\x01" + struct.pack("<QI", 0, 0)]

    # Prepared-cloud payloads in the harness's structured form (odd first byte) for its cloud of
    # 800 points: the geometry's arrays, then the hierarchy: none, or one level of one cell.
    n = 800

    def array(fmt, values):
        return struct.pack("<Q", len(values)) + b"".join(struct.pack("<" + fmt, *v) for v in values)

    geometry = (array("fff", [(0.0, 0.0, 1.0)] * n) + array("f", [(0.05,)] * n) + array("B", [(1,)] * n)
                + array("bbbB", []) + array("I", [(i,) for i in range(n)]))
    head = struct.pack("<ff", 0.0, 0.0) + struct.pack("<fff", 0.0, 0.0, 0.0) + struct.pack("<f", 2.0)
    order = array("I", [(i,) for i in range(n)])
    surfel = struct.pack("<ffffffffffIBB", 0.5, 0.5, 0.5, 0.0, 0.0, 1.0, 0.5, 0.5, 0.5, 0.1, n, 4, 1)
    one_level = (struct.pack("<Q", 1) + struct.pack("<if", 0, 0.1) + array("Q", [(0,)])
                 + array("I", [(0,), (n,)]) + array("I", []) + array("I", [(0,), (1,)])
                 + struct.pack("<Q", 1) + surfel)
    out["prepared_cloud_fuzzer"] = [b"\x01" + geometry + head + order + struct.pack("<Q", 0),
                                    b"\x01" + geometry + head + order + one_level,
                                    b"\x00LFPPREP1\x01\x00\x00\x00"]
    # Spatial clouds: the harness's genuine file as it is (odd first byte, nothing written over
    # its sections), its sections' first bytes zeroed or all ones, and a bare magic.
    out["spatial_cloud_fuzzer"] = [b"\x01", b"\x01" + bytes(64), b"\x01" + b"\xff" * 4096,
                                   b"\x00LFPSPAT1\x01\x00\x00\x00"]
    return out


def main() -> int:
    if len(sys.argv) != 3:
        print("usage: fuzz_seeds.py SHARED_DATA OUT", file=sys.stderr)
        return 2
    shared, out = sys.argv[1], sys.argv[2]
    for harness, inputs in seeds(shared).items():
        folder = os.path.join(out, harness)
        os.makedirs(folder, exist_ok=True)
        for data in inputs:
            # Named by content, as libFuzzer names what it adds.
            with open(os.path.join(folder, hashlib.sha1(data).hexdigest()), "wb") as f:
                f.write(data)
    return 0


if __name__ == "__main__":
    sys.exit(main())
