/*
 * caveray's extensions to ANARI: extension names, the "matrix" and
 * "offAxis" cameras, renderer shading parameters, and plain C helpers for
 * hosts that drive ANARI's perspective camera on CAVE walls.
 *
 * Cameras (anariNewCamera(device, subtype)):
 *   "matrix"   view, proj: ANARI_FLOAT32_MAT4, column-major OpenGL matrices
 *              (NDC z in [-1, 1]), exactly what a CAVE host already has for
 *              each wall and eye. Advertised as ANARI_VSNRAY_CAMERA_MATRIX
 *              (the same names as anari-visionaray) and ANARI_CAVERAY_CAMERA_MATRIX.
 *   "offAxis"  lowerLeft, lowerRight, upperRight, eye: ANARI_FLOAT32_VEC3,
 *              the wall's corners and the tracked eye in world space.
 * Renderer "default", besides "background" (ANARI_FLOAT32_VEC4):
 *   "shading"              ANARI_STRING: none | shadows | ao | shadows+ao |
 *                          directional:N (N <= 64)
 *   "lightDirection"       ANARI_FLOAT32_VEC3, towards the light
 *   "stepFactor"           ANARI_FLOAT32, times half the smallest voxel
 *   "terminationThreshold" ANARI_FLOAT32, default 0.99
 * Device:
 *   "backend"  ANARI_STRING: auto (default) | gpu | cpu; the environment
 *              variable CAVERAY_BACKEND sets the default.
 *
 * Do not use the perspective camera's stereoMode on CAVE walls: shifting a
 * pinhole sideways is not the off-axis view of a wall. Give every eye of
 * every wall its own camera.
 */
#ifndef CAVERAY_CAVERAY_H
#define CAVERAY_CAVERAY_H

#include "anari.h"

#ifdef __cplusplus
extern "C" {
#endif

#define CAVERAY_EXTENSION_CAMERA_MATRIX_VSNRAY "ANARI_VSNRAY_CAMERA_MATRIX"
#define CAVERAY_EXTENSION_CAMERA_MATRIX "ANARI_CAVERAY_CAMERA_MATRIX"
#define CAVERAY_EXTENSION_CAMERA_OFF_AXIS "ANARI_CAVERAY_CAMERA_OFF_AXIS"
#define CAVERAY_EXTENSION_RENDERER_SHADING "ANARI_CAVERAY_RENDERER_SHADING"
/* Frames showing the two eyes of one wall render in one re-projection pass:
 * frame parameter "stereoPartner" (ANARI_FRAME), device parameter
 * "pairStereoFrames" (ANARI_BOOL, default true). */
#define CAVERAY_EXTENSION_FRAME_STEREO_PAIR "ANARI_CAVERAY_FRAME_STEREO_PAIR"
/* Frames that never keep a tracked display waiting: with frame parameter
 * "caveray.deadline" (ANARI_FLOAT32, milliseconds, 0 = off) set,
 * anariRenderFrame + anariFrameReady(ANARI_WAIT) return by the deadline with
 * the newest complete image warped to this render's camera, while the full
 * render goes on in the background. "caveray.warp" (ANARI_STRING: none,
 * quad, grid or layers; default quad) chooses the warp. Frame properties:
 * "caveray.imageAge" (ANARI_FLOAT32, ms from the call whose camera the shown
 * image was rendered for to this one; -1 where the frame shows its
 * background: before any image exists, or resized since and its warp
 * missed the deadline) and
 * "caveray.warp" (ANARI_STRING, the warp applied: none for the image of
 * this very camera). */
#define CAVERAY_EXTENSION_FRAME_DEADLINE "ANARI_CAVERAY_FRAME_DEADLINE"
/* The device as one rank of a data-parallel MPI job (a build with the mpi
 * feature): device parameter "caveray.mpi" (ANARI_STRING "world") joins the
 * job on a duplicate of MPI_COMM_WORLD, with the host's MPI (initialised at
 * MPI_THREAD_SERIALIZED or more) or initialising MPI itself (then
 * finalising it at exit). Each rank's world holds its part of the volumes
 * (a field of its brick with a one-voxel apron, placed by its origin) and
 * says which box of world space it owns: world parameter "caveray.region"
 * (ANARI_FLOAT32_BOX3; default the bounds of its volumes). Every rank
 * renders every frame, with the same camera (one view), in the same order;
 * each renders the samples in its box of the steps one renderer of all the
 * boxes would take, and the partial images are composited (direct-send) so
 * that every rank maps the whole frame. Volumes and color only: no depth or
 * hit channels, surfaces or deadline. A rank that cannot render a frame
 * says so in its exchanges, and every rank fails it. */
#define CAVERAY_EXTENSION_DEVICE_MPI "ANARI_CAVERAY_DEVICE_MPI"

/* The parameters of ANARI's "perspective" camera that show one wall from
 * one eye: a symmetric frustum widened to contain the wall, cropped back to
 * it by imageRegion. Set each field as the parameter of the same name
 * (position, direction, up: FLOAT32_VEC3; fovy, aspect: FLOAT32;
 * imageRegion: FLOAT32_BOX2 as min.x, min.y, max.x, max.y). */
typedef struct CaverayPinhole {
  float position[3];
  float direction[3];
  float up[3];
  float fovy;
  float aspect;
  float imageRegion[4];
} CaverayPinhole;

/* Off-axis strategy 2: the pinhole for a wall (three corners) and an eye.
 * Returns ANARI_STATUS_NO_ERROR, or ANARI_STATUS_INVALID_ARGUMENT for a
 * degenerate wall, an eye on or behind it, or non-finite input; then *out
 * is untouched and caverayLastError() says why. */
ANARIStatusCode caverayPinholeFromScreen(const float lowerLeft[3],
    const float lowerRight[3],
    const float upperRight[3],
    const float eye[3],
    CaverayPinhole *out);

/* Off-axis strategy 3: the pinhole recovered from a host's OpenGL view and
 * projection matrices (column-major): the eye is where the frustum's side
 * planes meet. Fails like the above for singular or non-perspective input. */
ANARIStatusCode caverayPinholeFromMatrices(
    const float view[16], const float proj[16], CaverayPinhole *out);

/* The OpenGL view and projection matrices (column-major) of a wall seen
 * from an eye, with clip distances 0 < nearClip < farClip: for the host's own
 * OpenGL pass, or for the "matrix" camera. */
ANARIStatusCode caverayMatricesFromScreen(const float lowerLeft[3],
    const float lowerRight[3],
    const float upperRight[3],
    const float eye[3],
    float nearClip,
    float farClip,
    float view[16],
    float proj[16]);

/* Why the last helper call on this thread failed; "" when it did not.
 * Valid until the next helper call on the same thread. */
const char *caverayLastError(void);

#ifdef __cplusplus
}
#endif

#endif /* CAVERAY_CAVERAY_H */
