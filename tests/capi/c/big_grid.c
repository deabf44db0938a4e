/* A UFIXED8 grid of any size through the C API, as a microscopy or
 * segmentation host would hand it over: shared with the device (no copy
 * on the host's side), on [-1, 1] in every axis whatever its voxel counts,
 * seen by a perspective camera. Writes the frame to DIR/frame.rgba.
 *
 * usage: big_grid DIR NX NY NZ W H
 * The backend comes from CAVERAY_BACKEND. Prints the memory the device
 * reports (the field's voxels; the frame's volumes, and on the GPU).
 * Exit status 0 when the frame rendered, 1 otherwise (every status
 * message is printed). */
#include <anari/anari.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "output.h"

static int failed;

static void on_status(const void *user, ANARIDevice device, ANARIObject source,
    ANARIDataType type, ANARIStatusSeverity severity, ANARIStatusCode code,
    const char *message)
{
  (void)user, (void)device, (void)source, (void)type, (void)code;
  if (severity <= ANARI_SEVERITY_ERROR)
    failed = 1;
  fprintf(stderr, "status %d: %s\n", (int)severity, message);
}

/* Shells about the centre and a tilted slab: detail along every axis, so
 * a misplaced brick shows. */
static uint8_t voxel(uint64_t x, uint64_t y, uint64_t z, uint64_t nx, uint64_t ny, uint64_t nz)
{
  float u = 2.0f * (float)x / (float)(nx - 1) - 1.0f;
  float v = 2.0f * (float)y / (float)(ny > 1 ? ny - 1 : 1) - 1.0f;
  float w = 2.0f * (float)z / (float)(nz > 1 ? nz - 1 : 1) - 1.0f;
  float r = sqrtf(u * u + v * v + w * w);
  float value = 0.5f + 0.5f * sinf(12.0f * r) * expf(-2.0f * r);
  if (fabsf(u + 0.5f * v - w) < 0.05f)
    value += 0.3f;
  if (value > 1.0f)
    value = 1.0f;
  return (uint8_t)(value * 255.0f + 0.5f);
}

int main(int argc, char **argv)
{
  float position[3] = {0.6f, 0.9f, 3.2f}, direction[3], up[3] = {0, 1, 0};
  float origin[3] = {-1, -1, -1}, spacing[3];
  float colors[2 * 3] = {0.2f, 0.4f, 1.0f, 1.0f, 0.8f, 0.3f};
  float opacities[2] = {0.0f, 1.0f}, unit = 0.05f, aspect;
  uint64_t nx, ny, nz, x, y, z, field_bytes = 0, resident = 0, gpu = 0;
  uint32_t size[2], w = 0, h = 0;
  uint8_t *voxels;
  ANARIDataType type = ANARI_UNKNOWN, color = ANARI_UFIXED8_VEC4;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray3D data;
  ANARIArray1D color_array, opacity_array, volumes;
  ANARISpatialField field;
  ANARIVolume volume;
  ANARIWorld world;
  ANARICamera camera;
  ANARIRenderer renderer;
  ANARIFrame frame;
  const void *pixels;
  int ok;
  if (argc != 7) {
    fprintf(stderr, "usage: big_grid DIR NX NY NZ W H\n");
    return 2;
  }
  nx = strtoull(argv[2], NULL, 10), ny = strtoull(argv[3], NULL, 10);
  nz = strtoull(argv[4], NULL, 10);
  size[0] = (uint32_t)atoi(argv[5]), size[1] = (uint32_t)atoi(argv[6]);
  voxels = malloc(nx * ny * nz);
  if (!voxels) {
    fprintf(stderr, "cannot allocate %llu voxels\n", (unsigned long long)(nx * ny * nz));
    return 1;
  }
  for (z = 0; z < nz; ++z)
    for (y = 0; y < ny; ++y)
      for (x = 0; x < nx; ++x)
        voxels[x + nx * (y + ny * z)] = voxel(x, y, z, nx, ny, nz);
  spacing[0] = 2.0f / (float)(nx - 1);
  spacing[1] = 2.0f / (float)(ny > 1 ? ny - 1 : 1);
  spacing[2] = 2.0f / (float)(nz > 1 ? nz - 1 : 1);

  lib = anariLoadLibrary("caveray", on_status, NULL);
  dev = anariNewDevice(lib, "default");
  data = anariNewArray3D(dev, voxels, NULL, NULL, ANARI_UFIXED8, nx, ny, nz);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &data);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, spacing);
  anariCommitParameters(dev, field);
  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  color_array = anariNewArray1D(dev, colors, NULL, NULL, ANARI_FLOAT32_VEC3, 2);
  opacity_array = anariNewArray1D(dev, opacities, NULL, NULL, ANARI_FLOAT32, 2);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &color_array);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &opacity_array);
  anariSetParameter(dev, volume, "unitDistance", ANARI_FLOAT32, &unit);
  anariCommitParameters(dev, volume);
  world = anariNewWorld(dev);
  volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  anariCommitParameters(dev, world);

  aspect = (float)size[0] / (float)size[1];
  direction[0] = -position[0], direction[1] = -position[1], direction[2] = -position[2];
  camera = anariNewCamera(dev, "perspective");
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, position);
  anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, direction);
  anariSetParameter(dev, camera, "up", ANARI_FLOAT32_VEC3, up);
  anariSetParameter(dev, camera, "aspect", ANARI_FLOAT32, &aspect);
  anariCommitParameters(dev, camera);
  renderer = anariNewRenderer(dev, "default");
  anariCommitParameters(dev, renderer);
  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, size);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &color);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariCommitParameters(dev, frame);

  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  pixels = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  ok = pixels && w == size[0] && h == size[1] && !failed
      && write_rgba(argv[1], "frame", pixels, w, h);
  if (pixels)
    anariUnmapFrame(dev, frame, "channel.color");
  ok = ok
      && anariGetProperty(dev, field, "caveray.residentBytes", ANARI_UINT64, &field_bytes,
          sizeof field_bytes, ANARI_WAIT)
      && anariGetProperty(dev, frame, "caveray.residentBytes", ANARI_UINT64, &resident,
          sizeof resident, ANARI_WAIT)
      && anariGetProperty(dev, frame, "caveray.gpuBytes", ANARI_UINT64, &gpu, sizeof gpu,
          ANARI_WAIT);
  printf("field_bytes=%llu resident_bytes=%llu gpu_bytes=%llu\n",
      (unsigned long long)field_bytes, (unsigned long long)resident, (unsigned long long)gpu);

  anariRelease(dev, frame);
  anariRelease(dev, renderer);
  anariRelease(dev, camera);
  anariRelease(dev, world);
  anariRelease(dev, volumes);
  anariRelease(dev, volume);
  anariRelease(dev, color_array);
  anariRelease(dev, opacity_array);
  anariRelease(dev, field);
  anariRelease(dev, data);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  free(voxels);
  printf("%s\n", ok ? "rendered" : "failed");
  return ok ? 0 : 1;
}
