/* A benchmark host for unstructured, AMR and NanoVDB volumes: what a
 * user of the C API sees, from the first commit to the frames after. The
 * vertices of an N^3 grid on [-1, 1]^3 hold the shells of bench_shells.c;
 * the same vertices are sent either as a structuredRegular field or as an
 * unstructured one, each grid cell cut into six tetrahedra around its
 * main diagonal (Kuhn), 6 (N - 1)^3 of them with values per vertex. Or
 * `--field amr`: the shells at the cell centres of two levels in
 * anari-visionaray's form (refinementRatio per level, block.bounds,
 * block.level, one data array, gridOrigin, gridSpacing), blocks of 8^3
 * cells: level 1 over the whole box, F / 2 cells across, level 0 (the
 * finest, F = 2 (N - 1) rounded down to a multiple of 16) over its middle
 * half, the parents kept; with --amr-units 1 in cell units as OpenCOVER
 * sends them (gridSpacing 1, the finest cell one unit, the whole scene
 * scaled to match: camera and unitDistance), so that a device whose step
 * is one unit (anari-visionaray's AMR step ignores gridSpacing) takes
 * the same samples at the same volumeSamplingRate. Or `--field nanovdb`:
 * the bytes of the NanoVDB grid buffer that --nvdb names, handed over
 * as they are as a `nanovdb` field (`data`, an ARRAY1D of UINT8; default
 * filter), the scene scaled to the grid's index box placed by its map.
 * A perspective camera circles them at 768^2 and every frame is
 * rendered, waited for and mapped.
 *
 *   cc -std=c99 -O2 -Iinclude examples/c/bench_cells.c -Ltarget/release \
 *      -lanari_library_caveray -Wl,-rpath,$PWD/target/release -lm -o bench_cells
 *   ./bench_cells [--field unstructured|structured|amr|nanovdb] [--vertices 57]
 *                 [--backend auto|cpu|gpu] [--size 768] [--frames 4]
 *                 [--rate 1] [--json out.json] [--ppm first_frame.ppm]
 *                 [--library caveray] [--renderer default] [--still 0|1]
 *                 [--ppm-dir DIR] [--amr-units 0|1] [--nvdb GRID_BUFFER]
 *
 * Built against the SDK's loader instead (-lanari), --library names any
 * device, so other devices run the same scene in the same process shape.
 * --still 1 keeps the camera where frame 0 had it, so a device that
 * accumulates samples over frames does so; --ppm-dir writes frames 1, 2,
 * 4, 8, ... there (frame_0001.ppm, ...) to see when its image stops
 * changing.
 *
 * Reports the first frame (from the first array handed over to the first
 * image mapped: the device's checks, its BVH, neighbours and brick
 * ranges, and the frame), the frames after it, and the process's peak
 * resident memory, which includes the host's own arrays. */
#define _POSIX_C_SOURCE 200809L
#include <anari/anari.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include "bench.h"

/* The six tetrahedra of a cell (corners in VTK's hexahedron order). */
static const int KUHN[6][4] = {
    {0, 1, 2, 6}, {0, 1, 5, 6}, {0, 3, 2, 6}, {0, 3, 7, 6}, {0, 4, 5, 6}, {0, 4, 7, 6}};

static double peak_rss_mib(void)
{
  struct rusage u;
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss / 1024.0;
}

