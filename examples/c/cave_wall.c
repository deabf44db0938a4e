/* The smallest useful CAVE plug-in body. A CAVE host already has, for each
 * wall and eye, the OpenGL view and projection matrices it renders its own
 * geometry with; caveray's "matrix" camera takes exactly those, so both
 * eyes of a volume come out correct on any wall, in any orientation.
 *
 * Here the host's matrices come from caverayMatricesFromScreen for a
 * 2 m x 2 m front wall and a tracked head 10 cm right of centre; the volume
 * is a 32^3 ball. Build and run from the repository root:
 *   cargo build --release
 *   cc -std=c99 -Iinclude examples/c/cave_wall.c -Ltarget/release \
 *      -lanari_library_caveray -Wl,-rpath,$PWD/target/release -o cave_wall
 *   ./cave_wall    # writes cave_wall_left.png and cave_wall_right.png
 */
#include <anari/anari.h>
#include <anari/caveray.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define N 32
#define W 256
#define H 256

static void on_status(const void *user, ANARIDevice device, ANARIObject source,
    ANARIDataType sourceType, ANARIStatusSeverity severity, ANARIStatusCode code,
    const char *message)
{
  (void)user, (void)device, (void)source, (void)sourceType, (void)code;
  if (severity <= ANARI_SEVERITY_WARNING)
    fprintf(stderr, "caveray: %s\n", message);
}

/* A PNG without a library: one zlib stream of stored (uncompressed)
 * deflate blocks, each CRC-checked chunk written as it goes. */
static unsigned long crc_table[256];

static unsigned long crc(unsigned long c, const unsigned char *p, size_t n)
{
  if (!crc_table[1])
    for (unsigned long i = 0; i < 256; ++i) {
      unsigned long v = i;
      for (int k = 0; k < 8; ++k)
        v = v & 1 ? 0xedb88320UL ^ (v >> 1) : v >> 1;
      crc_table[i] = v;
    }
  c ^= 0xffffffffUL;
  while (n--)
    c = crc_table[(c ^ *p++) & 0xff] ^ (c >> 8);
  return c ^ 0xffffffffUL;
}

static void put32(unsigned char *p, unsigned long v)
{
  p[0] = (unsigned char)(v >> 24), p[1] = (unsigned char)(v >> 16);
  p[2] = (unsigned char)(v >> 8), p[3] = (unsigned char)v;
}

static void chunk(FILE *f, const char *type, const unsigned char *data, size_t n)
{
  unsigned char head[8];
  put32(head, (unsigned long)n);
  memcpy(head + 4, type, 4);
  fwrite(head, 1, 8, f);
  fwrite(data, 1, n, f);
  put32(head, crc(crc(0, head + 4, 4), data, n));
  fwrite(head, 1, 4, f);
}

/* RGBA rows, the first mapped row the bottom one, as an RGB PNG. */
static int write_png(const char *path, const unsigned char *rgba, uint32_t w, uint32_t h)
{
  size_t row = 1 + 3 * (size_t)w, raw = row * h, at = 2;
  size_t blocks = (raw + 65534) / 65535, size = 2 + raw + 5 * blocks + 4;
  unsigned char *z = malloc(size), ihdr[13] = {0};
  unsigned long a = 1, b = 0;
  FILE *f;
  if (!z || !(f = fopen(path, "wb"))) {
    free(z);
    return 0;
  }
  z[0] = 0x78, z[1] = 0x01;
  for (size_t done = 0, y = 0, x = 0; done < raw;) {
    size_t n = raw - done < 65535 ? raw - done : 65535;
    z[at] = done + n == raw, z[at + 1] = n & 0xff, z[at + 2] = n >> 8;
    z[at + 3] = ~n & 0xff, z[at + 4] = (~n >> 8) & 0xff;
    at += 5;
    for (size_t i = 0; i < n; ++i, ++done) {
      unsigned char v = 0; /* filter byte 0 opens each row */
      if (x > 0)
        v = rgba[4 * ((h - 1 - y) * w + (x - 1) / 3) + (x - 1) % 3];
      z[at++] = v;
      a = (a + v) % 65521, b = (b + a) % 65521;
      if (++x == row)
        x = 0, ++y;
    }
  }
  put32(z + at, (b << 16) | a);
  put32(ihdr, w), put32(ihdr + 4, h);
  ihdr[8] = 8, ihdr[9] = 2; /* 8 bits, RGB */
  fwrite("\x89PNG\r\n\x1a\n", 1, 8, f);
  chunk(f, "IHDR", ihdr, 13);
  chunk(f, "IDAT", z, size);
  chunk(f, "IEND", NULL, 0);
  free(z);
  return fclose(f) == 0;
}

