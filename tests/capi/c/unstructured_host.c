/* An unstructured field as OpenCOVER's plug-in sends one (HOSTS.md): one
 * cell of each kind side by side along x (a tetrahedron, a hexahedron, a
 * wedge and a pyramid, VTK's vertex order), vertex.position padded past
 * the vertices the cells use, cell.type UINT8 with VTK's codes, values per
 * vertex, then the same field recommitted with values per cell and
 * cell.type as UINT32 (pynari's way); a volume with `id` and
 * `valueRange`. Checks that each cell shows, that a bad index is refused
 * with the array, the element and the reason while the device still
 * renders, and (under valgrind) that nothing leaks. Prints PASS/FAIL per
 * check; exit status 1 on any FAIL. */
#include <anari/anari.h>

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "expect.h"

#define SIZE 48
#define VERTICES 23

/* How many pixels of each quarter of the frame (by x) show the volume. */
static void lit_quarters(ANARIDevice dev, ANARIFrame frame, int out[4])
{
  uint32_t w = 0, h = 0, x, y;
  ANARIDataType type;
  const uint8_t *p;
  memset(out, 0, 4 * sizeof(int));
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  p = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  if (!p || w != SIZE || h != SIZE)
    return;
  for (y = 0; y < h; ++y)
    for (x = 0; x < w; ++x)
      if (p[4 * (y * w + x) + 3] > 40)
        out[x * 4 / w]++;
  anariUnmapFrame(dev, frame, "channel.color");
}

