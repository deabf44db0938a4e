/* A triangle mesh from the host's own memory, read where it lies: shared
 * arrays of positions (FLOAT32_VEC3), indices (UINT32_VEC3) and vertex
 * colors (FLOAT32_VEC4) are not copied while the host holds them (the
 * geometry's caveray.residentBytes is 0, and the process grows by less
 * than the arrays); when the host releases them while a frame renders
 * them, then scribbles over the memory and frees it, the device has
 * copied each first (after that render), said so once each at
 * PERFORMANCE severity, and every frame renders the same image.
 * Usage: in_place_mesh SCENE_FILE OUT_DIR N (the scene file gives the
 * camera and the box the mesh fills; N: the mesh has 2 N^2 triangles).
 * Writes OUT_DIR/mesh_held.rgba, mesh_freed.rgba and mesh_again.rgba;
 * prints "grew KB arrays KB", "covered PERCENT" and "copies N"; exit
 * status 0 only if every check held and the status callback saw no
 * error. */
#include <anari/anari.h>

#include <math.h>
#include <string.h>

#include "in_place.h"

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

int main(int argc, char **argv)
{
  Scene s;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray1D positions, indices, colors, surfaces;
  ANARIGeometry geometry;
  ANARIMaterial material;
  ANARISurface surface;
  ANARIWorld world;
  ANARIFrame first, second;
  float *position, *color, center[3], radius = INFINITY;
  uint32_t *index;
  size_t n, vertices, triangles, bytes, i, j;
  long before, grew;
  int k, ok = 1;

  if (argc != 4 || !scene_load(argv[1], &s) || (n = strtoul(argv[3], NULL, 10)) < 2) {
    fprintf(stderr, "usage: in_place_mesh SCENE_FILE OUT_DIR N\n");
    return 2;
  }
  /* A bumpy sphere's band filling the middle of the scene's box. */
  for (k = 0; k < 3; ++k) {
    float extent = s.spacing[k] * (float)(s.dims[k] - 1);
    center[k] = s.origin[k] + 0.5f * extent;
    radius = fminf(radius, 0.35f * extent);
  }
  vertices = (n + 1) * (n + 1);
  triangles = 2 * n * n;
  bytes = vertices * 7 * sizeof(float) + triangles * 3 * sizeof(uint32_t);
  position = (float *)malloc(vertices * 3 * sizeof(float));
  color = (float *)malloc(vertices * 4 * sizeof(float));
  index = (uint32_t *)malloc(triangles * 3 * sizeof(uint32_t));
  for (i = 0; i <= n; ++i)
    for (j = 0; j <= n; ++j) {
      /* A band short of the poles: no triangle of zero area, which
       * would be left out of a copy of the indices. */
      double theta = M_PI * (0.1 + 0.8 * (double)i / (double)n);
      double phi = 2.0 * M_PI * (double)j / (double)n;
      double r = radius * (1.0 + 0.08 * sin(6.0 * theta) * sin(6.0 * phi));
      double d[3] = {sin(theta) * cos(phi), sin(theta) * sin(phi), cos(theta)};
      size_t v = i * (n + 1) + j;
      for (k = 0; k < 3; ++k) {
        position[3 * v + k] = center[k] + (float)(r * d[k]);
        color[4 * v + k] = (float)(0.5 + 0.5 * d[k]);
      }
      color[4 * v + 3] = 1.0f;
    }
  for (i = 0; i < n; ++i)
    for (j = 0; j < n; ++j) {
      uint32_t a = (uint32_t)(i * (n + 1) + j), b = a + 1, c = a + (uint32_t)(n + 1), d = c + 1;
      uint32_t *t = index + 6 * (i * n + j);
      t[0] = a, t[1] = c, t[2] = b, t[3] = b, t[4] = c, t[5] = d;
    }

  lib = anariLoadLibrary("caveray", watch_status, "in_place_mesh");
  dev = anariNewDevice(lib, "default");
  /* The CPU renderer: probing a GPU would load a driver, whose memory is
   * not what this measures. */
  anariSetParameter(dev, dev, "backend", ANARI_STRING, "cpu");
  anariCommitParameters(dev, dev);

  before = resident_kb();
  positions = anariNewArray1D(dev, position, NULL, NULL, ANARI_FLOAT32_VEC3, vertices);
  colors = anariNewArray1D(dev, color, NULL, NULL, ANARI_FLOAT32_VEC4, vertices);
  indices = anariNewArray1D(dev, index, NULL, NULL, ANARI_UINT32_VEC3, triangles);
  geometry = anariNewGeometry(dev, "triangle");
  anariSetParameter(dev, geometry, "vertex.position", ANARI_ARRAY1D, &positions);
  anariSetParameter(dev, geometry, "vertex.color", ANARI_ARRAY1D, &colors);
  anariSetParameter(dev, geometry, "primitive.index", ANARI_ARRAY1D, &indices);
  anariCommitParameters(dev, geometry);
  material = anariNewMaterial(dev, "matte");
  anariSetParameter(dev, material, "color", ANARI_STRING, "color");
  anariCommitParameters(dev, material);
  surface = anariNewSurface(dev);
  anariSetParameter(dev, surface, "geometry", ANARI_GEOMETRY, &geometry);
  anariSetParameter(dev, surface, "material", ANARI_MATERIAL, &material);
  anariCommitParameters(dev, surface);
  surfaces = anariNewArray1D(dev, &surface, NULL, NULL, ANARI_SURFACE, 1);
  world = anariNewWorld(dev);
  anariSetParameter(dev, world, "surface", ANARI_ARRAY1D, &surfaces);
  anariCommitParameters(dev, world);

  /* While the host holds its memory, the geometry holds none of it. */
  ok &= holds(dev, geometry, 0, "in_place_mesh: the geometry, while the host holds the arrays,");
  first = new_frame(dev, &s, world);
  ok &= render_saved(dev, first, argv[2], "mesh_held");
  grew = resident_kb() - before;
  printf("grew %ld KB arrays %zu KB\n", grew, bytes / 1024);
  {
    uint32_t w = 0, h = 0;
    ANARIDataType type = ANARI_UNKNOWN;
    const uint8_t *p =
        (const uint8_t *)anariMapFrame(dev, first, "channel.color", &w, &h, &type);
    size_t covered = 0;
    for (i = 0; p && i < (size_t)w * h; ++i)
      covered += p[4 * i + 3] == 255 && (p[4 * i] | p[4 * i + 1] | p[4 * i + 2]) != 0;
    if (p)
      anariUnmapFrame(dev, first, "channel.color");
    printf("covered %zu\n", w && h ? 100 * covered / ((size_t)w * h) : 0);
  }

  /* Released while a frame renders them, then scribbled over and freed:
   * the copies wait for that render, and later frames read them. */
  second = new_frame(dev, &s, world);
  anariRenderFrame(dev, second);
  anariRelease(dev, positions);
  anariRelease(dev, colors);
  anariRelease(dev, indices);
  for (i = 0; i < vertices * 3; ++i)
    position[i] = NAN;
  for (i = 0; i < vertices * 4; ++i)
    color[i] = -1.0f;
  memset(index, 0xff, triangles * 3 * sizeof(uint32_t));
  free(position);
  free(color);
  free(index);
  anariFrameReady(dev, second, ANARI_WAIT);
  ok &= save(dev, second, argv[2], "mesh_freed");
  ok &= render_saved(dev, first, argv[2], "mesh_again");
  ok &= holds(dev, geometry, bytes, "in_place_mesh: the geometry, after the release,");
  printf("copies %d\n", copies);
  if (copies != 3) {
    fprintf(stderr, "in_place_mesh: %d PERFORMANCE notes of a copy, not three\n", copies);
    ok = 0;
  }

  anariRelease(dev, first);
  anariRelease(dev, second);
  anariRelease(dev, world);
  anariRelease(dev, surfaces);
  anariRelease(dev, surface);
  anariRelease(dev, material);
  anariRelease(dev, geometry);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  scene_free(&s);
  return ok && status_count == 0 ? 0 : 1;
}
