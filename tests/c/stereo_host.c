/* A host using ANARI_KHR_CAMERA_STEREO through the C API: it checks that
 * the device reports the extension, renders a perspective camera's left
 * and right eyes as frames of their own, then both in one sideBySide
 * frame twice as wide. Usage: stereo_host OUT_DIR. Writes
 * OUT_DIR/{left,right,pair}.rgba (RGBA8, lower-left first); exit status 0
 * only if every render succeeded and no warning or error was reported. */
#include <anari/anari.h>

#include <string.h>

#include "output.h"
#include "status.h"

#define W 48
#define H 48

/* Renders `frame` and writes its colour to DIR/NAME.rgba. */
static int render(ANARIDevice dev, ANARIFrame frame, const char *dir, const char *name,
    uint32_t w, uint32_t h)
{
  uint32_t mw = 0, mh = 0;
  ANARIDataType type = ANARI_UNKNOWN;
  const void *pixels;
  int ok;
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  pixels = anariMapFrame(dev, frame, "channel.color", &mw, &mh, &type);
  if (!pixels || mw != w || mh != h || type != ANARI_UFIXED8_VEC4) {
    fprintf(stderr, "stereo_host: no %ux%u image for %s\n", w, h, name);
    return 0;
  }
  ok = write_rgba(dir, name, pixels, w, h);
  anariUnmapFrame(dev, frame, "channel.color");
  return ok;
}

int main(int argc, char **argv)
{
  static float voxels[8 * 8 * 8];
  float origin[3] = {-1, -1, -1}, spacing[3] = {2.0f / 7, 2.0f / 7, 2.0f / 7};
  float position[3] = {0, 0, 3}, ipd = 0.3f, opacity = 0.3f;
  float colors[6] = {1.0f, 0.2f, 0.1f, 0.1f, 0.3f, 1.0f};
  uint32_t single[2] = {W, H}, pair[2] = {2 * W, H};
  ANARIDataType rgba8 = ANARI_UFIXED8_VEC4;
  const char *const *extensions = NULL;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray3D data;
  ANARIArray1D color_array, volumes;
  ANARISpatialField field;
  ANARIVolume volume;
  ANARIWorld world;
  ANARIRenderer renderer;
  ANARICamera camera;
  ANARIFrame frame;
  int ok = 1, i, reported = 0;

  if (argc != 2) {
    fprintf(stderr, "usage: stereo_host OUT_DIR\n");
    return 2;
  }
  for (i = 0; i < 8 * 8 * 8; ++i)
    voxels[i] = 0.2f + 0.8f * (float)(i % 8) / 7.0f;
  status_level = ANARI_SEVERITY_WARNING;
  lib = anariLoadLibrary("caveray", count_status, "stereo_host");
  dev = anariNewDevice(lib, "default");
  if (anariGetProperty(dev, dev, "extension", ANARI_STRING_LIST, &extensions, sizeof extensions, ANARI_WAIT) == 1)
    for (i = 0; extensions && extensions[i]; ++i)
      reported |= strcmp(extensions[i], "ANARI_KHR_CAMERA_STEREO") == 0;
  if (!reported) {
    fprintf(stderr, "stereo_host: ANARI_KHR_CAMERA_STEREO is not reported\n");
    ok = 0;
  }

  data = anariNewArray3D(dev, voxels, NULL, NULL, ANARI_FLOAT32, 8, 8, 8);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &data);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, spacing);
  anariCommitParameters(dev, field);
  anariRelease(dev, data);
  color_array = anariNewArray1D(dev, colors, NULL, NULL, ANARI_FLOAT32_VEC3, 2);
  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &color_array);
  anariSetParameter(dev, volume, "opacity", ANARI_FLOAT32, &opacity);
  anariCommitParameters(dev, volume);
  anariRelease(dev, color_array);
  world = anariNewWorld(dev);
  volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  anariCommitParameters(dev, world);
  anariRelease(dev, volumes);
  renderer = anariNewRenderer(dev, "default");
  anariCommitParameters(dev, renderer);
  camera = anariNewCamera(dev, "perspective");
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, position);
  anariSetParameter(dev, camera, "interpupillaryDistance", ANARI_FLOAT32, &ipd);
  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &rgba8);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);

  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, single);
  anariCommitParameters(dev, frame);
  anariSetParameter(dev, camera, "stereoMode", ANARI_STRING, "left");
  anariCommitParameters(dev, camera);
  ok &= render(dev, frame, argv[1], "left", W, H);
  anariSetParameter(dev, camera, "stereoMode", ANARI_STRING, "right");
  anariCommitParameters(dev, camera);
  ok &= render(dev, frame, argv[1], "right", W, H);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, pair);
  anariCommitParameters(dev, frame);
  anariSetParameter(dev, camera, "stereoMode", ANARI_STRING, "sideBySide");
  anariCommitParameters(dev, camera);
  ok &= render(dev, frame, argv[1], "pair", 2 * W, H);

  anariRelease(dev, frame);
  anariRelease(dev, camera);
  anariRelease(dev, renderer);
  anariRelease(dev, world);
  anariRelease(dev, volume);
  anariRelease(dev, field);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  return ok && status_count == 0 ? 0 : 1;
}
