/*
 * The FMI 2.0 logger of the instances this toolkit makes (crane_fmu/cosim/fmi2.py): it formats an FMU's
 * printf-style message (variadic, which ctypes cannot receive) and hands it to the one Python function that
 * fmi2.py sets here. fmpy has such a proxy (fmpy.logging), but its target is one per process, replaced by every
 * host in the process that uses it (fmpy's simulate_fmu, a test's own callbacks): the instances made before then
 * lost their messages, and their errors the reason (a batch path's row then differed from its case run alone).
 * This target is set by fmi2.py alone.
 */
#include <stdarg.h>
#include <stdio.h>

typedef void (*Sink)(void *environment, const char *instance, int status, const char *category, const char *message);

static Sink sink;

void set_sink(Sink target) { sink = target; }

void log_message(void *environment, const char *instance, int status, const char *category, const char *message,
                 ...) {
    char buffer[2048]; /* fmpy's proxy's length: the same messages */
    va_list args;
    va_start(args, message);
    vsnprintf(buffer, sizeof buffer, message ? message : "", args);
    va_end(args);
    if (sink) sink(environment, instance, status, category, buffer);
}