int main(void)
{
  /* Cells one unit wide at x = 0, 1.5, 3 and 4.5 (shifted to centre). */
  static float positions[3 * VERTICES * 3]; /* 3 x the vertices: padding */
  static const float cells[VERTICES][3] = {
      /* tetrahedron */
      {0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1},
      /* hexahedron */
      {1.5f, 0, 0}, {2.5f, 0, 0}, {2.5f, 1, 0}, {1.5f, 1, 0},
      {1.5f, 0, 1}, {2.5f, 0, 1}, {2.5f, 1, 1}, {1.5f, 1, 1},
      /* wedge */
      {3, 0, 0}, {4, 0, 0}, {3, 1, 0}, {3, 0, 1}, {4, 0, 1}, {3, 1, 1},
      /* pyramid */
      {4.5f, 0, 0}, {5.5f, 0, 0}, {5.5f, 1, 0}, {4.5f, 1, 0}, {5, 0.5f, 1},
  };
  static uint32_t index[VERTICES], bad[VERTICES];
  uint32_t cell_index[4] = {0, 4, 12, 18};
  uint8_t types8[4] = {10, 12, 13, 14};
  uint32_t types32[4] = {10, 12, 13, 14};
  float vertex_data[VERTICES], cell_data[4] = {0.4f, 0.6f, 0.8f, 1.0f};
  float eye[3] = {0, 0, 5}, range[2] = {0, 1}, opacity[2] = {0.5f, 0.5f};
  float tf_colors[6] = {1, 1, 1, 1, 1, 1}, background[4] = {0, 0, 0, 0};
  unsigned size[2] = {SIZE, SIZE};
  ANARIDataType color_type = ANARI_UFIXED8_VEC4;
  uint32_t id = 2;
  int i, k, q[4];
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray1D position_array, index_array, bad_array, cell_array, type8_array, type32_array;
  ANARIArray1D vertex_array, cell_data_array, volumes, tf_color, tf_opacity;
  ANARISpatialField field;
  ANARIVolume volume;
  ANARIWorld world;
  ANARIRenderer renderer;
  ANARICamera camera;
  ANARIFrame frame;

  for (i = 0; i < VERTICES; ++i) {
    for (k = 0; k < 3; ++k)
      positions[3 * i + k] = cells[i][k] - (k == 0 ? 2.75f : 0.5f);
    index[i] = bad[i] = (uint32_t)i;
    vertex_data[i] = 0.3f + 0.03f * (float)i;
  }
  bad[13] = 3 * VERTICES; /* past every position, padding included */
  reset();
  lib = anariLoadLibrary("caveray", on_status, NULL);
  check("library loads", lib != NULL);
  dev = anariNewDevice(lib, "default");
  anariSetParameter(dev, dev, "backend", ANARI_STRING, "cpu");
  anariCommitParameters(dev, dev);

  position_array = anariNewArray1D(dev, positions, NULL, NULL, ANARI_FLOAT32_VEC3, 3 * VERTICES);
  index_array = anariNewArray1D(dev, index, NULL, NULL, ANARI_UINT32, VERTICES);
  bad_array = anariNewArray1D(dev, bad, NULL, NULL, ANARI_UINT32, VERTICES);
  cell_array = anariNewArray1D(dev, cell_index, NULL, NULL, ANARI_UINT32, 4);
  type8_array = anariNewArray1D(dev, types8, NULL, NULL, ANARI_UINT8, 4);
  type32_array = anariNewArray1D(dev, types32, NULL, NULL, ANARI_UINT32, 4);
  vertex_array = anariNewArray1D(dev, vertex_data, NULL, NULL, ANARI_FLOAT32, VERTICES);
  cell_data_array = anariNewArray1D(dev, cell_data, NULL, NULL, ANARI_FLOAT32, 4);

  field = anariNewSpatialField(dev, "unstructured");
  anariSetParameter(dev, field, "vertex.position", ANARI_ARRAY1D, &position_array);
  anariSetParameter(dev, field, "index", ANARI_ARRAY1D, &bad_array);
  anariSetParameter(dev, field, "cell.index", ANARI_ARRAY1D, &cell_array);
  anariSetParameter(dev, field, "cell.type", ANARI_ARRAY1D, &type8_array);
  anariSetParameter(dev, field, "vertex.data", ANARI_ARRAY1D, &vertex_array);
  anariCommitParameters(dev, field);
  expect("an index past the positions", ERR, BAD_ARG, "index[13] = 69 is past the 69 vertex positions");
  anariSetParameter(dev, field, "index", ANARI_ARRAY1D, &index_array);
  anariCommitParameters(dev, field);
  expect_quiet("the field commits");

  tf_color = anariNewArray1D(dev, tf_colors, NULL, NULL, ANARI_FLOAT32_VEC3, 2);
  tf_opacity = anariNewArray1D(dev, opacity, NULL, NULL, ANARI_FLOAT32, 2);
  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &tf_color);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &tf_opacity);
  anariSetParameter(dev, volume, "valueRange", ANARI_FLOAT32_BOX1, range);
  anariSetParameter(dev, volume, "id", ANARI_UINT32, &id);
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
  anariCommitParameters(dev, camera);
  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, size);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &color_type);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariCommitParameters(dev, frame);
  expect_quiet("the scene commits");

  lit_quarters(dev, frame, q);
  printf("     vertex data: lit %d %d %d %d\n", q[0], q[1], q[2], q[3]);
  check("every cell shows with vertex data", q[0] > 5 && q[1] > 5 && q[2] > 5 && q[3] > 5);
  expect_quiet("the render");

  /* The next time step: values per cell, cell.type as pynari sends it. */
  anariUnsetParameter(dev, field, "vertex.data");
  anariSetParameter(dev, field, "cell.data", ANARI_ARRAY1D, &cell_data_array);
  anariSetParameter(dev, field, "cell.type", ANARI_ARRAY1D, &type32_array);
  anariCommitParameters(dev, field);
  expect_quiet("the field with cell data commits");
  lit_quarters(dev, frame, q);
  printf("     cell data: lit %d %d %d %d\n", q[0], q[1], q[2], q[3]);
  check("every cell shows with cell data", q[0] > 5 && q[1] > 5 && q[2] > 5 && q[3] > 5);
  expect_quiet("the second render");

  anariRelease(dev, position_array);
  anariRelease(dev, index_array);
  anariRelease(dev, bad_array);
  anariRelease(dev, cell_array);
  anariRelease(dev, type8_array);
  anariRelease(dev, type32_array);
  anariRelease(dev, vertex_array);
  anariRelease(dev, cell_data_array);
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
