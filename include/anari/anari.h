/*
 * caveray's own declaration of the Khronos ANARI 1.x C API.
 *
 * Names, values and signatures match the ANARI SDK (loader protocol 0.14 and
 * later), so existing C and C++ hosts compile unchanged against this header.
 * Link with -lanari_library_caveray.
 *
 * Conventions worth knowing when filling parameters:
 *   - scalars and vectors are passed by pointer, STRING and VOID_POINTER by
 *     value, object parameters as a pointer to the handle;
 *   - ANARI_BOOL is one byte (non-zero is true);
 *   - matrices (ANARI_FLOAT32_MAT4) are column-major;
 *   - the first pixel of a mapped frame is the lower-left one.
 */
#ifndef CAVERAY_ANARI_ANARI_H
#define CAVERAY_ANARI_ANARI_H

#include <stddef.h>
#include <stdint.h>

/* Default arguments exist only in C++; C hosts always pass every argument. */
#ifdef __cplusplus
#define CAVERAY_ANARI_DEFAULT(x) = x
#else
#define CAVERAY_ANARI_DEFAULT(x)
#endif

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Handles ---- */

#ifdef __cplusplus
/*
 * In C++ every handle is a pointer into this hierarchy, so a camera (or the
 * device itself) converts implicitly to ANARIObject and a 1D array to
 * ANARIArray, while unrelated handles still refuse to mix.
 */
typedef struct anari_library_ {} *ANARILibrary;
typedef struct anari_object_ {} *ANARIObject;
typedef struct anari_device_ : anari_object_ {} *ANARIDevice;
typedef struct anari_array_ : anari_object_ {} *ANARIArray;
typedef struct anari_array1d_ : anari_array_ {} *ANARIArray1D;
typedef struct anari_array2d_ : anari_array_ {} *ANARIArray2D;
typedef struct anari_array3d_ : anari_array_ {} *ANARIArray3D;
typedef struct anari_camera_ : anari_object_ {} *ANARICamera;
typedef struct anari_frame_ : anari_object_ {} *ANARIFrame;
typedef struct anari_geometry_ : anari_object_ {} *ANARIGeometry;
typedef struct anari_group_ : anari_object_ {} *ANARIGroup;
typedef struct anari_instance_ : anari_object_ {} *ANARIInstance;
typedef struct anari_light_ : anari_object_ {} *ANARILight;
typedef struct anari_material_ : anari_object_ {} *ANARIMaterial;
typedef struct anari_renderer_ : anari_object_ {} *ANARIRenderer;
typedef struct anari_surface_ : anari_object_ {} *ANARISurface;
typedef struct anari_sampler_ : anari_object_ {} *ANARISampler;
typedef struct anari_spatial_field_ : anari_object_ {} *ANARISpatialField;
typedef struct anari_volume_ : anari_object_ {} *ANARIVolume;
typedef struct anari_world_ : anari_object_ {} *ANARIWorld;
#else
/* C has no upcasts, so every handle is void * and any handle fits any slot. */
typedef void *ANARILibrary;
typedef void *ANARIDevice;
typedef void *ANARIObject;
typedef void *ANARIArray;
typedef void *ANARIArray1D;
typedef void *ANARIArray2D;
typedef void *ANARIArray3D;
typedef void *ANARICamera;
typedef void *ANARIFrame;
typedef void *ANARIGeometry;
typedef void *ANARIGroup;
typedef void *ANARIInstance;
typedef void *ANARILight;
typedef void *ANARIMaterial;
typedef void *ANARIRenderer;
typedef void *ANARISurface;
typedef void *ANARISampler;
typedef void *ANARISpatialField;
typedef void *ANARIVolume;
typedef void *ANARIWorld;
#endif

/* ---- Enumerations: macros, so #ifdef checks in hosts keep working ---- */

typedef int ANARIDataType;
typedef int ANARIStatusSeverity;
typedef int ANARIStatusCode;
typedef unsigned int ANARIWaitMask;

#define ANARI_NO_WAIT 0
#define ANARI_WAIT 1

#define ANARI_SEVERITY_FATAL_ERROR 1
#define ANARI_SEVERITY_ERROR 2
#define ANARI_SEVERITY_WARNING 3
#define ANARI_SEVERITY_PERFORMANCE_WARNING 4
#define ANARI_SEVERITY_INFO 5
#define ANARI_SEVERITY_DEBUG 6

#define ANARI_STATUS_NO_ERROR 0
#define ANARI_STATUS_UNKNOWN_ERROR 1
#define ANARI_STATUS_INVALID_ARGUMENT 2
#define ANARI_STATUS_INVALID_OPERATION 3
#define ANARI_STATUS_OUT_OF_MEMORY 4
#define ANARI_STATUS_UNSUPPORTED_DEVICE 5
#define ANARI_STATUS_VERSION_MISMATCH 6

