/* An SDK-viewer-style host, from what anari_viewer sends (HOSTS.md): an
 * orthographic camera, frame `accumulation` on, only `channel.color`
 * (sRGB), anariFrameReady(NO_WAIT) polled until the frame is ready, the
 * frame rendered again unchanged to accumulate (refine), and anariDiscardFrame
 * when the view changes in the middle of a (deliberately slow) render;
 * `duration` and `numSamples` read.
 * The scene is a solid box [-1, 1]^3 of color (0.2, 0.8, 0.4) and
 * opacity 0.5 per unit distance, seen down -z through a 4 x 4 window, on
 * a (0.1, 0.1, 0.1) background: the inner half of the image sees 2 units
 * of box.
 * Usage: viewer_host OUT_DIR. Writes OUT_DIR/viewer.rgba (64 x 64, sRGB).
 * Exit status 0 only if every step behaved, no warning or error was
 * reported, and exactly one INFO message reported the discard. */
#define _POSIX_C_SOURCE 199309L /* nanosleep under -std=c99 */

#include <anari/anari.h>

#include <stdlib.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "output.h"

static int problems = 0, discards = 0;

static void on_status(const void *program, ANARIDevice d, ANARIObject source,
    ANARIDataType sourceType, ANARIStatusSeverity severity, ANARIStatusCode code,
    const char *message)
{
  (void)d, (void)source, (void)sourceType, (void)code;
  if (severity <= ANARI_SEVERITY_WARNING) {
    ++problems;
    fprintf(stderr, "%s: %s\n", (const char *)program, message);
  } else if (severity == ANARI_SEVERITY_INFO && strstr(message, "discarded")) {
    ++discards;
  }
}

/* The viewer's loop: poll without blocking until the frame is done. */
static long poll_until_ready(ANARIDevice dev, ANARIFrame frame)
{
  struct timespec pause = {0, 1000000};
  long polls = 0;
  while (!anariFrameReady(dev, frame, ANARI_NO_WAIT)) {
    ++polls;
    nanosleep(&pause, NULL);
  }
  return polls;
}

static int int_property(ANARIDevice dev, ANARIObject o, const char *name)
{
  int32_t v = -1;
  if (anariGetProperty(dev, o, name, ANARI_INT32, &v, sizeof v, ANARI_WAIT) != 1)
    return -1;
  return v;
}

