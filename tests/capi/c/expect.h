/* The checks the C misuse programs share: a status callback that keeps
 * the last warning or error, and PASS/FAIL lines counted in `failures`. */
#ifndef CAVERAY_TEST_EXPECT_H
#define CAVERAY_TEST_EXPECT_H

#include <anari/anari.h>

#include <stdio.h>
#include <string.h>

typedef struct Seen {
  int count;
  ANARIStatusSeverity severity;
  ANARIStatusCode code;
  ANARIObject source;
  char message[1024];
} Seen;

static Seen seen;
static int failures = 0;
/* INFO messages that reported a render stopped by discard or release. */
static int discards = 0;

static void on_status(const void *user, ANARIDevice d, ANARIObject source,
    ANARIDataType sourceType, ANARIStatusSeverity severity, ANARIStatusCode code,
    const char *message)
{
  (void)user, (void)d, (void)sourceType;
  if (severity == ANARI_SEVERITY_INFO && strstr(message, "discarded"))
    discards++;
  if (severity > ANARI_SEVERITY_WARNING)
    return; /* other info and debug messages are not what these tests check */
  seen.count++;
  seen.severity = severity;
  seen.code = code;
  seen.source = source;
  strncpy(seen.message, message, sizeof seen.message - 1);
}

static void reset(void)
{
  memset(&seen, 0, sizeof seen);
}

/* The last message must have this severity, code and contain `text`. */
static void expect(const char *what, ANARIStatusSeverity severity,
    ANARIStatusCode code, const char *text)
{
  int ok = seen.count > 0 && seen.severity == severity && seen.code == code
      && strstr(seen.message, text) != NULL;
  printf("%s %s: [%d/%d] %s\n", ok ? "PASS" : "FAIL", what, seen.severity,
      seen.code, seen.count ? seen.message : "(no message)");
  if (!ok) {
    printf("     expected severity %d, code %d, text '%s'\n", severity, code, text);
    failures++;
  }
  reset();
}

static void expect_quiet(const char *what)
{
  int ok = seen.count == 0;
  printf("%s %s%s%s\n", ok ? "PASS" : "FAIL", what, ok ? "" : ": unexpected ",
      ok ? "" : seen.message);
  failures += !ok;
  reset();
}

static void check(const char *what, int ok)
{
  printf("%s %s\n", ok ? "PASS" : "FAIL", what);
  failures += !ok;
}

#define ERR ANARI_SEVERITY_ERROR
#define WARN ANARI_SEVERITY_WARNING
#define BAD_ARG ANARI_STATUS_INVALID_ARGUMENT
#define BAD_OP ANARI_STATUS_INVALID_OPERATION

#endif