/* Data types: all of the ANARI SDK's, with its numbers. A vector type is
 * its scalar's value plus (components - 1). */
#define ANARI_UNKNOWN 0
#define ANARI_DATA_TYPE 100
#define ANARI_STRING 101
#define ANARI_VOID_POINTER 102
#define ANARI_BOOL 103 /* one byte */
#define ANARI_STRING_LIST 150
#define ANARI_DATA_TYPE_LIST 151
#define ANARI_PARAMETER_LIST 152

#define ANARI_FUNCTION_POINTER 200
#define ANARI_MEMORY_DELETER 201
#define ANARI_STATUS_CALLBACK 202
#define ANARI_FRAME_COMPLETION_CALLBACK 203

#define ANARI_LIBRARY 500
#define ANARI_DEVICE 501
#define ANARI_OBJECT 502
#define ANARI_ARRAY 503
#define ANARI_ARRAY1D 504
#define ANARI_ARRAY2D 505
#define ANARI_ARRAY3D 506
#define ANARI_CAMERA 507
#define ANARI_FRAME 508
#define ANARI_GEOMETRY 509
#define ANARI_GROUP 510
#define ANARI_INSTANCE 511
#define ANARI_LIGHT 512
#define ANARI_MATERIAL 513
#define ANARI_RENDERER 514
#define ANARI_SURFACE 515
#define ANARI_SAMPLER 516
#define ANARI_SPATIAL_FIELD 517
#define ANARI_VOLUME 518
#define ANARI_WORLD 519

#define ANARI_INT8 1000
#define ANARI_INT8_VEC2 1001
#define ANARI_INT8_VEC3 1002
#define ANARI_INT8_VEC4 1003
#define ANARI_UINT8 1004
#define ANARI_UINT8_VEC2 1005
#define ANARI_UINT8_VEC3 1006
#define ANARI_UINT8_VEC4 1007
#define ANARI_INT16 1008
#define ANARI_INT16_VEC2 1009
#define ANARI_INT16_VEC3 1010
#define ANARI_INT16_VEC4 1011
#define ANARI_UINT16 1012
#define ANARI_UINT16_VEC2 1013
#define ANARI_UINT16_VEC3 1014
#define ANARI_UINT16_VEC4 1015
#define ANARI_INT32 1016
#define ANARI_INT32_VEC2 1017
#define ANARI_INT32_VEC3 1018
#define ANARI_INT32_VEC4 1019
#define ANARI_UINT32 1020
#define ANARI_UINT32_VEC2 1021
#define ANARI_UINT32_VEC3 1022
#define ANARI_UINT32_VEC4 1023
#define ANARI_INT64 1024
#define ANARI_INT64_VEC2 1025
#define ANARI_INT64_VEC3 1026
#define ANARI_INT64_VEC4 1027
#define ANARI_UINT64 1028
#define ANARI_UINT64_VEC2 1029
#define ANARI_UINT64_VEC3 1030
#define ANARI_UINT64_VEC4 1031
/* Fixed-point types map to [0,1] (unsigned) or [-1,1] (signed). */
#define ANARI_FIXED8 1032
#define ANARI_FIXED8_VEC2 1033
#define ANARI_FIXED8_VEC3 1034
#define ANARI_FIXED8_VEC4 1035
#define ANARI_UFIXED8 1036
#define ANARI_UFIXED8_VEC2 1037
#define ANARI_UFIXED8_VEC3 1038
#define ANARI_UFIXED8_VEC4 1039
#define ANARI_FIXED16 1040
#define ANARI_FIXED16_VEC2 1041
#define ANARI_FIXED16_VEC3 1042
#define ANARI_FIXED16_VEC4 1043
#define ANARI_UFIXED16 1044
#define ANARI_UFIXED16_VEC2 1045
#define ANARI_UFIXED16_VEC3 1046
#define ANARI_UFIXED16_VEC4 1047
#define ANARI_FIXED32 1048
#define ANARI_FIXED32_VEC2 1049
#define ANARI_FIXED32_VEC3 1050
#define ANARI_FIXED32_VEC4 1051
#define ANARI_UFIXED32 1052
#define ANARI_UFIXED32_VEC2 1053
#define ANARI_UFIXED32_VEC3 1054
#define ANARI_UFIXED32_VEC4 1055
#define ANARI_FIXED64 1056
#define ANARI_FIXED64_VEC2 1057
#define ANARI_FIXED64_VEC3 1058
#define ANARI_FIXED64_VEC4 1059
#define ANARI_UFIXED64 1060
#define ANARI_UFIXED64_VEC2 1061
#define ANARI_UFIXED64_VEC3 1062
#define ANARI_UFIXED64_VEC4 1063
#define ANARI_FLOAT16 1064 /* IEEE 754 binary16 */
#define ANARI_FLOAT16_VEC2 1065
#define ANARI_FLOAT16_VEC3 1066
#define ANARI_FLOAT16_VEC4 1067
#define ANARI_FLOAT32 1068
#define ANARI_FLOAT32_VEC2 1069
#define ANARI_FLOAT32_VEC3 1070
#define ANARI_FLOAT32_VEC4 1071
#define ANARI_FLOAT64 1072
#define ANARI_FLOAT64_VEC2 1073
#define ANARI_FLOAT64_VEC3 1074
#define ANARI_FLOAT64_VEC4 1075

