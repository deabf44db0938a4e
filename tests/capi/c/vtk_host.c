/* A VTK/ParaView-style host, from what VTK's ANARI pass sends (HOSTS.md):
 * each dataset's volume in its own group, placed by a `transform`
 * instance in the world's `instance` array; two datasets, the scene's
 * phantom and a constant field (valueRange lo == hi); color and opacity
 * as FLOAT32_VEC3 / FLOAT32 arrays and no unitDistance; a 1 x 2 gradient
 * as the renderer's `background` (ARRAY2D); a perspective camera with
 * near and far; `name` set on every object, and set again with every
 * commit of the second update; the frame rendered twice in a row and then
 * waited on, and `duration` read.
 * Usage: vtk_host SCENE_FILE TRANSFORMS_FILE OUT_DIR, where TRANSFORMS_FILE
 * holds the two instances' FLOAT32_MAT4s (column-major, 32 numbers).
 * Writes OUT_DIR/vtk.rgba (after the first update) and OUT_DIR/vtk2.rgba
 * (after the second). Exit status 0 only if every render succeeded and
 * the status callback saw no warning or error. */
#include <anari/anari.h>
#include <anari/caveray.h>

#include "scene.h"
#include "status.h"

/* What VTK does on every update: name the object, then commit it. */
static void named_commit(ANARIDevice dev, ANARIObject o, const char *name)
{
  anariSetParameter(dev, o, "name", ANARI_STRING, name);
  anariCommitParameters(dev, o);
}

/* A group holding `volume`, placed by `transform`. */
static ANARIInstance place(ANARIDevice dev, ANARIVolume volume, const float *transform)
{
  ANARIGroup group = anariNewGroup(dev);
  ANARIArray1D volumes = anariNewArray1D(dev, &volume, NULL, NULL, ANARI_VOLUME, 1);
  ANARIInstance instance = anariNewInstance(dev, "transform");
  anariSetParameter(dev, group, "volume", ANARI_ARRAY1D, &volumes);
  named_commit(dev, group, "vtkGroup");
  anariRelease(dev, volumes);
  anariSetParameter(dev, instance, "group", ANARI_GROUP, &group);
  anariSetParameter(dev, instance, "transform", ANARI_FLOAT32_MAT4, transform);
  named_commit(dev, instance, "vtkInstance");
  anariRelease(dev, group);
  return instance;
}

