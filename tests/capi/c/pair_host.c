/* An OpenCOVER-style host rendering one wall's two eyes as two frames,
 * one channel after the other (render, wait, next), as its ANARI plug-in
 * does: a perspective camera per eye from caverayPinholeFromScreen (fovy,
 * aspect, imageRegion), frames committed before their size is set,
 * sRGB color. It renders the wall at four head positions twice: with
 * the device's pairStereoFrames off, then on, so that the second eye can
 * come from the first eye's re-projection pass; then names each frame
 * the other's stereoPartner (ANARI_CAVERAY_FRAME_STEREO_PAIR) and renders
 * once more.
 * Usage: pair_host SCENE_FILE OUT_DIR DX,DY,DZ (the right eye minus the
 * scene's eye). Writes OUT_DIR/{alone,paired}_{left,right}.rgba for the
 * first head position and prints both runs' times; exit status 0 only if
 * every render succeeded and no warning or error was reported. */
/* clock_gettime under -std=c99. */
#define _POSIX_C_SOURCE 199309L

#include <anari/anari.h>
#include <anari/caveray.h>

#include <time.h>

#include "scene.h"
#include "status.h"

#define POSITIONS 4

static double now_ms(void)
{
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return 1e3 * (double)t.tv_sec + 1e-6 * (double)t.tv_nsec;
}

/* Points `camera` from `eye` at the wall, as OpenCOVER does per channel. */
static int aim(ANARIDevice dev, ANARICamera camera, const Scene *s, const float *eye)
{
  CaverayPinhole p;
  if (caverayPinholeFromScreen(s->ll, s->lr, s->ur, eye, &p) != ANARI_STATUS_NO_ERROR) {
    fprintf(stderr, "pair_host: %s\n", caverayLastError());
    return 0;
  }
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, p.position);
  anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, p.direction);
  anariSetParameter(dev, camera, "up", ANARI_FLOAT32_VEC3, p.up);
  anariSetParameter(dev, camera, "fovy", ANARI_FLOAT32, &p.fovy);
  anariSetParameter(dev, camera, "aspect", ANARI_FLOAT32, &p.aspect);
  anariSetParameter(dev, camera, "imageRegion", ANARI_FLOAT32_BOX2, p.imageRegion);
  anariCommitParameters(dev, camera);
  return 1;
}

/* Renders `frame`, waits, and writes its color to DIR/NAME.rgba if NAME. */
static int render(ANARIDevice dev, ANARIFrame frame, const char *dir, const char *name)
{
  uint32_t w = 0, h = 0;
  ANARIDataType type = ANARI_UNKNOWN;
  const void *pixels;
  int ok = 1;
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  pixels = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  if (!pixels) {
    fprintf(stderr, "pair_host: no image for %s\n", name ? name : "a frame");
    return 0;
  }
  if (name)
    ok = write_rgba(dir, name, pixels, w, h);
  anariUnmapFrame(dev, frame, "channel.color");
  return ok;
}

/* Both eyes at head positions 0..POSITIONS-1 (the head stepping along
 * the wall's rows), the first written as PREFIX_left and PREFIX_right.
 * Returns the milliseconds it took, or a negative number on failure. */