/* Per frame, per wall, per eye: hand over the host's matrices and render. */
static int render_eye(ANARIDevice dev, ANARIFrame frame, ANARICamera camera,
    const float view[16], const float proj[16], const char *path)
{
  uint32_t w, h;
  ANARIDataType type;
  const unsigned char *rgba;
  size_t lit = 0;
  int ok;

  anariSetParameter(dev, camera, "view", ANARI_FLOAT32_MAT4, view);
  anariSetParameter(dev, camera, "proj", ANARI_FLOAT32_MAT4, proj);
  anariCommitParameters(dev, camera);
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  rgba = (const unsigned char *)anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  if (!rgba)
    return 0;
  for (size_t i = 0; i < (size_t)w * h; ++i)
    lit += rgba[4 * i] > 20 || rgba[4 * i + 1] > 20 || rgba[4 * i + 2] > 20;
  ok = write_png(path, rgba, w, h);
  anariUnmapFrame(dev, frame, "channel.color");
  if (ok)
    printf("wrote %s: %ux%u, the volume on %zu pixels\n", path, w, h, lit);
  else
    fprintf(stderr, "cave_wall: cannot write %s\n", path);
  return ok;
}

int main(void)
{
  static float voxels[N * N * N];
  float origin[3] = {-0.4f, 1.0f, -1.4f}, spacing[3] = {0.8f / (N - 1), 0.8f / (N - 1), 0.8f / (N - 1)};
  float colors[2 * 3] = {0.2f, 0.4f, 1.0f, 1.0f, 0.8f, 0.3f}, opacities[2] = {0.0f, 1.0f};
  float unit = 0.05f; /* opacities per 5 cm: the ball is 80 cm across */
  float ll[3] = {-1, 0.4f, -2}, lr[3] = {1, 0.4f, -2}, ur[3] = {1, 2.4f, -2};
  float eyes[2][3] = {{0.0675f, 1.6f, 0}, {0.1325f, 1.6f, 0}}; /* head at x = 0.1 m, ipd 65 mm */
  float view[16], proj[16];
  const char *paths[2] = {"cave_wall_left.png", "cave_wall_right.png"};
  unsigned size[2] = {W, H};
  ANARIDataType color = ANARI_UFIXED8_VEC4;
  int i, j, k, ok = 1;

  for (k = 0; k < N; ++k)
    for (j = 0; j < N; ++j)
      for (i = 0; i < N; ++i) {
        float x = (i - 15.5f) / 15.5f, y = (j - 15.5f) / 15.5f, z = (k - 15.5f) / 15.5f;
        float r2 = x * x + y * y + z * z;
        voxels[(k * N + j) * N + i] = r2 < 1.0f ? 1.0f - r2 : 0.0f;
      }

  ANARILibrary lib = anariLoadLibrary("caveray", on_status, NULL);
  ANARIDevice dev = anariNewDevice(lib, "default");

  ANARIArray3D data = anariNewArray3D(dev, voxels, NULL, NULL, ANARI_FLOAT32, N, N, N);
  ANARISpatialField field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &data);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, spacing);
  anariCommitParameters(dev, field);

  ANARIArray1D c = anariNewArray1D(dev, colors, NULL, NULL, ANARI_FLOAT32_VEC3, 2);
  ANARIArray1D o = anariNewArray1D(dev, opacities, NULL, NULL, ANARI_FLOAT32, 2);
  ANARIVolume volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &c);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &o);
  anariSetParameter(dev, volume, "unitDistance", ANARI_FLOAT32, &unit);
  anariCommitParameters(dev, volume);

  ANARIWorld world = anariNewWorld(dev);
  ANARIArray1D volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  anariCommitParameters(dev, world);

  ANARIRenderer renderer = anariNewRenderer(dev, "default");
  anariCommitParameters(dev, renderer);
  ANARICamera camera = anariNewCamera(dev, "matrix");

  ANARIFrame frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, size);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &color);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariCommitParameters(dev, frame);

  for (i = 0; i < 2; ++i) {
    if (caverayMatricesFromScreen(ll, lr, ur, eyes[i], 0.05f, 100.0f, view, proj)
        != ANARI_STATUS_NO_ERROR) {
      fprintf(stderr, "cave_wall: %s\n", caverayLastError());
      ok = 0;
      continue;
    }
    ok &= render_eye(dev, frame, camera, view, proj, paths[i]);
  }

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
  return ok ? 0 : 1;
}
