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

int main(int argc, char **argv)
{
  static uint8_t first[4 * SIZE * SIZE], second[4 * SIZE * SIZE];
  float eye[3] = {1.5f, -2.0f, 30.0f}, up[3] = {0, 1, 0}, dir[3] = {0, 0, -1};
  float range[2] = {0, 1}, opacity[2] = {0.0f, 0.8f};
  float tf_colors[6] = {0.2f, 0.4f, 1, 1, 0.6f, 0.2f}, background[4] = {0, 0, 0, 0};
  unsigned size[2] = {SIZE, SIZE};
  ANARIDataType color_type = ANARI_UFIXED8_VEC4;
  uint64_t n = 0;
  uint8_t *blob;
  int mid, edge;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray1D data, volumes, tf_color, tf_opacity;
  ANARISpatialField field;
  ANARIVolume volume;
  ANARIWorld world;
  ANARIRenderer renderer;
  ANARICamera camera;
  ANARIFrame frame;

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

  check("the grid renders", render(dev, frame, first));
  mid = lit(first, SIZE / 3, 2 * SIZE / 3);
  edge = lit(first, 0, SIZE / 8);
  printf("     lit in the middle third %d, at the left edge %d\n", mid, edge);
  check("the sphere shows in the middle and not at the edge", mid > 100 && edge == 0);
  expect_quiet("the render");

  anariSetParameter(dev, field, "filter", ANARI_STRING, "cubic");
  anariCommitParameters(dev, field);
  expect("cubic", WARN, ANARI_STATUS_NO_ERROR, "'cubic' is not implemented");
  check("cubic renders", render(dev, frame, second));
  check("cubic reads as linear", memcmp(first, second, sizeof first) == 0);

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
