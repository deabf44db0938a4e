/* Object parameters a commit refuses for holding the wrong kind, each of
 * them closing a loop back to the object it is set on: a group whose
 * 'volume' array holds an instance of that group, a group whose 'surface'
 * array (ANARI_OBJECT) holds the group, a world whose 'instance' array
 * holds the world, a field whose 'data' is an array of instances that
 * place the field's own volume. Each refusal must name the parameter and
 * say it was unset; the refused values must keep nothing alive (each
 * array's deleter runs once its handle is released, before the device
 * is), so under valgrind nothing is lost; and the group, given a valid
 * volume array afterwards, renders. Prints PASS/FAIL per check; exit
 * status 1 on any FAIL. */
#include <anari/anari.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "expect.h"

static int deletions = 0;
static void count_deletion(const void *user, const void *memory)
{
  (void)user;
  deletions++;
  free((void *)memory);
}

/* A captured array of `n` handles: the device calls its deleter when
 * nothing uses it any more. */
static ANARIArray1D handles(ANARIDevice dev, ANARIDataType element, const ANARIObject *objects, int n)
{
  ANARIObject *memory = (ANARIObject *)malloc((size_t)n * sizeof *memory);
  memcpy(memory, objects, (size_t)n * sizeof *memory);
  return anariNewArray1D(dev, memory, count_deletion, NULL, element, (uint64_t)n);
}

/* A 4^3 field on [-1, 1]^3 of values 0 to 1 along x. */
static ANARISpatialField ramp_field(ANARIDevice dev)
{
  float voxels[4 * 4 * 4];
  float origin[3] = {-1, -1, -1}, spacing[3] = {2.0f / 3, 2.0f / 3, 2.0f / 3};
  ANARIArray3D data;
  ANARISpatialField field;
  int i;
  for (i = 0; i < 4 * 4 * 4; ++i)
    voxels[i] = (float)(i % 4) / 3.0f;
  data = anariNewArray3D(dev, voxels, NULL, NULL, ANARI_FLOAT32, 4, 4, 4);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &data);
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, spacing);
  anariCommitParameters(dev, field);
  anariRelease(dev, data);
  return field;
}

static ANARIVolume ramp_volume(ANARIDevice dev, ANARISpatialField field)
{
  float range[2] = {0, 1}, opacity = 1.0f, white[3] = {1, 1, 1};
  ANARIVolume volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "valueRange", ANARI_FLOAT32_BOX1, range);
  anariSetParameter(dev, volume, "opacity", ANARI_FLOAT32, &opacity);
  anariSetParameter(dev, volume, "color", ANARI_FLOAT32_VEC3, white);
  anariCommitParameters(dev, volume);
  return volume;
}

static ANARIInstance place(ANARIDevice dev, ANARIGroup group)
{
  ANARIInstance instance = anariNewInstance(dev, "transform");
  anariSetParameter(dev, instance, "group", ANARI_GROUP, &group);
  anariCommitParameters(dev, instance);
  return instance;
}