#define ANARI_UFIXED8_R_SRGB 2000
#define ANARI_UFIXED8_RA_SRGB 2001
#define ANARI_UFIXED8_RGB_SRGB 2002
#define ANARI_UFIXED8_RGBA_SRGB 2003
#define ANARI_INT32_BOX1 2004
#define ANARI_INT32_BOX2 2005
#define ANARI_INT32_BOX3 2006
#define ANARI_INT32_BOX4 2007
#define ANARI_FLOAT32_BOX1 2008
#define ANARI_FLOAT32_BOX2 2009
#define ANARI_FLOAT32_BOX3 2010
#define ANARI_FLOAT32_BOX4 2011
#define ANARI_FLOAT32_MAT2 2012
#define ANARI_FLOAT32_MAT3 2013
#define ANARI_FLOAT32_MAT4 2014 /* column-major */
#define ANARI_FLOAT32_MAT2x3 2015
#define ANARI_FLOAT32_MAT3x4 2016
#define ANARI_FLOAT32_QUAT_IJKW 2017 /* i, j, k, then w */

#define ANARI_UINT64_REGION1 2104
#define ANARI_UINT64_REGION2 2105
#define ANARI_UINT64_REGION3 2106
#define ANARI_UINT64_REGION4 2107

#define ANARI_FLOAT64_BOX1 2208
#define ANARI_FLOAT64_BOX2 2209
#define ANARI_FLOAT64_BOX3 2210
#define ANARI_FLOAT64_BOX4 2211

/* ---- Callbacks and parameter records ---- */

typedef void (*ANARIStatusCallback)(const void *userPtr, ANARIDevice device,
    ANARIObject source, ANARIDataType sourceType, ANARIStatusSeverity severity,
    ANARIStatusCode code, const char *message);

/* Called once the device no longer needs memory shared via anariNewArray*. */
typedef void (*ANARIMemoryDeleter)(const void *userPtr, const void *appMemory);

typedef void (*ANARIFrameCompletionCallback)(const void *userPtr,
    ANARIDevice device, ANARIFrame frame);

/* Initial device parameters for anariNewInitializedDevice. */
typedef struct ANARIParameterValue {
  const char *name;
  ANARIDataType type;
  const void *value;
} ANARIParameterValue;

typedef struct ANARIParameter {
  const char *name;
  ANARIDataType type;
} ANARIParameter;

/* ---- Library ---- */

/* Via the SDK loader, "caveray" opens libanari_library_caveray and
 * "environment" reads $ANARI_LIBRARY. */
ANARILibrary anariLoadLibrary(const char *name,
    ANARIStatusCallback statusCallback CAVERAY_ANARI_DEFAULT(0),
    const void *statusCallbackUserData CAVERAY_ANARI_DEFAULT(0));
void anariUnloadLibrary(ANARILibrary library);

void anariLoadModule(ANARILibrary library, const char *name);
void anariUnloadModule(ANARILibrary library, const char *name);

/* ---- Device ---- */

/* The device is itself an object: it takes parameters, and
 * anariRelease(dev, dev) releases it. */
ANARIDevice anariNewDevice(ANARILibrary library, const char *deviceSubtype);
ANARIDevice anariNewInitializedDevice(ANARILibrary library,
    const char *deviceSubtype, const ANARIParameterValue *parameters);

const char **anariGetDeviceSubtypes(ANARILibrary library);
const char **anariGetDeviceExtensions(ANARILibrary library,
    const char *deviceSubtype);

/* ---- Arrays ---- */

/* deleter (with userData) is how the device hands appMemory back. */
ANARIArray1D anariNewArray1D(ANARIDevice device, const void *appMemory,
    ANARIMemoryDeleter deleter, const void *userData, ANARIDataType dataType,
    uint64_t numItems1);
ANARIArray2D anariNewArray2D(ANARIDevice device, const void *appMemory,
    ANARIMemoryDeleter deleter, const void *userData, ANARIDataType dataType,
    uint64_t numItems1, uint64_t numItems2);
/* x varies fastest, matching structuredRegular field data. */
ANARIArray3D anariNewArray3D(ANARIDevice device, const void *appMemory,
    ANARIMemoryDeleter deleter, const void *userData, ANARIDataType dataType,
    uint64_t numItems1, uint64_t numItems2, uint64_t numItems3);

