/* Hosts in their own units: stereo as hosts send it, with the eye distance
 * in the scene's own length units rather than metres.
 *
 *   units_host scene OUT_DIR    a VTK/ParaView-style scene modelled 64 units
 *                               wide, seen by a perspective camera 200 units
 *                               away, interpupillaryDistance 6 (scene units)
 *   units_host rig OUT_DIR      a CAVE front wall 3000 x 2400 mm, a head at
 *                               1700 mm and a volume 600 mm across, eyes 63.5
 *                               mm apart: the wall's perspective camera
 *                               (caverayPinholeFromScreen at the head) and the
 *                               offAxis camera in every stereo mode, then
 *                               OpenCOVER's channels: one perspective camera
 *                               with imageRegion per eye, no stereoMode
 *
 * Every stereo mode (left, right, sideBySide, topBottom) is rendered into
 * OUT_DIR/<camera>_<mode>.rgba (RGBA8, lower-left first; sideBySide is
 * 2W x H, topBottom W x 2H), the OpenCOVER channels into
 * OUT_DIR/channel_{left,right}.rgba. Exit status 0 only if every render
 * succeeded and no warning or error was reported. */
#include <anari/anari.h>
#include <anari/caveray.h>

#include <string.h>

#include "output.h"
#include "status.h"

#define W 64
#define H 48
#define N 16

static const char *const MODES[4] = {"left", "right", "sideBySide", "topBottom"};

/* A ball of N^3 voxels over [lo, lo + side]^3: 1 at its centre, 0 at its
 * surface and beyond. */
static ANARIWorld ball_world(ANARIDevice dev, const float lo[3], float side)
{
  static float voxels[N * N * N];
  float spacing[3], colors[6] = {1.0f, 0.4f, 0.1f, 0.2f, 0.5f, 1.0f}, opacity[2] = {0.0f, 0.8f};
  float unit = side / 10;
  ANARIArray3D data;
  ANARIArray1D color, alpha, volumes;
  ANARISpatialField field;
  ANARIVolume volume;
  ANARIWorld world;
  int x, y, z;
  for (z = 0; z < N; ++z)
    for (y = 0; y < N; ++y)
      for (x = 0; x < N; ++x) {
        float dx = 2.0f * x / (N - 1) - 1, dy = 2.0f * y / (N - 1) - 1, dz = 2.0f * z / (N - 1) - 1;
        float r = dx * dx + dy * dy + dz * dz;
        voxels[(z * N + y) * N + x] = r < 1 ? 1 - r : 0;
      }
  spacing[0] = spacing[1] = spacing[2] = side / (N - 1);
  data = anariNewArray3D(dev, voxels, NULL, NULL, ANARI_FLOAT32, N, N, N);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &data);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, lo);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, spacing);
  anariCommitParameters(dev, field);
  anariRelease(dev, data);
  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  color = anariNewArray1D(dev, colors, NULL, NULL, ANARI_FLOAT32_VEC3, 2);
  alpha = anariNewArray1D(dev, opacity, NULL, NULL, ANARI_FLOAT32, 2);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &color);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &alpha);
  /* Absorption per the scene's own length: a tenth of the ball. */
  anariSetParameter(dev, volume, "unitDistance", ANARI_FLOAT32, &unit);
  anariCommitParameters(dev, volume);
  anariRelease(dev, color);
  anariRelease(dev, alpha);
  world = anariNewWorld(dev);
  volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  anariCommitParameters(dev, world);
  anariRelease(dev, volumes);
  anariRelease(dev, volume);
  anariRelease(dev, field);
  return world;
}

/* Renders `frame` at w x h and writes its color to DIR/NAME.rgba. */
static int render(ANARIDevice dev, ANARIFrame frame, const char *dir, const char *name,
    uint32_t w, uint32_t h)
{
  uint32_t size[2] = {w, h}, mw = 0, mh = 0;
  ANARIDataType type = ANARI_UNKNOWN;
  const void *pixels;
  int ok;
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, size);
  anariCommitParameters(dev, frame);
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  pixels = anariMapFrame(dev, frame, "channel.color", &mw, &mh, &type);
  if (!pixels || mw != w || mh != h || type != ANARI_UFIXED8_VEC4) {
    fprintf(stderr, "units_host: no %ux%u image for %s\n", w, h, name);
    return 0;
  }
  ok = write_rgba(dir, name, pixels, w, h);
  anariUnmapFrame(dev, frame, "channel.color");
  return ok;
}

/* `camera` (named `label`) in every stereo mode, eyes `ipd` apart. */
static int every_mode(ANARIDevice dev, ANARIFrame frame, ANARICamera camera, const char *label,
    float ipd, const char *dir)
{
  char name[64];
  int ok = 1, m;
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariSetParameter(dev, camera, "interpupillaryDistance", ANARI_FLOAT32, &ipd);
  for (m = 0; m < 4; ++m) {
    anariSetParameter(dev, camera, "stereoMode", ANARI_STRING, MODES[m]);
    anariCommitParameters(dev, camera);
    snprintf(name, sizeof name, "%s_%s", label, MODES[m]);
    ok &= render(dev, frame, dir, name, m == 2 ? 2 * W : W, m == 3 ? 2 * H : H);
  }
  return ok;
}

