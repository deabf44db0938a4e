/* A host using ANARI_KHR_CAMERA_STEREO through the C API: it checks that
 * the device reports the extension, renders a perspective camera's left
 * and right eyes as frames of their own, then both in one sideBySide
 * frame twice as wide. Usage: stereo_host OUT_DIR. Writes
 * OUT_DIR/{left,right,pair}.rgba (RGBA8, lower-left first); exit status 0
 * only if every render succeeded and no warning or error was reported. */
#include <anari/anari.h>

#include <string.h>

#include "output.h"
#include "ramp_world.h"
#include "status.h"

#define W 48
#define H 48

/* Renders `frame` and writes its color to DIR/NAME.rgba. */
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
  float position[3] = {0, 0, 3}, ipd = 0.3f, opacity = 0.3f;
  float colors[6] = {1.0f, 0.2f, 0.1f, 0.1f, 0.3f, 1.0f};
  uint32_t single[2] = {W, H}, pair[2] = {2 * W, H};
  ANARIDataType rgba8 = ANARI_UFIXED8_VEC4;
  const char *const *extensions = NULL;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIWorld world;
  ANARIRenderer renderer;
  ANARICamera camera;
  ANARIFrame frame;
  int ok = 1, i, reported = 0;

  if (argc != 2) {
    fprintf(stderr, "usage: stereo_host OUT_DIR\n");
    return 2;
  }
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

  world = ramp_world(dev, 0.2f, 1.0f, opacity, colors, 2);
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
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  return ok && status_count == 0 ? 0 : 1;
}