int main(int argc, char **argv)
{
  const char *backend = "auto", *kind = "unstructured", *json = NULL, *ppm = NULL;
  const char *library = "caveray", *renderer_kind = "default", *ppm_dir = NULL, *nvdb = NULL;
  unsigned size = 768, n = 57, frames = 4, still = 0, amr_units = 0, i;
  float rate = 1.0f;
  for (i = 1; i + 1 < (unsigned)argc; i += 2) {
    const char *k = argv[i], *v = argv[i + 1];
    if (!strcmp(k, "--backend")) backend = v;
    else if (!strcmp(k, "--field")) kind = v;
    else if (!strcmp(k, "--size")) size = (unsigned)atoi(v);
    else if (!strcmp(k, "--vertices")) n = (unsigned)atoi(v);
    else if (!strcmp(k, "--frames")) frames = (unsigned)atoi(v);
    else if (!strcmp(k, "--rate")) rate = (float)atof(v);
    else if (!strcmp(k, "--json")) json = v;
    else if (!strcmp(k, "--ppm")) ppm = v;
    else if (!strcmp(k, "--library")) library = v;
    else if (!strcmp(k, "--renderer")) renderer_kind = v;
    else if (!strcmp(k, "--still")) still = (unsigned)atoi(v);
    else if (!strcmp(k, "--ppm-dir")) ppm_dir = v;
    else if (!strcmp(k, "--amr-units")) amr_units = (unsigned)atoi(v);
    else if (!strcmp(k, "--nvdb")) nvdb = v;
    else {
      fprintf(stderr, "bench_cells: unknown option %s\n", k);
      return 2;
    }
  }
  int mesh = !strcmp(kind, "unstructured"), amr = !strcmp(kind, "amr");
  int vdb = !strcmp(kind, "nanovdb");
  if ((unsigned)argc % 2 == 0 || size < 1 || size > 8192 || n < (amr ? 9 : 2) || n > 300 || frames < 1
      || frames > 10000 || !(rate > 0) || (!mesh && !amr && !vdb && strcmp(kind, "structured"))
      || (vdb && !nvdb)) {
    fprintf(stderr, "bench_cells: need --field unstructured|structured|amr|nanovdb (nanovdb with "
                    "--nvdb FILE, a NanoVDB grid buffer), --size 1..8192, --vertices 2..300 "
                    "(9.. for amr), --frames 1..10000, --rate > 0\n");
    return 2;
  }

  /* NanoVDB: the grid's bytes, and its box from its header: the root's
   * index box (vertex-centred voxels, inclusive) through the diagonal of
   * the map's double-precision matrix and its translation. */
  uint8_t *grid = NULL;
  size_t grid_bytes = 0;
  int32_t vdb_lo[3] = {0, 0, 0}, vdb_hi[3] = {0, 0, 0};
  float vdb_min[3] = {-1, -1, -1}, vdb_max[3] = {1, 1, 1};
  if (vdb) {
    FILE *f = fopen(nvdb, "rb");
    long end = -1;
    if (!f || fseek(f, 0, SEEK_END) != 0 || (end = ftell(f)) < 0 || fseek(f, 0, SEEK_SET) != 0) {
      fprintf(stderr, "bench_cells: cannot read %s\n", nvdb);
      return 1;
    }
    grid_bytes = (size_t)end;
    if (grid_bytes < 736) {
      fprintf(stderr, "bench_cells: %s is %zu bytes, too short for a NanoVDB grid\n", nvdb,
          grid_bytes);
      return 1;
    }
    grid = malloc(grid_bytes);
    if (!grid) {
      fprintf(stderr, "bench_cells: no memory for the %zu bytes of %s\n", grid_bytes, nvdb);
      return 1;
    }
    size_t got = fread(grid, 1, grid_bytes, f);
    fclose(f);
    if (got != grid_bytes) {
      fprintf(stderr, "bench_cells: cannot read the %zu bytes of %s\n", grid_bytes, nvdb);
      return 1;
    }
    uint64_t root;
    double mat[9], vec[3];
    memcpy(&root, grid + 672 + 24, sizeof root);
    memcpy(mat, grid + 296 + 88, sizeof mat);
    memcpy(vec, grid + 296 + 232, sizeof vec);
    if (memcmp(grid, "NanoVDB", 7) || root > grid_bytes - 672 - 24) {
      fprintf(stderr, "bench_cells: %s is not a NanoVDB grid buffer\n", nvdb);
      return 1;
    }
    memcpy(vdb_lo, grid + 672 + root, sizeof vdb_lo);
    memcpy(vdb_hi, grid + 672 + root + 12, sizeof vdb_hi);
    for (int k = 0; k < 3; ++k) {
      double a = mat[4 * k] * vdb_lo[k] + vec[k], b = mat[4 * k] * vdb_hi[k] + vec[k];
      if (vdb_lo[k] > vdb_hi[k]) {
        fprintf(stderr, "bench_cells: %s has no active voxels\n", nvdb);
        return 1;
      }
      vdb_min[k] = (float)(a < b ? a : b);
      vdb_max[k] = (float)(a < b ? b : a);
    }
  }

  /* The host's own arrays, made before the clock starts. */
  size_t verts = (size_t)n * n * n, cubes = (size_t)(n - 1) * (n - 1) * (n - 1);
  size_t cells = mesh ? 6 * cubes : 0;
  float s = 2.0f / (n - 1);
  float *values = vdb ? NULL : malloc(verts * sizeof *values);
  float *positions = mesh ? malloc(3 * verts * sizeof *positions) : NULL;
  uint32_t *index = mesh ? malloc(4 * cells * sizeof *index) : NULL;
  uint32_t *cell_index = mesh ? malloc(cells * sizeof *cell_index) : NULL;
  uint8_t *cell_type = mesh ? malloc(cells) : NULL;
  if ((!vdb && !values) || (mesh && (!positions || !index || !cell_index || !cell_type))) {
    fprintf(stderr, "bench_cells: no memory for %u^3 vertices\n", n);
    return 1;
  }
  for (size_t z = 0; z < n && values; ++z)
    for (size_t y = 0; y < n; ++y)
      for (size_t x = 0; x < n; ++x) {
        size_t v = (z * n + y) * n + x;
        values[v] = shells(x * s - 1, y * s - 1, z * s - 1);
        if (mesh) {
          positions[3 * v] = x * s - 1;
          positions[3 * v + 1] = y * s - 1;
          positions[3 * v + 2] = z * s - 1;
        }
      }
  if (mesh) {
    size_t c = 0;
    for (size_t z = 0; z + 1 < n; ++z)
      for (size_t y = 0; y + 1 < n; ++y)
        for (size_t x = 0; x + 1 < n; ++x) {
          size_t o = (z * n + y) * n + x, row = n, slab = (size_t)n * n;
          uint32_t h[8] = {(uint32_t)o, (uint32_t)(o + 1), (uint32_t)(o + 1 + row),
              (uint32_t)(o + row), (uint32_t)(o + slab), (uint32_t)(o + 1 + slab),
              (uint32_t)(o + 1 + row + slab), (uint32_t)(o + row + slab)};
          for (int t = 0; t < 6; ++t, ++c) {
            cell_index[c] = (uint32_t)(4 * c);
            cell_type[c] = 10;
            for (int k = 0; k < 4; ++k)
              index[4 * c + k] = h[KUHN[t][k]];
          }
        }
  }
  /* AMR: F finest cells across; blocks of 8^3, the coarse level first. */
  unsigned fine = (2 * (n - 1)) / 16 * 16, per = fine / 16, nblocks = 2 * per * per * per;
  int32_t *amr_bounds = amr ? malloc(6 * nblocks * sizeof *amr_bounds) : NULL;
  int32_t *amr_levels = amr ? malloc(nblocks * sizeof *amr_levels) : NULL;
  float *amr_data = amr ? malloc((size_t)nblocks * 512 * sizeof *amr_data) : NULL;
  if (amr && (!amr_bounds || !amr_levels || !amr_data)) {
    fprintf(stderr, "bench_cells: no memory for the AMR blocks\n");
    return 1;
  }
  if (amr) {
    size_t b = 0, at = 0;
    for (int level = 1; level >= 0; --level) {
      /* Level 1 covers cells 0..F/2 of its own; level 0 the middle half,
       * fine cells F/4..3F/4. */
      unsigned first = level ? 0 : fine / 4, w = level ? 2 : 1;
      float h = 2.0f / fine;
      for (unsigned bz = 0; bz < per; ++bz)
        for (unsigned by = 0; by < per; ++by)
          for (unsigned bx = 0; bx < per; ++bx, ++b) {
            int32_t lo[3] = {(int32_t)(first + 8 * bx), (int32_t)(first + 8 * by),
                (int32_t)(first + 8 * bz)};
            for (int k = 0; k < 3; ++k) {
              amr_bounds[6 * b + k] = lo[k];
              amr_bounds[6 * b + 3 + k] = lo[k] + 7;
            }
            amr_levels[b] = level;
            for (int z = 0; z < 8; ++z)
              for (int y = 0; y < 8; ++y)
                for (int x = 0; x < 8; ++x)
                  amr_data[at++] = shells((lo[0] + x + 0.5f) * w * h - 1,
                      (lo[1] + y + 0.5f) * w * h - 1, (lo[2] + z + 0.5f) * w * h - 1);
          }
    }
  }
  double host_mib = peak_rss_mib();

  float colors[4 * 3] = {0.2f, 0.4f, 1.0f, 0.2f, 0.4f, 1.0f, 0.5f, 0.8f, 0.6f, 1.0f, 0.7f, 0.2f};
  float opacities[11] = {0, 0, 0.0375f, 0.075f, 0.1125f, 0.15f, 0.22f, 0.29f, 0.36f, 0.43f, 0.5f};
  /* A fog grid's core is all 1, hundreds of voxels deep: its ramp (blue
   * to green) drawn as a rim, its core (orange) kept translucent. */
  static const float fog_opacities[11] = {
      0, 0.3f, 0.4f, 0.4f, 0.4f, 0.4f, 0.4f, 0.3f, 0.2f, 0.1f, 0.05f};
  if (vdb)
    memcpy(opacities, fog_opacities, sizeof opacities);
  float origin[3] = {-1, -1, -1}, spacing[3] = {s, s, s};
  /* World units per unit of the scene on [-1, 1]^3, and its centre. */
  float scale = amr && amr_units ? fine / 2.0f : 1.0f, centre[3] = {0, 0, 0};
  if (vdb) {
    scale = 0.0f;
    for (int k = 0; k < 3; ++k) {
      centre[k] = 0.5f * (vdb_min[k] + vdb_max[k]);
      if (0.5f * (vdb_max[k] - vdb_min[k]) > scale)
        scale = 0.5f * (vdb_max[k] - vdb_min[k]);
    }
    if (!(scale > 0))
      scale = 1.0f;
  }
  float unit = 0.2f * scale, fovy = 40.0f * 3.14159265f / 180.0f, up[3] = {0, 1, 0}, range[2] = {0, 1};
  unsigned fsize[2] = {size, size};
  ANARIDataType color = ANARI_UFIXED8_RGBA_SRGB;
  int ok = 1;

  ANARILibrary lib = anariLoadLibrary(library, on_status, NULL);
  if (!lib) {
    fprintf(stderr, "bench_cells: cannot load %s\n", library);
    return 1;
  }
  ANARIDevice dev = anariNewDevice(lib, "default");
  anariSetParameter(dev, dev, "backend", ANARI_STRING, backend);
  anariCommitParameters(dev, dev);

  double t_start = now_ms();
  ANARISpatialField field;
  ANARIArray arrays[5] = {0};
  if (vdb) {
    field = anariNewSpatialField(dev, "nanovdb");
    arrays[0] = anariNewArray1D(dev, grid, NULL, NULL, ANARI_UINT8, grid_bytes);
    anariSetParameter(dev, field, "data", ANARI_ARRAY1D, &arrays[0]);
  } else if (amr) {
    uint32_t ratios[2] = {2, 2};
    float amr_origin[3] = {-scale, -scale, -scale}, amr_spacing[3];
    for (int k = 0; k < 3; ++k)
      amr_spacing[k] = 2.0f * scale / fine;
    field = anariNewSpatialField(dev, "amr");
    arrays[0] = anariNewArray1D(dev, ratios, NULL, NULL, ANARI_UINT32, 2);
    arrays[1] = anariNewArray1D(dev, amr_bounds, NULL, NULL, ANARI_INT32_BOX3, nblocks);
    arrays[2] = anariNewArray1D(dev, amr_levels, NULL, NULL, ANARI_INT32, nblocks);
    arrays[3] = anariNewArray1D(dev, amr_data, NULL, NULL, ANARI_FLOAT32, (uint64_t)nblocks * 512);
    anariSetParameter(dev, field, "refinementRatio", ANARI_ARRAY1D, &arrays[0]);
    anariSetParameter(dev, field, "block.bounds", ANARI_ARRAY1D, &arrays[1]);
    anariSetParameter(dev, field, "block.level", ANARI_ARRAY1D, &arrays[2]);
    anariSetParameter(dev, field, "data", ANARI_ARRAY1D, &arrays[3]);
    anariSetParameter(dev, field, "gridOrigin", ANARI_FLOAT32_VEC3, amr_origin);
    anariSetParameter(dev, field, "gridSpacing", ANARI_FLOAT32_VEC3, amr_spacing);
  } else if (mesh) {
    field = anariNewSpatialField(dev, "unstructured");
    arrays[0] = anariNewArray1D(dev, positions, NULL, NULL, ANARI_FLOAT32_VEC3, verts);
    arrays[1] = anariNewArray1D(dev, index, NULL, NULL, ANARI_UINT32, 4 * cells);
    arrays[2] = anariNewArray1D(dev, cell_index, NULL, NULL, ANARI_UINT32, cells);
    arrays[3] = anariNewArray1D(dev, cell_type, NULL, NULL, ANARI_UINT8, cells);
    arrays[4] = anariNewArray1D(dev, values, NULL, NULL, ANARI_FLOAT32, verts);
    anariSetParameter(dev, field, "vertex.position", ANARI_ARRAY1D, &arrays[0]);
    anariSetParameter(dev, field, "index", ANARI_ARRAY1D, &arrays[1]);
    anariSetParameter(dev, field, "cell.index", ANARI_ARRAY1D, &arrays[2]);
    anariSetParameter(dev, field, "cell.type", ANARI_ARRAY1D, &arrays[3]);
    anariSetParameter(dev, field, "vertex.data", ANARI_ARRAY1D, &arrays[4]);
  } else {
    field = anariNewSpatialField(dev, "structuredRegular");
    arrays[0] = anariNewArray3D(dev, values, NULL, NULL, ANARI_FLOAT32, n, n, n);
    anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &arrays[0]);
    anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, origin);
    anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, spacing);
  }
  anariCommitParameters(dev, field);

  ANARIArray1D c = anariNewArray1D(dev, colors, NULL, NULL, ANARI_FLOAT32_VEC3, 4);
  ANARIArray1D o = anariNewArray1D(dev, opacities, NULL, NULL, ANARI_FLOAT32, 11);
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

  ANARIRenderer renderer = anariNewRenderer(dev, renderer_kind);
  anariSetParameter(dev, renderer, "volumeSamplingRate", ANARI_FLOAT32, &rate);
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
  /* Frame 0 is the first frame: it is timed from t_start. */
  for (i = 0; i <= frames && ms; ++i) {
    float a = still ? 0.0f : 2.0f * 3.14159265f * i / (frames + 1), d = 3.2f;
    float dir[3] = {-scale * d * sinf(a), -scale * 0.3f, -scale * d * cosf(a)};
    float pos[3] = {centre[0] - dir[0], centre[1] - dir[1], centre[2] - dir[2]};
    anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, pos);
    anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, dir);
    anariCommitParameters(dev, camera);
    double t0 = i == 0 ? t_start : now_ms();
    anariRenderFrame(dev, frame);
    anariFrameReady(dev, frame, ANARI_WAIT);
    unsigned w, h;
    ANARIDataType type;
    const unsigned char *rgba = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
    ms[i] = now_ms() - t0;
    if (!rgba || w != size || h != size) {
      fprintf(stderr, "bench_cells: frame %u did not map\n", i);
      ok = 0;
    } else if (type != color && (ppm || ppm_dir)) {
      if (i == 0)
        fprintf(stderr, "bench_cells: the device mapped another pixel type; no PPM written\n");
    } else if ((i == 0 && ppm) || (ppm_dir && i > 0 && (i & (i - 1)) == 0)) {
      char name[4096];
      if (i == 0)
        snprintf(name, sizeof name, "%s", ppm);
      else
        snprintf(name, sizeof name, "%s/frame_%04u.ppm", ppm_dir, i);
      FILE *f = fopen(name, "wb");
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
    }
    fprintf(stderr, "[%u/%u] %.1f ms%s\n", i, frames, ms[i], i ? "" : " (first frame)");
  }
  unsigned long long samples = 0;
  anariGetProperty(dev, frame, "caveray.volumeSamples", ANARI_UINT64, &samples, sizeof samples,
      ANARI_WAIT);
  double mean = sum / frames, peak = peak_rss_mib();
  /* The lattice: the grid's voxels, or the vertices of the other fields. */
  unsigned dims[3] = {n, n, n};
  if (vdb)
    for (int k = 0; k < 3; ++k)
      dims[k] = (unsigned)((int64_t)vdb_hi[k] - vdb_lo[k] + 1);
  printf("bench_cells: %s, %s renderer, %s field on %ux%ux%u %s (%zu tetrahedra, %zu grid bytes) "
         "at %ux%u, backend %s, rate %g: first frame %.1f ms, then mean %.1f ms (min %.1f, "
         "max %.1f) over %u frames; peak RSS %.1f MiB (%.1f MiB of it the host's arrays)\n",
      library, renderer_kind, kind, dims[0], dims[1], dims[2], vdb ? "voxels" : "vertices", cells,
      grid_bytes, size, size, backend, rate, ms ? ms[0] : 0.0, mean, lo, hi, frames, peak,
      host_mib);

  if (json && ms) {
    char model[256];
    FILE *f = fopen(json, "w");
    cpu_model(model, sizeof model);
    if (!f) {
      fprintf(stderr, "bench_cells: cannot write %s\n", json);
      ok = 0;
    } else {
      fprintf(f, "{\n  \"benchmark\": \"capi-cells\",\n  \"machine\": {\"cpu\": \"%s\", "
                 "\"threads\": %ld},\n",
          model, sysconf(_SC_NPROCESSORS_ONLN));
      fprintf(f, "  \"library\": \"%s\",\n  \"renderer\": \"%s\",\n  \"still\": %u,\n",
          library, renderer_kind, still);
      fprintf(f, "  \"field\": \"%s\",\n  \"backend\": \"%s\",\n  \"rate\": %g,\n", kind,
          backend, rate);
      fprintf(f, "  \"vertices\": [%u, %u, %u],\n  \"tetrahedra\": %zu,\n", dims[0], dims[1],
          dims[2], cells);
      fprintf(f, "  \"grid_bytes\": %zu,\n", grid_bytes);
      fprintf(f, "  \"image\": [%u, %u],\n  \"last_frame_samples\": %llu,\n", size, size,
          samples);
      fprintf(f, "  \"first_frame_ms\": %.3f,\n  \"ms\": [", ms[0]);
      for (i = 1; i <= frames; ++i)
        fprintf(f, "%s%.3f", i > 1 ? ", " : "", ms[i]);
      fprintf(f, "],\n  \"mean_ms\": %.3f,\n  \"min_ms\": %.3f,\n  \"max_ms\": %.3f,\n",
          mean, lo, hi);
      fprintf(f, "  \"peak_rss_mib\": %.1f,\n  \"host_arrays_mib\": %.1f\n}\n", peak,
          host_mib);
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
  for (i = 0; i < 5; ++i)
    if (arrays[i])
      anariRelease(dev, arrays[i]);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  free(values);
  free(positions);
  free(index);
  free(cell_index);
  free(cell_type);
  free(amr_bounds);
  free(amr_levels);
  free(amr_data);
  free(grid);
  return ok ? 0 : 1;
}
