/* A hostile host: completion callbacks that call back into the device,
 * release it or wait on their own frame; a second host thread calling
 * while a frame renders; releases and discards in the middle of long
 * renders of every kind; deadline frames resized between renders.
 * Usage: hostile_host CASE [PANEL_SIZE] (the panel "discard" renders,
 * 2048 unless given). Prints PASS/FAIL per check and "measured: NAME
 * MS" lines (times are printed, never checked); exit status 1 on any FAIL.
 * A deadlock is a failure too: an alarm ends the program after 120 s. */
#define _DEFAULT_SOURCE /* usleep */
#include <anari/anari.h>
#include <anari/caveray.h>

#include <pthread.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "expect.h"
#include "ramp_world.h"

/* Messages that are not warnings or errors, for the checks that look for
 * the INFO a discard or a deadline frame gives. */
static volatile int errors_seen = 0;
static char last_error[1024];

static void on_any(const void *user, ANARIDevice d, ANARIObject source, ANARIDataType type,
    ANARIStatusSeverity severity, ANARIStatusCode code, const char *message)
{
  if (severity <= ANARI_SEVERITY_ERROR) {
    errors_seen++;
    strncpy(last_error, message, sizeof last_error - 1);
  }
  on_status(user, d, source, type, severity, code, message);
}

static double now_ms(void)
{
  struct timespec t;
  clock_gettime(CLOCK_MONOTONIC, &t);
  return 1e3 * (double)t.tv_sec + 1e-6 * (double)t.tv_nsec;
}

static void measured(const char *name, double ms)
{
  printf("measured: %s %.1f ms\n", name, ms);
}

typedef struct Scene {
  ANARIDevice dev;
  ANARIWorld world;
  ANARICamera camera;
  ANARIRenderer renderer;
  ANARIFrame frame;
} Scene;

static ANARIDevice new_device(ANARILibrary lib)
{
  ANARIDevice dev = anariNewDevice(lib, "default");
  anariSetParameter(dev, dev, "statusCallback", ANARI_STATUS_CALLBACK,
      (const void *)&(ANARIStatusCallback){on_any});
  anariCommitParameters(dev, dev);
  return dev;
}

static void set_size(Scene *s, unsigned w, unsigned h)
{
  unsigned size[2] = {w, h};
  float aspect = (float)w / (float)h;
  anariSetParameter(s->dev, s->camera, "aspect", ANARI_FLOAT32, &aspect);
  anariCommitParameters(s->dev, s->camera);
  anariSetParameter(s->dev, s->frame, "size", ANARI_UINT32_VEC2, size);
  anariCommitParameters(s->dev, s->frame);
}

/* The ramp volume seen from `z` by a perspective camera, `shading` on. */
static Scene volume_scene(ANARIDevice dev, unsigned w, unsigned h, const char *shading, float z)
{
  Scene s;
  float position[3] = {0, 0, z}, direction[3] = {0, 0, -1};
  ANARIDataType rgba8 = ANARI_UFIXED8_VEC4;
  s.dev = dev;
  s.world = ramp_world(dev, 0.f, 1.f, 0.6f, NULL, 0);
  s.camera = anariNewCamera(dev, "perspective");
  anariSetParameter(dev, s.camera, "position", ANARI_FLOAT32_VEC3, position);
  anariSetParameter(dev, s.camera, "direction", ANARI_FLOAT32_VEC3, direction);
  s.renderer = anariNewRenderer(dev, "default");
  anariSetParameter(dev, s.renderer, "shading", ANARI_STRING, shading);
  anariCommitParameters(dev, s.renderer);
  s.frame = anariNewFrame(dev);
  anariSetParameter(dev, s.frame, "channel.color", ANARI_DATA_TYPE, &rgba8);
  anariSetParameter(dev, s.frame, "world", ANARI_WORLD, &s.world);
  anariSetParameter(dev, s.frame, "renderer", ANARI_RENDERER, &s.renderer);
  anariSetParameter(dev, s.frame, "camera", ANARI_CAMERA, &s.camera);
  set_size(&s, w, h);
  return s;
}

