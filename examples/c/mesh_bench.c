/*
 * mesh_bench.c -- time one ANARI device rendering a ~1M-triangle mesh, the
 * same scene for any device (docs/benchmarks.md compares caveray with the
 * reference device and anari-visionaray this way).
 *
 * Uses only the standard ANARI C API (anari/anari.h). Linked to caveray it
 * times caveray; built against the ANARI SDK's loader (libanari.so) it loads
 * the device named on the command line. Usage:
 *
 *   mesh_bench <library> [frames=10] [outdir=.]
 *
 * The scene: a closed bumpy UV sphere (708 x 708 quads, radius
 * 1 + 0.1 sin(8 theta) sin(8 phi)), indexed `triangle` geometry with
 * vertex.position, vertex.color (FLOAT32_VEC4, from the analytic normal)
 * and primitive.index, 1 001 112 triangles; beside it 1024 spheres (a
 * `sphere` geometry, radius 0.04, on a 32 x 32 grid of a shell of radius
 * 1.35); `matte` material whose color is the attribute "color" for the
 * mesh and (0.8, 0.7, 0.6) for the spheres; one `directional` light
 * (-1,-1,-1); renderer `default`, background (0.1, 0.1, 0.1, 1);
 * perspective camera at (0, 0, 3.5) looking down -z, fovy 60 deg, aspect
 * 1; frame 768 x 768, channel.color UFIXED8_RGBA_SRGB, channel.depth
 * FLOAT32.  The arrays are the host's own memory, shared with the device
 * (anariNewArray1D with a pointer), held until the end: 26 MB for the
 * mesh, as a host that keeps its data does.  MESH_BENCH_NORMALS=1 adds
 * vertex.normal (analytic, 6 MB more).
 *
 * Timings (CLOCK_MONOTONIC):
 *   first_frame_ms : commit of geometry/surface/world/frame + the first
 *                    anariRenderFrame + anariFrameReady(WAIT) (includes the
 *                    acceleration-structure build);
 *   frame_ms_*     : `frames` further renders, each anariRenderFrame +
 *                    anariFrameReady(WAIT).  Before each one the camera
 *                    position is re-committed, alternating z between 3.5 and
 *                    3.5001, because both helide and caveray skip the render
 *                    of a frame in which nothing changed; the last render is
 *                    at z = 3.5 exactly (frames is forced even).
 *   duration_property_ms : median of the frame's `duration` property
 *                    (FLOAT32 seconds in the ANARI spec) over those renders.
 *   peak_rss_mb    : the process's peak resident memory (getrusage) at
 *                    the end, host arrays included (host_arrays_mb).
 *
 * With library "caveray" the device parameter backend = "cpu" is set (see
 * caveray's docs/c_api.md) unless MESH_BENCH_BACKEND names another value
 * ("none" to leave it unset).  MESH_BENCH_RENDERER overrides the renderer
 * subtype (default "default").  MESH_BENCH_VERBOSE=1 prints INFO messages and
 * per-frame times to stderr.
 */
#define _POSIX_C_SOURCE 200809L
#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif
#include <anari/anari.h>

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>

#define N_THETA 708
#define N_PHI 708
#define IMG 768
#define N_SPHERES 32 /* per side of the grid */

