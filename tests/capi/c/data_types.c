/* Every ANARIDataType the ANARI SDK 0.17 header declares, by name and
 * value: a host written against the SDK's header builds against caveray's
 * (a name missing here is a compile error) with the same numbers, and the
 * device takes or refuses each type by its name. An array of one element
 * of every value type is made (where no caveray parameter reads such
 * arrays, the warning names the type), and a parameter of every type but
 * the declared one is refused, the message naming both. Prints PASS/FAIL
 * per check; exit status 1 on any FAIL. */
#include <anari/anari.h>

#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "expect.h"

static const struct {
  const char *name;
  ANARIDataType code;
  int sdk;
} TYPES[] = {
    {"ANARI_UNKNOWN", ANARI_UNKNOWN, 0},
    {"ANARI_DATA_TYPE", ANARI_DATA_TYPE, 100},
    {"ANARI_STRING", ANARI_STRING, 101},
    {"ANARI_VOID_POINTER", ANARI_VOID_POINTER, 102},
    {"ANARI_BOOL", ANARI_BOOL, 103},
    {"ANARI_STRING_LIST", ANARI_STRING_LIST, 150},
    {"ANARI_DATA_TYPE_LIST", ANARI_DATA_TYPE_LIST, 151},
    {"ANARI_PARAMETER_LIST", ANARI_PARAMETER_LIST, 152},
    {"ANARI_FUNCTION_POINTER", ANARI_FUNCTION_POINTER, 200},
    {"ANARI_MEMORY_DELETER", ANARI_MEMORY_DELETER, 201},
    {"ANARI_STATUS_CALLBACK", ANARI_STATUS_CALLBACK, 202},
    {"ANARI_FRAME_COMPLETION_CALLBACK", ANARI_FRAME_COMPLETION_CALLBACK, 203},
    {"ANARI_LIBRARY", ANARI_LIBRARY, 500},
    {"ANARI_DEVICE", ANARI_DEVICE, 501},
    {"ANARI_OBJECT", ANARI_OBJECT, 502},
    {"ANARI_ARRAY", ANARI_ARRAY, 503},
    {"ANARI_ARRAY1D", ANARI_ARRAY1D, 504},
    {"ANARI_ARRAY2D", ANARI_ARRAY2D, 505},
    {"ANARI_ARRAY3D", ANARI_ARRAY3D, 506},
    {"ANARI_CAMERA", ANARI_CAMERA, 507},
    {"ANARI_FRAME", ANARI_FRAME, 508},
    {"ANARI_GEOMETRY", ANARI_GEOMETRY, 509},
    {"ANARI_GROUP", ANARI_GROUP, 510},
    {"ANARI_INSTANCE", ANARI_INSTANCE, 511},
    {"ANARI_LIGHT", ANARI_LIGHT, 512},
    {"ANARI_MATERIAL", ANARI_MATERIAL, 513},
    {"ANARI_RENDERER", ANARI_RENDERER, 514},
    {"ANARI_SURFACE", ANARI_SURFACE, 515},
    {"ANARI_SAMPLER", ANARI_SAMPLER, 516},
    {"ANARI_SPATIAL_FIELD", ANARI_SPATIAL_FIELD, 517},
    {"ANARI_VOLUME", ANARI_VOLUME, 518},
    {"ANARI_WORLD", ANARI_WORLD, 519},
    {"ANARI_INT8", ANARI_INT8, 1000},
    {"ANARI_INT8_VEC2", ANARI_INT8_VEC2, 1001},
    {"ANARI_INT8_VEC3", ANARI_INT8_VEC3, 1002},
    {"ANARI_INT8_VEC4", ANARI_INT8_VEC4, 1003},
    {"ANARI_UINT8", ANARI_UINT8, 1004},
    {"ANARI_UINT8_VEC2", ANARI_UINT8_VEC2, 1005},
    {"ANARI_UINT8_VEC3", ANARI_UINT8_VEC3, 1006},
    {"ANARI_UINT8_VEC4", ANARI_UINT8_VEC4, 1007},
    {"ANARI_INT16", ANARI_INT16, 1008},
    {"ANARI_INT16_VEC2", ANARI_INT16_VEC2, 1009},
    {"ANARI_INT16_VEC3", ANARI_INT16_VEC3, 1010},
    {"ANARI_INT16_VEC4", ANARI_INT16_VEC4, 1011},
    {"ANARI_UINT16", ANARI_UINT16, 1012},
    {"ANARI_UINT16_VEC2", ANARI_UINT16_VEC2, 1013},
    {"ANARI_UINT16_VEC3", ANARI_UINT16_VEC3, 1014},
    {"ANARI_UINT16_VEC4", ANARI_UINT16_VEC4, 1015},
    {"ANARI_INT32", ANARI_INT32, 1016},
    {"ANARI_INT32_VEC2", ANARI_INT32_VEC2, 1017},
    {"ANARI_INT32_VEC3", ANARI_INT32_VEC3, 1018},
    {"ANARI_INT32_VEC4", ANARI_INT32_VEC4, 1019},
    {"ANARI_UINT32", ANARI_UINT32, 1020},
    {"ANARI_UINT32_VEC2", ANARI_UINT32_VEC2, 1021},
    {"ANARI_UINT32_VEC3", ANARI_UINT32_VEC3, 1022},
    {"ANARI_UINT32_VEC4", ANARI_UINT32_VEC4, 1023},
    {"ANARI_INT64", ANARI_INT64, 1024},
    {"ANARI_INT64_VEC2", ANARI_INT64_VEC2, 1025},
    {"ANARI_INT64_VEC3", ANARI_INT64_VEC3, 1026},
    {"ANARI_INT64_VEC4", ANARI_INT64_VEC4, 1027},
    {"ANARI_UINT64", ANARI_UINT64, 1028},
    {"ANARI_UINT64_VEC2", ANARI_UINT64_VEC2, 1029},
    {"ANARI_UINT64_VEC3", ANARI_UINT64_VEC3, 1030},
    {"ANARI_UINT64_VEC4", ANARI_UINT64_VEC4, 1031},
    {"ANARI_FIXED8", ANARI_FIXED8, 1032},
    {"ANARI_FIXED8_VEC2", ANARI_FIXED8_VEC2, 1033},
    {"ANARI_FIXED8_VEC3", ANARI_FIXED8_VEC3, 1034},
    {"ANARI_FIXED8_VEC4", ANARI_FIXED8_VEC4, 1035},
    {"ANARI_UFIXED8", ANARI_UFIXED8, 1036},
    {"ANARI_UFIXED8_VEC2", ANARI_UFIXED8_VEC2, 1037},
    {"ANARI_UFIXED8_VEC3", ANARI_UFIXED8_VEC3, 1038},
    {"ANARI_UFIXED8_VEC4", ANARI_UFIXED8_VEC4, 1039},
    {"ANARI_FIXED16", ANARI_FIXED16, 1040},
    {"ANARI_FIXED16_VEC2", ANARI_FIXED16_VEC2, 1041},
    {"ANARI_FIXED16_VEC3", ANARI_FIXED16_VEC3, 1042},
    {"ANARI_FIXED16_VEC4", ANARI_FIXED16_VEC4, 1043},
    {"ANARI_UFIXED16", ANARI_UFIXED16, 1044},
    {"ANARI_UFIXED16_VEC2", ANARI_UFIXED16_VEC2, 1045},
    {"ANARI_UFIXED16_VEC3", ANARI_UFIXED16_VEC3, 1046},
    {"ANARI_UFIXED16_VEC4", ANARI_UFIXED16_VEC4, 1047},
    {"ANARI_FIXED32", ANARI_FIXED32, 1048},
    {"ANARI_FIXED32_VEC2", ANARI_FIXED32_VEC2, 1049},
    {"ANARI_FIXED32_VEC3", ANARI_FIXED32_VEC3, 1050},
    {"ANARI_FIXED32_VEC4", ANARI_FIXED32_VEC4, 1051},
    {"ANARI_UFIXED32", ANARI_UFIXED32, 1052},
    {"ANARI_UFIXED32_VEC2", ANARI_UFIXED32_VEC2, 1053},
    {"ANARI_UFIXED32_VEC3", ANARI_UFIXED32_VEC3, 1054},
    {"ANARI_UFIXED32_VEC4", ANARI_UFIXED32_VEC4, 1055},
    {"ANARI_FIXED64", ANARI_FIXED64, 1056},
    {"ANARI_FIXED64_VEC2", ANARI_FIXED64_VEC2, 1057},
    {"ANARI_FIXED64_VEC3", ANARI_FIXED64_VEC3, 1058},
    {"ANARI_FIXED64_VEC4", ANARI_FIXED64_VEC4, 1059},
    {"ANARI_UFIXED64", ANARI_UFIXED64, 1060},
    {"ANARI_UFIXED64_VEC2", ANARI_UFIXED64_VEC2, 1061},
    {"ANARI_UFIXED64_VEC3", ANARI_UFIXED64_VEC3, 1062},
    {"ANARI_UFIXED64_VEC4", ANARI_UFIXED64_VEC4, 1063},
    {"ANARI_FLOAT16", ANARI_FLOAT16, 1064},
    {"ANARI_FLOAT16_VEC2", ANARI_FLOAT16_VEC2, 1065},
    {"ANARI_FLOAT16_VEC3", ANARI_FLOAT16_VEC3, 1066},
    {"ANARI_FLOAT16_VEC4", ANARI_FLOAT16_VEC4, 1067},
    {"ANARI_FLOAT32", ANARI_FLOAT32, 1068},
    {"ANARI_FLOAT32_VEC2", ANARI_FLOAT32_VEC2, 1069},
    {"ANARI_FLOAT32_VEC3", ANARI_FLOAT32_VEC3, 1070},
    {"ANARI_FLOAT32_VEC4", ANARI_FLOAT32_VEC4, 1071},
    {"ANARI_FLOAT64", ANARI_FLOAT64, 1072},
    {"ANARI_FLOAT64_VEC2", ANARI_FLOAT64_VEC2, 1073},
    {"ANARI_FLOAT64_VEC3", ANARI_FLOAT64_VEC3, 1074},
    {"ANARI_FLOAT64_VEC4", ANARI_FLOAT64_VEC4, 1075},
    {"ANARI_UFIXED8_R_SRGB", ANARI_UFIXED8_R_SRGB, 2000},
    {"ANARI_UFIXED8_RA_SRGB", ANARI_UFIXED8_RA_SRGB, 2001},
    {"ANARI_UFIXED8_RGB_SRGB", ANARI_UFIXED8_RGB_SRGB, 2002},
    {"ANARI_UFIXED8_RGBA_SRGB", ANARI_UFIXED8_RGBA_SRGB, 2003},
    {"ANARI_INT32_BOX1", ANARI_INT32_BOX1, 2004},
    {"ANARI_INT32_BOX2", ANARI_INT32_BOX2, 2005},
    {"ANARI_INT32_BOX3", ANARI_INT32_BOX3, 2006},
    {"ANARI_INT32_BOX4", ANARI_INT32_BOX4, 2007},
    {"ANARI_FLOAT32_BOX1", ANARI_FLOAT32_BOX1, 2008},
    {"ANARI_FLOAT32_BOX2", ANARI_FLOAT32_BOX2, 2009},
    {"ANARI_FLOAT32_BOX3", ANARI_FLOAT32_BOX3, 2010},
    {"ANARI_FLOAT32_BOX4", ANARI_FLOAT32_BOX4, 2011},
    {"ANARI_FLOAT32_MAT2", ANARI_FLOAT32_MAT2, 2012},
    {"ANARI_FLOAT32_MAT3", ANARI_FLOAT32_MAT3, 2013},
    {"ANARI_FLOAT32_MAT4", ANARI_FLOAT32_MAT4, 2014},
    {"ANARI_FLOAT32_MAT2x3", ANARI_FLOAT32_MAT2x3, 2015},
    {"ANARI_FLOAT32_MAT3x4", ANARI_FLOAT32_MAT3x4, 2016},
    {"ANARI_FLOAT32_QUAT_IJKW", ANARI_FLOAT32_QUAT_IJKW, 2017},
    {"ANARI_UINT64_REGION1", ANARI_UINT64_REGION1, 2104},
    {"ANARI_UINT64_REGION2", ANARI_UINT64_REGION2, 2105},
    {"ANARI_UINT64_REGION3", ANARI_UINT64_REGION3, 2106},
    {"ANARI_UINT64_REGION4", ANARI_UINT64_REGION4, 2107},
    {"ANARI_FLOAT64_BOX1", ANARI_FLOAT64_BOX1, 2208},
    {"ANARI_FLOAT64_BOX2", ANARI_FLOAT64_BOX2, 2209},
    {"ANARI_FLOAT64_BOX3", ANARI_FLOAT64_BOX3, 2210},
    {"ANARI_FLOAT64_BOX4", ANARI_FLOAT64_BOX4, 2211},
};