static void move_camera(Scene *s, float z)
{
  float position[3] = {0.05f * z, 0, z};
  anariSetParameter(s->dev, s->camera, "position", ANARI_FLOAT32_VEC3, position);
  anariCommitParameters(s->dev, s->camera);
}

static void set_deadline(Scene *s, float ms, const char *warp)
{
  anariSetParameter(s->dev, s->frame, "caveray.deadline", ANARI_FLOAT32, &ms);
  anariSetParameter(s->dev, s->frame, "caveray.warp", ANARI_STRING, warp);
  anariCommitParameters(s->dev, s->frame);
}

static int wait_flag(volatile int *flag, double ms)
{
  double until = now_ms() + ms;
  while (!*flag && now_ms() < until)
    usleep(1000);
  return *flag;
}

static void release_scene(Scene *s)
{
  anariRelease(s->dev, s->frame);
  anariRelease(s->dev, s->camera);
  anariRelease(s->dev, s->renderer);
  anariRelease(s->dev, s->world);
}

/* Whether the frame's color channel maps (a render that left an image). */
static int has_image(Scene *s)
{
  uint32_t w = 0, h = 0;
  ANARIDataType type;
  const void *pixels = anariMapFrame(s->dev, s->frame, "channel.color", &w, &h, &type);
  if (pixels)
    anariUnmapFrame(s->dev, s->frame, "channel.color");
  return pixels != NULL;
}

/* ---- callbacks that release the device ---- */

static volatile int callback_done = 0;

/* Set once the host has dropped its scene handles: until then the device
 * is the host's to use, so the callback's release waits for it. */
static volatile int host_released = 0;

static void release_device(const void *user, ANARIDevice dev, ANARIFrame frame)
{
  (void)user, (void)frame;
  wait_flag(&host_released, 10000);
  anariRelease(dev, dev);
  callback_done = 1;
}


/* The host hands its last reference to the frame's completion callback,
 * which releases the device on the render thread or, for a deadline frame,
 * the presenter. */
static void callback_releases(ANARILibrary lib, float deadline)
{
  ANARIDevice dev = new_device(lib);
  Scene s = volume_scene(dev, 64, 64, "none", 3.f);
  int version = 0;
  if (deadline > 0)
    set_deadline(&s, deadline, "quad");
  anariSetParameter(dev, s.frame, "frameCompletionCallback", ANARI_FRAME_COMPLETION_CALLBACK,
      (const void *)&(ANARIFrameCompletionCallback){release_device});
  anariCommitParameters(dev, s.frame);
  callback_done = 0;
  errors_seen = 0;
  host_released = 0;
  anariRenderFrame(dev, s.frame);
  release_scene(&s);
  reset();
  host_released = 1;
  check("the callback ran and released the device", wait_flag(&callback_done, 60000));
  usleep(200000);
  check("releasing the device from a callback reports no error", errors_seen == 0);
  if (errors_seen)
    printf("     the error: %s\n", last_error);
  check("the released device is gone",
      anariGetProperty(dev, dev, "version", ANARI_INT32, &version, sizeof version, ANARI_WAIT) == 0);
}

/* The callback keeps calling into the device while the host releases it:
 * the callback's thread may end up holding the last reference. */
static volatile int keep_asking = 0;
static volatile int asked = 0;

static void ask_version(const void *user, ANARIDevice dev, ANARIFrame frame)
{
  int version = 0, i;
  (void)user, (void)frame;
  keep_asking = 1;
  for (i = 0; i < 200000; ++i) {
    if (anariGetProperty(dev, dev, "version", ANARI_INT32, &version, sizeof version, ANARI_WAIT) != 1)
      break;
    asked++;
  }
  keep_asking = 0;
  callback_done = 1;
}