int main(void)
{
  float eye[3] = {0, 0, 4}, dir[3] = {0, 0, -1}, up[3] = {0, 1, 0};
  unsigned size[2] = {16, 16};
  ANARIDataType color = ANARI_UFIXED8_VEC4, type;
  uint32_t w = 0, h = 0;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARISpatialField field, looped_field;
  ANARIVolume volume, looped_volume;
  ANARIGroup group, self_group, field_group;
  ANARIInstance instance, field_instance;
  ANARIWorld world, self_world;
  ANARIArray1D array, volumes, instances;
  ANARIArray3D grid;
  ANARICamera camera;
  ANARIRenderer renderer;
  ANARIFrame frame;
  ANARIObject *cells;
  const unsigned char *pixels;
  int i, lit = 0;

  reset();
  lib = anariLoadLibrary("caveray", on_status, NULL);
  dev = anariNewDevice(lib, "default");
  field = ramp_field(dev);
  volume = ramp_volume(dev, field);
  expect_quiet("a field and its volume");

  /* group -> 'volume' array -> instance -> group */
  group = anariNewGroup(dev);
  anariCommitParameters(dev, group);
  instance = place(dev, group);
  expect_quiet("an instance of an empty group");
  array = handles(dev, ANARI_INSTANCE, (ANARIObject *)&instance, 1);
  anariSetParameter(dev, group, "volume", ANARI_ARRAY1D, &array);
  anariRelease(dev, array);
  anariCommitParameters(dev, group);
  expect("group 'volume' array of its own instance", ERR, BAD_ARG,
      "'volume' array holds ANARI_INSTANCE; expected ANARI_VOLUME; 'volume' is unset");
  check("the refused array is released at once", deletions == 1);
  anariCommitParameters(dev, group);
  expect_quiet("recommitting the group: the refused value is gone");

  /* group -> 'surface' array (ANARI_OBJECT) -> the group */
  self_group = anariNewGroup(dev);
  array = handles(dev, ANARI_OBJECT, (ANARIObject *)&self_group, 1);
  anariSetParameter(dev, self_group, "surface", ANARI_ARRAY1D, &array);
  anariRelease(dev, array);
  anariCommitParameters(dev, self_group);
  expect("group 'surface' array holding the group", ERR, BAD_ARG, "expected only ANARI_SURFACEs; 'surface' is unset");
  check("the 'surface' array is released", deletions == 2);
  anariRelease(dev, self_group);

  /* world -> 'instance' array (ANARI_OBJECT) -> the world */
  self_world = anariNewWorld(dev);
  {
    ANARIObject both[2];
    both[0] = instance;
    both[1] = self_world;
    array = handles(dev, ANARI_OBJECT, both, 2);
  }
  anariSetParameter(dev, self_world, "instance", ANARI_ARRAY1D, &array);
  anariRelease(dev, array);
  anariCommitParameters(dev, self_world);
  expect("world 'instance' array holding the world", ERR, BAD_ARG, "expected only ANARI_INSTANCEs; 'instance' is unset");
  check("the 'instance' array is released", deletions == 3);
  anariRelease(dev, self_world);

  /* field -> 'data' (ARRAY3D of instances) -> instance -> group -> volume -> field */
  looped_field = ramp_field(dev);
  looped_volume = ramp_volume(dev, looped_field);
  field_group = anariNewGroup(dev);
  volumes = handles(dev, ANARI_VOLUME, (ANARIObject *)&looped_volume, 1);
  anariSetParameter(dev, field_group, "volume", ANARI_ARRAY1D, &volumes);
  anariRelease(dev, volumes);
  anariCommitParameters(dev, field_group);
  field_instance = place(dev, field_group);
  expect_quiet("a group of a volume, placed");
  cells = (ANARIObject *)malloc(sizeof *cells);
  cells[0] = field_instance;
  grid = anariNewArray3D(dev, cells, count_deletion, NULL, ANARI_INSTANCE, 1, 1, 1);
  anariSetParameter(dev, looped_field, "data", ANARI_ARRAY3D, &grid);
  anariRelease(dev, grid);
  anariCommitParameters(dev, looped_field);
  expect("field 'data' of instances placing its own volume", ERR, BAD_ARG, "'data' holds ANARI_INSTANCE");
  check("the 'data' array is released", deletions == 4);
  anariRelease(dev, field_instance);
  anariRelease(dev, field_group);
  check("the volume list goes with its group", deletions == 5);
  anariRelease(dev, looped_volume);
  anariRelease(dev, looped_field);

  /* The group still works: a valid volume array, placed in a world, renders. */
  volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  anariSetParameter(dev, group, "volume", ANARI_ARRAY1D, &volumes);
  anariRelease(dev, volumes);
  anariCommitParameters(dev, group);
  anariCommitParameters(dev, instance);
  expect_quiet("the group with a valid volume array");
  world = anariNewWorld(dev);
  instances = anariNewArray1D(dev, &instance, NULL, NULL, ANARI_INSTANCE, 1);
  anariSetParameter(dev, world, "instance", ANARI_ARRAY1D, &instances);
  anariRelease(dev, instances);
  anariCommitParameters(dev, world);
  camera = anariNewCamera(dev, "perspective");
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, eye);
  anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, dir);
  anariSetParameter(dev, camera, "up", ANARI_FLOAT32_VEC3, up);
  anariCommitParameters(dev, camera);
  renderer = anariNewRenderer(dev, "default");
  anariCommitParameters(dev, renderer);
  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, size);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &color);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariCommitParameters(dev, frame);
  anariRenderFrame(dev, frame);
  check("the frame is ready", anariFrameReady(dev, frame, ANARI_WAIT) == 1);
  expect_quiet("rendering the group");
  pixels = (const unsigned char *)anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  check("the frame maps", pixels != NULL && w == 16 && h == 16 && type == ANARI_UFIXED8_VEC4);
  for (i = 0; pixels && i < 16 * 16; ++i)
    lit += pixels[4 * i + 3] > 0;
  check("the group's volume shows", lit > 16);
  anariUnmapFrame(dev, frame, "channel.color");

  anariRelease(dev, frame);
  anariRelease(dev, renderer);
  anariRelease(dev, camera);
  anariRelease(dev, world);
  anariRelease(dev, instance);
  anariRelease(dev, group);
  anariRelease(dev, volume);
  anariRelease(dev, field);
  check("every captured array's deleter ran once", deletions == 5);
  anariRelease(dev, dev);
  check("and no more after the device", deletions == 5);
  anariUnloadLibrary(lib);
  expect_quiet("releasing everything");

  printf("%s: %d failure(s)\n", failures ? "FAIL" : "done", failures);
  return failures ? 1 : 0;
}
