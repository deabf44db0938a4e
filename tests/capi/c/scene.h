/* The scene the C host tests render, read from a text file the Rust test
 * writes: volume, transfer function, frame size, one wall and eye, and the
 * wall's OpenGL matrices. Shared by render_wall.c and loader.cpp. */
#ifndef CAVERAY_TEST_SCENE_H
#define CAVERAY_TEST_SCENE_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "output.h"

typedef struct Scene {
  unsigned dims[3];
  float *voxels; /* FLOAT32, x fastest */
  float origin[3], spacing[3];
  float range[2];
  unsigned ncolors;
  float *colors; /* RGBA */
  unsigned nopacities;
  float *opacities;
  float unitDistance;
  unsigned size[2];
  float ll[3], lr[3], ur[3], eye[3];
  float view[16], proj[16];
} Scene;

static int read_floats(FILE *f, const char *key, float *v, unsigned n)
{
  char word[64];
  unsigned i;
  if (fscanf(f, "%63s", word) != 1 || strcmp(word, key) != 0) {
    fprintf(stderr, "scene: expected '%s'\n", key);
    return 0;
  }
  for (i = 0; i < n; ++i)
    if (fscanf(f, "%f", &v[i]) != 1)
      return 0;
  return 1;
}

static int read_count(FILE *f, const char *key, unsigned *n)
{
  char word[64];
  return fscanf(f, "%63s %u", word, n) == 2 && strcmp(word, key) == 0;
}

/* Returns 1 on success; free with scene_free. */
static int scene_load(const char *path, Scene *s)
{
  char word[64], raw[4096];
  size_t count;
  FILE *f = fopen(path, "r"), *v;
  float size[2];
  memset(s, 0, sizeof *s);
  if (!f)
    return 0;
  if (fscanf(f, "%63s %u %u %u %4095s", word, &s->dims[0], &s->dims[1],
          &s->dims[2], raw) != 5)
    goto fail;
  count = (size_t)s->dims[0] * s->dims[1] * s->dims[2];
  s->voxels = (float *)malloc(count * sizeof(float));
  v = fopen(raw, "rb");
  if (!v || fread(s->voxels, sizeof(float), count, v) != count) {
    if (v)
      fclose(v);
    goto fail;
  }
  fclose(v);
  if (!read_floats(f, "origin", s->origin, 3)
      || !read_floats(f, "spacing", s->spacing, 3)
      || !read_floats(f, "range", s->range, 2) || !read_count(f, "colors", &s->ncolors))
    goto fail;
  s->colors = (float *)malloc(4 * s->ncolors * sizeof(float));
  if (!read_floats(f, "rgba", s->colors, 4 * s->ncolors)
      || !read_count(f, "opacities", &s->nopacities))
    goto fail;
  s->opacities = (float *)malloc(s->nopacities * sizeof(float));
  if (!read_floats(f, "alpha", s->opacities, s->nopacities)
      || !read_floats(f, "unit", &s->unitDistance, 1)
      || !read_floats(f, "size", size, 2) || !read_floats(f, "ll", s->ll, 3)
      || !read_floats(f, "lr", s->lr, 3) || !read_floats(f, "ur", s->ur, 3)
      || !read_floats(f, "eye", s->eye, 3) || !read_floats(f, "view", s->view, 16)
      || !read_floats(f, "proj", s->proj, 16))
    goto fail;
  s->size[0] = (unsigned)size[0];
  s->size[1] = (unsigned)size[1];
  fclose(f);
  return 1;
fail:
  fprintf(stderr, "scene: cannot read %s\n", path);
  fclose(f);
  return 0;
}

static void scene_free(Scene *s)
{
  free(s->voxels);
  free(s->colors);
  free(s->opacities);
}

#endif
