/* A volume from the host's own memory, read where it lies: a shared
 * FLOAT32 array (anariNewArray3D with the host's pointer, no deleter) is
 * not copied while the host holds it (the field's caveray.residentBytes is
 * 0, and the process grows by far less than the voxels); when the host
 * releases the array while a frame renders it, and then scribbles over
 * its memory and frees it, the device has copied it first (after that
 * render), said so once at PERFORMANCE severity, and every frame renders
 * the same image.
 * Usage: in_place_host SCENE_FILE OUT_DIR. Writes OUT_DIR/held.rgba (the
 * host's memory) and OUT_DIR/freed.rgba (after it is freed); prints
 * "grew KB voxels KB" and "copies N"; exit status 0 only if every check
 * held and the status callback saw no error. */
#include <anari/anari.h>

#include <math.h>
#include <string.h>

#include "in_place.h"

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
  ANARIFrame first, second;
  float *data;
  size_t count, i;
  long before, grew;
  int ok = 1;

  if (argc != 3 || !scene_load(argv[1], &s)) {
    fprintf(stderr, "usage: in_place_host SCENE_FILE OUT_DIR\n");
    return 2;
  }
  count = (size_t)s.dims[0] * s.dims[1] * s.dims[2];
  lib = anariLoadLibrary("caveray", watch_status, "in_place_host");
  dev = anariNewDevice(lib, "default");
  /* The CPU renderer: probing a GPU would load a driver, whose memory is
   * not what this measures. */
  anariSetParameter(dev, dev, "backend", ANARI_STRING, "cpu");
  anariCommitParameters(dev, dev);

  data = (float *)malloc(count * sizeof(float));
  memcpy(data, s.voxels, count * sizeof(float));
  before = resident_kb();
  voxels = anariNewArray3D(dev, data, NULL, NULL, ANARI_FLOAT32, s.dims[0], s.dims[1], s.dims[2]);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &voxels);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, s.origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, s.spacing);
  anariCommitParameters(dev, field);

  colors = anariNewArray1D(dev, s.colors, NULL, NULL, ANARI_FLOAT32_VEC4, s.ncolors);
  opacities = anariNewArray1D(dev, s.opacities, NULL, NULL, ANARI_FLOAT32, s.nopacities);
  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &colors);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &opacities);
  anariSetParameter(dev, volume, "valueRange", ANARI_FLOAT32_BOX1, s.range);
  anariSetParameter(dev, volume, "unitDistance", ANARI_FLOAT32, &s.unitDistance);
  anariCommitParameters(dev, volume);
  volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  world = anariNewWorld(dev);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  anariCommitParameters(dev, world);

  /* While the host holds its memory, the field holds none of it. */
  ok &= holds(dev, field, 0, "in_place_host: the field, while the host holds the voxels,");
  first = new_frame(dev, &s, world);
  ok &= render_saved(dev, first, argv[2], "held");
  grew = resident_kb() - before;
  printf("grew %ld KB voxels %zu KB\n", grew, count * sizeof(float) / 1024);

  /* Released while a frame renders it, then scribbled over and freed: the
   * copy waits for that render, and later frames read the copy. */
  second = new_frame(dev, &s, world);
  anariRenderFrame(dev, second);
  anariRelease(dev, voxels);
  for (i = 0; i < count; ++i)
    data[i] = NAN;
  free(data);
  anariFrameReady(dev, second, ANARI_WAIT);
  ok &= save(dev, second, argv[2], "freed");
  ok &= render_saved(dev, first, argv[2], "again");
  ok &= holds(dev, field, count * sizeof(float), "in_place_host: the field, after the release,");
  printf("copies %d\n", copies);
  if (copies != 1) {
    fprintf(stderr, "in_place_host: %d PERFORMANCE notes of a copy, not one\n", copies);
    ok = 0;
  }

  anariRelease(dev, first);
  anariRelease(dev, second);
  anariRelease(dev, world);
  anariRelease(dev, volumes);
  anariRelease(dev, volume);
  anariRelease(dev, colors);
  anariRelease(dev, opacities);
  anariRelease(dev, field);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  scene_free(&s);
  return ok && status_count == 0 ? 0 : 1;
}
