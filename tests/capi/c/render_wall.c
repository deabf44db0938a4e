/* Test (a): a C host renders one CAVE wall with each of caveray's three
 * ways to express an off-axis view (perspective + imageRegion from
 * caverayPinholeFromScreen, the "matrix" camera, the "offAxis" camera)
 * through the plain ANARI C API, and writes the mapped color channels.
 * Usage: render_wall SCENE_FILE OUT_DIR. Exit status 0 only if every
 * render succeeded and the status callback saw no error. */
#include <anari/anari.h>
#include <anari/caveray.h>

#include "scene.h"
#include "status.h"

static int render(ANARIDevice dev, ANARIFrame frame, ANARICamera camera,
    const char *dir, const char *name)
{
  uint32_t w = 0, h = 0;
  ANARIDataType type = ANARI_UNKNOWN;
  const void *pixels;
  int ok;
  anariCommitParameters(dev, camera);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariCommitParameters(dev, frame);
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  pixels = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  ok = pixels && type == ANARI_UFIXED8_VEC4 && write_rgba(dir, name, pixels, w, h);
  if (pixels)
    anariUnmapFrame(dev, frame, "channel.color");
  anariRelease(dev, camera);
  return ok;
}

int main(int argc, char **argv)
{
  Scene s;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray3D voxels;
  ANARIArray1D colors, opacities, volumes;
  ANARISpatialField field;
  ANARIVolume volume;
  ANARIWorld world;
  ANARIRenderer renderer;
  ANARIFrame frame;
  ANARICamera camera;
  CaverayPinhole pinhole;
  ANARIDataType color_type = ANARI_UFIXED8_VEC4;
  int ok = 1;

  if (argc != 3 || !scene_load(argv[1], &s)) {
    fprintf(stderr, "usage: render_wall SCENE_FILE OUT_DIR\n");
    return 2;
  }
  lib = anariLoadLibrary("caveray", count_status, "render_wall");
  dev = anariNewDevice(lib, "default");

  voxels = anariNewArray3D(dev, s.voxels, NULL, NULL, ANARI_FLOAT32, s.dims[0],
      s.dims[1], s.dims[2]);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &voxels);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, s.origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, s.spacing);
  anariCommitParameters(dev, field);

  colors = anariNewArray1D(dev, s.colors, NULL, NULL, ANARI_FLOAT32_VEC4, s.ncolors);
  opacities = anariNewArray1D(dev, s.opacities, NULL, NULL, ANARI_FLOAT32, s.nopacities);
  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &colors);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &opacities);
  anariSetParameter(dev, volume, "valueRange", ANARI_FLOAT32_BOX1, s.range);
  anariSetParameter(dev, volume, "unitDistance", ANARI_FLOAT32, &s.unitDistance);
  anariCommitParameters(dev, volume);

  world = anariNewWorld(dev);
  volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  anariCommitParameters(dev, world);

  renderer = anariNewRenderer(dev, "default");
  anariCommitParameters(dev, renderer);

  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, s.size);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &color_type);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);

  /* Strategy 2: ANARI's own perspective camera, widened and cropped. */
  if (caverayPinholeFromScreen(s.ll, s.lr, s.ur, s.eye, &pinhole) != ANARI_STATUS_NO_ERROR) {
    fprintf(stderr, "render_wall: %s\n", caverayLastError());
    ok = 0;
  }
  camera = anariNewCamera(dev, "perspective");
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, pinhole.position);
  anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, pinhole.direction);
  anariSetParameter(dev, camera, "up", ANARI_FLOAT32_VEC3, pinhole.up);
  anariSetParameter(dev, camera, "fovy", ANARI_FLOAT32, &pinhole.fovy);
  anariSetParameter(dev, camera, "aspect", ANARI_FLOAT32, &pinhole.aspect);
  anariSetParameter(dev, camera, "imageRegion", ANARI_FLOAT32_BOX2, pinhole.imageRegion);
  ok &= render(dev, frame, camera, argv[2], "perspective");

  /* Strategy 1: the host's OpenGL matrices as they are. */
  camera = anariNewCamera(dev, "matrix");
  anariSetParameter(dev, camera, "view", ANARI_FLOAT32_MAT4, s.view);
  anariSetParameter(dev, camera, "proj", ANARI_FLOAT32_MAT4, s.proj);
  ok &= render(dev, frame, camera, argv[2], "matrix");

  /* caveray's native off-axis camera: the wall and the eye. */
  camera = anariNewCamera(dev, "offAxis");
  anariSetParameter(dev, camera, "lowerLeft", ANARI_FLOAT32_VEC3, s.ll);
  anariSetParameter(dev, camera, "lowerRight", ANARI_FLOAT32_VEC3, s.lr);
  anariSetParameter(dev, camera, "upperRight", ANARI_FLOAT32_VEC3, s.ur);
  anariSetParameter(dev, camera, "eye", ANARI_FLOAT32_VEC3, s.eye);
  ok &= render(dev, frame, camera, argv[2], "offAxis");

  anariRelease(dev, frame);
  anariRelease(dev, renderer);
  anariRelease(dev, world);
  anariRelease(dev, volumes);
  anariRelease(dev, volume);
  anariRelease(dev, opacities);
  anariRelease(dev, colors);
  anariRelease(dev, field);
  anariRelease(dev, voxels);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  scene_free(&s);
  return ok && status_count == 0 ? 0 : 1;
}