void *anariMapArray(ANARIDevice device, ANARIArray array);
void anariUnmapArray(ANARIDevice device, ANARIArray array);

/* ---- Objects ---- */

/* Unknown subtypes still yield an object (and a warning); it renders
 * nothing and never crashes. */
ANARILight anariNewLight(ANARIDevice device, const char *type);
ANARICamera anariNewCamera(ANARIDevice device, const char *type);
ANARIGeometry anariNewGeometry(ANARIDevice device, const char *type);
ANARISpatialField anariNewSpatialField(ANARIDevice device, const char *type);
ANARIVolume anariNewVolume(ANARIDevice device, const char *type);
ANARIMaterial anariNewMaterial(ANARIDevice device, const char *type);
ANARISampler anariNewSampler(ANARIDevice device, const char *type);
ANARIInstance anariNewInstance(ANARIDevice device, const char *type);
ANARIRenderer anariNewRenderer(ANARIDevice device, const char *type);

ANARISurface anariNewSurface(ANARIDevice device);
ANARIGroup anariNewGroup(ANARIDevice device);
ANARIWorld anariNewWorld(ANARIDevice device);
ANARIFrame anariNewFrame(ANARIDevice device);

/* Generic constructor for extension object types. */
ANARIObject anariNewObject(ANARIDevice device, const char *objectType,
    const char *type);

/* Also used for the device itself: anariRelease(dev, dev). */
void anariRelease(ANARIDevice device, ANARIObject object);
void anariRetain(ANARIDevice device, ANARIObject object);

/* ---- Parameters ---- */

/* mem points at the value, except for STRING and VOID_POINTER where mem is the
 * value itself; object parameters pass a pointer to the handle. */
void anariSetParameter(ANARIDevice device, ANARIObject object,
    const char *name, ANARIDataType dataType, const void *mem);
void anariUnsetParameter(ANARIDevice device, ANARIObject object,
    const char *name);
void anariUnsetAllParameters(ANARIDevice device, ANARIObject object);

/* Map an array parameter directly; elementStride receives the stride. */
void *anariMapParameterArray1D(ANARIDevice device, ANARIObject object,
    const char *name, ANARIDataType dataType, uint64_t numElements1,
    uint64_t *elementStride);
void *anariMapParameterArray2D(ANARIDevice device, ANARIObject object,
    const char *name, ANARIDataType dataType, uint64_t numElements1,
    uint64_t numElements2, uint64_t *elementStride);
void *anariMapParameterArray3D(ANARIDevice device, ANARIObject object,
    const char *name, ANARIDataType dataType, uint64_t numElements1,
    uint64_t numElements2, uint64_t numElements3, uint64_t *elementStride);
void anariUnmapParameterArray(ANARIDevice device, ANARIObject object,
    const char *name);

void anariCommitParameters(ANARIDevice device, ANARIObject object);

/* ---- Introspection and properties ---- */

/* Subtype lists, object info and parameter info, as the SDK exposes them. */
const char **anariGetObjectSubtypes(ANARIDevice device,
    ANARIDataType objectType);
const void *anariGetObjectInfo(ANARIDevice device, ANARIDataType objectType,
    const char *objectSubtype, const char *infoName, ANARIDataType infoType);
const void *anariGetParameterInfo(ANARIDevice device, ANARIDataType objectType,
    const char *objectSubtype, const char *parameterName,
    ANARIDataType parameterType, const char *infoName, ANARIDataType infoType);

/*
 * size is the byte size of mem. Device properties:
 * "version" (INT32), "extension" (STRING_LIST), "geometryMaxIndex" (UINT64);
 * frame: "duration" (FLOAT32 seconds of the last render).
 */
int anariGetProperty(ANARIDevice device, ANARIObject object, const char *name,
    ANARIDataType dataType, void *mem, uint64_t size, ANARIWaitMask mask);

/* ---- Frames ---- */

/* mask is ANARI_NO_WAIT (poll) or ANARI_WAIT. */
void anariRenderFrame(ANARIDevice device, ANARIFrame frame);
int anariFrameReady(ANARIDevice device, ANARIFrame frame, ANARIWaitMask mask);
void anariDiscardFrame(ANARIDevice device, ANARIFrame frame);

/* channel is e.g. "channel.color" or "channel.depth"; the first pixel is
 * the lower-left one. */
const void *anariMapFrame(ANARIDevice device, ANARIFrame frame,
    const char *channel, uint32_t *width, uint32_t *height,
    ANARIDataType *pixelType);
void anariUnmapFrame(ANARIDevice device, ANARIFrame frame, const char *channel);

#ifdef __cplusplus
} /* extern "C" */
#endif

#undef CAVERAY_ANARI_DEFAULT

#endif /* CAVERAY_ANARI_ANARI_H */
