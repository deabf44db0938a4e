/* A data-parallel host: each process of `mpirun -np N` builds its slab of
 * one 48^3 volume (the cells it owns along x and one voxel of apron beyond
 * each inner face), says which box of world space it owns
 * ("caveray.region"), and renders the same oblique camera on a device in
 * MPI mode ("caveray.mpi" = "world"); every rank maps the composited frame
 * and rank 0 writes it to DIR/bricks.rgba. With "whole" one process renders
 * the whole volume on a plain device and writes DIR/whole.rgba; with
 * "unowned" the ranks say no region, so their bricks' bounds (aprons
 * included) overlap and every rank must refuse the frame. With "cells"
 * the slab goes as an unstructured field instead: its cells (apron
 * included) cut into six tetrahedra each, values at the vertices. The host
 * links no MPI itself: it learns its rank from the launcher's environment.
 *
 * Usage: mpi_bricks DIR [whole|unowned|ranks] [cells] */
#include <anari/anari.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "output.h"
#include "status.h"

#define N 48
#define SIZE 96

static float value_at(int i, int j, int k)
{
  float x = (float)i / (N - 1), y = (float)j / (N - 1), z = (float)k / (N - 1);
  float a = (x - 0.35f) * (x - 0.35f) + (y - 0.5f) * (y - 0.5f) + (z - 0.5f) * (z - 0.5f);
  float b = (x - 0.7f) * (x - 0.7f) + (y - 0.45f) * (y - 0.45f) + (z - 0.6f) * (z - 0.6f);
  return expf(-a * 18.0f) + 0.8f * expf(-b * 30.0f) + 0.1f * sinf(9.0f * x + 5.0f * z);
}

/* The six tetrahedra of a cell (corners in VTK's hexahedron order). */
static const int KUHN[6][4] = {
    {0, 1, 2, 6}, {0, 1, 5, 6}, {0, 3, 2, 6}, {0, 3, 7, 6}, {0, 4, 5, 6}, {0, 4, 7, 6}};

/* The slab's nx * N * N vertices (x fastest) as an unstructured field of
 * tetrahedra; the arrays are the device's to free. */
static ANARISpatialField tetrahedra(ANARIDevice dev, const float *values, int nx, int first,
    float spacing, ANARIArray1D arrays[5])
{
  size_t verts = (size_t)nx * N * N, cells = 6 * (size_t)(nx - 1) * (N - 1) * (N - 1), c = 0;
  float *p;
  uint32_t *index, *cell_index;
  uint8_t *types;
  float *data;
  int i, j, k, t, q;
  ANARISpatialField field = anariNewSpatialField(dev, "unstructured");
  arrays[0] = anariNewArray1D(dev, NULL, NULL, NULL, ANARI_FLOAT32_VEC3, verts);
  arrays[1] = anariNewArray1D(dev, NULL, NULL, NULL, ANARI_UINT32, 4 * cells);
  arrays[2] = anariNewArray1D(dev, NULL, NULL, NULL, ANARI_UINT32, cells);
  arrays[3] = anariNewArray1D(dev, NULL, NULL, NULL, ANARI_UINT8, cells);
  arrays[4] = anariNewArray1D(dev, NULL, NULL, NULL, ANARI_FLOAT32, verts);
  p = anariMapArray(dev, arrays[0]);
  index = anariMapArray(dev, arrays[1]);
  cell_index = anariMapArray(dev, arrays[2]);
  types = anariMapArray(dev, arrays[3]);
  data = anariMapArray(dev, arrays[4]);
  for (k = 0; k < N; ++k)
    for (j = 0; j < N; ++j)
      for (i = 0; i < nx; ++i) {
        size_t v = ((size_t)k * N + j) * nx + i;
        p[3 * v] = (first + i) * spacing;
        p[3 * v + 1] = j * spacing;
        p[3 * v + 2] = k * spacing;
        data[v] = values[v];
      }
  for (k = 0; k + 1 < N; ++k)
    for (j = 0; j + 1 < N; ++j)
      for (i = 0; i + 1 < nx; ++i) {
        uint32_t o = (uint32_t)(((size_t)k * N + j) * nx + i), row = nx, slab = nx * N;
        uint32_t h[8] = {o, o + 1, o + 1 + row, o + row, o + slab, o + 1 + slab,
            o + 1 + row + slab, o + row + slab};
        for (t = 0; t < 6; ++t, ++c) {
          cell_index[c] = (uint32_t)(4 * c);
          types[c] = 10;
          for (q = 0; q < 4; ++q)
            index[4 * c + q] = h[KUHN[t][q]];
        }
      }
  for (i = 0; i < 5; ++i)
    anariUnmapArray(dev, arrays[i]);
  anariSetParameter(dev, field, "vertex.position", ANARI_ARRAY1D, &arrays[0]);
  anariSetParameter(dev, field, "index", ANARI_ARRAY1D, &arrays[1]);
  anariSetParameter(dev, field, "cell.index", ANARI_ARRAY1D, &arrays[2]);
  anariSetParameter(dev, field, "cell.type", ANARI_ARRAY1D, &arrays[3]);
  anariSetParameter(dev, field, "vertex.data", ANARI_ARRAY1D, &arrays[4]);
  return field;
}

