/* Test (b): every misuse a host can commit through the C API reaches the
 * status callback with the right severity, code and message, returns a
 * neutral value, and leaves the device working: the program ends by
 * rendering a frame. Prints PASS/FAIL per check; exit status 1 on any FAIL. */
#include <anari/anari.h>
#include <anari/caveray.h>

#include <stdio.h>
#include <string.h>

#include "expect.h"

static int deletions = 0;
static void count_deletion(const void *user, const void *memory)
{
  (void)user, (void)memory;
  deletions++;
}

int main(void)
{
  static float voxels[8 * 8 * 8];
  static float shared[4] = {0.f, 0.5f, 1.f, 1.f};
  float vec4[4] = {0, 0, 0, 1}, zero[16] = {0}, identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
  float ll[3] = {-1, -1, -2}, lr[3] = {1, -1, -2}, ur[3] = {1, 1, -2};
  float eye[3] = {0, 0, 1}, behind[3] = {0, 0, -5}, f = 1.0f;
  unsigned size[2] = {16, 16};
  int i, version = 0;
  ANARIDataType color = ANARI_UFIXED8_VEC4, type;
  uint32_t w, h;
  float fvalue;
  ANARILibrary lib;
  ANARIDevice dev, other;
  ANARICamera camera, foreign, released, off_axis;
  ANARIArray1D array, colors, values;
  ANARIArray3D grid;
  ANARISpatialField field;
  ANARIVolume volume;
  ANARIWorld world;
  ANARIRenderer renderer;
  ANARIFrame frame;
  ANARIObject garbage = (ANARIObject)(uintptr_t)0x1234;
  const void *pixels;
  void *mapped;
  CaverayPinhole pinhole;

  for (i = 0; i < 8 * 8 * 8; ++i)
    voxels[i] = (float)(i % 8) / 7.0f;

  reset();
  lib = anariLoadLibrary("caveray", on_status, NULL);
  check("library loads", lib != NULL);
  expect_quiet("loading caveray");

  /* Libraries and devices. */
  check("NULL library gives no device", anariNewDevice(NULL, "default") == NULL);
  expect("NULL library", ERR, BAD_ARG, "library handle is NULL");
  check("unknown device subtype gives no device", anariNewDevice(lib, "optix") == NULL);
  expect("unknown device subtype", ERR, ANARI_STATUS_UNSUPPORTED_DEVICE, "'optix' does not exist");
  check("loading another library fails", anariLoadLibrary("helide", on_status, NULL) == NULL);
  expect("foreign library name", ERR, ANARI_STATUS_UNSUPPORTED_DEVICE, "not 'helide'");
  anariLoadModule(lib, "extras");
  expect("module", WARN, BAD_ARG, "caveray has no modules");

  dev = anariNewDevice(lib, "default");
  other = anariNewDevice(lib, "default");
  check("devices are created", dev && other);
  anariSetParameter(dev, dev, "statusCallback", ANARI_STATUS_CALLBACK, (const void *)&(ANARIStatusCallback){on_status});
  anariCommitParameters(dev, dev);
  expect_quiet("device status callback set through a parameter");
  anariCommitParameters(NULL, NULL);
  expect("NULL device", ERR, BAD_ARG, "device handle is NULL");
  check("version property", anariGetProperty(dev, dev, "version", ANARI_INT32, &version, sizeof version, ANARI_WAIT) == 1 && version == 1);
  check("a property of the wrong type is refused",
      anariGetProperty(dev, dev, "version", ANARI_FLOAT32, &fvalue, sizeof fvalue, ANARI_WAIT) == 0);
  expect("property type", ERR, BAD_ARG, "property 'version' is ANARI_INT32");
  check("an unknown property is absent",
      anariGetProperty(dev, dev, "color", ANARI_INT32, &version, sizeof version, ANARI_WAIT) == 0);
  expect_quiet("unknown property");

  /* Handles. */
  camera = anariNewCamera(dev, "matrix");
  anariCommitParameters(dev, NULL);
  expect("NULL object", ERR, BAD_ARG, "object handle is NULL");
  anariCommitParameters(dev, garbage);
  expect("garbage handle", ERR, BAD_ARG, "is not an ANARI handle");
  foreign = anariNewCamera(other, "perspective");
  anariCommitParameters(dev, foreign);
  expect("handle of another device", ERR, BAD_ARG, "belongs to another device");
  released = anariNewCamera(dev, "perspective");
  anariRelease(dev, released);
  anariCommitParameters(dev, released);
  expect("released handle", ERR, BAD_ARG, "was released");
  anariRelease(dev, released);
  expect("released twice", ERR, BAD_ARG, "was released");
  check("unknown object type gives no object", anariNewObject(dev, "teapot", "utah") == NULL);
  expect("unknown object type", ERR, BAD_ARG, "'teapot' is not an ANARI object type");
  {
    ANARIGeometry g = anariNewGeometry(dev, "torus");
    expect("unimplemented geometry", WARN, ANARI_STATUS_NO_ERROR, "does not implement geometry 'torus'");
    check("an inert geometry is still created", g != NULL);
    anariSetParameter(dev, g, "vertex.position", ANARI_FLOAT32, &f);
    anariCommitParameters(dev, g);
    expect_quiet("parameters on an inert object");
    anariRelease(dev, g);
  }
  {
    ANARICamera c = anariNewCamera(dev, "fisheye");
    expect("unimplemented camera subtype", WARN, ANARI_STATUS_NO_ERROR, "does not implement camera 'fisheye'");
    anariRelease(dev, c);
  }

  /* Parameters. */
  anariSetParameter(dev, camera, "view", ANARI_FLOAT32_VEC4, vec4);
  expect("wrong parameter type", ERR, BAD_ARG, "'view' expects ANARI_FLOAT32_MAT4, got ANARI_FLOAT32_VEC4");
  anariSetParameter(dev, camera, "fov", ANARI_FLOAT32, &f);
  expect("unknown parameter", WARN, ANARI_STATUS_NO_ERROR, "has no parameter 'fov'");
  anariSetParameter(dev, camera, "view", 4242, identity);
  expect("unknown data type", ERR, BAD_ARG, "4242 is not an ANARI data type");
  anariSetParameter(dev, camera, "view", ANARI_FLOAT32_MAT4, NULL);
  expect("NULL value", ERR, BAD_ARG, "value pointer for a ANARI_FLOAT32_MAT4 is NULL");
  anariSetParameter(dev, camera, NULL, ANARI_FLOAT32_MAT4, identity);
  expect("NULL parameter name", ERR, BAD_ARG, "parameter name is NULL");
  anariCommitParameters(dev, camera);
  expect("missing required parameter", ERR, BAD_ARG, "required parameter 'view'");
  anariSetParameter(dev, camera, "view", ANARI_FLOAT32_MAT4, identity);
  anariSetParameter(dev, camera, "proj", ANARI_FLOAT32_MAT4, zero);
  anariCommitParameters(dev, camera);
  expect("singular matrices for the matrix camera", ERR, BAD_ARG, "is singular");

  /* Walls and eyes. */
  off_axis = anariNewCamera(dev, "offAxis");
  anariSetParameter(dev, off_axis, "lowerLeft", ANARI_FLOAT32_VEC3, ll);
  anariSetParameter(dev, off_axis, "lowerRight", ANARI_FLOAT32_VEC3, ll);
  anariSetParameter(dev, off_axis, "upperRight", ANARI_FLOAT32_VEC3, ur);
  anariSetParameter(dev, off_axis, "eye", ANARI_FLOAT32_VEC3, eye);
  anariCommitParameters(dev, off_axis);
  expect("degenerate wall", ERR, BAD_ARG, "wall has zero area");
  anariSetParameter(dev, off_axis, "lowerRight", ANARI_FLOAT32_VEC3, lr);
  anariSetParameter(dev, off_axis, "eye", ANARI_FLOAT32_VEC3, behind);
  anariCommitParameters(dev, off_axis);
  expect("eye behind the wall", ERR, BAD_ARG, "eye is on or behind the wall");
  check("helper refuses an eye behind the wall",
      caverayPinholeFromScreen(ll, lr, ur, behind, &pinhole) == ANARI_STATUS_INVALID_ARGUMENT
          && strstr(caverayLastError(), "behind the wall") != NULL);
  check("helper refuses singular matrices",
      caverayPinholeFromMatrices(identity, zero, &pinhole) == ANARI_STATUS_INVALID_ARGUMENT);
  check("helper refuses NULL", caverayPinholeFromScreen(NULL, lr, ur, eye, &pinhole) == ANARI_STATUS_INVALID_ARGUMENT
      && strstr(caverayLastError(), "lowerLeft is NULL") != NULL);
  anariSetParameter(dev, off_axis, "eye", ANARI_FLOAT32_VEC3, eye);
  anariCommitParameters(dev, off_axis);
  expect_quiet("a valid wall and eye");

  /* Arrays. */
  array = anariNewArray1D(dev, NULL, NULL, NULL, ANARI_FLOAT32, 4);
  mapped = anariMapArray(dev, array);
  check("device-owned array maps", mapped != NULL);
  check("mapping twice gives NULL", anariMapArray(dev, array) == NULL);
  expect("mapping twice", ERR, BAD_OP, "is already mapped");
  anariUnmapArray(dev, array);
  anariUnmapArray(dev, array);
  expect("unmapping twice", ERR, BAD_OP, "is not mapped");
  check("unknown element type gives no array",
      anariNewArray1D(dev, shared, count_deletion, NULL, 777, 4) == NULL);
  expect("unknown element type", ERR, BAD_ARG, "element type 777");
  check("a failed array does not call the deleter", deletions == 0);
  anariMapArray(dev, camera);
  expect("mapping a camera", ERR, BAD_ARG, "is not an array");

  grid = anariNewArray3D(dev, voxels, NULL, NULL, ANARI_FLOAT32, 8, 8, 8);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY1D, &array);
  expect("1D array as volume data", ERR, BAD_ARG, "'data' expects ANARI_ARRAY3D");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &array);
  expect("1D array declared as 3D", ERR, BAD_ARG, "'data' expects ANARI_ARRAY3D");
  {
    ANARIArray3D empty = anariNewArray3D(dev, NULL, NULL, NULL, ANARI_FLOAT32, 8, 0, 8);
    anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &empty);
    anariCommitParameters(dev, field);
    expect("volume with a zero dimension", ERR, BAD_ARG, "dimension 0");
    anariRelease(dev, empty);
  }
  {
    ANARIArray3D ints = anariNewArray3D(dev, NULL, NULL, NULL, ANARI_INT32, 8, 8, 8);
    anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &ints);
    anariCommitParameters(dev, field);
    expect("volume of INT32", ERR, BAD_ARG, "'data' holds ANARI_INT32");
    anariRelease(dev, ints);
  }
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &grid);
  anariCommitParameters(dev, field);
  expect_quiet("a valid field");

  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  {
    /* Every FLOAT32/UFIXED8/UFIXED16/sRGB layout is a color; UINT32 is not. */
    ANARIArray1D words = anariNewArray1D(dev, NULL, NULL, NULL, ANARI_UINT32, 4);
    anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &words);
    anariRelease(dev, words);
  }
  anariCommitParameters(dev, volume);
  expect("color array of UINT32", ERR, BAD_ARG, "'color' array holds ANARI_UINT32; expected FLOAT32, UFIXED8, UFIXED16 or UFIXED32");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &camera);
  expect("camera as the field", ERR, BAD_ARG, "'value' expects ANARI_SPATIAL_FIELD");
  {
    ANARIArray1D none = anariNewArray1D(dev, NULL, NULL, NULL, ANARI_FLOAT32, 0);
    anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &none);
    anariUnsetParameter(dev, volume, "color");
    anariCommitParameters(dev, volume);
    expect("empty opacity array", ERR, BAD_ARG, "'opacity' array is empty");
    anariRelease(dev, none);
  }
  /* A shared array: the deleter runs once, when nothing uses it any more. */
  colors = anariNewArray1D(dev, shared, count_deletion, NULL, ANARI_FLOAT32, 4);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &colors);
  anariRelease(dev, colors);
  check("deleter waits while a parameter uses the array", deletions == 0);
  anariCommitParameters(dev, volume);
  expect_quiet("a valid volume");

  world = anariNewWorld(dev);
  values = anariNewArray1D(dev, shared, NULL, NULL, ANARI_FLOAT32, 4);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &values);
  anariCommitParameters(dev, world);
  expect("world volume array of FLOAT32", ERR, BAD_ARG, "'volume' array holds ANARI_FLOAT32; expected ANARI_VOLUME");
  anariRelease(dev, values);
  values = anariNewArray1D(dev, &camera, NULL, NULL, ANARI_VOLUME, 1);
  expect("a camera in a volume array", ERR, BAD_ARG, "is a camera, not ANARI_VOLUME");
  anariRelease(dev, values);
  values = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  anariSetParameter(dev, world, "volume", ANARI_ARRAY1D, &values);
  anariCommitParameters(dev, world);
  expect_quiet("a valid world");

  /* Frames. */
  renderer = anariNewRenderer(dev, "default");
  anariSetParameter(dev, renderer, "shading", ANARI_STRING, "phong");
  anariCommitParameters(dev, renderer);
  expect("unknown shading", ERR, BAD_ARG, "unknown shading mode \"phong\"");
  anariSetParameter(dev, renderer, "shading", ANARI_STRING, "shadows");
  anariCommitParameters(dev, renderer);
  expect_quiet("shadows");

  frame = anariNewFrame(dev);
  anariRenderFrame(dev, frame);
  expect("uncommitted frame", ERR, BAD_OP, "has not been committed");
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, size);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &color);
  anariCommitParameters(dev, frame);
  anariRenderFrame(dev, frame);
  expect("frame without camera", ERR, BAD_OP, "no camera");
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &off_axis);
  anariCommitParameters(dev, frame);
  anariRenderFrame(dev, frame);
  expect("frame without renderer", ERR, BAD_OP, "no renderer");
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariCommitParameters(dev, frame);
  anariRenderFrame(dev, frame);
  expect("frame without world", ERR, BAD_OP, "no world");
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariCommitParameters(dev, frame);
  anariRenderFrame(dev, frame);
  expect("frame with an unusable camera", ERR, BAD_OP, "is not usable");
  check("a failed render leaves nothing to map",
      anariMapFrame(dev, frame, "channel.color", &w, &h, &type) == NULL && w == 0 && type == ANARI_UNKNOWN);
  expect("mapping a failed frame", ERR, BAD_OP, "the last render failed");

  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &off_axis);
  anariCommitParameters(dev, frame);
  anariRenderFrame(dev, frame);
  check("frame is ready", anariFrameReady(dev, frame, ANARI_WAIT) == 1);
  expect_quiet("rendering after all that misuse");
  pixels = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  check("the frame maps", pixels != NULL && w == 16 && h == 16 && type == ANARI_UFIXED8_VEC4);
  check("mapping twice gives NULL", anariMapFrame(dev, frame, "channel.color", &w, &h, &type) == NULL);
  expect("mapping a frame twice", ERR, BAD_OP, "is already mapped");
  anariRenderFrame(dev, frame);
  expect("rendering into a mapped frame", ERR, BAD_OP, "is mapped");
  anariUnmapFrame(dev, frame, "channel.color");
  anariUnmapFrame(dev, frame, "channel.color");
  expect("unmapping twice", ERR, BAD_OP, "is not mapped");
  check("no depth channel", anariMapFrame(dev, frame, "channel.depth", &w, &h, &type) == NULL);
  expect("mapping a missing depth channel", ERR, BAD_OP, "no depth channel");
  check("no normal channel", anariMapFrame(dev, frame, "channel.normal", &w, &h, &type) == NULL);
  expect("mapping a channel the frame was not given", ERR, BAD_OP,
      "no channel.normal channel; set 'channel.normal'");
  check("unknown channel", anariMapFrame(dev, frame, "channel.tangent", &w, &h, &type) == NULL);
  expect("mapping an unknown channel", ERR, BAD_ARG, "unknown channel 'channel.tangent'");
  check("duration property", anariGetProperty(dev, frame, "duration", ANARI_FLOAT32, &fvalue, sizeof fvalue, ANARI_WAIT) == 1 && fvalue > 0.0f);
  anariRenderFrame(dev, camera);
  expect("rendering a camera", ERR, BAD_ARG, "is not a frame");

  /* Releasing a device, then using it. */
  anariRelease(other, foreign);
  anariRelease(other, other);
  check("a released device gives no objects", anariNewCamera(other, "perspective") == NULL);
  expect("released device", ERR, BAD_ARG, "is not a live caveray device");

  anariRelease(dev, frame);
  anariRelease(dev, renderer);
  anariRelease(dev, world);
  anariRelease(dev, values);
  check("deleter waits while the volume lives", deletions == 0);
  anariRelease(dev, volume);
  check("deleter runs when the last user of the array goes", deletions == 1);
  anariRelease(dev, field);
  anariRelease(dev, grid);
  anariRelease(dev, array);
  anariRelease(dev, camera);
  anariRelease(dev, off_axis);
  anariRelease(dev, dev);
  check("the shared array's deleter ran exactly once", deletions == 1);
  anariUnloadLibrary(lib);
  anariUnloadLibrary(lib);
  expect("unloading twice", ERR, BAD_ARG, "is not a loaded caveray library");

  printf("%s: %d failure(s)\n", failures ? "FAIL" : "done", failures);
  return failures ? 1 : 0;
}