static void release_while_called(ANARILibrary lib)
{
  int run;
  for (run = 0; run < 6; ++run) {
    ANARIDevice dev = new_device(lib);
    Scene s = volume_scene(dev, 32, 32, "none", 3.f);
    anariSetParameter(dev, s.frame, "frameCompletionCallback", ANARI_FRAME_COMPLETION_CALLBACK,
        (const void *)&(ANARIFrameCompletionCallback){ask_version});
    anariCommitParameters(dev, s.frame);
    callback_done = 0;
    asked = 0;
    errors_seen = 0;
    anariRenderFrame(dev, s.frame);
    while (!keep_asking && !callback_done)
      usleep(100);
    usleep(1000 * (run + 1));
    release_scene(&s);
    anariRelease(dev, dev);
    wait_flag(&callback_done, 60000);
    usleep(50000);
    printf("run %d: the callback asked %d times before the device went\n", run, asked);
  }
  check("every callback ended", callback_done);
}

/* ---- a callback that renders its own frame and waits on it ---- */

static volatile int reentered = 0;
static volatile int ready_in_callback = -1;

static void render_and_wait(const void *user, ANARIDevice dev, ANARIFrame frame)
{
  (void)user;
  if (reentered++)
    return;
  reset();
  anariRenderFrame(dev, frame);
  ready_in_callback = anariFrameReady(dev, frame, ANARI_WAIT);
  expect("waiting on its own frame from its completion callback", ERR,
      ANARI_STATUS_INVALID_OPERATION, "completion callback");
  callback_done = 1;
}

static void callback_waits_on_own_frame(ANARILibrary lib)
{
  ANARIDevice dev = new_device(lib);
  Scene s = volume_scene(dev, 32, 32, "none", 3.f);
  anariSetParameter(dev, s.frame, "frameCompletionCallback", ANARI_FRAME_COMPLETION_CALLBACK,
      (const void *)&(ANARIFrameCompletionCallback){render_and_wait});
  anariCommitParameters(dev, s.frame);
  callback_done = 0;
  anariRenderFrame(dev, s.frame);
  check("the callback's wait returned", wait_flag(&callback_done, 60000));
  check("waiting on its own frame from its callback is refused", ready_in_callback == 0);
  check("the frame's second render completes", anariFrameReady(dev, s.frame, ANARI_WAIT) == 1);
  reset();
  anariRenderFrame(dev, s.frame);
  check("the host's next render completes", anariFrameReady(dev, s.frame, ANARI_WAIT) == 1);
  check("and has an image", has_image(&s));
  release_scene(&s);
  anariRelease(dev, dev);
}

/* A render refused at once (the frame has no camera) still completes: its
 * callback runs, and may call into the device. */
static volatile int refused_called = 0;

static void ask_about_frame(const void *user, ANARIDevice dev, ANARIFrame frame)
{
  float duration = 0;
  (void)user;
  anariGetProperty(dev, frame, "duration", ANARI_FLOAT32, &duration, sizeof duration, ANARI_NO_WAIT);
  anariFrameReady(dev, frame, ANARI_NO_WAIT);
  refused_called = 1;
}

static void callback_of_refused_render(ANARILibrary lib)
{
  ANARIDevice dev = new_device(lib);
  ANARIFrame frame = anariNewFrame(dev);
  unsigned size[2] = {8, 8};
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, size);
  anariSetParameter(dev, frame, "frameCompletionCallback", ANARI_FRAME_COMPLETION_CALLBACK,
      (const void *)&(ANARIFrameCompletionCallback){ask_about_frame});
  anariCommitParameters(dev, frame);
  errors_seen = 0;
  anariRenderFrame(dev, frame);
  check("a render refused at once reports why", errors_seen > 0);
  check("and its callback ran, calling into the device", refused_called);
  anariRelease(dev, frame);
  anariRelease(dev, dev);
}

/* ---- a second host thread while a frame renders ---- */

typedef struct Asker {
  ANARIDevice dev;
  volatile int stop;
  double worst;
  int calls;
} Asker;

static void *ask_loop(void *arg)
{
  Asker *a = (Asker *)arg;
  int version;
  while (!a->stop) {
    double t = now_ms();
    anariGetProperty(a->dev, a->dev, "version", ANARI_INT32, &version, sizeof version, ANARI_WAIT);
    t = now_ms() - t;
    if (t > a->worst)
      a->worst = t;
    a->calls++;
    usleep(500);
  }
  return NULL;
}

