/* The status callback the C host tests pass to anariLoadLibrary: messages
 * at `status_level` or worse (lower is worse) are printed with the
 * program's name and counted in `status_count`, which each program's exit
 * status checks. */
#ifndef CAVERAY_TEST_STATUS_H
#define CAVERAY_TEST_STATUS_H

#include <anari/anari.h>

#include <stdio.h>

static int status_count = 0;
static ANARIStatusSeverity status_level = ANARI_SEVERITY_ERROR;

static void count_status(const void *program, ANARIDevice d, ANARIObject source,
    ANARIDataType sourceType, ANARIStatusSeverity severity, ANARIStatusCode code,
    const char *message)
{
  (void)d, (void)source, (void)sourceType, (void)code;
  if (severity <= status_level) {
    ++status_count;
    fprintf(stderr, "%s: %s\n", (const char *)program, message);
  }
}

#endif
