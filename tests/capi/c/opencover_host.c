/* An OpenCOVER-style host, from what its ANARI plug-in sends (HOSTS.md):
 * the library loaded as "environment" ($ANARI_LIBRARY), a renderer subtype
 * from the host's config, a field with FLOAT32 data and filter "linear", a
 * transfer function with color and opacity arrays of different lengths
 * and no valueRange or unitDistance, an `id` and `name` on objects, the
 * renderer's ambient and denoise settings, an empty clip plane list, one
 * directional light, the frame committed before its size is set, color as
 * sRGB with depth mapped together, the perspective camera of one wall and
 * eye (imageRegion from caverayPinholeFromScreen), and the channel rendered
 * 64 times with nothing changed, as OpenCOVER does to accumulate.
 * Usage: opencover_host SCENE_FILE OUT_DIR. Writes OUT_DIR/opencover.rgba
 * (sRGB) and OUT_DIR/opencover.depth (FLOAT32); exit status 0 only if every
 * render succeeded, the status callback saw no warning or error, and the
 * 63 re-renders kept the first image. */
#include <anari/anari.h>
#include <anari/caveray.h>

#include "scene.h"
#include "status.h"

/* `n` colors (RGB) or opacities resampled from the scene's table. */
static float *resample(const float *table, unsigned count, unsigned stride,
    unsigned channels, unsigned n)
{
  float *out = (float *)malloc((size_t)n * channels * sizeof(float));
  unsigned i, c;
  for (i = 0; i < n; ++i) {
    unsigned at = (unsigned)((double)i * (count - 1) / (n - 1) + 0.5);
    for (c = 0; c < channels; ++c)
      out[i * channels + c] = table[at * stride + c];
  }
  return out;
}

