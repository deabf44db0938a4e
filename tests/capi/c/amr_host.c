/* An `amr` field as OpenCOVER's plug-in sends one from a FLASH file
 * (HOSTS.md): `cellWidth` per level (level 0 the finest), `block.bounds`
 * as INT32_BOX3 in each level's own index space, `block.level` INT32 and
 * `block.data` an array declared ANARI_ARRAY1D holding one ARRAY3D of
 * FLOAT32 per block, log-transformed values, the parent block sent
 * beside its children, no origin or spacing; a volume with `valueRange`.
 * Then the same cells in anari-visionaray's form (`refinementRatio`, one
 * `data`), which must give the same image. Checks that the field shows,
 * that a block past the levels is refused with its number and the device
 * renders on, and (under valgrind) that nothing leaks. Prints PASS/FAIL
 * per check; exit status 1 on any FAIL. */
#include <anari/anari.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "expect.h"

#define SIZE 40
#define COARSE 8 /* cells per axis of the parent, 2 units wide */
#define FINE 8   /* cells per axis of each child, 1 unit wide */
#define BLOCKS 3

/* A density peaking at the box's centre (8, 8, 8), as FLASH's dens. */
static float density(float x, float y, float z)
{
  float dx = x - 8.0f, dy = y - 8.0f, dz = z - 8.0f;
  return 1.0f + 100.0f * expf(-(dx * dx + dy * dy + dz * dz) / 12.0f);
}

/* Fills block b's cells (width w, lower cell lo) with log10(density). */
static void fill(float *out, int n, float w, const int lo[3])
{
  int x, y, z;
  for (z = 0; z < n; ++z)
    for (y = 0; y < n; ++y)
      for (x = 0; x < n; ++x)
        *out++ = log10f(density((lo[0] + x + 0.5f) * w, (lo[1] + y + 0.5f) * w,
            (lo[2] + z + 0.5f) * w));
}

/* RGBA8 pixels of one render, into `out` (SIZE x SIZE). */
static int render(ANARIDevice dev, ANARIFrame frame, uint8_t *out)
{
  uint32_t w = 0, h = 0;
  ANARIDataType type;
  const uint8_t *p;
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  p = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  if (!p || w != SIZE || h != SIZE)
    return 0;
  memcpy(out, p, 4 * SIZE * SIZE);
  anariUnmapFrame(dev, frame, "channel.color");
  return 1;
}

static int lit(const uint8_t *p, int x0, int x1)
{
  int n = 0, x, y;
  for (y = 0; y < SIZE; ++y)
    for (x = x0; x < x1; ++x)
      if (p[4 * (y * SIZE + x) + 3] > 40)
        n++;
  return n;
}

