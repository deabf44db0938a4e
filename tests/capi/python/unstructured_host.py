"""A Python host of caveray's unstructured field through pynari: one
hexahedron (VTK's vertex order) with a value at each corner, cell.type as
UINT32 because pynari has no 8-bit integer type, every array a numpy
array pynari wraps itself.

    unstructured_host.py SCENE.json OUT.rgba

SCENE.json (written by tests/capi/python_host.rs) holds the corners, their
values, the colour map, the camera and the frame size. OUT.rgba receives
the frame's RGBA8 pixels, bottom row first. ANARI_LIBRARY=caveray
chooses the device, CAVERAY_BACKEND its backend.
"""

import json
import sys

import numpy as np
import pynari as anari


def main(scene_path, out_path):
    with open(scene_path) as f:
        scene = json.load(f)
    width, height = scene["size"]
    device = anari.newDevice("default")

    field = device.newSpatialField("unstructured")
    positions = np.array(scene["corners"], dtype=np.float32)
    field.setParameter("vertex.position", anari.ARRAY1D, device.newArray(anari.float3, positions))
    field.setParameter("vertex.data", anari.ARRAY1D,
                       device.newArray(anari.float, np.array(scene["values"], dtype=np.float32)))
    field.setParameter("index", anari.ARRAY1D,
                       device.newArray(anari.uint, np.arange(8, dtype=np.uint32)))
    field.setParameter("cell.index", anari.ARRAY1D,
                       device.newArray(anari.uint, np.array([0], dtype=np.uint32)))
    field.setParameter("cell.type", anari.ARRAY1D,
                       device.newArray(anari.uint, np.array([12], dtype=np.uint32)))
    field.commitParameters()

    volume = device.newVolume("transferFunction1D")
    volume.setParameter("value", anari.SPATIAL_FIELD, field)
    colors = np.array(scene["colors"], dtype=np.float32)
    volume.setParameter("color", anari.ARRAY, device.newArray(anari.float4, colors))
    volume.setParameter("unitDistance", anari.FLOAT32, scene["unit_distance"])
    volume.commitParameters()

    world = device.newWorld()
    world.setParameterArray("volume", anari.VOLUME, [volume])
    world.commitParameters()

    camera = device.newCamera("perspective")
    camera.setParameter("position", anari.float3, tuple(scene["position"]))
    camera.setParameter("direction", anari.float3, tuple(scene["direction"]))
    camera.setParameter("up", anari.float3, tuple(scene["up"]))
    camera.setParameter("fovy", anari.FLOAT32, scene["fovy"])
    camera.setParameter("aspect", anari.FLOAT32, width / height)
    camera.commitParameters()

    renderer = device.newRenderer("default")
    renderer.setParameter("background", anari.float4, (0.0, 0.0, 0.0, 1.0))
    renderer.commitParameters()

    frame = device.newFrame()
    frame.setParameter("size", anari.uint2, (width, height))
    frame.setParameter("channel.color", anari.DATA_TYPE, anari.UFIXED8_VEC4)
    frame.setParameter("world", anari.OBJECT, world)
    frame.setParameter("camera", anari.OBJECT, camera)
    frame.setParameter("renderer", anari.OBJECT, renderer)
    frame.commitParameters()
    frame.render()
    pixels = np.array(frame.get("channel.color"), dtype=np.uint8).reshape(-1)
    if pixels.size != 4 * width * height:
        print(f"unstructured_host: channel.color holds {pixels.size} bytes, "
              f"expected {4 * width * height}", file=sys.stderr)
        return 1
    pixels.tofile(out_path)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