static double walk(ANARIDevice dev, const Scene *s, const float *baseline,
    ANARICamera cameras[2], ANARIFrame frames[2], const char *dir, const char *prefix)
{
  char name[64];
  double start = now_ms();
  int i, e, k;
  for (i = 0; i < POSITIONS; ++i) {
    for (e = 0; e < 2; ++e) {
      float eye[3];
      for (k = 0; k < 3; ++k)
        eye[k] = s->eye[k] + (e ? baseline[k] : 0.0f) + (k == 0 ? 7.0f * (float)i : 0.0f);
      if (!aim(dev, cameras[e], s, eye))
        return -1.0;
    }
    for (e = 0; e < 2; ++e) {
      snprintf(name, sizeof name, "%s_%s", prefix, e ? "right" : "left");
      if (!render(dev, frames[e], dir, i == 0 ? name : NULL))
        return -1.0;
    }
  }
  return now_ms() - start;
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
  ANARIFrame frames[2];
  ANARICamera cameras[2];
  ANARIDataType srgb = ANARI_UFIXED8_RGBA_SRGB;
  float background[4] = {0, 0, 0, 1}, baseline[3], half_step = 0.5f;
  uint8_t off = 0, on = 1;
  double alone, paired;
  int ok = 1, e;

  if (argc != 4 || sscanf(argv[3], "%f,%f,%f", &baseline[0], &baseline[1], &baseline[2]) != 3
      || !scene_load(argv[1], &s)) {
    fprintf(stderr, "usage: pair_host SCENE_FILE OUT_DIR DX,DY,DZ\n");
    return 2;
  }
  status_level = ANARI_SEVERITY_WARNING;
  lib = anariLoadLibrary("environment", count_status, "pair_host");
  dev = anariNewDevice(lib, "default");

  voxels = anariNewArray3D(dev, s.voxels, NULL, NULL, ANARI_FLOAT32, s.dims[0], s.dims[1], s.dims[2]);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &voxels);
  anariSetParameter(dev, field, "filter", ANARI_STRING, "linear");
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, s.origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, s.spacing);
  anariCommitParameters(dev, field);
  anariRelease(dev, voxels);
  colors = anariNewArray1D(dev, s.colors, NULL, NULL, ANARI_FLOAT32_VEC4, s.ncolors);
  opacities = anariNewArray1D(dev, s.opacities, NULL, NULL, ANARI_FLOAT32, s.nopacities);
  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &colors);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &opacities);
  anariSetParameter(dev, volume, "valueRange", ANARI_FLOAT32_BOX1, s.range);
  anariSetParameter(dev, volume, "unitDistance", ANARI_FLOAT32, &s.unitDistance);
  anariCommitParameters(dev, volume);
  anariRelease(dev, colors);
  anariRelease(dev, opacities);
  world = anariNewWorld(dev);
  volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  anariCommitParameters(dev, world);
  anariRelease(dev, volumes);
  renderer = anariNewRenderer(dev, "default");
  anariSetParameter(dev, renderer, "background", ANARI_FLOAT32_VEC4, background);
  /* The phantom's thin shells alias into moire at the default step, in
   * each eye's own pattern, which no re-projection reproduces. */
  anariSetParameter(dev, renderer, "stepFactor", ANARI_FLOAT32, &half_step);
  anariCommitParameters(dev, renderer);

  for (e = 0; e < 2; ++e) {
    cameras[e] = anariNewCamera(dev, "perspective");
    frames[e] = anariNewFrame(dev);
    anariSetParameter(dev, frames[e], "channel.color", ANARI_DATA_TYPE, &srgb);
    anariSetParameter(dev, frames[e], "world", ANARI_WORLD, &world);
    anariSetParameter(dev, frames[e], "renderer", ANARI_RENDERER, &renderer);
    anariSetParameter(dev, frames[e], "camera", ANARI_CAMERA, &cameras[e]);
    anariCommitParameters(dev, frames[e]);
    anariSetParameter(dev, frames[e], "size", ANARI_UINT32_VEC2, s.size);
    anariCommitParameters(dev, frames[e]);
  }

  /* Warm-up: every pipeline compiled before anything is timed. */
  anariSetParameter(dev, dev, "pairStereoFrames", ANARI_BOOL, &on);
  anariCommitParameters(dev, dev);
  ok &= walk(dev, &s, baseline, cameras, frames, argv[2], "warm") >= 0.0;

  anariSetParameter(dev, dev, "pairStereoFrames", ANARI_BOOL, &off);
  anariCommitParameters(dev, dev);
  alone = walk(dev, &s, baseline, cameras, frames, argv[2], "alone");
  anariSetParameter(dev, dev, "pairStereoFrames", ANARI_BOOL, &on);
  anariCommitParameters(dev, dev);
  paired = walk(dev, &s, baseline, cameras, frames, argv[2], "paired");
  ok &= alone >= 0.0 && paired >= 0.0;
  printf("pair_host: %d head positions, both eyes: %.1f ms alone, %.1f ms paired\n",
      POSITIONS, alone, paired);

  /* Named partners, each naming the other, with automatic pairing off. */
  anariSetParameter(dev, dev, "pairStereoFrames", ANARI_BOOL, &off);
  anariCommitParameters(dev, dev);
  anariSetParameter(dev, frames[0], "stereoPartner", ANARI_FRAME, &frames[1]);
  anariSetParameter(dev, frames[1], "stereoPartner", ANARI_FRAME, &frames[0]);
  anariCommitParameters(dev, frames[0]);
  anariCommitParameters(dev, frames[1]);
  ok &= walk(dev, &s, baseline, cameras, frames, argv[2], "named") >= 0.0;

  for (e = 0; e < 2; ++e) {
    anariRelease(dev, frames[e]);
    anariRelease(dev, cameras[e]);
  }
  anariRelease(dev, renderer);
  anariRelease(dev, world);
  anariRelease(dev, volume);
  anariRelease(dev, field);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  scene_free(&s);
  return ok && status_count == 0 ? 0 : 1;
}
