/* Writing what a C host test mapped, for the Rust test to check. */
#ifndef CAVERAY_TEST_OUTPUT_H
#define CAVERAY_TEST_OUTPUT_H

#include <stdio.h>

/* Writes w*h RGBA8 pixels, lower-left first, as they were mapped. */
static inline int write_rgba(const char *dir, const char *name, const void *pixels,
    unsigned w, unsigned h)
{
  char path[4200];
  FILE *f;
  size_t n = (size_t)w * h * 4;
  snprintf(path, sizeof path, "%s/%s.rgba", dir, name);
  f = fopen(path, "wb");
  if (!f || fwrite(pixels, 1, n, f) != n) {
    if (f)
      fclose(f);
    return 0;
  }
  fclose(f);
  return 1;
}

/* Writes `n` floats as they are in memory to DIR/NAME. */
static inline int write_floats(const char *dir, const char *name, const float *v, size_t n)
{
  char path[4200];
  FILE *f;
  snprintf(path, sizeof path, "%s/%s", dir, name);
  f = fopen(path, "wb");
  if (!f || fwrite(v, sizeof(float), n, f) != n) {
    if (f)
      fclose(f);
    return 0;
  }
  fclose(f);
  return 1;
}

#endif
