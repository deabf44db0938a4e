/* Inputs that used to bring the host down, through the C API: each must
 * reach the status callback as a clear error (or warning) and leave the
 * device working; a release must stop a render in progress rather than
 * wait for it. Prints PASS/FAIL per check; exit status 1 on any FAIL. */
#include <anari/anari.h>

#define _DEFAULT_SOURCE /* alarm */
#include <math.h>
#include <stdint.h>
#include <unistd.h>

#include "expect.h"
#include "ramp_world.h"

static ANARIFrame new_frame(ANARIDevice dev, ANARIWorld world, ANARIRenderer renderer,
    ANARICamera camera, uint32_t w, uint32_t h)
{
  uint32_t size[2];
  ANARIDataType color = ANARI_UFIXED8_VEC4;
  ANARIFrame frame = anariNewFrame(dev);
  size[0] = w, size[1] = h;
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, size);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &color);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariCommitParameters(dev, frame);
  return frame;
}

/* Renders `frame` and says whether it gave an image. */
static int renders(ANARIDevice dev, ANARIFrame frame)
{
  uint32_t w = 0, h = 0;
  ANARIDataType type = ANARI_UNKNOWN;
  const void *pixels;
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  pixels = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  if (pixels)
    anariUnmapFrame(dev, frame, "channel.color");
  return pixels != NULL;
}

int main(void)
{
  float position[3] = {0, 0, 4}, direction[3] = {0, 0, -1}, up[3] = {0, 1, 0};
  float bad[3], tiny = 1e-6f, tinier = 1e-30f, one = 1.0f, opacity = 0.3f;
  const char *word = "x";
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray1D strings;
  ANARIWorld world;
  ANARIRenderer renderer, slow;
  ANARICamera camera;
  ANARIFrame small, huge, big;
  reset();
  alarm(600);
  lib = anariLoadLibrary("caveray", on_status, NULL);
  dev = anariNewDevice(lib, "default");

  /* An array no caveray parameter can read says so when made. */
  strings = anariNewArray1D(dev, &word, NULL, NULL, ANARI_STRING, 1);
  expect("an array of strings", WARN, ANARI_STATUS_NO_ERROR,
      "no caveray parameter reads arrays of ANARI_STRING");
  anariRelease(dev, strings);

  world = ramp_world(dev, 0.0f, 1.0f, opacity, NULL, 0);
  camera = anariNewCamera(dev, "perspective");
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, position);
  anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, direction);
  anariSetParameter(dev, camera, "up", ANARI_FLOAT32_VEC3, up);
  anariCommitParameters(dev, camera);
  renderer = anariNewRenderer(dev, "default");
  anariCommitParameters(dev, renderer);
  expect_quiet("a sound scene");

  /* Steps that would never end. */
  anariSetParameter(dev, renderer, "stepFactor", ANARI_FLOAT32, &tiny);
  anariCommitParameters(dev, renderer);
  expect("stepFactor 1e-6", ERR, BAD_ARG, "stepFactor must be from 0.015625 to 64, got 1e-6");
  anariSetParameter(dev, renderer, "stepFactor", ANARI_FLOAT32, &tinier);
  anariCommitParameters(dev, renderer);
  expect("stepFactor 1e-30", ERR, BAD_ARG, "stepFactor must be from 0.015625 to 64, got 1e-30");
  anariSetParameter(dev, renderer, "stepFactor", ANARI_FLOAT32, &one);
  anariCommitParameters(dev, renderer);
  expect_quiet("stepFactor 1 again");

  /* Eyes that are not numbers. */
  bad[0] = INFINITY, bad[1] = 0, bad[2] = 4;
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, bad);
  anariCommitParameters(dev, camera);
  expect("an eye at infinity", ERR, BAD_ARG, "finite");
  bad[0] = NAN;
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, bad);
  anariCommitParameters(dev, camera);
  expect("an eye at NaN", ERR, BAD_ARG, "finite");
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, position);
  anariCommitParameters(dev, camera);
  expect_quiet("the eye back");

  /* A frame far beyond memory: refused, not an abort. */
  huge = new_frame(dev, world, renderer, camera, 100000, 100000);
  check("a 100000 x 100000 frame gives no image", !renders(dev, huge));
  expect("mapping the 100000 x 100000 frame", ERR, BAD_OP,
      "a frame of 100000x100000 is 10000000000 pixels; caveray renders up to 268435456");
  anariRelease(dev, huge);

  small = new_frame(dev, world, renderer, camera, 16, 16);
  check("a small frame still renders", renders(dev, small));
  expect_quiet("after the budget errors");

  /* A slow render (4096^2 with shadows on the CPU reference would take
   * minutes) stops when its frame is released... */
  slow = anariNewRenderer(dev, "default");
  anariSetParameter(dev, slow, "shading", ANARI_STRING, "shadows");
  anariCommitParameters(dev, slow);
  big = new_frame(dev, world, slow, camera, 4096, 4096);
  anariRenderFrame(dev, big);
  anariRelease(dev, big);
  check("the device renders again after a released frame", renders(dev, small));
  check("the released frame's render was stopped", discards == 1);

  /* ...and when the device is released. */
  big = new_frame(dev, world, slow, camera, 4096, 4096);
  anariRenderFrame(dev, big);
  anariRelease(dev, big);
  anariRelease(dev, small);
  anariRelease(dev, slow);
  anariRelease(dev, renderer);
  anariRelease(dev, camera);
  anariRelease(dev, world);
  anariRelease(dev, dev);
  /* The release returns within a fifth of a second; unloading the library
   * waits for the device's teardown, which ends only once the render has
   * stopped (rendering on would take minutes; the alarm fails the run). */
  anariUnloadLibrary(lib);
  printf("the released device's render stopped: the library unloaded\n");

  printf("%s: %d failure(s)\n", failures ? "FAIL" : "done", failures);
  return failures ? 1 : 0;
}
