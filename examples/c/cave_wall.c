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
 *   ./cave_wall    # writes cave_wall_left.ppm and cave_wall_right.ppm
 */
#include <anari/anari.h>
#include <anari/caveray.h>

#include <stdio.h>

#define N 32
#define W 64
#define H 64

static void on_status(const void *user, ANARIDevice device, ANARIObject source,
    ANARIDataType sourceType, ANARIStatusSeverity severity, ANARIStatusCode code,
    const char *message)
{
  (void)user, (void)device, (void)source, (void)sourceType, (void)code;
  if (severity <= ANARI_SEVERITY_WARNING)
    fprintf(stderr, "caveray: %s\n", message);
}

/* Per frame, per wall, per eye: hand over the host's matrices and render. */
static int render_eye(ANARIDevice dev, ANARIFrame frame, ANARICamera camera,
    const float view[16], const float proj[16], const char *path)
{
  uint32_t w, h, x, y;
  ANARIDataType type;
  const unsigned char *rgba;
  FILE *f;

  anariSetParameter(dev, camera, "view", ANARI_FLOAT32_MAT4, view);
  anariSetParameter(dev, camera, "proj", ANARI_FLOAT32_MAT4, proj);
  anariCommitParameters(dev, camera);
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  rgba = (const unsigned char *)anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  if (!rgba || !(f = fopen(path, "wb")))
    return 0;
  fprintf(f, "P6\n%u %u\n255\n", w, h);
  for (y = h; y-- > 0;) /* the first mapped row is the bottom one */
    for (x = 0; x < w; ++x)
      fwrite(rgba + 4 * (y * w + x), 1, 3, f);
  fclose(f);
  anariUnmapFrame(dev, frame, "channel.color");
  return 1;
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
  const char *paths[2] = {"cave_wall_left.ppm", "cave_wall_right.ppm"};
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