int main(int argc, char **argv)
{
  float solid[64], origin[3] = {-1, -1, -1}, spacing[3] = {2.0f / 3, 2.0f / 3, 2.0f / 3};
  float color[3] = {0.2f, 0.8f, 0.4f}, opacity = 0.5f, background[4] = {0.1f, 0.1f, 0.1f, 1};
  float position[3] = {0, 0, 5}, moved[3] = {0.5f, 0, 5}, direction[3] = {0, 0, -1};
  float up[3] = {0, 1, 0}, height = 4.0f, aspect = 1.0f, duration = -1.0f;
  uint32_t small[2] = {64, 64}, large[2] = {2048, 2048}, w = 0, h = 0;
  ANARIDataType srgb = ANARI_UFIXED8_RGBA_SRGB, type = ANARI_UNKNOWN;
  uint8_t yes = 1;
  unsigned char first[64 * 64 * 4];
  const void *pixels;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray3D data;
  ANARIArray1D volumes;
  ANARISpatialField field;
  ANARIVolume volume;
  ANARIWorld world;
  ANARIRenderer renderer;
  ANARICamera camera;
  ANARIFrame frame;
  int ok = 1, i;

  if (argc != 2) {
    fprintf(stderr, "usage: viewer_host OUT_DIR\n");
    return 2;
  }
  for (i = 0; i < 64; ++i)
    solid[i] = 1.0f;
  lib = anariLoadLibrary("caveray", on_status, "viewer_host");
  dev = anariNewDevice(lib, "default");

  data = anariNewArray3D(dev, solid, NULL, NULL, ANARI_FLOAT32, 4, 4, 4);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &data);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, spacing);
  anariCommitParameters(dev, field);
  anariRelease(dev, data);
  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "color", ANARI_FLOAT32_VEC3, color);
  anariSetParameter(dev, volume, "opacity", ANARI_FLOAT32, &opacity);
  anariCommitParameters(dev, volume);
  world = anariNewWorld(dev);
  volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  anariCommitParameters(dev, world);
  anariRelease(dev, volumes);

  renderer = anariNewRenderer(dev, "default");
  anariSetParameter(dev, renderer, "background", ANARI_FLOAT32_VEC4, background);
  anariCommitParameters(dev, renderer);
  camera = anariNewCamera(dev, "orthographic");
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, position);
  anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, direction);
  anariSetParameter(dev, camera, "up", ANARI_FLOAT32_VEC3, up);
  anariSetParameter(dev, camera, "height", ANARI_FLOAT32, &height);
  anariSetParameter(dev, camera, "aspect", ANARI_FLOAT32, &aspect);
  anariCommitParameters(dev, camera);

  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, small);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &srgb);
  anariSetParameter(dev, frame, "accumulation", ANARI_BOOL, &yes);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariCommitParameters(dev, frame);

  /* Two frames of the viewer's loop with nothing changed. */
  for (i = 0; i < 2; ++i) {
    anariRenderFrame(dev, frame);
    poll_until_ready(dev, frame);
    pixels = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
    if (!pixels || w != 64 || h != 64 || type != ANARI_UFIXED8_RGBA_SRGB) {
      fprintf(stderr, "viewer_host: no 64x64 sRGB color (render %d)\n", i);
      return 1;
    }
    if (i == 0) {
      memcpy(first, pixels, sizeof first);
      ok &= write_rgba(argv[1], "viewer", pixels, w, h);
    } else {
      /* Accumulating: the second render adds a sample a fraction of a
       * pixel off each centre. The box's edges lie on pixel borders and
       * its depth along the rays does not change, so the image hardly
       * does. */
      int k, worst = 0;
      for (k = 0; k < (int)sizeof first; ++k) {
        int d = abs((int)first[k] - (int)((const unsigned char *)pixels)[k]);
        worst = d > worst ? d : worst;
      }
      if (worst > 2) {
        fprintf(stderr, "viewer_host: the refined frame moved by %d levels\n", worst);
        ok = 0;
      }
    }
    anariUnmapFrame(dev, frame, "channel.color");
  }
  if (int_property(dev, frame, "numSamples") != 2) {
    fprintf(stderr, "viewer_host: numSamples %d after two renders\n",
        int_property(dev, frame, "numSamples"));
    ok = 0;
  }

  /* The user drags: a large, slow render starts, and the view changes
   * again at once; the viewer discards the frame and starts anew. */
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, large);
  anariCommitParameters(dev, frame);
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, moved);
  anariCommitParameters(dev, camera);
  anariRenderFrame(dev, frame);
  anariDiscardFrame(dev, frame);
  poll_until_ready(dev, frame);
  if (int_property(dev, frame, "numSamples") != 0) {
    fprintf(stderr, "viewer_host: the discarded frame kept samples\n");
    ok = 0;
  }
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, small);
  anariCommitParameters(dev, frame);
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, position);
  anariCommitParameters(dev, camera);
  anariRenderFrame(dev, frame);
  poll_until_ready(dev, frame);
  pixels = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  if (!pixels || w != 64 || h != 64 || memcmp(first, pixels, sizeof first) != 0) {
    fprintf(stderr, "viewer_host: the view after the discard is not the first view\n");
    ok = 0;
  }
  if (pixels)
    anariUnmapFrame(dev, frame, "channel.color");
  if (anariGetProperty(dev, frame, "duration", ANARI_FLOAT32, &duration, sizeof duration, ANARI_WAIT) != 1
      || !(duration >= 0.0f)) {
    fprintf(stderr, "viewer_host: no duration\n");
    ok = 0;
  }

  anariRelease(dev, frame);
  anariRelease(dev, camera);
  anariRelease(dev, renderer);
  anariRelease(dev, world);
  anariRelease(dev, volume);
  anariRelease(dev, field);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  if (discards != 1) {
    fprintf(stderr, "viewer_host: %d INFO messages reported a discard, not 1\n", discards);
    ok = 0;
  }
  return ok && problems == 0 ? 0 : 1;
}
