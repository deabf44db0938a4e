/* A tracked-display host: it renders at a fixed rate (one frame every
 * PERIOD_MS, as a 90 Hz display would ask) with frame parameter
 * "caveray.deadline" = DEADLINE_MS and "caveray.warp" = WARP, moving the
 * camera sideways every frame, then holding it still. Each frame is
 * anariRenderFrame + anariFrameReady(ANARI_WAIT) + map/unmap; the time the
 * host waited, the shown image's age and the warp that made it are read
 * per frame.
 * The scene: a 48^3 field of nested ellipsoids, a slow renderer (ambient
 * occlusion), so a whole render takes longer than the deadline.
 * Usage: deadline_host DEADLINE_MS WARP PERIOD_MS FRAMES SIZE.
 * Prints one line per frame and a summary line
 *   "waits: max M ms mean A ms deadline D ms frames N warped W fresh F
 *    shown none a quad b grid c layers d"
 * (W: frames warped by WARP; a..d: older images shown by each warp, which
 * differs from WARP where WARP would have missed the deadline).
 * Exit status 0 only if no warning or error was reported, every property
 * answered, the first frame showed the background (or its own image), later
 * frames showed the volume, and once the camera stood still a frame showed
 * its own, unwarped image. */
#define _POSIX_C_SOURCE 199309L

#include <anari/anari.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static int problems = 0;

static void on_status(const void *program, ANARIDevice d, ANARIObject source,
    ANARIDataType sourceType, ANARIStatusSeverity severity, ANARIStatusCode code,
    const char *message)
{
  (void)d, (void)source, (void)sourceType, (void)code;
  if (severity <= ANARI_SEVERITY_WARNING) {
    ++problems;
    fprintf(stderr, "%s: %s\n", (const char *)program, message);
  }
}

static double now_ms(void)
{
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return t.tv_sec * 1e3 + t.tv_nsec / 1e6;
}

static void sleep_until(double ms)
{
  double left = ms - now_ms();
  if (left > 0) {
    struct timespec pause = {(time_t)(left / 1e3), (long)(fmod(left, 1e3) * 1e6)};
    nanosleep(&pause, NULL);
  }
}

/* Nested ellipsoids: a shell, a softer inside, two dense cores. */
static float field_value(float x, float y, float z)
{
  float r = x * x / 0.8f + y * y / 0.6f + z * z / 0.7f;
  float a = (x - 0.3f) * (x - 0.3f) + y * y + z * z;
  float b = (x + 0.35f) * (x + 0.35f) + (y - 0.2f) * (y - 0.2f) + z * z;
  if (a < 0.04f || b < 0.03f)
    return 1.0f;
  if (r < 0.8f)
    return 0.45f;
  if (r < 1.0f)
    return 0.8f;
  return 0.0f;
}