int main(int argc, char **argv)
{
  Scene s;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray3D voxels;
  ANARIArray1D colors, opacities, volumes, lights, clips;
  ANARISpatialField field;
  ANARIVolume volume;
  ANARILight sun;
  ANARIWorld world;
  ANARIRenderer renderer;
  ANARIFrame frame;
  ANARICamera camera;
  CaverayPinhole pinhole;
  ANARIDataType srgb = ANARI_UFIXED8_RGBA_SRGB, depth_type = ANARI_FLOAT32;
  float *rgb, *alpha, background[4] = {0, 0, 0, 1}, ambient[3] = {1, 1, 1};
  float sun_direction[3] = {0, -1, 0}, one = 1.0f, first_pixel[4];
  uint32_t id = 7, w = 0, h = 0;
  int32_t pixel_samples = 1, numSamples = 0;
  uint8_t no = 0;
  ANARIDataType type = ANARI_UNKNOWN;
  const void *pixels;
  const float *depth;
  int ok = 1, i;

  if (argc != 3 || !scene_load(argv[1], &s)) {
    fprintf(stderr, "usage: opencover_host SCENE_FILE OUT_DIR\n");
    return 2;
  }
  status_level = ANARI_SEVERITY_WARNING;
  lib = anariLoadLibrary("environment", count_status, "opencover_host");
  dev = anariNewDevice(lib, "default");

  voxels = anariNewArray3D(dev, s.voxels, NULL, NULL, ANARI_FLOAT32, s.dims[0], s.dims[1], s.dims[2]);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &voxels);
  anariSetParameter(dev, field, "filter", ANARI_STRING, "linear");
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, s.origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, s.spacing);
  anariCommitParameters(dev, field);
  anariRelease(dev, voxels);

  /* 64 colors and 256 opacities: different lengths, as OpenCOVER sends. */
  rgb = resample(s.colors, s.ncolors, 4, 3, 64);
  alpha = resample(s.opacities, s.nopacities, 1, 1, s.nopacities);
  colors = anariNewArray1D(dev, rgb, NULL, NULL, ANARI_FLOAT32_VEC3, 64);
  opacities = anariNewArray1D(dev, alpha, NULL, NULL, ANARI_FLOAT32, s.nopacities);
  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "name", ANARI_STRING, "phantom");
  anariSetParameter(dev, volume, "id", ANARI_UINT32, &id);
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &colors);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &opacities);
  if (s.range[0] != 0.0f || s.range[1] != 1.0f)
    anariSetParameter(dev, volume, "valueRange", ANARI_FLOAT32_BOX1, s.range);
  anariSetParameter(dev, volume, "unitDistance", ANARI_FLOAT32, &s.unitDistance);
  anariCommitParameters(dev, volume);
  anariRelease(dev, colors);
  anariRelease(dev, opacities);
  free(rgb);
  free(alpha);

  sun = anariNewLight(dev, "directional");
  anariSetParameter(dev, sun, "direction", ANARI_FLOAT32_VEC3, sun_direction);
  anariSetParameter(dev, sun, "irradiance", ANARI_FLOAT32, &one);
  anariCommitParameters(dev, sun);

  world = anariNewWorld(dev);
  volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  lights = anariNewArray1D(dev, &sun, NULL, NULL, ANARI_LIGHT, 1);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  anariSetParameter(dev, world, "light", ANARI_ARRAY1D, &lights);
  anariCommitParameters(dev, world);
  anariRelease(dev, volumes);
  anariRelease(dev, lights);

  renderer = anariNewRenderer(dev, "raycast");
  anariSetParameter(dev, renderer, "background", ANARI_FLOAT32_VEC4, background);
  anariSetParameter(dev, renderer, "ambientColor", ANARI_FLOAT32_VEC3, ambient);
  anariSetParameter(dev, renderer, "ambientRadiance", ANARI_FLOAT32, &one);
  anariSetParameter(dev, renderer, "denoise", ANARI_BOOL, &no);
  anariSetParameter(dev, renderer, "pixelSamples", ANARI_INT32, &pixel_samples);
  clips = anariNewArray1D(dev, NULL, NULL, NULL, ANARI_FLOAT32_VEC4, 0);
  anariSetParameter(dev, renderer, "clipPlane", ANARI_ARRAY1D, &clips);
  anariRelease(dev, clips);
  anariCommitParameters(dev, renderer);

  /* The frame is committed before the host knows its size. */
  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &srgb);
  anariSetParameter(dev, frame, "channel.depth", ANARI_DATA_TYPE, &depth_type);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariCommitParameters(dev, frame);

  if (caverayPinholeFromScreen(s.ll, s.lr, s.ur, s.eye, &pinhole) != ANARI_STATUS_NO_ERROR) {
    fprintf(stderr, "opencover_host: %s\n", caverayLastError());
    return 1;
  }
  camera = anariNewCamera(dev, "perspective");
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, pinhole.position);
  anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, pinhole.direction);
  anariSetParameter(dev, camera, "up", ANARI_FLOAT32_VEC3, pinhole.up);
  anariSetParameter(dev, camera, "fovy", ANARI_FLOAT32, &pinhole.fovy);
  anariSetParameter(dev, camera, "aspect", ANARI_FLOAT32, &pinhole.aspect);
  anariSetParameter(dev, camera, "imageRegion", ANARI_FLOAT32_BOX2, pinhole.imageRegion);
  anariCommitParameters(dev, camera);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, s.size);
  anariCommitParameters(dev, frame);

  for (i = 0; i < 64; ++i) {
    anariRenderFrame(dev, frame);
    anariFrameReady(dev, frame, ANARI_WAIT);
    pixels = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
    depth = (const float *)anariMapFrame(dev, frame, "channel.depth", &w, &h, &type);
    if (!pixels || !depth) {
      ok = 0;
      break;
    }
    if (i == 0) {
      ok &= write_rgba(argv[2], "opencover", pixels, w, h);
      ok &= write_floats(argv[2], "opencover.depth", depth, (size_t)w * h);
      memcpy(first_pixel, depth + (size_t)w * h / 2, sizeof first_pixel);
    } else if (memcmp(first_pixel, depth + (size_t)w * h / 2, sizeof first_pixel) != 0) {
      fprintf(stderr, "opencover_host: render %d changed the depth\n", i);
      ok = 0;
    }
    anariUnmapFrame(dev, frame, "channel.color");
    anariUnmapFrame(dev, frame, "channel.depth");
  }
  if (anariGetProperty(dev, frame, "numSamples", ANARI_INT32, &numSamples, sizeof numSamples, ANARI_WAIT) != 1
      || numSamples != 64) {
    fprintf(stderr, "opencover_host: numSamples %d after 64 renders of one image\n", numSamples);
    ok = 0;
  }

  anariRelease(dev, camera);
  anariRelease(dev, frame);
  anariRelease(dev, renderer);
  anariRelease(dev, world);
  anariRelease(dev, sun);
  anariRelease(dev, volume);
  anariRelease(dev, field);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  scene_free(&s);
  return ok && status_count == 0 ? 0 : 1;
}