/* The host renders a busy frame again while another thread asks the
 * device for its version: the other thread's calls return while the
 * first render is still running. */
static void second_thread(ANARILibrary lib, float deadline)
{
  ANARIDevice dev = new_device(lib);
  Scene s = volume_scene(dev, 512, 512, "ao", 3.f);
  Asker a = {dev, 0, 0.0, 0};
  pthread_t thread;
  int before;
  if (deadline > 0)
    set_deadline(&s, deadline, "quad");
  expect_quiet("the scene commits without a word");
  anariRenderFrame(dev, s.frame);
  pthread_create(&thread, NULL, ask_loop, &a);
  usleep(20000);
  before = a.calls;
  anariRenderFrame(dev, s.frame); /* waits for the first render, alone */
  check("the second thread's calls went on while the frame rendered", a.calls > before);
  anariFrameReady(dev, s.frame, ANARI_WAIT);
  a.stop = 1;
  pthread_join(thread, NULL);
  measured(deadline > 0 ? "second thread, deadline frame: worst call" : "second thread: worst call",
      a.worst);
  release_scene(&s);
  anariRelease(dev, dev);
}

/* ---- releases and discards in the middle of long renders ---- */

/* A 10 s deadline and no image yet: the device's release ends the
 * presenter instead of waiting for its deadline. */
static void release_deadline(ANARILibrary lib, int keep_handles)
{
  ANARIDevice dev = new_device(lib);
  Scene s = volume_scene(dev, 512, 512, "ao", 3.f);
  double t;
  set_deadline(&s, 10000.f, "quad");
  anariRenderFrame(dev, s.frame);
  usleep(20000);
  if (!keep_handles)
    release_scene(&s); /* else the device's release takes its objects along */
  t = now_ms();
  anariRelease(dev, dev);
  t = now_ms() - t;
  measured(keep_handles ? "device release, its frame held, 10 s deadline pending"
                        : "device release, 10 s deadline pending",
      t);
  check("the release did not wait for the deadline", t < 5000);
}

static ANARIWorld iso_world(ANARIDevice dev)
{
  float voxels[16 * 16 * 16], origin[3] = {-1, -1, -1}, spacing[3], isovalue = 0.5f;
  float color[3] = {0.9f, 0.8f, 0.6f};
  ANARIArray3D data;
  ANARIArray1D surfaces;
  ANARISpatialField field;
  ANARIGeometry geometry;
  ANARIMaterial material;
  ANARISurface surface;
  ANARIWorld world;
  int i;
  for (i = 0; i < 3; ++i)
    spacing[i] = 2.0f / 15;
  for (i = 0; i < 16 * 16 * 16; ++i) {
    float x = spacing[0] * (i % 16) - 1, y = spacing[1] * (i / 16 % 16) - 1,
          z = spacing[2] * (i / 256) - 1;
    voxels[i] = 1.0f - (x * x + y * y + z * z);
  }
  data = anariNewArray3D(dev, voxels, NULL, NULL, ANARI_FLOAT32, 16, 16, 16);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &data);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, spacing);
  anariCommitParameters(dev, field);
  anariRelease(dev, data);
  geometry = anariNewGeometry(dev, "isosurface");
  anariSetParameter(dev, geometry, "field", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, geometry, "isovalue", ANARI_FLOAT32, &isovalue);
  anariCommitParameters(dev, geometry);
  material = anariNewMaterial(dev, "matte");
  anariSetParameter(dev, material, "color", ANARI_FLOAT32_VEC3, color);
  anariCommitParameters(dev, material);
  surface = anariNewSurface(dev);
  anariSetParameter(dev, surface, "geometry", ANARI_GEOMETRY, &geometry);
  anariSetParameter(dev, surface, "material", ANARI_MATERIAL, &material);
  anariCommitParameters(dev, surface);
  surfaces = anariNewArray1D(dev, &surface, NULL, NULL, ANARI_SURFACE, 1);
  world = anariNewWorld(dev);
  anariSetParameter(dev, world, "surface", ANARI_ARRAY1D, &surfaces);
  anariCommitParameters(dev, world);
  anariRelease(dev, surfaces);
  anariRelease(dev, surface);
  anariRelease(dev, material);
  anariRelease(dev, geometry);
  anariRelease(dev, field);
  return world;
}

