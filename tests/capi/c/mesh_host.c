/* A visualization host's surfaces beside its volume, as ParaView and
 * OpenCOVER send them: a volume, a quad mesh behind it colored per
 * primitive from shared host memory, sphere glyphs with UFIXED8 vertex
 * colors, all in one world. Checks that the nearest surface shows through
 * the volume, that bad indices are refused at commit and the device still
 * renders, and (under valgrind) that nothing leaks. Prints PASS/FAIL per
 * check; exit status 1 on any FAIL. */
#include <anari/anari.h>

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "expect.h"

#define SIZE 32

static int deletions = 0;
static void count_deletion(const void *user, const void *memory)
{
  (void)user, (void)memory;
  deletions++;
}

static const uint8_t *pixel(const uint8_t *p, int x, int y)
{
  return p + 4 * (y * SIZE + x);
}

int main(void)
{
  static float voxels[4 * 4 * 4];
  /* A quad at z = -0.5 behind the volume's centre, split into a left and
   * a right half; a sphere in front of the volume, right of centre. */
  static float quad_positions[] = {-2, -2, -0.5f, 0, -2, -0.5f, 0, 2, -0.5f, -2, 2, -0.5f,
      2, -2, -0.5f, 2, 2, -0.5f};
  static uint32_t quads[] = {0, 1, 2, 3, 1, 4, 5, 2};
  static uint32_t bad_quads[] = {0, 1, 2, 3, 1, 4, 5, 99};
  static float quad_colors[] = {1, 0, 0, 1, 0, 0, 1, 1};
  float sphere_position[3] = {0.6f, 0, 1.2f}, radius = 0.25f;
  uint8_t sphere_color[4] = {0, 255, 0, 255};
  float eye[3] = {0, 0, 3}, zero = 0.0f, opacity[2] = {0.15f, 0.15f};
  float tf_colors[6] = {1, 1, 1, 1, 1, 1}, range[2] = {0, 1};
  float origin[3] = {-1, -1, -1}, spacing[3] = {2.f / 3, 2.f / 3, 2.f / 3};
  unsigned size[2] = {SIZE, SIZE};
  ANARIDataType color_type = ANARI_UFIXED8_VEC4, id_type = ANARI_UINT32, type;
  uint32_t mesh_id = 3, glyph_id = 4;
  uint32_t w, h;
  int i;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray1D positions, index, bad_index, colors, sphere_positions, sphere_colors;
  ANARIArray1D surfaces, volumes, tf_color, tf_opacity;
  ANARIArray3D grid;
  ANARIGeometry mesh, glyphs;
  ANARIMaterial by_color;
  ANARISurface mesh_surface, glyph_surface;
  ANARISurface list[2];
  ANARISpatialField field;
  ANARIVolume volume;
  ANARIWorld world;
  ANARIRenderer renderer;
  ANARICamera camera;
  ANARIFrame frame;
  const uint8_t *p;

  for (i = 0; i < 64; ++i)
    voxels[i] = 0.5f;
  reset();
  lib = anariLoadLibrary("caveray", on_status, NULL);
  check("library loads", lib != NULL);
  dev = anariNewDevice(lib, "default");
  anariSetParameter(dev, dev, "backend", ANARI_STRING, "cpu");
  anariCommitParameters(dev, dev);

  /* The quad mesh, its arrays in the host's memory until released. */
  positions = anariNewArray1D(dev, quad_positions, count_deletion, NULL, ANARI_FLOAT32_VEC3, 6);
  index = anariNewArray1D(dev, quads, count_deletion, NULL, ANARI_UINT32_VEC4, 2);
  colors = anariNewArray1D(dev, quad_colors, count_deletion, NULL, ANARI_FLOAT32_VEC4, 2);
  mesh = anariNewGeometry(dev, "quad");
  anariSetParameter(dev, mesh, "vertex.position", ANARI_ARRAY1D, &positions);
  anariSetParameter(dev, mesh, "primitive.index", ANARI_ARRAY1D, &index);
  anariSetParameter(dev, mesh, "primitive.color", ANARI_ARRAY1D, &colors);
  anariCommitParameters(dev, mesh);
  expect_quiet("quad mesh commits");

  /* A bad index is refused at commit, naming it. */
  bad_index = anariNewArray1D(dev, bad_quads, NULL, NULL, ANARI_UINT32_VEC4, 2);
  anariSetParameter(dev, mesh, "primitive.index", ANARI_ARRAY1D, &bad_index);
  anariCommitParameters(dev, mesh);
  expect("index out of range", ERR, BAD_ARG, "primitive 1 refers to vertex 99; there are 6 vertices");
  anariSetParameter(dev, mesh, "primitive.index", ANARI_ARRAY1D, &index);
  anariCommitParameters(dev, mesh);
  expect_quiet("the fixed mesh commits");

  sphere_positions = anariNewArray1D(dev, sphere_position, NULL, NULL, ANARI_FLOAT32_VEC3, 1);
  sphere_colors = anariNewArray1D(dev, sphere_color, NULL, NULL, ANARI_UFIXED8_VEC4, 1);
  glyphs = anariNewGeometry(dev, "sphere");
  anariSetParameter(dev, glyphs, "vertex.position", ANARI_ARRAY1D, &sphere_positions);
  anariSetParameter(dev, glyphs, "vertex.color", ANARI_ARRAY1D, &sphere_colors);
  anariSetParameter(dev, glyphs, "radius", ANARI_FLOAT32, &radius);
  anariCommitParameters(dev, glyphs);

  by_color = anariNewMaterial(dev, "matte");
  anariSetParameter(dev, by_color, "color", ANARI_STRING, "color");
  anariCommitParameters(dev, by_color);
  mesh_surface = anariNewSurface(dev);
  anariSetParameter(dev, mesh_surface, "geometry", ANARI_GEOMETRY, &mesh);
  anariSetParameter(dev, mesh_surface, "material", ANARI_MATERIAL, &by_color);
  anariSetParameter(dev, mesh_surface, "id", ANARI_UINT32, &mesh_id);
  anariCommitParameters(dev, mesh_surface);
  glyph_surface = anariNewSurface(dev);
  anariSetParameter(dev, glyph_surface, "geometry", ANARI_GEOMETRY, &glyphs);
  anariSetParameter(dev, glyph_surface, "material", ANARI_MATERIAL, &by_color);
  anariSetParameter(dev, glyph_surface, "id", ANARI_UINT32, &glyph_id);
  anariCommitParameters(dev, glyph_surface);

  /* A faint constant volume over [-1, 1]^3. */
  grid = anariNewArray3D(dev, voxels, NULL, NULL, ANARI_FLOAT32, 4, 4, 4);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &grid);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, spacing);
  anariCommitParameters(dev, field);
  tf_color = anariNewArray1D(dev, tf_colors, NULL, NULL, ANARI_FLOAT32_VEC3, 2);
  tf_opacity = anariNewArray1D(dev, opacity, NULL, NULL, ANARI_FLOAT32, 2);
  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &tf_color);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &tf_opacity);
  anariSetParameter(dev, volume, "valueRange", ANARI_FLOAT32_BOX1, range);
  anariCommitParameters(dev, volume);

  list[0] = mesh_surface;
  list[1] = glyph_surface;
  surfaces = anariNewArray1D(dev, list, NULL, NULL, ANARI_SURFACE, 2);
  volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  world = anariNewWorld(dev);
  anariSetParameter(dev, world, "surface", ANARI_ARRAY1D, &surfaces);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  anariCommitParameters(dev, world);

  renderer = anariNewRenderer(dev, "default");
  anariSetParameter(dev, renderer, "ambientRadiance", ANARI_FLOAT32, &zero);
  anariCommitParameters(dev, renderer);
  camera = anariNewCamera(dev, "perspective");
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, eye);
  anariCommitParameters(dev, camera);
  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, size);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &color_type);
  anariSetParameter(dev, frame, "channel.objectId", ANARI_DATA_TYPE, &id_type);
  anariSetParameter(dev, frame, "channel.primitiveId", ANARI_DATA_TYPE, &id_type);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariCommitParameters(dev, frame);
  expect_quiet("the scene commits");

  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  p = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  check("the frame renders", p != NULL && w == SIZE && h == SIZE);
  if (p) {
    const uint8_t *left = pixel(p, 6, SIZE / 2), *right = pixel(p, SIZE - 7, 4);
    const uint8_t *glyph = pixel(p, SIZE / 2 + 8, SIZE / 2);
    printf("     left %d %d %d, right %d %d %d, glyph %d %d %d\n", left[0], left[1], left[2],
        right[0], right[1], right[2], glyph[0], glyph[1], glyph[2]);
    /* The volume is white: the quads show tinted through it. */
    check("the left quad shows red through the volume", left[0] > left[2] + 60);
    check("the right quad shows blue through the volume", right[2] > right[0] + 60);
    check("the sphere in front shows green", glyph[1] > glyph[0] + 60 && glyph[1] > glyph[2] + 60);
    anariUnmapFrame(dev, frame, "channel.color");
  }
  expect_quiet("the render");

  /* What each pixel shows, by the ids the host gave: the quads (the host's
   * primitives 0 and 1) through the faint volume, the sphere in front. */
  {
    const uint32_t *objects = anariMapFrame(dev, frame, "channel.objectId", &w, &h, &type);
    check("the objectId channel maps as UINT32", objects != NULL && type == ANARI_UINT32);
    if (objects) {
      check("the quads' pixels report the mesh's id", objects[SIZE / 2 * SIZE + 6] == mesh_id
              && objects[4 * SIZE + SIZE - 7] == mesh_id);
      check("the sphere's pixel reports its id", objects[SIZE / 2 * SIZE + SIZE / 2 + 8] == glyph_id);
      anariUnmapFrame(dev, frame, "channel.objectId");
    }
  }
  {
    const uint32_t *prims = anariMapFrame(dev, frame, "channel.primitiveId", &w, &h, &type);
    check("the primitiveId channel maps", prims != NULL && type == ANARI_UINT32);
    if (prims) {
      check("the left and right quads are primitives 0 and 1",
          prims[SIZE / 2 * SIZE + 6] == 0 && prims[4 * SIZE + SIZE - 7] == 1);
      anariUnmapFrame(dev, frame, "channel.primitiveId");
    }
  }
  expect_quiet("the id channels");

  anariRelease(dev, positions);
  anariRelease(dev, index);
  anariRelease(dev, colors);
  anariRelease(dev, bad_index);
  anariRelease(dev, sphere_positions);
  anariRelease(dev, sphere_colors);
  anariRelease(dev, grid);
  anariRelease(dev, tf_color);
  anariRelease(dev, tf_opacity);
  anariRelease(dev, surfaces);
  anariRelease(dev, volumes);
  anariRelease(dev, mesh);
  anariRelease(dev, glyphs);
  anariRelease(dev, by_color);
  anariRelease(dev, mesh_surface);
  anariRelease(dev, glyph_surface);
  anariRelease(dev, field);
  anariRelease(dev, volume);
  anariRelease(dev, world);
  anariRelease(dev, renderer);
  anariRelease(dev, camera);
  anariRelease(dev, frame);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  check("the host's captured arrays are given back", deletions == 3);
  printf("%s: %d failure(s)\n", failures ? "FAIL" : "PASS", failures);
  return failures ? 1 : 0;
}