static double now_ms(void)
{
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

static int g_errors = 0;

static void status_cb(const void *user,
    ANARIDevice device,
    ANARIObject source,
    ANARIDataType sourceType,
    ANARIStatusSeverity severity,
    ANARIStatusCode code,
    const char *message)
{
  (void)user;
  (void)device;
  (void)source;
  (void)sourceType;
  (void)code;
  const char *verbose = getenv("MESH_BENCH_VERBOSE");
  if (severity == ANARI_SEVERITY_FATAL_ERROR || severity == ANARI_SEVERITY_ERROR) {
    g_errors++;
    fprintf(stderr, "[ANARI ERROR] %s\n", message);
  } else if (severity == ANARI_SEVERITY_WARNING) {
    fprintf(stderr, "[ANARI WARN] %s\n", message);
  } else if (severity == ANARI_SEVERITY_PERFORMANCE_WARNING) {
    fprintf(stderr, "[ANARI PERF] %s\n", message);
  } else if (verbose && severity == ANARI_SEVERITY_INFO) {
    fprintf(stderr, "[ANARI INFO] %s\n", message);
  } else if (verbose && atoi(verbose) > 1) {
    fprintf(stderr, "[ANARI DEBUG] %s\n", message);
  }
}

static int cmp_double(const void *a, const void *b)
{
  double x = *(const double *)a, y = *(const double *)b;
  return (x > y) - (x < y);
}

static double median(double *v, int n)
{
  qsort(v, n, sizeof(double), cmp_double);
  return (n % 2) ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

static void bumpy(double th, double ph, float *pos, float *nrm)
{
  const double st = sin(th), ct = cos(th), sp = sin(ph), cp = cos(ph);
  const double r = 1.0 + 0.1 * sin(8 * th) * sin(8 * ph);
  const double r_t = 0.8 * cos(8 * th) * sin(8 * ph);
  const double r_p = 0.8 * sin(8 * th) * cos(8 * ph);
  const double s[3] = {st * cp, ct, st * sp};
  const double s_t[3] = {ct * cp, -st, ct * sp};
  const double s_p[3] = {-st * sp, 0.0, st * cp};
  double dt[3], dp[3], n[3];
  for (int i = 0; i < 3; i++) {
    pos[i] = (float)(r * s[i]);
    dt[i] = r_t * s[i] + r * s_t[i];
    dp[i] = r_p * s[i] + r * s_p[i];
  }
  n[0] = dt[1] * dp[2] - dt[2] * dp[1];
  n[1] = dt[2] * dp[0] - dt[0] * dp[2];
  n[2] = dt[0] * dp[1] - dt[1] * dp[0];
  double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
  if (st < 1e-9 || len < 1e-12) {
    n[0] = s[0];
    n[1] = s[1];
    n[2] = s[2];
    len = 1.0;
  }
  if (n[0] * s[0] + n[1] * s[1] + n[2] * s[2] < 0)
    len = -len; /* point outwards */
  for (int i = 0; i < 3; i++)
    nrm[i] = (float)(n[i] / len);
}

static void set_camera_z(ANARIDevice d, ANARICamera cam, float z)
{
  float pos[3] = {0.f, 0.f, z};
  anariSetParameter(d, cam, "position", ANARI_FLOAT32_VEC3, pos);
  anariCommitParameters(d, cam);
}

int main(int argc, char **argv)
{
  if (argc < 2) {
    fprintf(stderr, "usage: %s <library> [frames=10] [outdir]\n", argv[0]);
    return 2;
  }
  const char *libName = argv[1];
  int frames = argc > 2 ? atoi(argv[2]) : 10;
  if (frames < 2)
    frames = 2;
  if (frames % 2)
    frames++;
  const char *outdir = argc > 3 ? argv[3] : ".";
  mkdir(outdir, 0755);

  double t_load0 = now_ms();
  ANARILibrary lib = anariLoadLibrary(libName, status_cb, NULL);
  if (!lib) {
    fprintf(stderr, "could not load ANARI library '%s'\n", libName);
    return 1;
  }
  ANARIDevice d = anariNewDevice(lib, "default");
  if (!d) {
    fprintf(stderr, "could not create device\n");
    return 1;
  }
  const char *backend = NULL;
  if (strcmp(libName, "caveray") == 0) {
    backend = getenv("MESH_BENCH_BACKEND");
    if (!backend)
      backend = "cpu";
    if (strcmp(backend, "none") == 0)
      backend = NULL;
  }
  if (backend)
    anariSetParameter(d, d, "backend", ANARI_STRING, backend);
  anariCommitParameters(d, d);
  double t_load1 = now_ms();

  /* ---- mesh ---- */
  const uint32_t nv = (N_THETA + 1) * (N_PHI + 1);
  /* pole bands: one non-degenerate triangle per quad */
  const uint32_t nt = 2u * N_THETA * N_PHI - 2u * N_PHI;

  const int withNormals = getenv("MESH_BENCH_NORMALS") && atoi(getenv("MESH_BENCH_NORMALS"));
  double t_up0 = now_ms();
  float *pos = (float *)malloc(sizeof(float) * 3 * nv);
  float *nrm = (float *)malloc(sizeof(float) * 3 * nv);
  float *col = (float *)malloc(sizeof(float) * 4 * nv);
  uint32_t *idx = (uint32_t *)malloc(sizeof(uint32_t) * 3 * nt);
  if (!pos || !nrm || !col || !idx) {
    fprintf(stderr, "out of memory\n");
    return 1;
  }
  for (uint32_t i = 0; i <= N_THETA; i++) {
    const double th = M_PI * i / N_THETA;
    for (uint32_t j = 0; j <= N_PHI; j++) {
      const double ph = 2.0 * M_PI * j / N_PHI;
      const uint32_t v = i * (N_PHI + 1) + j;
      bumpy(th, ph, pos + 3 * v, nrm + 3 * v);
    }
  }
  /* make the seam and the poles bit-identical (closed mesh) */
  for (uint32_t i = 0; i <= N_THETA; i++) {
    const uint32_t a = i * (N_PHI + 1), b = a + N_PHI;
    memcpy(pos + 3 * b, pos + 3 * a, 3 * sizeof(float));
    memcpy(nrm + 3 * b, nrm + 3 * a, 3 * sizeof(float));
  }
  for (uint32_t j = 1; j <= N_PHI; j++) {
    memcpy(pos + 3 * j, pos, 3 * sizeof(float));
    memcpy(nrm + 3 * j, nrm, 3 * sizeof(float));
    const uint32_t last = N_THETA * (N_PHI + 1);
    memcpy(pos + 3 * (last + j), pos + 3 * last, 3 * sizeof(float));
    memcpy(nrm + 3 * (last + j), nrm + 3 * last, 3 * sizeof(float));
  }
  for (uint32_t v = 0; v < nv; v++) {
    for (int c = 0; c < 3; c++)
      col[4 * v + c] = 0.5f + 0.45f * nrm[3 * v + c];
    col[4 * v + 3] = 1.f;
  }
  if (!withNormals) {
    free(nrm);
    nrm = NULL;
  }
  uint32_t t = 0;
  for (uint32_t i = 0; i < N_THETA; i++) {
    for (uint32_t j = 0; j < N_PHI; j++) {
      const uint32_t v00 = i * (N_PHI + 1) + j;
      const uint32_t v01 = v00 + 1;
      const uint32_t v10 = v00 + (N_PHI + 1);
      const uint32_t v11 = v10 + 1;
      /* counter-clockwise seen from outside */
      if (i != 0) {
        idx[3 * t + 0] = v00;
        idx[3 * t + 1] = v01;
        idx[3 * t + 2] = v11;
        t++;
      }
      if (i != N_THETA - 1) {
        idx[3 * t + 0] = v00;
        idx[3 * t + 1] = v11;
        idx[3 * t + 2] = v10;
        t++;
      }
    }
  }
  if (t != nt) {
    fprintf(stderr, "internal error: %u triangles, expected %u\n", t, nt);
    return 1;
  }
  /* 1024 small spheres on a shell around the mesh */
  const uint32_t ns = N_SPHERES * N_SPHERES;
  float *spos = (float *)malloc(sizeof(float) * 3 * ns);
  if (!spos) {
    fprintf(stderr, "out of memory\n");
    return 1;
  }
  for (uint32_t i = 0; i < N_SPHERES; i++)
    for (uint32_t j = 0; j < N_SPHERES; j++) {
      const double th = M_PI * (i + 0.5) / N_SPHERES, ph = 2.0 * M_PI * j / N_SPHERES;
      float *p = spos + 3 * (i * N_SPHERES + j);
      p[0] = (float)(1.35 * sin(th) * cos(ph));
      p[1] = (float)(1.35 * cos(th));
      p[2] = (float)(1.35 * sin(th) * sin(ph));
    }
  const double hostMB = (sizeof(float) * (3.0 + 4.0 + (nrm ? 3.0 : 0.0)) * nv
                            + sizeof(uint32_t) * 3.0 * nt + sizeof(float) * 3.0 * ns)
      / 1e6;

  ANARIArray1D aPos = anariNewArray1D(d, pos, NULL, NULL, ANARI_FLOAT32_VEC3, nv);
  ANARIArray1D aCol = anariNewArray1D(d, col, NULL, NULL, ANARI_FLOAT32_VEC4, nv);
  ANARIArray1D aNrm =
      nrm ? anariNewArray1D(d, nrm, NULL, NULL, ANARI_FLOAT32_VEC3, nv) : NULL;
  ANARIArray1D aIdx = anariNewArray1D(d, idx, NULL, NULL, ANARI_UINT32_VEC3, nt);
  ANARIArray1D aSph = anariNewArray1D(d, spos, NULL, NULL, ANARI_FLOAT32_VEC3, ns);
  double t_up1 = now_ms();

  ANARIGeometry geom = anariNewGeometry(d, "triangle");
  anariSetParameter(d, geom, "vertex.position", ANARI_ARRAY1D, &aPos);
  anariSetParameter(d, geom, "vertex.color", ANARI_ARRAY1D, &aCol);
  if (aNrm)
    anariSetParameter(d, geom, "vertex.normal", ANARI_ARRAY1D, &aNrm);
  anariSetParameter(d, geom, "primitive.index", ANARI_ARRAY1D, &aIdx);

  ANARIGeometry sgeom = anariNewGeometry(d, "sphere");
  anariSetParameter(d, sgeom, "vertex.position", ANARI_ARRAY1D, &aSph);
  float sradius = 0.04f;
  anariSetParameter(d, sgeom, "radius", ANARI_FLOAT32, &sradius);

  ANARIMaterial mat = anariNewMaterial(d, "matte");
  anariSetParameter(d, mat, "color", ANARI_STRING, "color");
  ANARIMaterial smat = anariNewMaterial(d, "matte");
  float color[3] = {0.8f, 0.7f, 0.6f};
  anariSetParameter(d, smat, "color", ANARI_FLOAT32_VEC3, color);

  ANARISurface surf = anariNewSurface(d);
  anariSetParameter(d, surf, "geometry", ANARI_GEOMETRY, &geom);
  anariSetParameter(d, surf, "material", ANARI_MATERIAL, &mat);
  ANARISurface ssurf = anariNewSurface(d);
  anariSetParameter(d, ssurf, "geometry", ANARI_GEOMETRY, &sgeom);
  anariSetParameter(d, ssurf, "material", ANARI_MATERIAL, &smat);

  ANARILight light = anariNewLight(d, "directional");
  float ldir[3] = {-1.f, -1.f, -1.f};
  anariSetParameter(d, light, "direction", ANARI_FLOAT32_VEC3, ldir);

  ANARIWorld world = anariNewWorld(d);
  ANARISurface surfaces[2] = {surf, ssurf};
  ANARIArray1D aSurf =
      anariNewArray1D(d, surfaces, NULL, NULL, ANARI_SURFACE, 2);
  ANARIArray1D aLight =
      anariNewArray1D(d, &light, NULL, NULL, ANARI_LIGHT, 1);
  anariSetParameter(d, world, "surface", ANARI_ARRAY1D, &aSurf);
  anariSetParameter(d, world, "light", ANARI_ARRAY1D, &aLight);

  const char *renSubtype = getenv("MESH_BENCH_RENDERER");
  if (!renSubtype)
    renSubtype = "default";
  ANARIRenderer ren = anariNewRenderer(d, renSubtype);
  float bg[4] = {0.1f, 0.1f, 0.1f, 1.f};
  anariSetParameter(d, ren, "background", ANARI_FLOAT32_VEC4, bg);
  anariCommitParameters(d, ren);

  ANARICamera cam = anariNewCamera(d, "perspective");
  float cpos[3] = {0.f, 0.f, 3.5f}, cdir[3] = {0.f, 0.f, -1.f},
        cup[3] = {0.f, 1.f, 0.f};
  float fovy = (float)(60.0 * M_PI / 180.0), aspect = 1.f;
  anariSetParameter(d, cam, "position", ANARI_FLOAT32_VEC3, cpos);
  anariSetParameter(d, cam, "direction", ANARI_FLOAT32_VEC3, cdir);
  anariSetParameter(d, cam, "up", ANARI_FLOAT32_VEC3, cup);
  anariSetParameter(d, cam, "fovy", ANARI_FLOAT32, &fovy);
  anariSetParameter(d, cam, "aspect", ANARI_FLOAT32, &aspect);
  anariCommitParameters(d, cam);

  ANARIFrame frame = anariNewFrame(d);
  uint32_t size[2] = {IMG, IMG};
  ANARIDataType colType = ANARI_UFIXED8_RGBA_SRGB, depthType = ANARI_FLOAT32;
  anariSetParameter(d, frame, "size", ANARI_UINT32_VEC2, size);
  anariSetParameter(d, frame, "channel.color", ANARI_DATA_TYPE, &colType);
  anariSetParameter(d, frame, "channel.depth", ANARI_DATA_TYPE, &depthType);
  anariSetParameter(d, frame, "renderer", ANARI_RENDERER, &ren);
  anariSetParameter(d, frame, "camera", ANARI_CAMERA, &cam);
  anariSetParameter(d, frame, "world", ANARI_WORLD, &world);

  /* ---- (a) world commit + first frame ---- */
  double t0 = now_ms();
  anariCommitParameters(d, geom);
  anariCommitParameters(d, sgeom);
  anariCommitParameters(d, mat);
  anariCommitParameters(d, smat);
  anariCommitParameters(d, surf);
  anariCommitParameters(d, ssurf);
  anariCommitParameters(d, light);
  anariCommitParameters(d, world);
  anariCommitParameters(d, frame);
  anariRenderFrame(d, frame);
  anariFrameReady(d, frame, ANARI_WAIT);
  double t1 = now_ms();
  const double first_ms = t1 - t0;
  float firstDur = -1.f;
  int haveFirstDur = anariGetProperty(
      d, frame, "duration", ANARI_FLOAT32, &firstDur, sizeof(firstDur), ANARI_WAIT);

  /* ---- (b) steady renders ---- */
  double *ms = (double *)calloc(frames, sizeof(double));
  double *dur = (double *)calloc(frames, sizeof(double));
  int nDur = 0;
  for (int i = 0; i < frames; i++) {
    /* i even -> 3.5001, i odd -> 3.5; the last (odd) one is at 3.5 */
    set_camera_z(d, cam, (i % 2 == 0) ? 3.5001f : 3.5f);
    double a = now_ms();
    anariRenderFrame(d, frame);
    anariFrameReady(d, frame, ANARI_WAIT);
    double b = now_ms();
    ms[i] = b - a;
    float du = -1.f;
    if (anariGetProperty(d, frame, "duration", ANARI_FLOAT32, &du, sizeof(du), ANARI_WAIT)) {
      dur[nDur++] = du * 1e3;
    }
    if (getenv("MESH_BENCH_VERBOSE"))
      fprintf(stderr, "frame %d: %.2f ms (duration %.2f ms)\n", i, ms[i], du * 1e3);
  }

  double msCopy[64];
  int nc = frames < 64 ? frames : 64;
  memcpy(msCopy, ms, nc * sizeof(double));
  double mn = ms[0];
  for (int i = 1; i < frames; i++)
    mn = ms[i] < mn ? ms[i] : mn;
  double med = median(ms, frames);
  double durMed = nDur ? median(dur, nDur) : -1.0;

  /* ---- image ---- */
  uint32_t w = 0, h = 0;
  ANARIDataType pt = ANARI_UNKNOWN;
  const uint8_t *px =
      (const uint8_t *)anariMapFrame(d, frame, "channel.color", &w, &h, &pt);
  char path[1024];
  uint64_t hitPixels = 0;
  if (px && w == IMG && h == IMG
      && (pt == ANARI_UFIXED8_RGBA_SRGB || pt == ANARI_UFIXED8_VEC4)) {
    snprintf(path, sizeof(path), "%s/mesh_%s.ppm", outdir, libName);
    FILE *f = fopen(path, "wb");
    if (f) {
      fprintf(f, "P6\n%u %u\n255\n", w, h);
      for (int y = (int)h - 1; y >= 0; y--) /* ANARI row 0 = bottom */
        for (uint32_t x = 0; x < w; x++)
          fwrite(px + 4 * ((size_t)y * w + x), 1, 3, f);
      fclose(f);
    }
  } else {
    fprintf(stderr, "could not map channel.color (w=%u h=%u type=%d)\n", w, h, (int)pt);
  }
  anariUnmapFrame(d, frame, "channel.color");
  const float *dp =
      (const float *)anariMapFrame(d, frame, "channel.depth", &w, &h, &pt);
  if (dp && pt == ANARI_FLOAT32 && w == IMG && h == IMG) {
    snprintf(path, sizeof(path), "%s/mesh_%s_mask.pgm", outdir, libName);
    FILE *f = fopen(path, "wb");
    if (f) {
      fprintf(f, "P5\n%u %u\n255\n", w, h);
      for (int y = (int)h - 1; y >= 0; y--)
        for (uint32_t x = 0; x < w; x++) {
          float z = dp[(size_t)y * w + x];
          uint8_t m = (isfinite(z) && z < 1e30f) ? 255 : 0;
          hitPixels += m ? 1 : 0;
          fputc(m, f);
        }
      fclose(f);
    }
    /* raw depth, top row first, for silhouette / depth comparison */
    snprintf(path, sizeof(path), "%s/mesh_%s_depth.f32", outdir, libName);
    f = fopen(path, "wb");
    if (f) {
      for (int y = (int)h - 1; y >= 0; y--)
        fwrite(dp + (size_t)y * w, sizeof(float), w, f);
      fclose(f);
    }
  } else {
    fprintf(stderr, "could not map channel.depth\n");
  }
  anariUnmapFrame(d, frame, "channel.depth");

  printf("{\"library\": \"%s\", \"renderer\": \"%s\", \"backend_param\": %s%s%s, \"triangles\": %u, "
         "\"vertices\": %u, \"size\": %d, \"first_frame_ms\": %.2f, "
         "\"frame_ms_median\": %.2f, \"frame_ms_min\": %.2f, "
         "\"duration_property_ms\": %.2f, \"first_frame_duration_property_ms\": %.2f, "
         "\"frames\": %d, \"frame_ms_all\": [",
      libName,
      renSubtype,
      backend ? "\"" : "",
      backend ? backend : "null",
      backend ? "\"" : "",
      nt,
      nv,
      IMG,
      first_ms,
      med,
      mn,
      durMed,
      haveFirstDur ? firstDur * 1e3 : -1.0,
      frames);
  for (int i = 0; i < nc; i++)
    printf("%s%.2f", i ? ", " : "", msCopy[i]);
  struct rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  printf("], \"array_fill_ms\": %.2f, \"load_device_ms\": %.2f, "
         "\"hit_pixels\": %llu, \"spheres\": %u, \"normals\": %s, "
         "\"host_arrays_mb\": %.1f, \"peak_rss_mb\": %.1f, \"anari_errors\": %d}\n",
      t_up1 - t_up0,
      t_load1 - t_load0,
      (unsigned long long)hitPixels,
      ns,
      nrm ? "true" : "false",
      hostMB,
      usage.ru_maxrss / 1024.0,
      g_errors);
  fflush(stdout);

  free(ms);
  free(dur);
  anariRelease(d, frame);
  anariRelease(d, cam);
  anariRelease(d, ren);
  anariRelease(d, world);
  anariRelease(d, aSurf);
  anariRelease(d, aLight);
  anariRelease(d, light);
  anariRelease(d, surf);
  anariRelease(d, ssurf);
  anariRelease(d, mat);
  anariRelease(d, smat);
  anariRelease(d, geom);
  anariRelease(d, sgeom);
  anariRelease(d, aPos);
  anariRelease(d, aCol);
  if (aNrm)
    anariRelease(d, aNrm);
  anariRelease(d, aIdx);
  anariRelease(d, aSph);
  anariRelease(d, d);
  anariUnloadLibrary(lib);
  /* Shared arrays: the host's memory outlives the device's use of it. */
  free(pos);
  free(nrm);
  free(col);
  free(idx);
  free(spos);
  return 0;
}
