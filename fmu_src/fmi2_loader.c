/*
 * The FMUs' Linux binary: a loader with no dependency on Python.
 *
 * fmi2Instantiate loads the CPython library the FMU was built for (LIBPYTHON, else its soname
 * LIBPYTHON_SONAME) with RTLD_GLOBAL, then the FMI wrapper (fmi2_wrapper.c, next to this file
 * as PythonWrapper.so) and forwards every FMI call to it. Where that Python is missing, the
 * host gets a clear log message and NULL from fmi2Instantiate instead of a failed dlopen of
 * the FMU or a crash.
 */
#define _GNU_SOURCE /* dladdr */
#include <dlfcn.h>
#include <libgen.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define EXPORT __attribute__((visibility("default")))

typedef void *C;
typedef unsigned int VR;
typedef void (*Logger)(void *, const char *, int, const char *, const char *, ...);
typedef struct { Logger logger; void *allocate, *release, *step_finished, *environment; } Callbacks;

#define FUNCTIONS(X)                                                                                          \
    X(void, fmi2FreeInstance, (C c), (c))                                                                     \
    X(int, fmi2SetDebugLogging, (C c, int on, size_t n, const char *const cats[]), (c, on, n, cats))          \
    X(int, fmi2SetupExperiment, (C c, int td, double tol, double t0, int sd, double t1), (c, td, tol, t0, sd, t1)) \
    X(int, fmi2EnterInitializationMode, (C c), (c))                                                           \
    X(int, fmi2ExitInitializationMode, (C c), (c))                                                            \
    X(int, fmi2Terminate, (C c), (c))                                                                         \
    X(int, fmi2Reset, (C c), (c))                                                                             \
    X(int, fmi2GetReal, (C c, const VR vr[], size_t n, double v[]), (c, vr, n, v))                           \
    X(int, fmi2GetInteger, (C c, const VR vr[], size_t n, int v[]), (c, vr, n, v))                           \
    X(int, fmi2GetBoolean, (C c, const VR vr[], size_t n, int v[]), (c, vr, n, v))                           \
    X(int, fmi2GetString, (C c, const VR vr[], size_t n, const char *v[]), (c, vr, n, v))                    \
    X(int, fmi2SetReal, (C c, const VR vr[], size_t n, const double v[]), (c, vr, n, v))                     \
    X(int, fmi2SetInteger, (C c, const VR vr[], size_t n, const int v[]), (c, vr, n, v))                     \
    X(int, fmi2SetBoolean, (C c, const VR vr[], size_t n, const int v[]), (c, vr, n, v))                     \
    X(int, fmi2SetString, (C c, const VR vr[], size_t n, const char *const v[]), (c, vr, n, v))              \
    X(int, fmi2GetFMUstate, (C c, void **s), (c, s))                                                          \
    X(int, fmi2SetFMUstate, (C c, void *s), (c, s))                                                           \
    X(int, fmi2FreeFMUstate, (C c, void **s), (c, s))                                                         \
    X(int, fmi2SerializedFMUstateSize, (C c, void *s, size_t *n), (c, s, n))                                  \
    X(int, fmi2SerializeFMUstate, (C c, void *s, char b[], size_t n), (c, s, b, n))                          \
    X(int, fmi2DeSerializeFMUstate, (C c, const char b[], size_t n, void **s), (c, b, n, s))                 \
    X(int, fmi2GetDirectionalDerivative, (C c, const VR u[], size_t nu, const VR z[], size_t nz,             \
      const double dv[], double dz[]), (c, u, nu, z, nz, dv, dz))                                             \
    X(int, fmi2SetRealInputDerivatives, (C c, const VR vr[], size_t n, const int o[], const double v[]),     \
      (c, vr, n, o, v))                                                                                       \
    X(int, fmi2GetRealOutputDerivatives, (C c, const VR vr[], size_t n, const int o[], double v[]),          \
      (c, vr, n, o, v))                                                                                       \
    X(int, fmi2DoStep, (C c, double t, double h, int prior), (c, t, h, prior))                               \
    X(int, fmi2CancelStep, (C c), (c))                                                                        \
    X(int, fmi2GetStatus, (C c, int k, int *v), (c, k, v))                                                    \
    X(int, fmi2GetRealStatus, (C c, int k, double *v), (c, k, v))                                             \
    X(int, fmi2GetIntegerStatus, (C c, int k, int *v), (c, k, v))                                             \
    X(int, fmi2GetBooleanStatus, (C c, int k, int *v), (c, k, v))                                             \
    X(int, fmi2GetStringStatus, (C c, int k, const char **v), (c, k, v))

/* Pointers into the wrapper, set once fmi2Instantiate has loaded it; every other call needs a
   component, which only exists after a successful fmi2Instantiate. */
#define POINTER(ret, name, params, args) static ret(*p_##name) params;
FUNCTIONS(POINTER)
#define FORWARD(ret, name, params, args) \
    EXPORT ret name params { return p_##name args; }
FUNCTIONS(FORWARD)

typedef C (*Instantiate)(const char *, int, const char *, const char *, const Callbacks *, int, int);
static Instantiate p_instantiate;

EXPORT const char *fmi2GetTypesPlatform(void) { return "default"; }
EXPORT const char *fmi2GetVersion(void) { return "2.0"; }

static int load(const char *name, const Callbacks *cb) {
    if (p_instantiate) return 1;
    char message[8192];
    if (!dlopen(LIBPYTHON, RTLD_NOW | RTLD_GLOBAL) && !dlopen(LIBPYTHON_SONAME, RTLD_NOW | RTLD_GLOBAL)) {
        snprintf(message, sizeof message,
                 "fmi2Instantiate: this FMU runs Python models and needs the CPython it was built with (%s, "
                 "at %s), which this machine does not have: %s", LIBPYTHON_SONAME, LIBPYTHON, dlerror());
        if (cb && cb->logger) cb->logger(cb->environment, name, 3, "logStatusError", "%s", message);
        return 0;
    }
    Dl_info self;
    char path[4096];
    dladdr((void *)&load, &self);
    snprintf(path, sizeof path, "%s", self.dli_fname);
    char wrapper[4200];
    snprintf(wrapper, sizeof wrapper, "%s/PythonWrapper.so", dirname(path));
    void *lib = dlopen(wrapper, RTLD_NOW | RTLD_LOCAL);
    if (!lib) {
        snprintf(message, sizeof message, "fmi2Instantiate: cannot load %s: %s", wrapper, dlerror());
        if (cb && cb->logger) cb->logger(cb->environment, name, 3, "logStatusError", "%s", message);
        return 0;
    }
#define RESOLVE(ret, name, params, args) p_##name = (ret(*) params)dlsym(lib, #name);
    FUNCTIONS(RESOLVE)
    p_instantiate = (Instantiate)dlsym(lib, "fmi2Instantiate");
    return p_instantiate != NULL;
}

EXPORT C fmi2Instantiate(const char *name, int type, const char *guid, const char *resources, const Callbacks *cb,
                         int visible, int logging) {
    if (!load(name, cb)) return NULL;
    return p_instantiate(name, type, guid, resources, cb, visible, logging);
}