/* An 8-view panel camera on the plane z = 0.5. */
static ANARICamera panel_camera(ANARIDevice dev)
{
  float ll[3] = {-1, -1, 1.5f}, lr[3] = {1, -1, 1.5f}, ur[3] = {1, 1, 1.5f};
  float distance = 2.f, spacing = 0.05f, pitch = 3.75f, slant = 0.15625f;
  int views = 8;
  ANARICamera camera = anariNewCamera(dev, "multiView");
  anariSetParameter(dev, camera, "lowerLeft", ANARI_FLOAT32_VEC3, ll);
  anariSetParameter(dev, camera, "lowerRight", ANARI_FLOAT32_VEC3, lr);
  anariSetParameter(dev, camera, "upperRight", ANARI_FLOAT32_VEC3, ur);
  anariSetParameter(dev, camera, "views", ANARI_INT32, &views);
  anariSetParameter(dev, camera, "viewingDistance", ANARI_FLOAT32, &distance);
  anariSetParameter(dev, camera, "viewSpacing", ANARI_FLOAT32, &spacing);
  anariSetParameter(dev, camera, "lens.pitch", ANARI_FLOAT32, &pitch);
  anariSetParameter(dev, camera, "lens.slant", ANARI_FLOAT32, &slant);
  anariCommitParameters(dev, camera);
  return camera;
}

/* KIND "iso": an isosurface; "panel": a multi-view panel of the volume;
 * "stereo": both eyes side by side. The render is discarded at once: the
 * frame becomes ready without an image and the INFO says it was
 * discarded. Then the same render again, and the device released while it
 * runs. */
static void discard_long(ANARILibrary lib, const char *kind, unsigned size)
{
  ANARIDevice dev = new_device(lib);
  Scene s = volume_scene(dev, 32, 32, "ao", 3.f);
  double t;
  char name[128];
  if (strcmp(kind, "iso") == 0) {
    ANARIWorld world = iso_world(dev);
    anariSetParameter(dev, s.frame, "world", ANARI_WORLD, &world);
    anariRelease(dev, world);
  } else if (strcmp(kind, "panel") == 0) {
    ANARICamera camera = panel_camera(dev);
    anariSetParameter(dev, s.frame, "camera", ANARI_CAMERA, &camera);
    anariRelease(dev, camera);
  } else {
    anariSetParameter(dev, s.camera, "stereoMode", ANARI_STRING, "sideBySide");
    anariCommitParameters(dev, s.camera);
  }
  anariCommitParameters(dev, s.frame);
  /* A small render first: the renderer is open and its shaders compiled,
   * so what is measured below is the stop alone. */
  anariRenderFrame(dev, s.frame);
  anariFrameReady(dev, s.frame, ANARI_WAIT);
  set_size(&s, size, size);
  discards = 0;
  anariRenderFrame(dev, s.frame);
  usleep(50000);
  t = now_ms();
  anariDiscardFrame(dev, s.frame);
  anariFrameReady(dev, s.frame, ANARI_WAIT);
  t = now_ms() - t;
  snprintf(name, sizeof name, "%s %ux%u: discard to ready", kind, size, size);
  measured(name, t);
  check("the discarded render says so", discards > 0);
  check("the discarded render leaves no image", !has_image(&s));
  anariRenderFrame(dev, s.frame);
  usleep(50000);
  release_scene(&s);
  t = now_ms();
  anariRelease(dev, dev);
  snprintf(name, sizeof name, "%s %ux%u: device release while it renders", kind, size, size);
  measured(name, now_ms() - t);
}

