/* A conformance-test-style host, from what the ANARI CTS volume cases send
 * (HOSTS.md): `valueRange` as FLOAT32_VEC2, one FLOAT32_VEC3 color and one
 * FLOAT32 opacity, `unitDistance` 0.1, color (FLOAT32_VEC4) and depth
 * channels, and the camera placed from the world's `bounds`; then a
 * color/opacity array volume rendered with `filter` "nearest" and again
 * with "linear".
 * The field is an 8^3 ramp along x (voxel i holds i / 7) on [-1, 1]^3.
 * Usage: cts_host OUT_DIR. Writes OUT_DIR/cts.bounds (the six numbers),
 * cts_single.color / cts_single.depth, cts_nearest.color and
 * cts_linear.color (FLOAT32, RGBA / one per pixel, lower-left first) and
 * cts.camera (position, direction, up, fovy, aspect). Exit status 0 only
 * if every render succeeded and the status callback saw no warning or
 * error. */
#include <anari/anari.h>

#include <math.h>
#include <string.h>

#include "output.h"
#include "status.h"

#define SIZE 33

static ANARIVolume new_volume(ANARIDevice dev, ANARISpatialField field)
{
  float range[2] = {0.0f, 1.0f}, unit = 0.1f;
  ANARIVolume v = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, v, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, v, "valueRange", ANARI_FLOAT32_VEC2, range);
  anariSetParameter(dev, v, "unitDistance", ANARI_FLOAT32, &unit);
  return v;
}

static void show(ANARIDevice dev, ANARIWorld world, ANARIVolume v)
{
  ANARIArray1D list = anariNewArray1D(dev, &v, NULL, NULL, ANARI_VOLUME, 1);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &list);
  anariCommitParameters(dev, world);
  anariRelease(dev, list);
}

/* Renders and writes the color (and depth if `depth_name`). */
static int render(ANARIDevice dev, ANARIFrame frame, const char *dir,
    const char *color_name, const char *depth_name)
{
  uint32_t w = 0, h = 0;
  ANARIDataType type = ANARI_UNKNOWN;
  const float *color, *depth;
  int ok = 1;
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  color = (const float *)anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  if (!color || w != SIZE || h != SIZE || type != ANARI_FLOAT32_VEC4) {
    fprintf(stderr, "cts_host: no FLOAT32_VEC4 color for %s\n", color_name);
    return 0;
  }
  ok &= write_floats(dir, color_name, color, 4 * SIZE * SIZE);
  anariUnmapFrame(dev, frame, "channel.color");
  if (depth_name) {
    depth = (const float *)anariMapFrame(dev, frame, "channel.depth", &w, &h, &type);
    if (!depth || type != ANARI_FLOAT32) {
      fprintf(stderr, "cts_host: no depth\n");
      return 0;
    }
    ok &= write_floats(dir, depth_name, depth, SIZE * SIZE);
    anariUnmapFrame(dev, frame, "channel.depth");
  }
  return ok;
}