int main(void)
{
  /* The parent covers [0, 16)^3 in finest cells; two children side by
   * side refine [0, 16) x [4, 12) x [4, 12). */
  static const int32_t bounds[BLOCKS][6] = {
      {0, 0, 0, 7, 7, 7},
      {0, 4, 4, 7, 11, 11},
      {8, 4, 4, 15, 11, 11},
  };
  static const int32_t levels[BLOCKS] = {1, 0, 0};
  static const int32_t bad_levels[BLOCKS] = {1, 0, 2};
  static const float widths[2] = {1.0f, 2.0f};
  static float coarse[COARSE * COARSE * COARSE];
  static float fine[2][FINE * FINE * FINE];
  static float all[COARSE * COARSE * COARSE + 2 * FINE * FINE * FINE];
  static uint8_t first[4 * SIZE * SIZE], second[4 * SIZE * SIZE];
  float eye[3] = {8, 8, 40}, up[3] = {0, 1, 0}, dir[3] = {0, 0, -1};
  float range[2] = {0, 2}, opacity[2] = {0.0f, 0.8f};
  float tf_colors[6] = {0.2f, 0.4f, 1, 1, 0.6f, 0.2f}, background[4] = {0, 0, 0, 0};
  unsigned size[2] = {SIZE, SIZE};
  uint32_t ratio = 2;
  ANARIDataType color_type = ANARI_UFIXED8_VEC4;
  int i, mid, edge, n = 0;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray1D width_array, bounds_array, level_array, bad_level_array, data_list, all_array;
  ANARIArray1D volumes, tf_color, tf_opacity;
  ANARIArray3D blocks[BLOCKS];
  ANARISpatialField field;
  ANARIVolume volume;
  ANARIWorld world;
  ANARIRenderer renderer;
  ANARICamera camera;
  ANARIFrame frame;

  fill(coarse, COARSE, 2.0f, bounds[0]);
  fill(fine[0], FINE, 1.0f, bounds[1]);
  fill(fine[1], FINE, 1.0f, bounds[2]);
  memcpy(all, coarse, sizeof coarse);
  n = COARSE * COARSE * COARSE;
  memcpy(all + n, fine[0], sizeof fine[0]);
  memcpy(all + n + FINE * FINE * FINE, fine[1], sizeof fine[1]);

  reset();
  lib = anariLoadLibrary("caveray", on_status, NULL);
  check("library loads", lib != NULL);
  dev = anariNewDevice(lib, "default");
  anariSetParameter(dev, dev, "backend", ANARI_STRING, "cpu");
  anariCommitParameters(dev, dev);

  width_array = anariNewArray1D(dev, widths, NULL, NULL, ANARI_FLOAT32, 2);
  bounds_array = anariNewArray1D(dev, bounds, NULL, NULL, ANARI_INT32_BOX3, BLOCKS);
  level_array = anariNewArray1D(dev, levels, NULL, NULL, ANARI_INT32, BLOCKS);
  bad_level_array = anariNewArray1D(dev, bad_levels, NULL, NULL, ANARI_INT32, BLOCKS);
  blocks[0] = anariNewArray3D(dev, coarse, NULL, NULL, ANARI_FLOAT32, COARSE, COARSE, COARSE);
  blocks[1] = anariNewArray3D(dev, fine[0], NULL, NULL, ANARI_FLOAT32, FINE, FINE, FINE);
  blocks[2] = anariNewArray3D(dev, fine[1], NULL, NULL, ANARI_FLOAT32, FINE, FINE, FINE);
  /* OpenCOVER declares the list's element type ANARI_ARRAY1D. */
  data_list = anariNewArray1D(dev, blocks, NULL, NULL, ANARI_ARRAY1D, BLOCKS);
  expect_quiet("the block arrays are made");

  field = anariNewSpatialField(dev, "amr");
  anariSetParameter(dev, field, "cellWidth", ANARI_ARRAY1D, &width_array);
  anariSetParameter(dev, field, "block.bounds", ANARI_ARRAY1D, &bounds_array);
  anariSetParameter(dev, field, "block.level", ANARI_ARRAY1D, &bad_level_array);
  anariSetParameter(dev, field, "block.data", ANARI_ARRAY1D, &data_list);
  anariCommitParameters(dev, field);
  expect("a block past the levels", ERR, BAD_ARG, "block 2 is at level 2, and the field has 2 levels");
  anariSetParameter(dev, field, "block.level", ANARI_ARRAY1D, &level_array);
  anariCommitParameters(dev, field);
  expect_quiet("the field commits");
  /* The host may let go of its arrays once the field holds them. */
  for (i = 0; i < BLOCKS; ++i)
    anariRelease(dev, blocks[i]);

  tf_color = anariNewArray1D(dev, tf_colors, NULL, NULL, ANARI_FLOAT32_VEC3, 2);
  tf_opacity = anariNewArray1D(dev, opacity, NULL, NULL, ANARI_FLOAT32, 2);
  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &tf_color);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &tf_opacity);
  anariSetParameter(dev, volume, "valueRange", ANARI_FLOAT32_BOX1, range);
  anariCommitParameters(dev, volume);
  volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  world = anariNewWorld(dev);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  anariCommitParameters(dev, world);
  renderer = anariNewRenderer(dev, "default");
  anariSetParameter(dev, renderer, "background", ANARI_FLOAT32_VEC4, background);
  anariCommitParameters(dev, renderer);
  camera = anariNewCamera(dev, "perspective");
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, eye);
  anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, dir);
  anariSetParameter(dev, camera, "up", ANARI_FLOAT32_VEC3, up);
  anariCommitParameters(dev, camera);
  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, size);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &color_type);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariCommitParameters(dev, frame);
  expect_quiet("the scene commits");

  check("the OpenCOVER form renders", render(dev, frame, first));
  mid = lit(first, SIZE / 3, 2 * SIZE / 3);
  edge = lit(first, 0, SIZE / 8);
  printf("     lit in the middle third %d, at the left edge %d\n", mid, edge);
  check("the dense middle shows and the thin edge does not", mid > 100 && edge < mid / 10);
  expect_quiet("the render");

  /* The same cells as anari-visionaray sends them. */
  all_array = anariNewArray1D(dev, all, NULL, NULL, ANARI_FLOAT32, n + 2 * FINE * FINE * FINE);
  anariUnsetParameter(dev, field, "cellWidth");
  anariUnsetParameter(dev, field, "block.data");
  anariSetParameter(dev, field, "refinementRatio", ANARI_UINT32, &ratio);
  anariSetParameter(dev, field, "data", ANARI_ARRAY1D, &all_array);
  anariCommitParameters(dev, field);
  expect_quiet("the visionaray form commits");
  check("the visionaray form renders", render(dev, frame, second));
  check("both forms give the same image", memcmp(first, second, sizeof first) == 0);

  anariRelease(dev, width_array);
  anariRelease(dev, bounds_array);
  anariRelease(dev, level_array);
  anariRelease(dev, bad_level_array);
  anariRelease(dev, data_list);
  anariRelease(dev, all_array);
  anariRelease(dev, tf_color);
  anariRelease(dev, tf_opacity);
  anariRelease(dev, volumes);
  anariRelease(dev, field);
  anariRelease(dev, volume);
  anariRelease(dev, world);
  anariRelease(dev, renderer);
  anariRelease(dev, camera);
  anariRelease(dev, frame);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  printf("%s: %d failure(s)\n", failures ? "FAIL" : "PASS", failures);
  return failures ? 1 : 0;
}
