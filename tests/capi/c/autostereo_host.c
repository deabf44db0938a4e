/* An autostereoscopic-display host: an isosurface (ANARI_KHR_GEOMETRY_ISOSURFACE)
 * of a ball field in a matte material, seen through caveray's multiView
 * camera (ANARI_CAVERAY_CAMERA_MULTI_VIEW) as an 8-view lenticular panel.
 * The host renders the interleaved panel image, then each view alone (the
 * camera's "view"), and interleaves the views itself by the lens formula
 * of docs/autostereo.md, written here again:
 *   k = 3x + c, u = k + offset - 3 * slant * y,
 *   view = floor(frac(u / pitch) * views).
 * The panel must equal that subpixel by subpixel with method perSubpixel,
 * and within 2 levels on 98 % of subpixels with method passes. Then the
 * misuse a host can make: a geometry without a field, a camera with no
 * views, a panel frame with a depth channel; each must be reported by
 * message and code and leave the device usable.
 * Usage: autostereo_host [WIDTH HEIGHT] (default 40 x 24).
 * Prints PASS/FAIL lines; exit status 0 only if none failed. */
#include <anari/anari.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "expect.h"

enum { N = 20, VIEWS = 8 };
static const float PITCH = 3.75f, SLANT = 0.15625f;

/* 1 - |p| on [-1, 1]^3 with a smaller ball stuck to it. */
static float ball(float x, float y, float z)
{
  float big = 1.0f - sqrtf(x * x + y * y + z * z);
  float dx = x - 0.35f, dy = y - 0.25f, dz = z - 0.4f;
  float small = 1.0f - 2.0f * sqrtf(dx * dx + dy * dy + dz * dz);
  return big > small ? big : small;
}

static unsigned view_of(unsigned x, unsigned y, unsigned c)
{
  double u = 3.0 * x + c - 3.0 * SLANT * y;
  double along = u / PITCH;
  along = (along - floor(along)) * VIEWS;
  return (unsigned)floor(along + 1e-9) % VIEWS;
}

/* Renders `frame` and copies its RGBA8 pixels into `out` (w * h * 4). */
static int render(ANARIDevice dev, ANARIFrame frame, unsigned char *out, unsigned w, unsigned h)
{
  uint32_t mw = 0, mh = 0;
  ANARIDataType type = ANARI_UNKNOWN;
  const void *pixels;
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  pixels = anariMapFrame(dev, frame, "channel.color", &mw, &mh, &type);
  if (!pixels || mw != w || mh != h || type != ANARI_UFIXED8_VEC4) {
    if (pixels)
      anariUnmapFrame(dev, frame, "channel.color");
    return 0;
  }
  memcpy(out, pixels, (size_t)w * h * 4);
  anariUnmapFrame(dev, frame, "channel.color");
  return 1;
}

static void set_int(ANARIDevice dev, ANARIObject o, const char *name, int v)
{
  anariSetParameter(dev, o, name, ANARI_INT32, &v);
}

static void set_float(ANARIDevice dev, ANARIObject o, const char *name, float v)
{
  anariSetParameter(dev, o, name, ANARI_FLOAT32, &v);
}