int main(int argc, char **argv)
{
  Scene s;
  FILE *tf;
  float transforms[32], constant[64], range[2] = {0.5f, 0.5f};
  float cells[3], near_far[2] = {1.0f, 1.0e6f}, duration = -1.0f;
  float gradient[8] = {0.1f, 0.1f, 0.3f, 1.0f, 0.0f, 0.0f, 0.0f, 1.0f};
  float rgb2[6] = {0.1f, 0.4f, 1.0f, 1.0f, 0.8f, 0.1f}, alpha2[2] = {0.002f, 0.002f};
  float *rgb;
  ANARILibrary lib;
  ANARIDevice dev;
  ANARIArray3D voxels, constants;
  ANARIArray2D background;
  ANARIArray1D colors, opacities, instances;
  ANARISpatialField field, flat;
  ANARIVolume volume, haze;
  ANARIInstance placed[2];
  ANARIWorld world;
  ANARIRenderer renderer;
  ANARIFrame frame;
  ANARICamera camera;
  CaverayPinhole pinhole;
  ANARIDataType rgba8 = ANARI_UFIXED8_VEC4, depth_type = ANARI_FLOAT32;
  uint32_t w = 0, h = 0;
  ANARIDataType type = ANARI_UNKNOWN;
  const void *pixels;
  int ok = 1, i, update;
  unsigned c, k;

  if (argc != 4 || !scene_load(argv[1], &s)) {
    fprintf(stderr, "usage: vtk_host SCENE_FILE TRANSFORMS_FILE OUT_DIR\n");
    return 2;
  }
  tf = fopen(argv[2], "r");
  for (i = 0; tf && i < 32; ++i)
    if (fscanf(tf, "%f", &transforms[i]) != 1)
      break;
  if (tf)
    fclose(tf);
  if (i != 32) {
    fprintf(stderr, "vtk_host: cannot read 32 numbers from %s\n", argv[2]);
    scene_free(&s);
    return 2;
  }
  status_level = ANARI_SEVERITY_WARNING;
  lib = anariLoadLibrary("environment", count_status, "vtk_host");
  dev = anariNewDevice(lib, "default");

  voxels = anariNewArray3D(dev, s.voxels, NULL, NULL, ANARI_FLOAT32, s.dims[0], s.dims[1], s.dims[2]);
  field = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, field, "data", ANARI_ARRAY3D, &voxels);
  anariSetParameter(dev, field, "filter", ANARI_STRING, "linear");
  anariSetParameter(dev, field, "origin", ANARI_FLOAT32_VEC3, s.origin);
  anariSetParameter(dev, field, "spacing", ANARI_FLOAT32_VEC3, s.spacing);
  named_commit(dev, field, "phantom field");
  anariRelease(dev, voxels);

  /* VTK's color map: RGB samples of the table, the opacities as they are. */
  rgb = (float *)malloc(3 * s.ncolors * sizeof(float));
  for (c = 0; c < s.ncolors; ++c)
    for (k = 0; k < 3; ++k)
      rgb[3 * c + k] = s.colors[4 * c + k];
  colors = anariNewArray1D(dev, rgb, NULL, NULL, ANARI_FLOAT32_VEC3, s.ncolors);
  opacities = anariNewArray1D(dev, s.opacities, NULL, NULL, ANARI_FLOAT32, s.nopacities);
  volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, volume, "color", ANARI_ARRAY1D, &colors);
  anariSetParameter(dev, volume, "opacity", ANARI_ARRAY1D, &opacities);
  anariSetParameter(dev, volume, "valueRange", ANARI_FLOAT32_BOX1, s.range);
  named_commit(dev, volume, "phantom");
  anariRelease(dev, colors);
  anariRelease(dev, opacities);

  /* The second dataset: a constant field over the same box. */
  for (i = 0; i < 64; ++i)
    constant[i] = 0.5f;
  for (k = 0; k < 3; ++k)
    cells[k] = s.spacing[k] * (float)(s.dims[k] - 1) / 3.0f;
  constants = anariNewArray3D(dev, constant, NULL, NULL, ANARI_FLOAT32, 4, 4, 4);
  flat = anariNewSpatialField(dev, "structuredRegular");
  anariSetParameter(dev, flat, "data", ANARI_ARRAY3D, &constants);
  anariSetParameter(dev, flat, "origin", ANARI_FLOAT32_VEC3, s.origin);
  anariSetParameter(dev, flat, "spacing", ANARI_FLOAT32_VEC3, cells);
  named_commit(dev, flat, "constant field");
  anariRelease(dev, constants);
  colors = anariNewArray1D(dev, rgb2, NULL, NULL, ANARI_FLOAT32_VEC3, 2);
  opacities = anariNewArray1D(dev, alpha2, NULL, NULL, ANARI_FLOAT32, 2);
  haze = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, haze, "value", ANARI_SPATIAL_FIELD, &flat);
  anariSetParameter(dev, haze, "color", ANARI_ARRAY1D, &colors);
  anariSetParameter(dev, haze, "opacity", ANARI_ARRAY1D, &opacities);
  anariSetParameter(dev, haze, "valueRange", ANARI_FLOAT32_BOX1, range);
  named_commit(dev, haze, "constant");
  anariRelease(dev, colors);
  anariRelease(dev, opacities);

  placed[0] = place(dev, volume, transforms);
  placed[1] = place(dev, haze, transforms + 16);
  instances = anariNewArray1D(dev, placed, NULL, NULL, ANARI_INSTANCE, 2);
  world = anariNewWorld(dev);
  anariSetParameter(dev, world, "instance", ANARI_ARRAY1D, &instances);
  named_commit(dev, world, "vtkWorld");
  anariRelease(dev, instances);

  background = anariNewArray2D(dev, gradient, NULL, NULL, ANARI_FLOAT32_VEC4, 1, 2);
  renderer = anariNewRenderer(dev, "default");
  anariSetParameter(dev, renderer, "background", ANARI_ARRAY2D, &background);
  named_commit(dev, renderer, "vtkRenderer");
  anariRelease(dev, background);

  if (caverayPinholeFromScreen(s.ll, s.lr, s.ur, s.eye, &pinhole) != ANARI_STATUS_NO_ERROR) {
    fprintf(stderr, "vtk_host: %s\n", caverayLastError());
    return 1;
  }
  camera = anariNewCamera(dev, "perspective");
  anariSetParameter(dev, camera, "position", ANARI_FLOAT32_VEC3, pinhole.position);
  anariSetParameter(dev, camera, "direction", ANARI_FLOAT32_VEC3, pinhole.direction);
  anariSetParameter(dev, camera, "up", ANARI_FLOAT32_VEC3, pinhole.up);
  anariSetParameter(dev, camera, "fovy", ANARI_FLOAT32, &pinhole.fovy);
  anariSetParameter(dev, camera, "aspect", ANARI_FLOAT32, &pinhole.aspect);
  anariSetParameter(dev, camera, "imageRegion", ANARI_FLOAT32_BOX2, pinhole.imageRegion);
  anariSetParameter(dev, camera, "near", ANARI_FLOAT32, &near_far[0]);
  anariSetParameter(dev, camera, "far", ANARI_FLOAT32, &near_far[1]);
  named_commit(dev, camera, "vtkCamera");

  frame = anariNewFrame(dev);
  anariSetParameter(dev, frame, "channel.color", ANARI_DATA_TYPE, &rgba8);
  anariSetParameter(dev, frame, "channel.depth", ANARI_DATA_TYPE, &depth_type);
  anariSetParameter(dev, frame, "world", ANARI_WORLD, &world);
  anariSetParameter(dev, frame, "renderer", ANARI_RENDERER, &renderer);
  anariSetParameter(dev, frame, "camera", ANARI_CAMERA, &camera);
  anariSetParameter(dev, frame, "size", ANARI_UINT32_VEC2, s.size);
  named_commit(dev, frame, "vtkFrame");

  for (update = 0; update < 2 && ok; ++update) {
    if (update == 1) {
      /* VTK's next update: every object named and committed again. */
      named_commit(dev, field, "phantom field");
      named_commit(dev, volume, "phantom");
      named_commit(dev, flat, "constant field");
      named_commit(dev, haze, "constant");
      named_commit(dev, placed[0], "vtkInstance");
      named_commit(dev, placed[1], "vtkInstance");
      named_commit(dev, world, "vtkWorld");
      named_commit(dev, renderer, "vtkRenderer");
      named_commit(dev, camera, "vtkCamera");
      named_commit(dev, frame, "vtkFrame");
    }
    anariRenderFrame(dev, frame);
    anariRenderFrame(dev, frame);
    anariFrameReady(dev, frame, ANARI_WAIT);
    if (anariGetProperty(dev, frame, "duration", ANARI_FLOAT32, &duration, sizeof duration, ANARI_WAIT) != 1
        || !(duration >= 0.0f)) {
      fprintf(stderr, "vtk_host: no duration (%g)\n", duration);
      ok = 0;
    }
    pixels = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
    if (!pixels || w != s.size[0] || h != s.size[1] || type != ANARI_UFIXED8_VEC4) {
      fprintf(stderr, "vtk_host: no %ux%u color channel\n", s.size[0], s.size[1]);
      ok = 0;
    } else {
      ok &= write_rgba(argv[3], update == 0 ? "vtk" : "vtk2", pixels, w, h);
      anariUnmapFrame(dev, frame, "channel.color");
    }
  }

  anariRelease(dev, frame);
  anariRelease(dev, camera);
  anariRelease(dev, renderer);
  anariRelease(dev, world);
  anariRelease(dev, placed[0]);
  anariRelease(dev, placed[1]);
  anariRelease(dev, haze);
  anariRelease(dev, flat);
  anariRelease(dev, volume);
  anariRelease(dev, field);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  free(rgb);
  scene_free(&s);
  return ok && status_count == 0 ? 0 : 1;
}
