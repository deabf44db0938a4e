"""A volume rendered by caveray from Python, through pynari.

A field made with numpy (two interlocking tori), a transfer function whose
colours carry the opacity in their alpha, a perspective camera, and the
image saved as a PNG. From the repository root:

    cargo build --release
    python3 -m venv .venv && .venv/bin/pip install pynari numpy
    ANARI_LIBRARY=caveray LD_LIBRARY_PATH=target/release \\
        .venv/bin/python examples/python/volume.py

CAVERAY_BACKEND=cpu or gpu in the environment picks caveray's renderer
(default: auto).
"""

import os
import struct
import sys
import zlib

import numpy as np
import pynari as anari

OUT = "out/examples/python"
SIZE = (512, 384)


def tori(n=96):
    """Distance to two interlocking tori, mapped to [0, 1] (1 on the rings)."""
    z, y, x = np.mgrid[-1:1:n * 1j, -1:1:n * 1j, -1:1:n * 1j]
    major, minor = 0.5, 0.16
    a = np.hypot(np.hypot(x + 0.25, y) - major, z)
    b = np.hypot(np.hypot(x - 0.25, z) - major, y)
    d = np.minimum(a, b)
    return np.clip(1.0 - d / minor, 0.0, 1.0).astype(np.float32)


def write_png(path, rgba, width, height):
    """RGBA8 rows, the first one the image's bottom, as a PNG."""
    rows = rgba.reshape(height, width, 4)[::-1]
    raw = b"".join(b"\x00" + row.tobytes() for row in rows)

    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body))

    header = struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
                + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))


def main():
    device = anari.newDevice("default")

    field = device.newSpatialField("structuredRegular")
    voxels = tori()
    n = voxels.shape[0]
    field.setParameter("data", anari.ARRAY3D, device.newArray(anari.float, voxels))
    field.setParameter("origin", anari.float3, (-1, -1, -1))
    field.setParameter("spacing", anari.float3, (2 / (n - 1),) * 3)
    field.commitParameters()

    # Alpha is the opacity: transparent outside the rings, opaque on them.
    colors = np.array([[0.1, 0.2, 0.6, 0.0],
                       [0.2, 0.6, 1.0, 0.3],
                       [1.0, 0.7, 0.2, 1.0]], dtype=np.float32)
    volume = device.newVolume("transferFunction1D")
    volume.setParameter("value", anari.SPATIAL_FIELD, field)
    volume.setParameter("color", anari.ARRAY, device.newArray(anari.float4, colors))
    volume.setParameter("unitDistance", anari.FLOAT32, 0.05)
    volume.commitParameters()

    world = device.newWorld()
    world.setParameterArray("volume", anari.VOLUME, [volume])
    world.commitParameters()

    camera = device.newCamera("perspective")
    camera.setParameter("position", anari.float3, (0.4, 0.8, 2.0))
    camera.setParameter("direction", anari.float3, (-0.4, -0.8, -2.0))
    camera.setParameter("up", anari.float3, (0, 1, 0))
    camera.setParameter("aspect", anari.FLOAT32, SIZE[0] / SIZE[1])
    camera.commitParameters()

    renderer = device.newRenderer("default")
    renderer.setParameter("background", anari.float4, (0.05, 0.05, 0.08, 1.0))
    renderer.commitParameters()

    frame = device.newFrame()
    frame.setParameter("size", anari.uint2, SIZE)
    frame.setParameter("channel.color", anari.DATA_TYPE, anari.UFIXED8_RGBA_SRGB)
    frame.setParameter("world", anari.OBJECT, world)
    frame.setParameter("camera", anari.OBJECT, camera)
    frame.setParameter("renderer", anari.OBJECT, renderer)
    frame.commitParameters()
    frame.render()
    pixels = np.array(frame.get("channel.color"), dtype=np.uint8).reshape(-1)

    os.makedirs(OUT, exist_ok=True)
    path = os.path.join(OUT, "volume.png")
    write_png(path, pixels, *SIZE)
    rgb = pixels.reshape(-1, 4)[:, :3].astype(np.int32)
    lit = int(np.count_nonzero(np.abs(rgb - rgb[0]).max(axis=1) > 20))
    print(f"wrote {path}: {SIZE[0]}x{SIZE[1]}, the volume on {lit} pixels")
    return 0 if lit > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