/* The first of the launchers' variables that is set: Open MPI's, then the
 * PMI ones that MPICH's hydra and PMIx launchers set. */
static int env_int(const char *const names[3], int otherwise)
{
  int i;
  for (i = 0; i < 3; ++i) {
    const char *v = getenv(names[i]);
    if (v)
      return atoi(v);
  }
  return otherwise;
}

static const char *const RANK_VARS[3] = {"OMPI_COMM_WORLD_RANK", "PMI_RANK", "PMIX_RANK"};
static const char *const SIZE_VARS[3] = {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE"};

int main(int argc, char **argv)
{
  const char *dir = argc > 1 ? argv[1] : ".";
  int whole = argc > 2 && strcmp(argv[2], "whole") == 0;
  int unowned = argc > 2 && strcmp(argv[2], "unowned") == 0;
  int cells = argc > 3 && strcmp(argv[3], "cells") == 0;
  int rank = whole ? 0 : env_int(RANK_VARS, 0);
  int ranks = whole ? 1 : env_int(SIZE_VARS, 1);
  /* Rank r owns the cells between vertices lo and hi along x. */
  int lo = (N - 1) * rank / ranks, hi = (N - 1) * (rank + 1) / ranks;
  int first = lo > 0 ? lo - 1 : 0, last = hi < N - 1 ? hi + 1 : N - 1;
  int nx = last - first + 1, i, j, k;
  float spacing = 1.0f / (N - 1);
  float origin[3] = {first * spacing, 0, 0}, spacings[3] = {spacing, spacing, spacing};
  float region[6] = {lo * spacing, 0, 0, hi * spacing, 1, 1};
  float *voxels = malloc(sizeof(float) * nx * N * N);
  float colors[4 * 3] = {0.1f, 0.2f, 0.9f, 0.2f, 0.9f, 0.4f, 1.0f, 0.8f, 0.2f, 1.0f, 0.2f, 0.1f};
  float opacities[4] = {0.02f, 0.5f, 1.0f, 1.0f}, unit = 0.1f;
  float range[2] = {0.0f, 1.1f};
  float eye[3] = {1.6f, 1.1f, -0.8f}, at[3] = {0.5f, 0.5f, 0.5f}, up[3] = {0, 1, 0}, dir3[3];
  float aspect = 1.0f, fovy = 0.75f;
  unsigned size[2] = {SIZE, SIZE};
  ANARIDataType color_type = ANARI_UFIXED8_RGBA_SRGB;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray3D data = NULL;
  ANARIArray1D mesh[5] = {NULL, NULL, NULL, NULL, NULL};
  ANARIArray1D color, opacity, volumes;
  ANARISpatialField field;
  ANARIVolume volume;
  ANARIWorld world;
  ANARICamera camera;
  ANARIRenderer renderer;
  ANARIFrame frame;
  const void *pixels;
  uint32_t w, h;
  ANARIDataType type;
  int ok;

  if (!voxels)
    return 2;
  for (k = 0; k < N; ++k)
    for (j = 0; j < N; ++j)
      for (i = 0; i < nx; ++i)
        voxels[(k * N + j) * nx + i] = value_at(first + i, j, k);

  lib = anariLoadLibrary("caveray", count_status, "mpi_bricks");
  dev = anariNewDevice(lib, "default");
  anariSetParameter(dev, dev, "backend", ANARI_STRING, "cpu");
  if (!whole)
    anariSetParameter(dev, dev, "caveray.mpi", ANARI_STRING, "world");
  anariCommitParameters(dev, dev);
  if (cells) {
    field = tetrahedra(dev, voxels, nx, first, spacing, mesh);
  } else {
    data = anariNewArray3D(dev, voxels, NULL, NULL, ANARI_FLOAT32, nx, N, N);
    field = anariNewSpatialField(dev, "structuredRegular");
    anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &data);
    anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, origin);
    anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, spacings);
  }
  anariCommitParameters(dev, field);
  volume = anariNewVolume(dev, "transferFunction1D");
  color = anariNewArray1D(dev, colors, NULL, NULL, ANARI_FLOAT32_VEC3, 4);
  opacity = anariNewArray1D(dev, opacities, NULL, NULL, ANARI_FLOAT32, 4);
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &color);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &opacity);
  anariSetParameter(dev, volume, "valueRange", ANARI_FLOAT32_BOX1, range);
  anariSetParameter(dev, volume, "unitDistance", ANARI_FLOAT32, &unit);
  anariCommitParameters(dev, volume);
  world = anariNewWorld(dev);
  volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  if (!whole && !unowned)
    anariSetParameter(dev, world, "caveray.region", ANARI_FLOAT32_BOX3, region);
  anariCommitParameters(dev, world);

  for (i = 0; i < 3; ++i)
    dir3[i] = at[i] - eye[i];
  camera = anariNewCamera(dev, "perspective");
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, eye);
  anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, dir3);
  anariSetParameter(dev, camera, "up", ANARI_FLOAT32_VEC3, up);
  anariSetParameter(dev, camera, "aspect", ANARI_FLOAT32, &aspect);
  anariSetParameter(dev, camera, "fovy", ANARI_FLOAT32, &fovy);
  anariCommitParameters(dev, camera);
  renderer = anariNewRenderer(dev, "default");
  anariCommitParameters(dev, renderer);
  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, size);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &color_type);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariCommitParameters(dev, frame);

  /* Twice: the second frame's collectives follow the first's. */
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  pixels = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  ok = pixels && w == SIZE && h == SIZE && type == ANARI_UFIXED8_RGBA_SRGB && status_count == 0;
  if (ok && rank == 0)
    ok = write_rgba(dir, whole ? (cells ? "whole_cells" : "whole") : (cells ? "cells" : "bricks"),
        pixels, w, h);
  anariUnmapFrame(dev, frame, "channel.color");
  printf("rank %d of %d: %s\n", rank, ranks, ok ? "mapped" : "FAILED");

  anariRelease(dev, frame);
  anariRelease(dev, renderer);
  anariRelease(dev, camera);
  anariRelease(dev, volumes);
  anariRelease(dev, world);
  anariRelease(dev, opacity);
  anariRelease(dev, color);
  anariRelease(dev, volume);
  anariRelease(dev, field);
  if (data)
    anariRelease(dev, data);
  for (i = 0; i < 5; ++i)
    if (mesh[i])
      anariRelease(dev, mesh[i]);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  free(voxels);
  return ok ? 0 : 1;
}