int main(int argc, char **argv)
{
  enum { N = 48 };
  static float voxels[N * N * N];
  float origin[3] = {-1, -1, -1}, spacing[3] = {2.0f / (N - 1), 2.0f / (N - 1), 2.0f / (N - 1)};
  float colors[4 * 3] = {0, 0, 0, 0.9f, 0.6f, 0.3f, 0.3f, 0.6f, 0.9f, 1, 1, 1};
  float opacities[4] = {0, 0.3f, 0.6f, 1};
  float background[4] = {0, 0, 0, 1}, position[3] = {0, 0, 3.5f}, direction[3] = {0, 0, -1};
  float up[3] = {0, 1, 0}, fovy = 0.9f, aspect = 1.0f, deadline, age;
  double period, max_wait = 0, sum_wait = 0;
  uint32_t size[2];
  ANARIDataType rgba = ANARI_UFIXED8_RGBA_SRGB;
  const char *warp, *shown;
  int frames, i, j, k, warped = 0, fresh = 0, shows = 0, ok = 1;
  /* Frames shown by each warp, the image's own camera counted apart. */
  const char *modes[4] = {"none", "quad", "grid", "layers"};
  int by_mode[4] = {0, 0, 0, 0};
  double still_since = 0;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray3D data;
  ANARIArray1D volumes, color_array, opacity_array;
  ANARISpatialField field;
  ANARIVolume volume;
  ANARIWorld world;
  ANARIRenderer renderer;
  ANARICamera camera;
  ANARIFrame frame;

  if (argc != 6) {
    fprintf(stderr, "usage: deadline_host DEADLINE_MS WARP PERIOD_MS FRAMES SIZE\n");
    return 2;
  }
  deadline = (float)atof(argv[1]);
  warp = argv[2];
  period = atof(argv[3]);
  frames = atoi(argv[4]);
  size[0] = size[1] = (uint32_t)atoi(argv[5]);
  for (k = 0; k < N; ++k)
    for (j = 0; j < N; ++j)
      for (i = 0; i < N; ++i)
        voxels[(k * N + j) * N + i] = field_value(
            -1 + 2.0f * i / (N - 1), -1 + 2.0f * j / (N - 1), -1 + 2.0f * k / (N - 1));

  lib = anariLoadLibrary("caveray", on_status, "deadline_host");
  dev = anariNewDevice(lib, "default");
  data = anariNewArray3D(dev, voxels, NULL, NULL, ANARI_FLOAT32, N, N, N);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &data);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, spacing);
  anariCommitParameters(dev, field);
  anariRelease(dev, data);
  color_array = anariNewArray1D(dev, colors, NULL, NULL, ANARI_FLOAT32_VEC3, 4);
  opacity_array = anariNewArray1D(dev, opacities, NULL, NULL, ANARI_FLOAT32, 4);
  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &color_array);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &opacity_array);
  anariCommitParameters(dev, volume);
  anariRelease(dev, color_array);
  anariRelease(dev, opacity_array);
  world = anariNewWorld(dev);
  volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &volumes);
  anariCommitParameters(dev, world);
  anariRelease(dev, volumes);
  anariRelease(dev, volume);
  anariRelease(dev, field);

  renderer = anariNewRenderer(dev, "default");
  anariSetParameter(dev, renderer, "background", ANARI_FLOAT32_VEC4, background);
  anariSetParameter(dev, renderer, "shading", ANARI_STRING, "ao");
  anariCommitParameters(dev, renderer);
  camera = anariNewCamera(dev, "perspective");
  anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, direction);
  anariSetParameter(dev, camera, "up", ANARI_FLOAT32_VEC3, up);
  anariSetParameter(dev, camera, "fovy", ANARI_FLOAT32, &fovy);
  anariSetParameter(dev, camera, "aspect", ANARI_FLOAT32, &aspect);

  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, size);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &rgba);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariSetParameter(dev, frame, "caveray.deadline", ANARI_FLOAT32, &deadline);
  anariSetParameter(dev, frame, "caveray.warp", ANARI_STRING, warp);
  anariCommitParameters(dev, frame);

  /* `frames` moving frames, then standing still (for up to a minute) until
   * the frame shows its own image. */
  for (i = 0;; ++i) {
    double start = now_ms(), waited;
    int moving = i < frames, lit = 0;
    if (!moving && still_since == 0)
      still_since = start;
    if (!moving && start - still_since > 60e3)
      break;
    const unsigned char *pixels;
    uint32_t w = 0, h = 0;
    ANARIDataType type = ANARI_UNKNOWN;
    if (moving)
      position[0] = -0.4f + 0.8f * (float)i / (float)frames;
    anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, position);
    anariCommitParameters(dev, camera);
    anariRenderFrame(dev, frame);
    anariFrameReady(dev, frame, ANARI_WAIT);
    waited = now_ms() - start;
    if (waited > max_wait)
      max_wait = waited;
    sum_wait += waited;
    age = -2;
    shown = NULL;
    if (!anariGetProperty(dev, frame, "caveray.imageAge", ANARI_FLOAT32, &age, sizeof age, ANARI_WAIT)
        || !anariGetProperty(dev, frame, "caveray.warp", ANARI_STRING, &shown, sizeof shown, ANARI_WAIT)
        || !shown) {
      fprintf(stderr, "deadline_host: frame %d has no caveray.imageAge or caveray.warp\n", i);
      ok = 0;
      break;
    }
    pixels = (const unsigned char *)anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
    for (j = 0; pixels && j < (int)(w * h); ++j)
      lit |= pixels[4 * j] > 8 || pixels[4 * j + 1] > 8 || pixels[4 * j + 2] > 8;
    anariUnmapFrame(dev, frame, "channel.color");
    printf("frame %d wait %.2f ms age %.1f ms warp %s%s\n", i, waited, age, shown,
        lit ? "" : " (background)");
    /* By its deadline the first frame has the background, or its own
     * image if that was quicker; nothing older exists. */
    if (i == 0 && (strcmp(shown, "none") != 0 || (age == -1.0f) == lit)) {
      fprintf(stderr, "deadline_host: the first frame is neither the background nor its own image\n");
      ok = 0;
    }
    if (age >= 0) {
      ++shows;
      if (!lit) {
        fprintf(stderr, "deadline_host: frame %d shows an image without the volume\n", i);
        ok = 0;
      }
    }
    if (age > 0 && strcmp(shown, warp) == 0)
      ++warped;
    for (j = 0; j < 4 && age > 0; ++j)
      by_mode[j] += strcmp(shown, modes[j]) == 0;
    if (!moving && age >= 0 && strcmp(shown, "none") == 0) {
      ++fresh;
      break;
    }
    sleep_until(start + period);
  }
  printf("waits: max %.2f ms mean %.2f ms deadline %.1f ms frames %d warped %d fresh %d"
         " shown none %d quad %d grid %d layers %d\n",
      max_wait, sum_wait / (i + fresh), deadline, i + fresh, warped, fresh, by_mode[0],
      by_mode[1], by_mode[2], by_mode[3]);
  if (shows == 0 || fresh != 1) {
    fprintf(stderr, "deadline_host: %d images shown, %d warped by %s, %d fresh\n", shows, warped,
        warp, fresh);
    ok = 0;
  }

  anariRelease(dev, frame);
  anariRelease(dev, camera);
  anariRelease(dev, renderer);
  anariRelease(dev, world);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  return ok && problems == 0 ? 0 : 1;
}
