/* The small scene the C misuse and stereo programs render: an 8^3 field on
 * [-1, 1]^3 whose voxel (i, j, k) holds lo + (hi - lo) * i / 7, through a
 * transferFunction1D of one opacity and, if `rgb` is given, `ncolors`
 * FLOAT32_VEC3 colors. Returns the world; the field and volume are the
 * world's alone. */
#ifndef CAVERAY_TEST_RAMP_WORLD_H
#define CAVERAY_TEST_RAMP_WORLD_H

#include <anari/anari.h>

static ANARIWorld ramp_world(ANARIDevice dev, float lo, float hi, float opacity,
    const float *rgb, uint64_t ncolors)
{
  float voxels[8 * 8 * 8];
  float origin[3] = {-1, -1, -1}, spacing[3] = {2.0f / 7, 2.0f / 7, 2.0f / 7};
  ANARIArray3D data;
  ANARIArray1D colors, volumes;
  ANARISpatialField field;
  ANARIVolume volume;
  ANARIWorld world;
  int i;
  for (i = 0; i < 8 * 8 * 8; ++i)
    voxels[i] = lo + (hi - lo) * (float)(i % 8) / 7.0f;
  /* Released while the field uses it: the device keeps its own copy. */
  data = anariNewArray3D(dev, voxels, NULL, NULL, ANARI_FLOAT32, 8, 8, 8);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &data);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, spacing);
  anariCommitParameters(dev, field);
  anariRelease(dev, data);
  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "opacity", ANARI_FLOAT32, &opacity);
  if (rgb) {
    colors = anariNewArray1D(dev, rgb, NULL, NULL, ANARI_FLOAT32_VEC3, ncolors);
    anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &colors);
    anariRelease(dev, colors);
  }
  anariCommitParameters(dev, volume);
  world = anariNewWorld(dev);
  volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  anariCommitParameters(dev, world);
  anariRelease(dev, volumes);
  anariRelease(dev, volume);
  anariRelease(dev, field);
  return world;
}

#endif