/* Whether `message` names type `name` itself, not one whose name only
 * begins with it (ANARI_INT8 in ANARI_INT8_VEC4). */
static int names(const char *message, const char *name)
{
  size_t n = strlen(name);
  const char *at;
  for (at = strstr(message, name); at; at = strstr(at + 1, name)) {
    char next = at[n];
    if (!(next == '_' || (next >= 'A' && next <= 'Z') || (next >= 'a' && next <= 'z')
            || (next >= '0' && next <= '9')))
      return 1;
  }
  return 0;
}

/* Values a parameter or an array element is handed: fixed-size types,
 * handles and pointers all fit in 64 bytes. */
static int is_value_type(int code)
{
  return code == ANARI_DATA_TYPE || code == ANARI_BOOL || code >= 1000;
}

int main(void)
{
  static unsigned char zeros[64];
  char what[256];
  size_t i, n = sizeof TYPES / sizeof TYPES[0];
  int value_types = 0;
  ANARILibrary lib = anariLoadLibrary("caveray", on_status, NULL);
  ANARIDevice dev = lib ? anariNewDevice(lib, "default") : NULL;
  ANARIRenderer renderer;
  if (!dev) {
    printf("FAIL no caveray device\n");
    return 1;
  }
  renderer = anariNewRenderer(dev, "default");
  check("the SDK's 134 data types", n == 134);
  reset();
  for (i = 0; i < n; ++i) {
    const char *name = TYPES[i].name;
    ANARIDataType code = TYPES[i].code;
    snprintf(what, sizeof what, "%s is %d as in the SDK", name, TYPES[i].sdk);
    check(what, code == TYPES[i].sdk);
    if (!is_value_type(code))
      continue;
    value_types++;
    {
      ANARIArray1D array = anariNewArray1D(dev, NULL, NULL, NULL, code, 1);
      int named = seen.count == 0 || names(seen.message, name);
      snprintf(what, sizeof what, "an array of %s is made, any warning naming it", name);
      check(what, array != NULL && named);
      if (!named)
        printf("     %s\n", seen.message);
      reset();
      if (array)
        anariRelease(dev, array);
    }
    anariSetParameter(dev, renderer, "volumeSamplingRate", code, zeros);
    snprintf(what, sizeof what, "volumeSamplingRate as %s", name);
    if (code == ANARI_FLOAT32)
      expect_quiet(what);
    else {
      char text[256];
      snprintf(text, sizeof text, "expects ANARI_FLOAT32, got %s", name);
      check(what, seen.count > 0 && names(seen.message, text));
      expect(what, ERR, BAD_ARG, text);
    }
  }
  snprintf(what, sizeof what, "%d value types tried", value_types);
  check(what, value_types > 100);
  anariRelease(dev, renderer);
  anariRelease(dev, dev);
  anariUnloadLibrary(lib);
  return failures ? 1 : 0;
}