static void set_pinhole(ANARIDevice dev, ANARICamera camera, const CaverayPinhole *p)
{
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, p->position);
  anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, p->direction);
  anariSetParameter(dev, camera, "up", ANARI_FLOAT32_VEC3, p->up);
  anariSetParameter(dev, camera, "fovy", ANARI_FLOAT32, &p->fovy);
  anariSetParameter(dev, camera, "aspect", ANARI_FLOAT32, &p->aspect);
  anariSetParameter(dev, camera, "imageRegion", ANARI_FLOAT32_BOX2, p->imageRegion);
}

/* VTK/ParaView: a dataset in its own coordinates, 64 units wide. */
static int scene_units(ANARIDevice dev, ANARIFrame frame, const char *dir)
{
  float lo[3] = {0, 0, 0}, position[3] = {32, 32, 200}, direction[3] = {0, 0, -1};
  float up[3] = {0, 1, 0}, aspect = (float)W / H;
  ANARIWorld world = ball_world(dev, lo, 64);
  ANARICamera camera = anariNewCamera(dev, "perspective");
  int ok;
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, position);
  anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, direction);
  anariSetParameter(dev, camera, "up", ANARI_FLOAT32_VEC3, up);
  /* VTK sets the eye's aspect, so each half of a split frame keeps it. */
  anariSetParameter(dev, camera, "aspect", ANARI_FLOAT32, &aspect);
  ok = every_mode(dev, frame, camera, "perspective", 6.0f, dir);
  anariRelease(dev, camera);
  anariRelease(dev, world);
  return ok;
}

/* A CAVE rig in millimetres. */
static int rig_units(ANARIDevice dev, ANARIFrame frame, const char *dir)
{
  float ll[3] = {-1500, 0, -1500}, lr[3] = {1500, 0, -1500}, ur[3] = {1500, 2400, -1500};
  float head[3] = {0, 1700, 0}, lo[3] = {-300, 1200, -1050}, ipd = 63.5f;
  const char *const channels[2] = {"channel_left", "channel_right"};
  CaverayPinhole pinhole;
  ANARIWorld world = ball_world(dev, lo, 600);
  ANARICamera wall, off_axis;
  int ok = 1, e;
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);

  wall = anariNewCamera(dev, "perspective");
  if (caverayPinholeFromScreen(ll, lr, ur, head, &pinhole) != ANARI_STATUS_NO_ERROR) {
    fprintf(stderr, "units_host: %s\n", caverayLastError());
    return 0;
  }
  set_pinhole(dev, wall, &pinhole);
  ok &= every_mode(dev, frame, wall, "wall", ipd, dir);

  off_axis = anariNewCamera(dev, "offAxis");
  anariSetParameter(dev, off_axis, "lowerLeft", ANARI_FLOAT32_VEC3, ll);
  anariSetParameter(dev, off_axis, "lowerRight", ANARI_FLOAT32_VEC3, lr);
  anariSetParameter(dev, off_axis, "upperRight", ANARI_FLOAT32_VEC3, ur);
  anariSetParameter(dev, off_axis, "eye", ANARI_FLOAT32_VEC3, head);
  ok &= every_mode(dev, frame, off_axis, "offAxis", ipd, dir);

  /* OpenCOVER: a channel per eye, the eye moved by the host, no stereoMode. */
  for (e = 0; e < 2; ++e) {
    float eye[3] = {head[0] + (e ? 0.5f : -0.5f) * ipd, head[1], head[2]};
    if (caverayPinholeFromScreen(ll, lr, ur, eye, &pinhole) != ANARI_STATUS_NO_ERROR) {
      fprintf(stderr, "units_host: %s\n", caverayLastError());
      return 0;
    }
    set_pinhole(dev, wall, &pinhole);
    anariSetParameter(dev, wall, "stereoMode", ANARI_STRING, "none");
    anariCommitParameters(dev, wall);
    anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &wall);
    ok &= render(dev, frame, dir, channels[e], W, H);
  }
  anariRelease(dev, off_axis);
  anariRelease(dev, wall);
  anariRelease(dev, world);
  return ok;
}

int main(int argc, char **argv)
{
  ANARIDataType rgba8 = ANARI_UFIXED8_VEC4;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIRenderer renderer;
  ANARIFrame frame;
  int ok;

  if (argc != 3 || (strcmp(argv[1], "scene") != 0 && strcmp(argv[1], "rig") != 0)) {
    fprintf(stderr, "usage: units_host scene|rig OUT_DIR\n");
    return 2;
  }
  status_level = ANARI_SEVERITY_WARNING;
  lib = anariLoadLibrary("caveray", count_status, "units_host");
  dev = anariNewDevice(lib, "default");
  renderer = anariNewRenderer(dev, "default");
  anariCommitParameters(dev, renderer);
  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &rgba8);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  ok = strcmp(argv[1], "scene") == 0 ? scene_units(dev, frame, argv[2])
                                     : rig_units(dev, frame, argv[2]);
  anariRelease(dev, frame);
  anariRelease(dev, renderer);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  return ok && status_count == 0 ? 0 : 1;
}