int main(int argc, char **argv)
{
  unsigned w = argc > 2 ? (unsigned)atoi(argv[1]) : 40, h = argc > 2 ? (unsigned)atoi(argv[2]) : 24;
  static float voxels[N * N * N];
  float origin[3] = {-1.0f, -1.0f, -2.2f}, spacing[3], isovalue = 0.5f;
  float ll[3] = {-0.5f, -0.3f, 0.0f}, lr[3] = {0.5f, -0.3f, 0.0f}, ur[3] = {0.5f, 0.3f, 0.0f};
  float color[3] = {0.9f, 0.8f, 0.6f};
  unsigned size[2] = {w, h};
  ANARIDataType rgba8 = ANARI_UFIXED8_VEC4, f32 = ANARI_FLOAT32;
  const char *const *extensions = NULL;
  int has_iso = 0, has_multi = 0;
  unsigned char *panel, *views[VIEWS], *mine;
  unsigned i, x, y, c, v, mismatched, off;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray3D data;
  ANARIArray1D isovalues, surfaces;
  ANARISpatialField field;
  ANARIGeometry geometry, broken;
  ANARIMaterial material;
  ANARISurface surface;
  ANARIWorld world;
  ANARICamera camera, empty;
  ANARIRenderer renderer;
  ANARIFrame frame;

  if (w == 0 || h == 0 || w > 4096 || h > 4096) {
    fprintf(stderr, "usage: autostereo_host [WIDTH HEIGHT]\n");
    return 2;
  }
  for (i = 0; i < 3; ++i)
    spacing[i] = 2.0f / (N - 1);
  for (i = 0; i < N * N * N; ++i)
    voxels[i] = ball(spacing[0] * (i % N) - 1.0f, spacing[1] * (i / N % N) - 1.0f,
        spacing[2] * (i / (N * N)) - 1.0f);

  lib = anariLoadLibrary("caveray", on_status, NULL);
  if (!lib) {
    printf("FAIL the library loads\n");
    return 1;
  }
  dev = anariNewDevice(lib, "default");
  if (anariGetProperty(dev, dev, "extension", ANARI_STRING_LIST, &extensions, sizeof extensions, ANARI_WAIT) == 1)
    for (i = 0; extensions && extensions[i]; ++i) {
      has_iso |= strcmp(extensions[i], "ANARI_KHR_GEOMETRY_ISOSURFACE") == 0;
      has_multi |= strcmp(extensions[i], "ANARI_CAVERAY_CAMERA_MULTI_VIEW") == 0;
    }
  check("the device reports ANARI_KHR_GEOMETRY_ISOSURFACE", has_iso);
  check("the device reports ANARI_CAVERAY_CAMERA_MULTI_VIEW", has_multi);

  data = anariNewArray3D(dev, voxels, NULL, NULL, ANARI_FLOAT32, N, N, N);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &data);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, spacing);
  anariCommitParameters(dev, field);
  anariRelease(dev, data);

  /* The iso-value as an array, as the CTS sends it. */
  isovalues = anariNewArray1D(dev, &isovalue, NULL, NULL, ANARI_FLOAT32, 1);
  geometry = anariNewGeometry(dev, "isosurface");
  anariSetParameter(dev, geometry, "field", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, geometry, "isovalue", ANARI_ARRAY1D, &isovalues);
  anariCommitParameters(dev, geometry);
  anariRelease(dev, isovalues);
  material = anariNewMaterial(dev, "matte");
  anariSetParameter(dev, material, "color", ANARI_FLOAT32_VEC3, color);
  anariCommitParameters(dev, material);
  surface = anariNewSurface(dev);
  anariSetParameter(dev, surface, "geometry", ANARI_GEOMETRY, &geometry);
  anariSetParameter(dev, surface, "material", ANARI_MATERIAL, &material);
  anariCommitParameters(dev, surface);
  surfaces = anariNewArray1D(dev, &surface, NULL, NULL, ANARI_SURFACE, 1);
  world = anariNewWorld(dev);
  anariSetParameter(dev, world, "surface", ANARI_ARRAY1D, &surfaces);
  anariCommitParameters(dev, world);
  anariRelease(dev, surfaces);

  camera = anariNewCamera(dev, "multiView");
  anariSetParameter(dev, camera, "lowerLeft", ANARI_FLOAT32_VEC3, ll);
  anariSetParameter(dev, camera, "lowerRight", ANARI_FLOAT32_VEC3, lr);
  anariSetParameter(dev, camera, "upperRight", ANARI_FLOAT32_VEC3, ur);
  set_int(dev, camera, "views", VIEWS);
  set_float(dev, camera, "viewingDistance", 2.0f);
  set_float(dev, camera, "viewSpacing", 0.05f);
  set_float(dev, camera, "lens.pitch", PITCH);
  set_float(dev, camera, "lens.slant", SLANT);
  anariSetParameter(dev, camera, "method", ANARI_STRING, "perSubpixel");
  anariCommitParameters(dev, camera);

  renderer = anariNewRenderer(dev, "default");
  anariCommitParameters(dev, renderer);
  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, size);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &rgba8);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariCommitParameters(dev, frame);
  expect_quiet("the scene commits without a word");

  panel = (unsigned char *)malloc((size_t)w * h * 4);
  mine = (unsigned char *)malloc((size_t)w * h * 4);
  check("the panel image renders", render(dev, frame, panel, w, h));
  for (v = 0; v < VIEWS; ++v) {
    views[v] = (unsigned char *)malloc((size_t)w * h * 4);
    set_int(dev, camera, "view", (int)v);
    anariCommitParameters(dev, camera);
    if (!render(dev, frame, views[v], w, h)) {
      check("each view renders alone", 0);
      memset(views[v], 0, (size_t)w * h * 4);
    }
  }
  for (y = 0; y < h; ++y)
    for (x = 0; x < w; ++x)
      for (c = 0; c < 4; ++c) {
        size_t at = 4 * ((size_t)y * w + x) + c;
        mine[at] = c < 3 ? views[view_of(x, y, c)][at] : 255;
      }
  mismatched = 0;
  for (i = 0; i < w * h * 4; ++i)
    mismatched += panel[i] != mine[i];
  printf("perSubpixel: %u of %u bytes differ from the views interleaved\n", mismatched, w * h * 4);
  check("perSubpixel: the panel is its views interleaved, exactly", mismatched == 0);
  mismatched = 0;
  for (v = 1; v < VIEWS; ++v)
    mismatched += memcmp(views[0], views[v], (size_t)w * h * 4) != 0;
  check("the views differ from one another", mismatched == VIEWS - 1);

  set_int(dev, camera, "view", -1);
  anariSetParameter(dev, camera, "method", ANARI_STRING, "passes");
  anariCommitParameters(dev, camera);
  check("the panel renders by passes", render(dev, frame, panel, w, h));
  off = 0;
  for (i = 0; i < w * h * 4; ++i)
    off += i % 4 != 3 && abs((int)panel[i] - (int)mine[i]) > 2;
  printf("passes: %u of %u subpixels differ by more than 2 levels\n", off, w * h * 3);
  check("passes: within 2 levels on 98 %% of subpixels", off * 50 < w * h * 3);
  expect_quiet("rendering said nothing amiss");

  /* Misuse. */
  broken = anariNewGeometry(dev, "isosurface");
  anariSetParameter(dev, broken, "isovalue", ANARI_FLOAT32, &isovalue);
  anariCommitParameters(dev, broken);
  expect("an isosurface without a field", ERR, BAD_ARG, "required parameter 'field'");
  anariRelease(dev, broken);
  empty = anariNewCamera(dev, "multiView");
  anariSetParameter(dev, empty, "lowerLeft", ANARI_FLOAT32_VEC3, ll);
  anariSetParameter(dev, empty, "lowerRight", ANARI_FLOAT32_VEC3, lr);
  anariSetParameter(dev, empty, "upperRight", ANARI_FLOAT32_VEC3, ur);
  set_int(dev, empty, "views", 0);
  set_float(dev, empty, "viewingDistance", 2.0f);
  set_float(dev, empty, "viewSpacing", 0.05f);
  set_float(dev, empty, "lens.pitch", PITCH);
  anariCommitParameters(dev, empty);
  expect("a multi-view camera with no views", ERR, BAD_ARG, "views must be 1 to 64");
  anariRelease(dev, empty);
  anariSetParameter(dev, frame, "channel.depth", ANARI_DATA_TYPE, &f32);
  anariCommitParameters(dev, frame);
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  expect("a panel frame with a depth channel", ERR, BAD_OP, "no depth channel");
  anariUnsetParameter(dev, frame, "channel.depth");
  anariCommitParameters(dev, frame);
  check("the device renders on after misuse", render(dev, frame, panel, w, h));
  expect_quiet("and says nothing more");

  for (v = 0; v < VIEWS; ++v)
    free(views[v]);
  free(panel);
  free(mine);
  anariRelease(dev, frame);
  anariRelease(dev, renderer);
  anariRelease(dev, camera);
  anariRelease(dev, world);
  anariRelease(dev, surface);
  anariRelease(dev, material);
  anariRelease(dev, geometry);
  anariRelease(dev, field);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  printf("%d failed\n", failures);
  return failures != 0;
}
