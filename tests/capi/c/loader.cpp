// Test (c): what the ANARI SDK's libanari does with a device library,
// without the SDK. It dlopens the library, calls
// anari_library_caveray_new_library, and from then on treats the returned
// library and device as C++ objects of the SDK's abstract classes, calling
// only virtual functions declared in the SDK's slot order (0.14 and later).
// Then both eyes of the wall through the same tables: two per-eye frames
// (offAxis cameras, the second named as the first's stereoPartner), the
// right eye alone in a third frame, and both in one sideBySide frame.
// Usage: loader LIBRARY.so SCENE_FILE OUT_DIR DX,DY,DZ (the right eye
// minus the scene's eye).
#include <anari/anari.h>

#include <dlfcn.h>
#include <cmath>
#include <cstring>

#include "scene.h"

struct LibraryImpl
{
  virtual ~LibraryImpl() = default; // slots 0 and 1
  virtual ANARIDevice newDevice(const char *subtype) = 0;
  virtual ANARIDevice newInitializedDevice(
      const char *subtype, const ANARIParameterValue *parameters) = 0;
  virtual const char **getDeviceExtensions(const char *deviceType) = 0;
  virtual const char **getDeviceSubtypes() = 0;
  virtual void loadModule(const char *name) = 0;
  virtual void unloadModule(const char *name) = 0;

  void *dlhandle;
  ANARIStatusCallback defaultStatusCB;
  const void *defaultStatusCBUserPtr;
};

struct DeviceImpl
{
  virtual ANARIArray1D newArray1D(const void *appMemory, ANARIMemoryDeleter,
      const void *userData, ANARIDataType, uint64_t) = 0;
  virtual ANARIArray2D newArray2D(const void *appMemory, ANARIMemoryDeleter,
      const void *userData, ANARIDataType, uint64_t, uint64_t) = 0;
  virtual ANARIArray3D newArray3D(const void *appMemory, ANARIMemoryDeleter,
      const void *userData, ANARIDataType, uint64_t, uint64_t, uint64_t) = 0;
  virtual ANARIGeometry newGeometry(const char *type) = 0;
  virtual ANARIMaterial newMaterial(const char *type) = 0;
  virtual ANARISampler newSampler(const char *type) = 0;
  virtual ANARISurface newSurface() = 0;
  virtual ANARISpatialField newSpatialField(const char *type) = 0;
  virtual ANARIVolume newVolume(const char *type) = 0;
  virtual ANARILight newLight(const char *type) = 0;
  virtual ANARIGroup newGroup() = 0;
  virtual ANARIInstance newInstance(const char *type) = 0;
  virtual ANARIWorld newWorld() = 0;
  virtual ANARICamera newCamera(const char *type) = 0;
  virtual ANARIRenderer newRenderer(const char *type) = 0;
  virtual ANARIFrame newFrame() = 0;
  virtual void setParameter(
      ANARIObject, const char *name, ANARIDataType, const void *mem) = 0;
  virtual void unsetParameter(ANARIObject, const char *name) = 0;
  virtual void unsetAllParameters(ANARIObject) = 0;
  virtual void *mapParameterArray1D(
      ANARIObject, const char *, ANARIDataType, uint64_t, uint64_t *) = 0;
  virtual void *mapParameterArray2D(ANARIObject, const char *, ANARIDataType,
      uint64_t, uint64_t, uint64_t *) = 0;
  virtual void *mapParameterArray3D(ANARIObject, const char *, ANARIDataType,
      uint64_t, uint64_t, uint64_t, uint64_t *) = 0;
  virtual void unmapParameterArray(ANARIObject, const char *) = 0;
  virtual void commitParameters(ANARIObject) = 0;
  virtual void release(ANARIObject) = 0;
  virtual void retain(ANARIObject) = 0;
  virtual void *mapArray(ANARIArray) = 0;
  virtual void unmapArray(ANARIArray) = 0;
  virtual int getProperty(ANARIObject, const char *, ANARIDataType, void *,
      uint64_t, ANARIWaitMask) = 0;
  virtual const char **getObjectSubtypes(ANARIDataType) = 0;
  virtual const void *getObjectInfo(
      ANARIDataType, const char *, const char *, ANARIDataType) = 0;
  virtual const void *getParameterInfo(ANARIDataType, const char *,
      const char *, ANARIDataType, const char *, ANARIDataType) = 0;
  virtual const void *frameBufferMap(
      ANARIFrame, const char *, uint32_t *, uint32_t *, ANARIDataType *) = 0;
  virtual void frameBufferUnmap(ANARIFrame, const char *) = 0;
  virtual void renderFrame(ANARIFrame) = 0;
  virtual int frameReady(ANARIFrame, ANARIWaitMask) = 0;
  virtual void discardFrame(ANARIFrame) = 0;
  virtual ANARIObject newObject(const char *objectType, const char *type) = 0;
  virtual void *getProcAddress(const char *name) = 0;
  virtual ~DeviceImpl() = default; // slots 39 and 40

