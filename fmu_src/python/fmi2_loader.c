/*
 * The FMI 2.0 FMUs' Linux binary: a loader with no dependency on Python. fmi2Instantiate finds a
 * CPython (find_python.h), loads the wrapper (the FMI 2.0 framework over the Python model,
 * python_model.c, next to this file as PythonWrapper.so) and every FMI call is forwarded to it. Where no Python is found, the host gets
 * NULL from fmi2Instantiate and a log message listing every place tried, never a failed dlopen of
 * the FMU or a crash.
 */
#include "find_python.h"
#include "fmi2Functions.h"
#include "fmi2_calls.h"

/* Pointers into the wrapper; a call before a successful fmi2Instantiate gets fmi2Error. */
#define POINTER(ret, name, params, args) static name##TYPE *p_##name;
FMI2_IMPLEMENTED(POINTER)
FMI2_UNSUPPORTED(POINTER)
static fmi2InstantiateTYPE *p_fmi2Instantiate;
static fmi2FreeInstanceTYPE *p_fmi2FreeInstance;

#define FORWARD(ret, name, params, args) \
    ret name params { return p_##name ? p_##name args : fmi2Error; }
FMI2_IMPLEMENTED(FORWARD)
FMI2_UNSUPPORTED(FORWARD)

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                              const fmi2CallbackFunctions *cb, fmi2Boolean visible, fmi2Boolean logging_on) {
    char message[10000], used[4400];
    void *wrapper = load_wrapper("fmi2Instantiate", message, sizeof message, used, sizeof used);
    if (!wrapper) {
        if (cb && cb->logger) cb->logger(cb->componentEnvironment, name, fmi2Error, "logStatusError", "%s", message);
        return NULL;
    }
    if (logging_on && cb && cb->logger) cb->logger(cb->componentEnvironment, name, fmi2OK, "logAll", "%s", used);
#define RESOLVE(ret, name, params, args) p_##name = (name##TYPE *)dlsym(wrapper, #name);
    FMI2_IMPLEMENTED(RESOLVE)
    FMI2_UNSUPPORTED(RESOLVE)
    RESOLVE(, fmi2FreeInstance, , )
    RESOLVE(, fmi2Instantiate, , )
    return p_fmi2Instantiate ? p_fmi2Instantiate(name, type, guid, location, cb, visible, logging_on) : NULL;
}

void fmi2FreeInstance(fmi2Component c) {
    if (p_fmi2FreeInstance) p_fmi2FreeInstance(c);
}
