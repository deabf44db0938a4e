/* What the in-place host tests share: a status callback that counts the
 * device's notes of a copy, the process's resident memory, an object's
 * caveray.residentBytes, and a frame of the scene's camera saved as RGBA. */
#ifndef CAVERAY_TEST_IN_PLACE_H
#define CAVERAY_TEST_IN_PLACE_H

#include <anari/anari.h>

#include <stdint.h>
#include <string.h>

#include "scene.h"
#include "status.h"

static int copies = 0;

static void watch_status(const void *program, ANARIDevice d, ANARIObject source,
    ANARIDataType sourceType, ANARIStatusSeverity severity, ANARIStatusCode code,
    const char *message)
{
  if (severity == ANARI_SEVERITY_PERFORMANCE_WARNING && strstr(message, "was copied"))
    ++copies;
  count_status(program, d, source, sourceType, severity, code, message);
}

/* Resident kilobytes of this process now (Linux). */
static long resident_kb(void)
{
  long pages = 0, resident = 0;
  FILE *f = fopen("/proc/self/statm", "r");
  if (!f)
    return -1;
  if (fscanf(f, "%ld %ld", &pages, &resident) != 2)
    resident = -1;
  fclose(f);
  return resident < 0 ? -1 : resident * 4;
}

static ANARIFrame new_frame(ANARIDevice dev, Scene *s, ANARIWorld world)
{
  ANARIDataType color_type = ANARI_UFIXED8_VEC4;
  ANARIRenderer renderer = anariNewRenderer(dev, "default");
  ANARICamera camera = anariNewCamera(dev, "matrix");
  ANARIFrame frame = anariNewFrame(dev);
  anariCommitParameters(dev, renderer);
  anariSetParameter(dev, camera, "view", ANARI_FLOAT32_MAT4, s->view);
  anariSetParameter(dev, camera, "proj", ANARI_FLOAT32_MAT4, s->proj);
  anariCommitParameters(dev, camera);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, s->size);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &color_type);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariCommitParameters(dev, frame);
  anariRelease(dev, camera);
  anariRelease(dev, renderer);
  return frame;
}

static int save(ANARIDevice dev, ANARIFrame frame, const char *dir, const char *name)
{
  uint32_t w = 0, h = 0;
  ANARIDataType type = ANARI_UNKNOWN;
  const void *pixels = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  int ok = pixels && type == ANARI_UFIXED8_VEC4 && write_rgba(dir, name, pixels, w, h);
  if (pixels)
    anariUnmapFrame(dev, frame, "channel.color");
  return ok;
}

static uint64_t resident_bytes(ANARIDevice dev, ANARIObject o)
{
  uint64_t bytes = UINT64_MAX;
  if (!anariGetProperty(dev, o, "caveray.residentBytes", ANARI_UINT64, &bytes, sizeof(bytes),
          ANARI_WAIT))
    return UINT64_MAX;
  return bytes;
}

/* Whether `what` (object `o`) holds `expected` bytes; says so where not. */
static int holds(ANARIDevice dev, ANARIObject o, uint64_t expected, const char *what)
{
  uint64_t held = resident_bytes(dev, o);
  if (held != expected)
    fprintf(stderr, "%s holds %llu bytes, not %llu\n", what, (unsigned long long)held,
        (unsigned long long)expected);
  return held == expected;
}

/* Renders `frame`, waits for it and saves its color as DIR/NAME.rgba. */
static int render_saved(ANARIDevice dev, ANARIFrame frame, const char *dir, const char *name)
{
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  return save(dev, frame, dir, name);
}

#endif
