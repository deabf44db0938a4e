/* The pattern of the ANARI SDK's test scenes and conformance tests: arrays
 * on the host's memory are set as parameters, their handles released, and
 * the memory overwritten and freed at once, all before the objects that use
 * them are committed. ANARI allows it (a shared array is the host's again
 * once its last handle is gone), so the device must have copied what it
 * still needs. A captured array (one with a deleter) stays the device's
 * until the deleter runs, exactly once, when nothing uses it any more.
 * Usage: release_then_free SCENE_FILE OUT_DIR. Writes OUT_DIR/freed.rgba
 * (matrix camera); exit status 0 only if the render succeeded, the status
 * callback saw no error and the deleter ran exactly once, at the end. */
#include <anari/anari.h>

#include <math.h>

#include "scene.h"
#include "status.h"

static int deleted = 0;

static void count_delete(const void *user, const void *memory)
{
  (void)user;
  ++deleted;
  free((void *)memory);
}

/* A copy of `n` floats the host owns until it frees them. */
static float *host_copy(const float *from, size_t n)
{
  float *to = (float *)malloc(n * sizeof(float));
  memcpy(to, from, n * sizeof(float));
  return to;
}

/* What a host may do once it released its last handle: reuse the memory,
 * then free it. NaN makes any later read by the device visible. */
static void scribble_and_free(float *memory, size_t n)
{
  size_t i;
  for (i = 0; i < n; ++i)
    memory[i] = NAN;
  free(memory);
}

int main(int argc, char **argv)
{
  Scene s;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray3D voxels;
  ANARIArray1D colors, opacities, volumes;
  ANARISpatialField field;
  ANARIVolume volume;
  ANARIWorld world;
  ANARIRenderer renderer;
  ANARIFrame frame;
  ANARICamera camera;
  ANARIVolume *volume_list;
  ANARIDataType color_type = ANARI_UFIXED8_VEC4;
  uint32_t w = 0, h = 0;
  ANARIDataType type = ANARI_UNKNOWN;
  const void *pixels;
  float *data, *rgba, *alpha;
  size_t count;
  int ok = 1;

  if (argc != 3 || !scene_load(argv[1], &s)) {
    fprintf(stderr, "usage: release_then_free SCENE_FILE OUT_DIR\n");
    return 2;
  }
  count = (size_t)s.dims[0] * s.dims[1] * s.dims[2];
  lib = anariLoadLibrary("caveray", count_status, "release_then_free");
  dev = anariNewDevice(lib, "default");

  data = host_copy(s.voxels, count);
  voxels = anariNewArray3D(dev, data, NULL, NULL, ANARI_FLOAT32, s.dims[0], s.dims[1], s.dims[2]);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &voxels);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, s.origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, s.spacing);
  anariRelease(dev, voxels);
  scribble_and_free(data, count);
  anariCommitParameters(dev, field);

  rgba = host_copy(s.colors, 4 * (size_t)s.ncolors);
  alpha = host_copy(s.opacities, s.nopacities);
  colors = anariNewArray1D(dev, rgba, NULL, NULL, ANARI_FLOAT32_VEC4, s.ncolors);
  opacities = anariNewArray1D(dev, alpha, NULL, NULL, ANARI_FLOAT32, s.nopacities);
  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &colors);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &opacities);
  anariSetParameter(dev, volume, "valueRange", ANARI_FLOAT32_BOX1, s.range);
  anariSetParameter(dev, volume, "unitDistance", ANARI_FLOAT32, &s.unitDistance);
  anariRelease(dev, colors);
  anariRelease(dev, opacities);
  scribble_and_free(rgba, 4 * (size_t)s.ncolors);
  scribble_and_free(alpha, s.nopacities);
  anariCommitParameters(dev, volume);
  anariRelease(dev, field);

  /* Captured: the device frees this list through the deleter. */
  volume_list = (ANARIVolume *)malloc(sizeof(ANARIVolume));
  volume_list[0] = volume;
  volumes = anariNewArray1D(dev, volume_list, count_delete, NULL, ANARI_VOLUME, 1);
  world = anariNewWorld(dev);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  anariRelease(dev, volumes);
  anariRelease(dev, volume);
  anariCommitParameters(dev, world);
  if (deleted != 0) {
    fprintf(stderr, "release_then_free: the deleter ran while the world uses the array\n");
    ok = 0;
  }

  renderer = anariNewRenderer(dev, "default");
  anariCommitParameters(dev, renderer);
  camera = anariNewCamera(dev, "matrix");
  anariSetParameter(dev, camera, "view", ANARI_FLOAT32_MAT4, s.view);
  anariSetParameter(dev, camera, "proj", ANARI_FLOAT32_MAT4, s.proj);
  anariCommitParameters(dev, camera);

  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, s.size);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &color_type);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariCommitParameters(dev, frame);
  anariRelease(dev, camera);
  anariRelease(dev, renderer);
  anariRelease(dev, world);

  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  pixels = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  ok &= pixels && type == ANARI_UFIXED8_VEC4 && write_rgba(argv[2], "freed", pixels, w, h);
  if (pixels)
    anariUnmapFrame(dev, frame, "channel.color");

  anariRelease(dev, frame);
  anariRelease(dev, dev);
  /* A released device's teardown may outlast its release (it runs on, in
   * the background, until unloading the library): by then the deleter has
   * run, exactly once. */
  anariUnloadLibrary(lib);
  if (deleted != 1) {
    fprintf(stderr, "release_then_free: the deleter ran %d times, not once\n", deleted);
    ok = 0;
  }
  scene_free(&s);
  return ok && status_count == 0 ? 0 : 1;
}
