/* What the benchmark hosts of examples/c/ share: the status callback,
 * a millisecond clock, the shells they render and the machine's CPU for
 * their reports. Included by bench_shells.c and bench_cells.c. */
#ifndef CAVERAY_EXAMPLES_BENCH_H
#define CAVERAY_EXAMPLES_BENCH_H

#include <anari/anari.h>

#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

static void on_status(const void *user, ANARIDevice device, ANARIObject source,
    ANARIDataType sourceType, ANARIStatusSeverity severity, ANARIStatusCode code,
    const char *message)
{
  (void)user, (void)device, (void)source, (void)sourceType, (void)code;
  if (severity <= ANARI_SEVERITY_WARNING)
    fprintf(stderr, "caveray: %s\n", message);
  else if (severity == ANARI_SEVERITY_INFO)
    fprintf(stderr, "caveray (info): %s\n", message);
}

static double now_ms(void)
{
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
}

/* The shells of caveray's `shells` volume: tents of half-width 0.05 peaking
 * at 1 on radii 0.3, 0.5, 0.7 and 0.9 of [-1, 1]^3. */
static float shells(float x, float y, float z)
{
  static const float radii[4] = {0.3f, 0.5f, 0.7f, 0.9f};
  float r = sqrtf(x * x + y * y + z * z), v = 0.0f;
  int i;
  for (i = 0; i < 4; ++i) {
    float t = 1.0f - fabsf(r - radii[i]) / 0.05f;
    if (t > v)
      v = t;
  }
  return v;
}

static void cpu_model(char *out, size_t n)
{
  char line[512];
  FILE *f = fopen("/proc/cpuinfo", "r");
  snprintf(out, n, "unknown");
  if (!f)
    return;
  while (fgets(line, sizeof line, f))
    if (strncmp(line, "model name", 10) == 0) {
      char *v = strchr(line, ':');
      if (v) {
        v += 1 + (v[1] == ' ');
        v[strcspn(v, "\n\"\\")] = 0;
        snprintf(out, n, "%s", v);
      }
      break;
    }
  fclose(f);
}

#endif
