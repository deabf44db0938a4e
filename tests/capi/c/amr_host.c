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
#include "volume_view.h"

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
  float eye[3] = {8, 8, 40}, range[2] = {0, 2};
  uint32_t ratio = 2;
  int i, mid, edge, n = 0;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray1D width_array, bounds_array, level_array, bad_level_array, data_list, all_array;
  ANARIArray3D blocks[BLOCKS];
  ANARISpatialField field;
  VolumeView view;

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

  view = volume_view(dev, field, range, eye, SIZE);
  expect_quiet("the scene commits");

  check("the OpenCOVER form renders", render_rgba(dev, view.frame, SIZE, first));
  mid = lit_columns(first, SIZE, SIZE / 3, 2 * SIZE / 3);
  edge = lit_columns(first, SIZE, 0, SIZE / 8);
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
  check("the visionaray form renders", render_rgba(dev, view.frame, SIZE, second));
  check("both forms give the same image", memcmp(first, second, sizeof first) == 0);

  anariRelease(dev, width_array);
  anariRelease(dev, bounds_array);
  anariRelease(dev, level_array);
  anariRelease(dev, bad_level_array);
  anariRelease(dev, data_list);
  anariRelease(dev, all_array);
  anariRelease(dev, field);
  volume_view_release(dev, &view);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  printf("%s: %d failure(s)\n", failures ? "FAIL" : "PASS", failures);
  return failures ? 1 : 0;
}
