/* One volume over `field` seen head-on by a perspective camera, as the
 * field hosts (amr_host.c, nanovdb_host.c) render it: a two-entry
 * transfer function over `range`, a transparent background, a square
 * frame of RGBA8; and the frame's pixels and how many of them show. */
#ifndef CAVERAY_TEST_VOLUME_VIEW_H
#define CAVERAY_TEST_VOLUME_VIEW_H

#include <anari/anari.h>

#include <stdint.h>
#include <string.h>

typedef struct VolumeView {
  ANARIArray1D tf_color, tf_opacity, volumes;
  ANARIVolume volume;
  ANARIWorld world;
  ANARIRenderer renderer;
  ANARICamera camera;
  ANARIFrame frame;
} VolumeView;

static VolumeView volume_view(ANARIDevice dev, ANARISpatialField field, const float range[2],
    const float eye[3], unsigned size)
{
  /* Shared arrays: the host's memory must outlive them. */
  static const float colors[6] = {0.2f, 0.4f, 1, 1, 0.6f, 0.2f}, opacity[2] = {0.0f, 0.8f};
  static const float up[3] = {0, 1, 0}, dir[3] = {0, 0, -1}, background[4] = {0, 0, 0, 0};
  ANARIDataType color_type = ANARI_UFIXED8_VEC4;
  unsigned frame_size[2];
  VolumeView v;
  frame_size[0] = frame_size[1] = size;
  v.tf_color = anariNewArray1D(dev, colors, NULL, NULL, ANARI_FLOAT32_VEC3, 2);
  v.tf_opacity = anariNewArray1D(dev, opacity, NULL, NULL, ANARI_FLOAT32, 2);
  v.volume = anariNewVolume(dev, "transferFunction1D");
  anariSetParameter(dev, v.volume, "value", ANARI_SPATIAL_FIELD, &field);
  anariSetParameter(dev, v.volume, "color", ANARI_ARRAY1D, &v.tf_color);
  anariSetParameter(dev, v.volume, "opacity", ANARI_ARRAY1D, &v.tf_opacity);
  anariSetParameter(dev, v.volume, "valueRange", ANARI_FLOAT32_BOX1, range);
  anariCommitParameters(dev, v.volume);
  v.volumes = anariNewArray1D(dev, &v.volume, NULL, NULL, ANARI_VOLUME, 1);
  v.world = anariNewWorld(dev);
  anariSetParameter(dev, v.world, "volume", ANARI_ARRAY1D, &v.volumes);
  anariCommitParameters(dev, v.world);
  v.renderer = anariNewRenderer(dev, "default");
  anariSetParameter(dev, v.renderer, "background", ANARI_FLOAT32_VEC4, background);
  anariCommitParameters(dev, v.renderer);
  v.camera = anariNewCamera(dev, "perspective");
  anariSetParameter(dev, v.camera, "position", ANARI_FLOAT32_VEC3, eye);
  anariSetParameter(dev, v.camera, "direction", ANARI_FLOAT32_VEC3, dir);
  anariSetParameter(dev, v.camera, "up", ANARI_FLOAT32_VEC3, up);
  anariCommitParameters(dev, v.camera);
  v.frame = anariNewFrame(dev);
  anariSetParameter(dev, v.frame, "size", ANARI_UINT32_VEC2, frame_size);
  anariSetParameter(dev, v.frame, "channel.color", ANARI_DATA_TYPE, &color_type);
  anariSetParameter(dev, v.frame, "world", ANARI_WORLD, &v.world);
  anariSetParameter(dev, v.frame, "renderer", ANARI_RENDERER, &v.renderer);
  anariSetParameter(dev, v.frame, "camera", ANARI_CAMERA, &v.camera);
  anariCommitParameters(dev, v.frame);
  return v;
}

static void volume_view_release(ANARIDevice dev, VolumeView *v)
{
  anariRelease(dev, v->tf_color);
  anariRelease(dev, v->tf_opacity);
  anariRelease(dev, v->volumes);
  anariRelease(dev, v->volume);
  anariRelease(dev, v->world);
  anariRelease(dev, v->renderer);
  anariRelease(dev, v->camera);
  anariRelease(dev, v->frame);
}

/* RGBA8 pixels of one render of `frame` (size x size) into `out`. */
static int render_rgba(ANARIDevice dev, ANARIFrame frame, unsigned size, uint8_t *out)
{
  uint32_t w = 0, h = 0;
  ANARIDataType type;
  const uint8_t *p;
  anariRenderFrame(dev, frame);
  anariFrameReady(dev, frame, ANARI_WAIT);
  p = anariMapFrame(dev, frame, "channel.color", &w, &h, &type);
  if (!p || w != size || h != size)
    return 0;
  memcpy(out, p, 4 * (size_t)size * size);
  anariUnmapFrame(dev, frame, "channel.color");
  return 1;
}

/* Pixels of columns x0..x1 whose alpha shows (above 40 of 255). */
static int lit_columns(const uint8_t *p, unsigned size, unsigned x0, unsigned x1)
{
  int n = 0;
  unsigned x, y;
  for (y = 0; y < size; ++y)
    for (x = x0; x < x1; ++x)
      if (p[4 * (y * size + x) + 3] > 40)
        n++;
  return n;
}

#endif
