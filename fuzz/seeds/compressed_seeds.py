#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""Write the seeds of the content-comparing fuzz targets (fuzz/FuzzCompressed.h):
compressed streams of the samples those targets hold, made with Python's own
gzip and zlib modules rather than with voxhap or the targets' zlib calls, in
several shapes: compression levels 0 (stored blocks), 1 and 9, a gzip member
with a file name, one with a header CRC (FHCRC), two concatenated members.

    python3 fuzz/seeds/compressed_seeds.py    (from the project's root)
"""
import gzip
import struct
import zlib
from pathlib import Path

NX, NY, NZ = 9, 7, 5  # kCompressedNx, Ny, Nz


def samples():
    out = bytearray()
    for k in range(NZ):
        for j in range(NY):
            for i in range(NX):
                out += struct.pack("<h", (i * 73 + j * 151 + k * 233) % 1500 - 1000)
    return bytes(out)


def nifti(data):
    """A single-file NIfTI-1 (348-byte header, empty extension flag, samples)."""
    h = bytearray(348)
    struct.pack_into("<i", h, 0, 348)                              # sizeof_hdr
    struct.pack_into("<8h", h, 40, 3, NX, NY, NZ, 1, 1, 1, 1)      # dim
    struct.pack_into("<hh", h, 70, 4, 16)                          # datatype INT16, bitpix
    struct.pack_into("<8f", h, 76, 1, 0.75, 0.75, 2.5, 0, 0, 0, 0)  # pixdim
    struct.pack_into("<f", h, 108, 352)                            # vox_offset
    h[123] = 2                                                     # xyzt_units: mm
    struct.pack_into("<h", h, 254, 1)                              # sform_code: scanner
    struct.pack_into("<4f", h, 280, -0.75, 0, 0, 20)               # srow_x
    struct.pack_into("<4f", h, 296, 0, -0.75, 0, 30)               # srow_y
    struct.pack_into("<4f", h, 312, 0, 0, 2.5, 10)                 # srow_z
    h[344:348] = b"n+1\0"
    return bytes(h) + bytes(4) + data


def gz(data, level=6, name=None):
    if name is None:
        return gzip.compress(data, compresslevel=level, mtime=0)
    import io
    buf = io.BytesIO()
    with gzip.GzipFile(filename=name, mode="wb", compresslevel=level, fileobj=buf, mtime=0) as f:
        f.write(data)
    return buf.getvalue()


def gz_fhcrc(data):
    """A gzip member with FHCRC set: the header's own CRC-16 (RFC 1952 §2.3.1)."""
    header = bytes([0x1F, 0x8B, 8, 0x02, 0, 0, 0, 0, 0, 255])
    header += struct.pack("<H", zlib.crc32(header) & 0xFFFF)
    c = zlib.compressobj(6, zlib.DEFLATED, -15)
    body = c.compress(data) + c.flush()
    return header + body + struct.pack("<II", zlib.crc32(data), len(data) & 0xFFFFFFFF)


def gzip_seeds(data):
    cut = len(data) // 3 + 1
    return {
        "level6.gz": gz(data),
        "stored.gz": gz(data, 0),
        "level1.gz": gz(data, 1),
        "level9-name.gz": gz(data, 9, "volume.raw"),
        "fhcrc.gz": gz_fhcrc(data),
        "two-members.gz": gz(data[:cut]) + gz(data[cut:]),
    }


def main():
    root = Path(__file__).resolve().parent
    raw = samples()
    for target, seeds in {
        "NrrdCompressed": gzip_seeds(raw),
        "NiftiCompressed": gzip_seeds(nifti(raw)),
        "MetaImageCompressed": {
            "zlib6.z": zlib.compress(raw, 6),
            "zlib0.z": zlib.compress(raw, 0),
            "zlib9.z": zlib.compress(raw, 9),
            "gzip6.gz": gz(raw),
        },
    }.items():
        for name, data in seeds.items():
            (root / target / name).write_bytes(data)


if __name__ == "__main__":
    main()