/* A deadline frame discarded while its presenter waits shows nothing. */
static void discard_deadline(ANARILibrary lib)
{
  ANARIDevice dev = new_device(lib);
  Scene s = volume_scene(dev, 64, 64, "none", 3.f);
  set_deadline(&s, 10000.f, "quad");
  anariRenderFrame(dev, s.frame);
  check("the first deadline render completes", anariFrameReady(dev, s.frame, ANARI_WAIT) == 1);
  errors_seen = 0;
  check("with an image", has_image(&s));
  if (errors_seen)
    printf("     the error: %s\n", last_error);
  set_deadline(&s, 2000.f, "quad");
  set_size(&s, 512, 512);
  anariSetParameter(dev, s.renderer, "shading", ANARI_STRING, "ao");
  anariCommitParameters(dev, s.renderer);
  move_camera(&s, 3.5f);
  discards = 0;
  anariRenderFrame(dev, s.frame);
  usleep(20000);
  anariDiscardFrame(dev, s.frame);
  anariFrameReady(dev, s.frame, ANARI_WAIT);
  check("the discarded deadline frame says so", discards > 0);
  check("the discarded deadline frame shows no warped image", !has_image(&s));
  release_scene(&s);
  anariRelease(dev, dev);
}

/* A deadline frame resized between renders always renders. */
static void resize_deadline(ANARILibrary lib, const char *warp)
{
  ANARIDevice dev = new_device(lib);
  Scene s = volume_scene(dev, 3, 256, "none", 3.f);
  int i, failed = 0, imaged = 0;
  set_deadline(&s, 6.f, warp);
  errors_seen = 0;
  for (i = 0; i < 36; ++i) {
    if (i % 6 == 3)
      set_size(&s, 256, 256);
    else if (i % 6 == 0)
      set_size(&s, 3, 256);
    move_camera(&s, 3.f + 0.01f * (float)i);
    anariRenderFrame(dev, s.frame);
    anariFrameReady(dev, s.frame, ANARI_WAIT);
    imaged += has_image(&s);
  }
  failed = errors_seen;
  printf("warp %s: %d of 36 renders failed, %d left an image\n", warp, failed, imaged);
  if (failed)
    printf("     the last error: %s\n", last_error);
  check("every resized deadline render succeeds", failed == 0 && imaged == 36);
  release_scene(&s);
  anariRelease(dev, dev);
}

int main(int argc, char **argv)
{
  ANARILibrary lib;
  const char *which = argc > 1 ? argv[1] : "";
  alarm(120);
  lib = anariLoadLibrary("caveray", on_any, NULL);
  if (!lib) {
    printf("FAIL the library loads\n");
    return 1;
  }
  if (strcmp(which, "callback-release") == 0) {
    callback_releases(lib, 0.f);
    callback_releases(lib, 5.f);
  } else if (strcmp(which, "release-while-called") == 0) {
    release_while_called(lib);
  } else if (strcmp(which, "callback-wait") == 0) {
    callback_waits_on_own_frame(lib);
    callback_of_refused_render(lib);
  } else if (strcmp(which, "second-thread") == 0) {
    second_thread(lib, 0.f);
    second_thread(lib, 8000.f);
  } else if (strcmp(which, "release-deadline") == 0) {
    release_deadline(lib, 0);
    release_deadline(lib, 1);
  } else if (strcmp(which, "discard") == 0) {
    discard_long(lib, "iso", 1024);
    discard_long(lib, "panel", argc > 2 ? (unsigned)atoi(argv[2]) : 2048);
    discard_long(lib, "stereo", 1024);
    discard_deadline(lib);
  } else if (strcmp(which, "resize-deadline") == 0) {
    resize_deadline(lib, "none");
    resize_deadline(lib, "quad");
  } else {
    fprintf(stderr, "usage: hostile_host callback-release | release-while-called | callback-wait |"
                    " second-thread | release-deadline | discard | resize-deadline\n");
    return 2;
  }
  anariUnloadLibrary(lib);
  printf("%s: %d failed\n", which, failures);
  return failures ? 1 : 0;
}
