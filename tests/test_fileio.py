"""The files seahaze writes (``seahaze.fileio``): what each format's encoder was asked for, read
back from the file itself, and that every value survives the trip.

The encoders' speed and sizes are measured in scripts/bench_writes.py, not here.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np
import OpenEXR
from PIL import Image

from seahaze import fileio

SIZE = (96, 40)  # width, height: three ZIP blocks of 16 lines, 40 lines uncompressed


def grainy_radiance(seed: int = 3) -> np.ndarray:
    """Float32 radiance with Monte Carlo-like grain, and the values a render can hold at its
    edges: zero, a denormal, a huge value."""
    rng = np.random.default_rng(seed)
    width, height = SIZE
    out = rng.gamma(2.0, 0.05, size=(height, width, 3)).astype(np.float32)
    out[0, 0] = (0.0, np.float32(1e-42), np.float32(3e38))
    return out


def png_zlib_level(path: Path) -> int:
    """The FLEVEL field of the PNG's zlib stream (RFC 1950: 0 fastest, 1 fast, 2 default,
    3 maximum), from the first IDAT chunk's first two bytes."""
    data = path.read_bytes()
    at = 8
    while at < len(data):
        (length,) = struct.unpack(">I", data[at : at + 4])
        kind = data[at + 4 : at + 8]
        if kind == b"IDAT":
            cmf, flg = data[at + 8], data[at + 9]
            assert (cmf * 256 + flg) % 31 == 0, "not a zlib header"
            return flg >> 6
        at += 12 + length
    raise AssertionError("no IDAT chunk")


def exr_compression(path: Path) -> int:
    """The file's compression, as OpenEXR itself reads the header."""
    with OpenEXR.File(str(path)) as exr:
        return int(exr.header()["compression"])


def test_radiance_exr_is_uncompressed_and_bit_exact(tmp_path: Path) -> None:
    radiance = grainy_radiance()
    path = tmp_path / "radiance.exr"
    fileio.write_rgb_exr(path, radiance)
    assert exr_compression(path) == int(OpenEXR.NO_COMPRESSION)
    back = fileio.read_exr(path)["RGB"]
    assert back.dtype == np.float32
    assert np.array_equal(back.view(np.uint32), radiance.view(np.uint32))
    # Uncompressed: 40 chunks of one line, each its y and size ahead of 96 × 3 floats.
    width, height = SIZE
    assert path.stat().st_size > height * (8 + width * 3 * 4)


def test_smooth_maps_are_zip_compressed_and_exact(tmp_path: Path) -> None:
    width, height = SIZE
    distance = np.linspace(50.0, 9000.0, width * height, dtype=np.float32).reshape(height, width)
    distance[:5] = np.inf  # sky rows
    path = tmp_path / "depth.exr"
    fileio.write_exr(path, {"Z": distance})
    assert exr_compression(path) == int(OpenEXR.ZIP_COMPRESSION)
    assert np.array_equal(fileio.read_exr(path)["Z"], distance)
    assert path.stat().st_size < distance.nbytes


def test_uncompressed_exr_passes_the_resume_check_until_truncated(tmp_path: Path) -> None:
    path = tmp_path / "radiance.exr"
    fileio.write_rgb_exr(path, grainy_radiance())
    assert fileio.check_exr(path, SIZE, {"R", "G", "B"}) is None
    data = path.read_bytes()
    path.write_bytes(data[:-100])  # the last line's pixels cut short
    assert fileio.check_exr(path, SIZE, {"R", "G", "B"}) == "is truncated"


def test_png_holds_every_pixel_at_the_chosen_zlib_level(tmp_path: Path) -> None:
    rng = np.random.default_rng(5)
    width, height = SIZE
    image8 = rng.integers(0, 256, size=(height, width, 3), dtype=np.uint8)
    path = tmp_path / "image.png"
    fileio.write_png(path, image8)
    assert np.array_equal(np.asarray(Image.open(path).convert("RGB")), image8)
    assert fileio.check_png(path, SIZE) is None
    # zlib's FLEVEL: 1 for levels 2-5 (RFC 1950), 2 for Pillow's default 6.
    assert fileio.PNG_COMPRESS_LEVEL in range(2, 6)
    assert png_zlib_level(path) == 1
    # The IDAT stream inflates to the filtered rows: one filter byte per row of 3·width bytes.
    raw = path.read_bytes()
    start = raw.index(b"IDAT") + 4
    (length,) = struct.unpack(">I", raw[start - 8 : start - 4])
    assert len(zlib.decompress(raw[start : start + length])) == height * (1 + 3 * width)
