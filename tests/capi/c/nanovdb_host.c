/* A `nanovdb` field as a host sends one (KHR_SPATIAL_FIELD_NANOVDB): the
 * grid's buffer, written by the NanoVDB library (argv[1]: a fog-volume
 * sphere, voxel size 0.5, centre (1.5, -2, 0.5), radius 6), in an
 * ARRAY1D of UINT8 made over the host's memory. Checks that a buffer
 * whose magic number is spoilt is refused by name, that the grid then
 * commits and the host may free its memory, that the sphere shows in the
 * middle and not at the edge, that `cubic` reads as linear with a
 * warning naming it, and (under valgrind) that nothing leaks. Prints
 * PASS/FAIL per check; exit status 1 on any FAIL. */
#include <anari/anari.h>

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "expect.h"
#include "volume_view.h"

#define SIZE 40

/* The file's bytes, or NULL; its size in *n. */
static uint8_t *slurp(const char *path, uint64_t *n)
{
  FILE *f = fopen(path, "rb");
  uint8_t *data = NULL;
  long size;
  if (!f)
    return NULL;
  if (fseek(f, 0, SEEK_END) == 0 && (size = ftell(f)) > 0 && fseek(f, 0, SEEK_SET) == 0) {
    data = malloc((size_t)size);
    if (data && fread(data, 1, (size_t)size, f) != (size_t)size) {
      free(data);
      data = NULL;
    }
    *n = (uint64_t)size;
  }
  fclose(f);
  return data;
}

int main(int argc, char **argv)
{
  static uint8_t first[4 * SIZE * SIZE], second[4 * SIZE * SIZE];
  float eye[3] = {1.5f, -2.0f, 30.0f}, range[2] = {0, 1};
  uint64_t n = 0;
  uint8_t *blob;
  int mid, edge;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray1D data;
  ANARISpatialField field;
  VolumeView view;

  if (argc != 2 || !(blob = slurp(argv[1], &n)) || n < 16) {
    printf("FAIL nanovdb_host: usage: nanovdb_host GRID.blob (a NanoVDB grid's buffer)\n");
    return 1;
  }
  reset();
  lib = anariLoadLibrary("caveray", on_status, NULL);
  check("library loads", lib != NULL);
  dev = anariNewDevice(lib, "default");
  anariSetParameter(dev, dev, "backend", ANARI_STRING, "cpu");
  anariCommitParameters(dev, dev);

  field = anariNewSpatialField(dev, "nanovdb");
  blob[0] ^= 0x20;
  data = anariNewArray1D(dev, blob, NULL, NULL, ANARI_UINT8, n);
  anariSetParameter(dev, field, "data", ANARI_ARRAY1D, &data);
  anariCommitParameters(dev, field);
  expect("a spoilt magic number", ERR, BAD_ARG, "magic number");
  anariRelease(dev, data);
  blob[0] ^= 0x20;
  data = anariNewArray1D(dev, blob, NULL, NULL, ANARI_UINT8, n);
  anariSetParameter(dev, field, "data", ANARI_ARRAY1D, &data);
  anariCommitParameters(dev, field);
  expect_quiet("the grid commits");
  /* The host may let go of its memory once the field holds the grid. */
  anariRelease(dev, data);
  free(blob);

  view = volume_view(dev, field, range, eye, SIZE);
  expect_quiet("the scene commits");

  check("the grid renders", render_rgba(dev, view.frame, SIZE, first));
  mid = lit_columns(first, SIZE, SIZE / 3, 2 * SIZE / 3);
  edge = lit_columns(first, SIZE, 0, SIZE / 8);
  printf("     lit in the middle third %d, at the left edge %d\n", mid, edge);
  check("the sphere shows in the middle and not at the edge", mid > 100 && edge == 0);
  expect_quiet("the render");

  anariSetParameter(dev, field, "filter", ANARI_STRING, "cubic");
  anariCommitParameters(dev, field);
  expect("cubic", WARN, ANARI_STATUS_NO_ERROR, "'cubic' is not implemented");
  check("cubic renders", render_rgba(dev, view.frame, SIZE, second));
  check("cubic reads as linear", memcmp(first, second, sizeof first) == 0);

  anariRelease(dev, field);
  volume_view_release(dev, &view);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  printf("%s: %d failure(s)\n", failures ? "FAIL" : "PASS", failures);
  return failures ? 1 : 0;
}