  ANARIStatusCallback defaultStatusCB;
  const void *defaultStatusCBUserPtr;
};

static int errors = 0;

static void on_status(const void *user, ANARIDevice, ANARIObject, ANARIDataType,
    ANARIStatusSeverity severity, ANARIStatusCode, const char *message)
{
  if (severity <= ANARI_SEVERITY_WARNING) {
    ++errors;
    fprintf(stderr, "loader: %s (user %p)\n", message, user);
  }
}

static int failures = 0;
static void check(const char *what, bool ok)
{
  printf("%s %s\n", ok ? "PASS" : "FAIL", what);
  failures += !ok;
}

static bool contains(const char **list, const char *name)
{
  for (; list && *list; ++list)
    if (strcmp(*list, name) == 0)
      return true;
  return false;
}

typedef void *(*NewLibrary)(void *, ANARIStatusCallback, const void *);

int main(int argc, char **argv)
{
  Scene s;
  float baseline[3];
  if (argc != 5 || sscanf(argv[4], "%f,%f,%f", &baseline[0], &baseline[1], &baseline[2]) != 3
      || !scene_load(argv[2], &s)) {
    fprintf(stderr, "usage: loader LIBRARY.so SCENE_FILE OUT_DIR DX,DY,DZ\n");
    return 2;
  }
  static int tag = 7;
  void *dl = dlopen(argv[1], RTLD_LAZY | RTLD_LOCAL);
  if (!dl) {
    fprintf(stderr, "loader: %s\n", dlerror());
    return 1;
  }
  NewLibrary newLibrary =
      (NewLibrary)dlsym(dl, "anari_library_caveray_new_library");
  check("entry point found", newLibrary != nullptr);
  if (!newLibrary)
    return 1;
  LibraryImpl *lib = (LibraryImpl *)newLibrary(dl, on_status, &tag);
  check("library keeps its data members where the SDK reads them",
      lib->dlhandle == dl && lib->defaultStatusCB == on_status
          && lib->defaultStatusCBUserPtr == &tag);
  check("device subtypes", contains(lib->getDeviceSubtypes(), "default"));
  check("extensions advertise the matrix camera",
      contains(lib->getDeviceExtensions("default"), "ANARI_VSNRAY_CAMERA_MATRIX")
          && contains(lib->getDeviceExtensions("default"), "ANARI_CAVERAY_CAMERA_MATRIX"));

  DeviceImpl *dev = (DeviceImpl *)lib->newDevice("default");
  check("device inherits the library's status callback",
      dev && dev->defaultStatusCB == on_status && dev->defaultStatusCBUserPtr == &tag);
  ANARIObject self = (ANARIObject)(void *)dev;

  int version = 0;
  check("version property",
      dev->getProperty(self, "version", ANARI_INT32, &version, sizeof version, ANARI_WAIT) == 1
          && version == 1);
  check("camera subtypes", contains(dev->getObjectSubtypes(ANARI_CAMERA), "matrix")
      && contains(dev->getObjectSubtypes(ANARI_CAMERA), "offAxis"));
  const ANARIParameter *params = (const ANARIParameter *)dev->getObjectInfo(
      ANARI_CAMERA, "matrix", "parameter", ANARI_PARAMETER_LIST);
  check("matrix camera parameters", params && strcmp(params[0].name, "view") == 0
      && params[0].type == ANARI_FLOAT32_MAT4 && strcmp(params[1].name, "proj") == 0
      && params[2].name == nullptr);
  const float *fovy = (const float *)dev->getParameterInfo(
      ANARI_CAMERA, "perspective", "fovy", ANARI_FLOAT32, "default", ANARI_FLOAT32);
  check("perspective fovy default", fovy && std::fabs(*fovy - 1.0471976f) < 1e-6f);
  const float *white = (const float *)dev->getParameterInfo(ANARI_VOLUME,
      "transferFunction1D", "color", ANARI_FLOAT32_VEC3, "default", ANARI_FLOAT32_VEC3);
  check("color default for a single color", white && white[0] == 1.0f && white[2] == 1.0f);
  const char *required = (const char *)dev->getParameterInfo(
      ANARI_CAMERA, "matrix", "view", ANARI_FLOAT32_MAT4, "required", ANARI_BOOL);
  check("matrix view is required", required && *required == 1);
  const char *about = (const char *)dev->getObjectInfo(
      ANARI_CAMERA, "offAxis", "description", ANARI_STRING);
  check("offAxis description", about && strstr(about, "wall") != nullptr);
  check("no extra procedures", dev->getProcAddress("anariFoo") == nullptr);

  ANARIArray3D voxels = dev->newArray3D(
      s.voxels, nullptr, nullptr, ANARI_FLOAT32, s.dims[0], s.dims[1], s.dims[2]);
  ANARISpatialField field = dev->newSpatialField("structuredRegular");
  dev->setParameter(field, "data", ANARI_ARRAY3D, &voxels);
  dev->setParameter(field, "origin", ANARI_FLOAT32_VEC3, s.origin);
  dev->setParameter(field, "spacing", ANARI_FLOAT32_VEC3, s.spacing);
  dev->commitParameters(field);

  // Parameter arrays mapped through the device, as hosts fill them.
  ANARIVolume volume = dev->newVolume("transferFunction1D");
  uint64_t stride = 0;
  float *colors = (float *)dev->mapParameterArray1D(
      volume, "color", ANARI_FLOAT32_VEC4, s.ncolors, &stride);
  check("mapped parameter array", colors != nullptr && stride == 16);
  memcpy(colors, s.colors, 16 * s.ncolors);
  dev->unmapParameterArray(volume, "color");
  float *opacities = (float *)dev->mapParameterArray1D(
      volume, "opacity", ANARI_FLOAT32, s.nopacities, &stride);
  memcpy(opacities, s.opacities, 4 * s.nopacities);
  dev->unmapParameterArray(volume, "opacity");
  dev->setParameter(volume, "value", ANARI_SPATIAL_FIELD, &field);
  dev->setParameter(volume, "valueRange", ANARI_FLOAT32_BOX1, s.range);
  dev->setParameter(volume, "unitDistance", ANARI_FLOAT32, &s.unitDistance);
  dev->commitParameters(volume);

  ANARIWorld world = dev->newWorld();
  ANARIArray1D volumes = dev->newArray1D(&volume, nullptr, nullptr, ANARI_VOLUME, 1);
  dev->setParameter(world, "volume", ANARI_ARRAY1D, &volumes);
  dev->commitParameters(world);

  ANARIRenderer renderer = dev->newRenderer("default");
  dev->commitParameters(renderer);

  ANARICamera camera = dev->newCamera("matrix");
  dev->setParameter(camera, "view", ANARI_FLOAT32_MAT4, s.view);
  dev->setParameter(camera, "proj", ANARI_FLOAT32_MAT4, s.proj);
  dev->commitParameters(camera);

  ANARIDataType color = ANARI_UFIXED8_VEC4, depth = ANARI_FLOAT32;
  ANARIFrame frame = dev->newFrame();
  dev->setParameter(frame, "size", ANARI_UINT32_VEC2, s.size);
  dev->setParameter(frame, "channel.color", ANARI_DATA_TYPE, &color);
  dev->setParameter(frame, "channel.depth", ANARI_DATA_TYPE, &depth);
  dev->setParameter(frame, "world", ANARI_WORLD, &world);
  dev->setParameter(frame, "renderer", ANARI_RENDERER, &renderer);
  dev->setParameter(frame, "camera", ANARI_CAMERA, &camera);
  dev->commitParameters(frame);
  dev->renderFrame(frame);
  check("frame ready", dev->frameReady(frame, ANARI_WAIT) == 1);

  uint32_t w = 0, h = 0;
  ANARIDataType type = ANARI_UNKNOWN;
  const void *pixels = dev->frameBufferMap(frame, "channel.color", &w, &h, &type);
  check("color maps", pixels && w == s.size[0] && h == s.size[1] && type == ANARI_UFIXED8_VEC4);
  check("color written", pixels && write_rgba(argv[3], "loader", pixels, w, h));
  const float *d = (const float *)dev->frameBufferMap(frame, "channel.depth", &w, &h, &type);
  bool finite = false;
  for (uint32_t i = 0; d && i < w * h; ++i)
    finite = finite || std::isfinite(d[i]);
  check("depth maps and sees the volume", d && type == ANARI_FLOAT32 && finite);
  dev->frameBufferUnmap(frame, "channel.depth");
  dev->frameBufferUnmap(frame, "channel.color");

  // Stereo: each eye an offAxis camera on the wall, at half the step (the
  // phantom's shells alias into moire at the default step, in each eye's
  // own pattern, which no re-projection reproduces).
  ANARIRenderer fine = dev->newRenderer("default");
  float half_step = 0.5f;
  dev->setParameter(fine, "stepFactor", ANARI_FLOAT32, &half_step);
  dev->commitParameters(fine);
  auto wall_camera = [&](const float *eye) {
    ANARICamera c = dev->newCamera("offAxis");
    dev->setParameter(c, "lowerLeft", ANARI_FLOAT32_VEC3, s.ll);
    dev->setParameter(c, "lowerRight", ANARI_FLOAT32_VEC3, s.lr);
    dev->setParameter(c, "upperRight", ANARI_FLOAT32_VEC3, s.ur);
    dev->setParameter(c, "eye", ANARI_FLOAT32_VEC3, eye);
    return c;
  };
  auto eye_frame = [&](ANARICamera c, uint32_t width) {
    uint32_t size[2] = {width, s.size[1]};
    ANARIFrame f = dev->newFrame();
    dev->setParameter(f, "size", ANARI_UINT32_VEC2, size);
    dev->setParameter(f, "channel.color", ANARI_DATA_TYPE, &color);
    dev->setParameter(f, "world", ANARI_WORLD, &world);
    dev->setParameter(f, "renderer", ANARI_RENDERER, &fine);
    dev->setParameter(f, "camera", ANARI_CAMERA, &c);
    return f;
  };
  auto render_to = [&](ANARIFrame f, const char *name) {
    dev->renderFrame(f);
    bool ok = dev->frameReady(f, ANARI_WAIT) == 1;
    uint32_t fw = 0, fh = 0;
    const void *p = dev->frameBufferMap(f, "channel.color", &fw, &fh, &type);
    ok = ok && p && write_rgba(argv[3], name, p, fw, fh);
    dev->frameBufferUnmap(f, "channel.color");
    check(name, ok);
  };
  float right_eye[3], centre[3];
  for (int k = 0; k < 3; ++k) {
    right_eye[k] = s.eye[k] + baseline[k];
    centre[k] = s.eye[k] + 0.5f * baseline[k];
  }
  ANARICamera left_camera = wall_camera(s.eye), right_camera = wall_camera(right_eye);
  dev->commitParameters(left_camera);
  dev->commitParameters(right_camera);
  ANARIFrame left = eye_frame(left_camera, s.size[0]);
  ANARIFrame right = eye_frame(right_camera, s.size[0]);
  dev->setParameter(left, "stereoPartner", ANARI_FRAME, &right);
  dev->commitParameters(left);
  dev->commitParameters(right);
  render_to(left, "pair_left");
  render_to(right, "pair_right");
  // The right eye alone: its own frame, no partner.
  uint8_t off = 0;
  dev->setParameter(self, "pairStereoFrames", ANARI_BOOL, &off);
  dev->commitParameters(self);
  ANARIFrame alone = eye_frame(right_camera, s.size[0]);
  dev->commitParameters(alone);
  render_to(alone, "alone_right");
  // Both eyes side by side in one frame.
  ANARICamera both = wall_camera(centre);
  float ipd = std::sqrt(baseline[0] * baseline[0] + baseline[1] * baseline[1]
      + baseline[2] * baseline[2]);
  dev->setParameter(both, "stereoMode", ANARI_STRING, "sideBySide");
  dev->setParameter(both, "interpupillaryDistance", ANARI_FLOAT32, &ipd);
  dev->setParameter(both, "eyeAxis", ANARI_FLOAT32_VEC3, baseline);
  dev->commitParameters(both);
  ANARIFrame pair = eye_frame(both, 2 * s.size[0]);
  dev->commitParameters(pair);
  render_to(pair, "side_by_side");

  ANARIObject objects[] = {frame, camera, left, right, alone, pair, left_camera, right_camera,
      both, fine, renderer, world, volumes, volume, field, voxels};
  for (ANARIObject o : objects)
    dev->release(o);
  dev->release(self); // the loader releases a device through slot 24
  delete lib;         // anariUnloadLibrary: deleting destructor, then dlclose
  dlclose(dl);
  scene_free(&s);

  check("no error or warning reached the status callback", errors == 0);
  return failures ? 1 : 0;
}
