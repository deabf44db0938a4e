"""A Python host of caveray through pynari, as a visualization scientist
writes one: numpy arrays, object lists pynari builds itself (element type
ANARI_OBJECT), a colour map whose alpha is the opacity, a background
gradient as an ARRAY1D, and the frame read back with frame.get.

    volume_host.py SCENE.json OUT.rgba

SCENE.json (written by tests/capi/python_host.rs) names the voxels (raw
FLOAT32, x fastest), the grid, the colour map, the camera and the frame
size. OUT.rgba receives the frame's RGBA8 pixels, bottom row first, as
channel.color holds them. ANARI_LIBRARY=caveray chooses the device.

With "stereo" in SCENE.json ({"ipd": metres, "modes": [...]}), the camera
then renders each stereo mode, eyes ipd apart, into OUT.<mode>.rgba: a
sideBySide frame twice as wide, a topBottom one twice as high.
"""

import json
import sys

import numpy as np
import pynari as anari


def main(scene_path, out_path):
    with open(scene_path) as f:
        scene = json.load(f)
    nx, ny, nz = scene["dims"]
    voxels = np.fromfile(scene["voxels"], dtype=np.float32).reshape(nz, ny, nx)
    width, height = scene["size"]

    device = anari.newDevice("default")

    field = device.newSpatialField("structuredRegular")
    field.setParameter("data", anari.ARRAY3D, device.newArray(anari.float, voxels))
    field.setParameter("origin", anari.float3, tuple(scene["origin"]))
    field.setParameter("spacing", anari.float3, tuple(scene["spacing"]))
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

    # As pynari's volume sample gives it: two colours, bottom first, in an
    # ARRAY1D (a 1 x 2 image).
    gradient = np.array(scene["gradient"], dtype=np.float32)
    renderer = device.newRenderer("default")
    renderer.setParameter("background", anari.ARRAY,
                          device.newArray(anari.float4, gradient))
    renderer.commitParameters()

    frame = device.newFrame()
    frame.setParameter("size", anari.uint2, (width, height))
    frame.setParameter("channel.color", anari.DATA_TYPE, anari.UFIXED8_VEC4)
    frame.setParameter("world", anari.OBJECT, world)
    frame.setParameter("camera", anari.OBJECT, camera)
    frame.setParameter("renderer", anari.OBJECT, renderer)
    frame.commitParameters()
    if not render(frame, width, height, out_path):
        return 1

    stereo = scene.get("stereo")
    if stereo:
        camera.setParameter("interpupillaryDistance", anari.FLOAT32, stereo["ipd"])
        for mode in stereo["modes"]:
            camera.setParameter("stereoMode", anari.STRING, mode)
            camera.commitParameters()
            w = 2 * width if mode == "sideBySide" else width
            h = 2 * height if mode == "topBottom" else height
            frame.setParameter("size", anari.uint2, (w, h))
            frame.commitParameters()
            if not render(frame, w, h, out_path[:-len(".rgba")] + f".{mode}.rgba"):
                return 1
    return 0


def render(frame, width, height, out_path):
    frame.render()
    pixels = np.array(frame.get("channel.color"), dtype=np.uint8).reshape(-1)
    if pixels.size != 4 * width * height:
        print(f"volume_host: channel.color holds {pixels.size} bytes, "
              f"expected {4 * width * height}", file=sys.stderr)
        return False
    pixels.tofile(out_path)
    print(f"volume_host: wrote {width}x{height} to {out_path}")
    return True


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:]))
