/* A benchmark host: what a user of the C API sees, frame by frame.
 * Four concentric spherical shells in an N^3 float volume (air between
 * them) fill most of a square frame; a perspective camera circles them and
 * every frame is rendered, waited for and mapped, as a viewer would.
 *
 *   cc -std=c99 -O2 -Iinclude examples/c/bench_shells.c -Ltarget/release \
 *      -lanari_library_caveray -Wl,-rpath,$PWD/target/release -lm -o bench_shells
 *   ./bench_shells [--backend auto|cpu|gpu] [--size 768] [--voxels 256]
 *                  [--frames 8] [--shading none] [--skipping 1|0]
 *                  [--json out.json] [--ppm first_frame.ppm]
 *
 * Prints each frame's milliseconds and a summary; --json writes them with
 * the machine's CPU, the backend and the samples the device counted. */
#define _POSIX_C_SOURCE 200809L
#include <anari/anari.h>
#include <anari/caveray.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bench.h"

int main(int argc, char **argv)
{
  const char *backend = "auto", *shading = "none", *json = NULL, *ppm = NULL;
  unsigned size = 768, n = 256, frames = 8, i;
  int skipping = 1;
  for (i = 1; i + 1 < (unsigned)argc; i += 2) {
    const char *k = argv[i], *v = argv[i + 1];
    if (!strcmp(k, "--backend")) backend = v;
    else if (!strcmp(k, "--size")) size = (unsigned)atoi(v);
    else if (!strcmp(k, "--voxels")) n = (unsigned)atoi(v);
    else if (!strcmp(k, "--frames")) frames = (unsigned)atoi(v);
    else if (!strcmp(k, "--shading")) shading = v;
    else if (!strcmp(k, "--skipping")) skipping = atoi(v);
    else if (!strcmp(k, "--json")) json = v;
    else if (!strcmp(k, "--ppm")) ppm = v;
    else {
      fprintf(stderr, "bench_shells: unknown option %s\n", k);
      return 2;
    }
  }
  if ((unsigned)argc % 2 == 0 || size < 1 || size > 8192 || n < 2 || n > 1024 || frames < 1
      || frames > 10000) {
    fprintf(stderr, "bench_shells: need --size 1..8192, --voxels 2..1024, --frames 1..10000\n");
    return 2;
  }

  size_t count = (size_t)n * n * n;
  float *voxels = malloc(count * sizeof *voxels);
  if (!voxels) {
    fprintf(stderr, "bench_shells: no memory for %u^3 voxels\n", n);
    return 1;
  }
  for (size_t k = 0; k < n; ++k)
    for (size_t j = 0; j < n; ++j)
      for (size_t l = 0; l < n; ++l) {
        float s = 2.0f / (n - 1);
        voxels[(k * n + j) * n + l] = shells(l * s - 1, j * s - 1, k * s - 1);
      }

  /* caveray's `shells` preset: clear below 0.1, translucent above. */
  float colors[4 * 3] = {0.2f, 0.4f, 1.0f, 0.2f, 0.4f, 1.0f, 0.5f, 0.8f, 0.6f, 1.0f, 0.7f, 0.2f};
  float opacities[11] = {0, 0, 0.0375f, 0.075f, 0.1125f, 0.15f, 0.22f, 0.29f, 0.36f, 0.43f, 0.5f};
  float origin[3] = {-1, -1, -1}, spacing[3] = {2.0f / (n - 1), 2.0f / (n - 1), 2.0f / (n - 1)};
  float unit = 0.2f, fovy = 40.0f * 3.14159265f / 180.0f, up[3] = {0, 1, 0};
  unsigned fsize[2] = {size, size};
  ANARIDataType color = ANARI_UFIXED8_RGBA_SRGB;
  int ok = 1;

  ANARILibrary lib = anariLoadLibrary("caveray", on_status, NULL);
  if (!lib) {
    fprintf(stderr, "bench_shells: cannot load caveray\n");
    return 1;
  }
  ANARIDevice dev = anariNewDevice(lib, "default");
  anariSetParameter(dev, dev, "backend", ANARI_STRING, backend);
  anariCommitParameters(dev, dev);

  ANARIArray3D data = anariNewArray3D(dev, voxels, NULL, NULL, ANARI_FLOAT32, n, n, n);
  ANARISpatialField field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &data);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, spacing);
  anariCommitParameters(dev, field);

  ANARIArray1D c = anariNewArray1D(dev, colors, NULL, NULL, ANARI_FLOAT32_VEC3, 4);
  ANARIArray1D o = anariNewArray1D(dev, opacities, NULL, NULL, ANARI_FLOAT32, 11);
  float range[2] = {0, 1};
  ANARIVolume volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &c);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &o);
  anariSetParameter(dev, volume, "valueRange", ANARI_FLOAT32_BOX1, range);
  anariSetParameter(dev, volume, "unitDistance", ANARI_FLOAT32, &unit);
  anariCommitParameters(dev, volume);

  ANARIWorld world = anariNewWorld(dev);
  ANARIArray1D volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  anariCommitParameters(dev, world);

  ANARIRenderer renderer = anariNewRenderer(dev, "default");
  anariSetParameter(dev, renderer, "shading", ANARI_STRING, shading);
  anariSetParameter(dev, renderer, "emptySpaceSkipping", ANARI_BOOL, &skipping);
  anariCommitParameters(dev, renderer);
  ANARICamera camera = anariNewCamera(dev, "perspective");
  anariSetParameter(dev, camera, "fovy", ANARI_FLOAT32, &fovy);
  anariSetParameter(dev, camera, "up", ANARI_FLOAT32_VEC3, up);

  ANARIFrame frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, fsize);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &color);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariCommitParameters(dev, frame);

  double *ms = calloc(frames + 1, sizeof *ms), sum = 0, lo = 1e300, hi = 0;
  /* Frame 0 warms up (uploads, pipelines, caches) and is not counted. */
  for (i = 0; i <= frames && ms; ++i) {
    float a = 2.0f * 3.14159265f * i / (frames + 1), d = 3.2f;
    float pos[3] = {d * sinf(a), 0.3f, d * cosf(a)}, dir[3] = {-pos[0], -pos[1], -pos[2]};
    anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, pos);
    anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, dir);
    anariCommitParameters(dev, camera);
    double t0 = now_ms();
    anariRenderFrame(dev, frame);
    anariFrameReady(dev, frame, ANARI_WAIT);
    unsigned w, h;
    ANARIDataType type;
    const unsigned char *rgba = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
    ms[i] = now_ms() - t0;
    if (!rgba || w != size || h != size) {
      fprintf(stderr, "bench_shells: frame %u did not map\n", i);
      ok = 0;
    } else if (i == 0 && ppm) {
      FILE *f = fopen(ppm, "wb");
      if (f) {
        fprintf(f, "P6\n%u %u\n255\n", w, h);
        for (unsigned y = h; y-- > 0;)
          for (unsigned x = 0; x < w; ++x)
            fwrite(rgba + 4 * ((size_t)y * w + x), 1, 3, f);
        fclose(f);
      }
    }
    anariUnmapFrame(dev, frame, "channel.color");
    if (i > 0) {
      sum += ms[i];
      lo = ms[i] < lo ? ms[i] : lo;
      hi = ms[i] > hi ? ms[i] : hi;
      fprintf(stderr, "[%u/%u] %.1f ms\n", i, frames, ms[i]);
    }
  }
  unsigned long long samples = 0;
  anariGetProperty(dev, frame, "caveray.volumeSamples", ANARI_UINT64, &samples, sizeof samples,
      ANARI_WAIT);
  double mean = sum / frames, spread = mean > 0 ? (hi - lo) / mean : 0;
  printf("bench_shells: %u^3 float shells at %ux%u, backend %s, shading %s, skipping %s: "
         "mean %.1f ms, min %.1f, max %.1f (spread %.0f%% of the mean) over %u frames\n",
      n, size, size, backend, shading, skipping ? "on" : "off", mean, lo, hi, 100 * spread,
      frames);

  if (json && ms) {
    char model[256];
    FILE *f = fopen(json, "w");
    cpu_model(model, sizeof model);
    if (!f) {
      fprintf(stderr, "bench_shells: cannot write %s\n", json);
      ok = 0;
    } else {
      fprintf(f, "{\n  \"benchmark\": \"capi-shells\",\n  \"machine\": {\"cpu\": \"%s\", "
                 "\"threads\": %ld},\n",
          model, sysconf(_SC_NPROCESSORS_ONLN));
      fprintf(f, "  \"backend\": \"%s\",\n  \"shading\": \"%s\",\n  \"skipping\": %s,\n", backend,
          shading, skipping ? "true" : "false");
      fprintf(f, "  \"voxels\": [%u, %u, %u],\n  \"image\": [%u, %u],\n", n, n, n, size, size);
      fprintf(f, "  \"last_frame_samples\": %llu,\n  \"ms\": [", samples);
      for (i = 1; i <= frames; ++i)
        fprintf(f, "%s%.3f", i > 1 ? ", " : "", ms[i]);
      fprintf(f, "],\n  \"mean_ms\": %.3f,\n  \"min_ms\": %.3f,\n  \"max_ms\": %.3f\n}\n", mean,
          lo, hi);
      fclose(f);
    }
  }

  free(ms);
  anariRelease(dev, frame);
  anariRelease(dev, camera);
  anariRelease(dev, renderer);
  anariRelease(dev, volumes);
  anariRelease(dev, world);
  anariRelease(dev, volume);
  anariRelease(dev, o);
  anariRelease(dev, c);
  anariRelease(dev, field);
  anariRelease(dev, data);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  free(voxels);
  return ok ? 0 : 1;
}