int main(int argc, char **argv)
{
  float ramp[512], origin[3] = {-1, -1, -1}, spacing[3] = {2.0f / 7, 2.0f / 7, 2.0f / 7};
  float color[3] = {1.0f, 0.5f, 0.25f}, opacity = 0.05f;
  float colors[8] = {1, 0, 0, 1, 0, 0, 1, 1}, opacities[2] = {0.05f, 0.05f};
  float bounds[6], camera_out[11], background[4] = {0, 0, 0, 0};
  float position[3], direction[3] = {0, 0, -1}, up[3] = {0, 1, 0};
  float fovy = 0.7f, aspect = 1.0f, diagonal = 0.0f;
  uint32_t size[2] = {SIZE, SIZE};
  ANARIDataType rgba32 = ANARI_FLOAT32_VEC4, depth_type = ANARI_FLOAT32;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray3D data;
  ANARIArray1D color_array, opacity_array;
  ANARISpatialField field;
  ANARIVolume single, mapped;
  ANARIWorld world;
  ANARIRenderer renderer;
  ANARICamera camera;
  ANARIFrame frame;
  FILE *f;
  char path[4200];
  int ok = 1, i;

  if (argc != 2) {
    fprintf(stderr, "usage: cts_host OUT_DIR\n");
    return 2;
  }
  for (i = 0; i < 512; ++i)
    ramp[i] = (float)(i % 8) / 7.0f;
  lib = anariLoadLibrary("caveray", count_status, "cts_host");
  status_level = ANARI_SEVERITY_WARNING;
  dev = anariNewDevice(lib, "default");

  data = anariNewArray3D(dev, ramp, NULL, NULL, ANARI_FLOAT32, 8, 8, 8);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &data);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, spacing);
  anariSetParameter(dev, field, "filter", ANARI_STRING, "nearest");
  anariCommitParameters(dev, field);
  anariRelease(dev, data);

  single = new_volume(dev, field);
  anariSetParameter(dev, single, "color", ANARI_FLOAT32_VEC3, color);
  anariSetParameter(dev, single, "opacity", ANARI_FLOAT32, &opacity);
  anariCommitParameters(dev, single);

  color_array = anariNewArray1D(dev, colors, NULL, NULL, ANARI_FLOAT32_VEC4, 2);
  opacity_array = anariNewArray1D(dev, opacities, NULL, NULL, ANARI_FLOAT32, 2);
  mapped = new_volume(dev, field);
  anariSetParameter(dev, mapped, "color", ANARI_ARRAY1D, &color_array);
  anariSetParameter(dev, mapped, "opacity", ANARI_ARRAY1D, &opacity_array);
  anariCommitParameters(dev, mapped);
  anariRelease(dev, color_array);
  anariRelease(dev, opacity_array);

  world = anariNewWorld(dev);
  show(dev, world, single);

  /* The CTS places its camera from the world's bounds. */
  if (anariGetProperty(dev, world, "bounds", ANARI_FLOAT32_BOX3, bounds, sizeof bounds, ANARI_WAIT) != 1) {
    fprintf(stderr, "cts_host: the world has no bounds\n");
    return 1;
  }
  for (i = 0; i < 3; ++i)
    diagonal += (bounds[3 + i] - bounds[i]) * (bounds[3 + i] - bounds[i]);
  diagonal = sqrtf(diagonal);
  for (i = 0; i < 3; ++i)
    position[i] = 0.5f * (bounds[i] + bounds[3 + i]);
  position[2] += 1.5f * diagonal;
  camera = anariNewCamera(dev, "perspective");
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, position);
  anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, direction);
  anariSetParameter(dev, camera, "up", ANARI_FLOAT32_VEC3, up);
  anariSetParameter(dev, camera, "fovy", ANARI_FLOAT32, &fovy);
  anariSetParameter(dev, camera, "aspect", ANARI_FLOAT32, &aspect);
  anariCommitParameters(dev, camera);

  renderer = anariNewRenderer(dev, "default");
  anariSetParameter(dev, renderer, "background", ANARI_FLOAT32_VEC4, background);
  anariCommitParameters(dev, renderer);

  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, size);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &rgba32);
  anariSetParameter(dev, frame, "channel.depth", ANARI_DATA_TYPE, &depth_type);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariCommitParameters(dev, frame);

  ok &= render(dev, frame, argv[1], "cts_single.color", "cts_single.depth");
  show(dev, world, mapped);
  ok &= render(dev, frame, argv[1], "cts_nearest.color", NULL);
  anariSetParameter(dev, field, "filter", ANARI_STRING, "linear");
  anariCommitParameters(dev, field);
  ok &= render(dev, frame, argv[1], "cts_linear.color", NULL);

  snprintf(path, sizeof path, "%s/cts.bounds", argv[1]);
  f = fopen(path, "w");
  if (f) {
    for (i = 0; i < 6; ++i)
      fprintf(f, "%.9e\n", bounds[i]);
    fclose(f);
  }
  memcpy(camera_out, position, sizeof position);
  memcpy(camera_out + 3, direction, sizeof direction);
  memcpy(camera_out + 6, up, sizeof up);
  camera_out[9] = fovy;
  camera_out[10] = aspect;
  ok &= write_floats(argv[1], "cts.camera", camera_out, 11);

  anariRelease(dev, frame);
  anariRelease(dev, camera);
  anariRelease(dev, renderer);
  anariRelease(dev, world);
  anariRelease(dev, mapped);
  anariRelease(dev, single);
  anariRelease(dev, field);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  return ok && f && status_count == 0 ? 0 : 1;
}
