/*
 * FMI 2.0 co-simulation over a pythonfmu slave class (an Fmi2Slave subclass), loaded by
 * fmi2_loader.c once it has found a CPython (3.10 or newer) for it.
 *
 * Replaces pythonfmu 0.7's Linux binary, which drops every log message (the reason of an error
 * included), turns every Python exception into fmi2Fatal, and cannot be loaded by a C host.
 * Here a Python exception is fmi2Error with the exception's text as the log message, the slave's
 * own messages reach the host's logger, and a call in the wrong state gets fmi2Error and a message
 * (the state machine of the FMI 2.0 standard, section 4.2.4, as in the Reference FMUs).
 */
#include "fmi2Functions.h"
#include "fmi2_functions.h"
#include "slave_bridge.h"

static const char *const METHODS[N_METHODS] = {
    [SETUP] = "setup_experiment", [ENTER] = "enter_initialization_mode", [EXIT] = "exit_initialization_mode",
    [TERMINATE] = "terminate", [DO_STEP] = "do_step", [GET_STATE] = "_get_fmu_state",
    [SET_STATE] = "_set_fmu_state", [TO_BYTES] = "_fmu_state_to_bytes", [FROM_BYTES] = "_fmu_state_from_bytes",
    [GET_F64] = "get_real", [SET_F64] = "set_real", [GET_I32] = "get_integer", [SET_I32] = "set_integer",
    [GET_BOOL] = "get_boolean", [SET_BOOL] = "set_boolean", [GET_STR] = "get_string", [SET_STR] = "set_string"};

typedef enum {
    INSTANTIATED = 1 << 0,
    INITIALIZATION = 1 << 1,
    STEP_COMPLETE = 1 << 2,
    STEP_FAILED = 1 << 3, /* the last step was discarded */
    TERMINATED = 1 << 4,
    ERROR = 1 << 5,
} Mode;
#define ANY_MODE (INSTANTIATED | INITIALIZATION | STEP_COMPLETE | STEP_FAILED | TERMINATED | ERROR)
#define GETTABLE (INITIALIZATION | STEP_COMPLETE | STEP_FAILED | TERMINATED | ERROR)
#define SETTABLE (INSTANTIATED | INITIALIZATION | STEP_COMPLETE)

typedef struct {
    Slave py;
    fmi2CallbackFunctions cb;
    int logging_on;
    Mode mode;
    double time; /* the last successful communication point */
} Instance;

static void emit(void *owner, int status, const char *category, const char *text) {
    Instance *c = owner;
    if (c->cb.logger && (status != fmi2OK || c->logging_on))
        c->cb.logger(c->cb.componentEnvironment, c->py.name ? c->py.name : "", (fmi2Status)status, category,
                     "%s", text);
}

static const char *mode_name(Mode mode) {
    switch (mode) {
    case INSTANTIATED: return "instantiated";
    case INITIALIZATION: return "in initialization mode";
    case STEP_COMPLETE: return "in step-complete state";
    case STEP_FAILED: return "in step-failed state (its last step was discarded)";
    case TERMINATED: return "terminated";
    default: return "in error state (after an fmi2Error; fmi2Reset or fmi2SetFMUstate recover it)";
    }
}

/* The state machine: may `function` be called in the instance's mode? If not, say so. */
static int allowed(Instance *c, const char *function, int modes) {
    if (!c) return 0;
    if (c->mode & modes) return 1;
    char text[256];
    snprintf(text, sizeof text, "%s must not be called when the instance is %s", function, mode_name(c->mode));
    emit(c, fmi2Error, "logStatusError", text);
    return 0;
}

/* Refuse a call with bad arguments: fmi2Error and the reason, the mode unchanged. */
static fmi2Status refuse(Instance *c, const char *text) {
    emit(c, fmi2Error, "logStatusError", text);
    return fmi2Error;
}

/* The status of a Python call's result (NULL: the exception is logged and the instance is in error). */
static fmi2Status finish(Instance *c, const char *function, PyObject *result) {
    if (result) return flush_log(&c->py), fmi2OK;
    log_failure(&c->py, function);
    c->mode = ERROR;
    return fmi2Error;
}

/* Call slave.<method>() with the GIL taken once; on success move to `next` (0: stay). */
static fmi2Status simple_call(fmi2Component component, const char *function, int modes, int method, Mode next) {
    Instance *c = component;
    if (!allowed(c, function, modes)) return fmi2Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *result = call_method(&c->py, method, NULL);
    fmi2Status status = finish(c, function, result);
    Py_XDECREF(result);
    PyGILState_Release(gil);
    if (status == fmi2OK && next) c->mode = next;
    return status;
}

FMI2_Export const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
FMI2_Export const char *fmi2GetVersion(void) { return fmi2Version; }

FMI2_Export fmi2Component fmi2Instantiate(fmi2String name, fmi2Type type, fmi2String guid, fmi2String location,
                                          const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                                          fmi2Boolean logging_on) {
    (void)guid;
    if (!functions || !name) return NULL;
    Instance *c = calloc(1, sizeof *c);
    if (!c) return NULL;
    c->cb = *functions;
    c->logging_on = logging_on;
    c->mode = INSTANTIATED;
    c->py.names = METHODS;
    c->py.emit = emit;
    c->py.owner = c;
    if (type != fmi2CoSimulation) {
        emit(c, fmi2Error, "logStatusError", "fmi2Instantiate: this FMU supports co-simulation only");
    } else if (open_slave(&c->py, "fmi2Instantiate", name, location, visible)) {
        return c;
    }
    free_slave_memory(&c->py);
    free(c);
    return NULL;
}

FMI2_Export void fmi2FreeInstance(fmi2Component component) {
    Instance *c = component;
    if (!c) return;
    PyGILState_STATE gil = PyGILState_Ensure();
    release_slave(&c->py);
    PyGILState_Release(gil);
    free_slave_memory(&c->py);
    free(c);
}

fmi2Status fmi2SetDebugLogging(fmi2Component component, fmi2Boolean on, size_t n, const fmi2String cats[]) {
    (void)n, (void)cats;
    Instance *c = component;
    if (!allowed(c, "fmi2SetDebugLogging", ANY_MODE)) return fmi2Error;
    c->logging_on = on;
    return fmi2OK;
}

fmi2Status fmi2SetupExperiment(fmi2Component component, fmi2Boolean tolerance_defined, fmi2Real tolerance,
                               fmi2Real start, fmi2Boolean stop_defined, fmi2Real stop) {
    Instance *c = component;
    if (!allowed(c, "fmi2SetupExperiment", INSTANTIATED)) return fmi2Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *args = Py_BuildValue("(dNN)", start, stop_defined ? PyFloat_FromDouble(stop) : Py_NewRef(Py_None),
                                   tolerance_defined ? PyFloat_FromDouble(tolerance) : Py_NewRef(Py_None));
    PyObject *result = args ? call_method(&c->py, SETUP, args) : NULL;
    fmi2Status status = finish(c, "fmi2SetupExperiment", result);
    Py_XDECREF(args);
    Py_XDECREF(result);
    PyGILState_Release(gil);
    if (status == fmi2OK) c->time = start;
    return status;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    return simple_call(c, "fmi2EnterInitializationMode", INSTANTIATED, ENTER, INITIALIZATION);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    return simple_call(c, "fmi2ExitInitializationMode", INITIALIZATION, EXIT, STEP_COMPLETE);
}

fmi2Status fmi2Terminate(fmi2Component c) {
    return simple_call(c, "fmi2Terminate", STEP_COMPLETE | STEP_FAILED, TERMINATE, TERMINATED);
}

fmi2Status fmi2Reset(fmi2Component component) {
    Instance *c = component;
    if (!allowed(c, "fmi2Reset", ANY_MODE)) return fmi2Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    fmi2Status status = new_slave(&c->py, 0) ? fmi2OK : (python_error(&c->py, "fmi2Reset"), fmi2Error);
    PyGILState_Release(gil);
    c->mode = status == fmi2OK ? INSTANTIATED : ERROR;
    return status;
}

/* fmi2Get<Type>: slave.get_<type>(value references), each item converted by `convert`. */
#define GETTER(Name, method, ctype, convert)                                                                 \
    fmi2Status Name(fmi2Component component, const fmi2ValueReference vr[], size_t n, ctype v[]) {           \
        Instance *c = component;                                                                             \
        if (!allowed(c, #Name, GETTABLE)) return fmi2Error;                                                  \
        if (n == 0) return fmi2OK;                                                                           \
        if (!vr || !v) return refuse(c, #Name ": NULL array");         \
        PyGILState_STATE gil = PyGILState_Ensure();                                                          \
        PyObject *values = get_values(&c->py, method, vr, n);                                                \
        for (size_t i = 0; values && i < n; i++) {                                                           \
            PyObject *x = item(values, i);                                                                   \
            convert;                                                                                         \
            if (PyErr_Occurred()) Py_CLEAR(values);                                                          \
        }                                                                                                    \
        fmi2Status status = finish(c, #Name, values);                                                        \
        Py_XDECREF(values);                                                                                  \
        PyGILState_Release(gil);                                                                             \
        return status;                                                                                       \
    }

GETTER(fmi2GetReal, GET_F64, fmi2Real, v[i] = PyFloat_AsDouble(x))
GETTER(fmi2GetInteger, GET_I32, fmi2Integer, v[i] = (fmi2Integer)PyLong_AsLong(x))
GETTER(fmi2GetBoolean, GET_BOOL, fmi2Boolean, v[i] = PyObject_IsTrue(x) > 0)
GETTER(fmi2GetString, GET_STR, fmi2String, v[i] = keep_string(&c->py, x, i))

/* fmi2Set<Type>: slave.set_<type>(value references, values made by `make`). */
#define SETTER(Name, method, ctype, make)                                                                    \
    fmi2Status Name(fmi2Component component, const fmi2ValueReference vr[], size_t n, const ctype v[]) {     \
        Instance *c = component;                                                                             \
        if (!allowed(c, #Name, SETTABLE)) return fmi2Error;                                                  \
        if (n == 0) return fmi2OK;                                                                           \
        if (!vr || !v) return refuse(c, #Name ": NULL array");         \
        PyGILState_STATE gil = PyGILState_Ensure();                                                          \
        int ok = set_values(&c->py, method, vr, n, LIST_OF(n, make));                                        \
        fmi2Status status = finish(c, #Name, ok ? Py_None : NULL);                                           \
        PyGILState_Release(gil);                                                                             \
        return status;                                                                                       \
    }

SETTER(fmi2SetReal, SET_F64, fmi2Real, PyFloat_FromDouble(v[i]))
SETTER(fmi2SetInteger, SET_I32, fmi2Integer, PyLong_FromLong(v[i]))
SETTER(fmi2SetBoolean, SET_BOOL, fmi2Boolean, PyBool_FromLong(v[i]))
SETTER(fmi2SetString, SET_STR, fmi2String, PyUnicode_FromString(v[i] ? v[i] : ""))

fmi2Status fmi2DoStep(fmi2Component component, fmi2Real t, fmi2Real h, fmi2Boolean no_prior) {
    (void)no_prior;
    Instance *c = component;
    if (!allowed(c, "fmi2DoStep", STEP_COMPLETE)) return fmi2Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *args = Py_BuildValue("(dd)", t, h);
    PyObject *result = args ? call_method(&c->py, DO_STEP, args) : NULL;
    int done = result ? PyObject_IsTrue(result) : -1;
    Py_XDECREF(args);
    Py_XDECREF(result);
    fmi2Status status = finish(c, "fmi2DoStep", done >= 0 ? Py_None : NULL);
    PyGILState_Release(gil);
    if (status == fmi2OK && done) c->time = t + h;
    else if (status == fmi2OK) c->mode = STEP_FAILED, status = fmi2Discard;
    return status;
}

fmi2Status fmi2GetRealStatus(fmi2Component component, const fmi2StatusKind kind, fmi2Real *v) {
    Instance *c = component;
    if (!allowed(c, "fmi2GetRealStatus", STEP_COMPLETE | STEP_FAILED | TERMINATED)) return fmi2Error;
    if (kind != fmi2LastSuccessfulTime || !v)
        return refuse(c, "fmi2GetRealStatus: only fmi2LastSuccessfulTime is known");
    *v = c->time;
    return fmi2OK;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component component, const fmi2StatusKind kind, fmi2Boolean *v) {
    Instance *c = component;
    if (!allowed(c, "fmi2GetBooleanStatus", STEP_COMPLETE | STEP_FAILED | TERMINATED)) return fmi2Error;
    if (kind != fmi2Terminated || !v)
        return refuse(c, "fmi2GetBooleanStatus: only fmi2Terminated is known");
    *v = fmi2False;
    return fmi2OK;
}

/* FMU states hold the slave's state object with the instance's mode and time (slave_bridge.h). */
#define WITH_GIL(function, ok)                                                                               \
    ({                                                                                                       \
        PyGILState_STATE gil_ = PyGILState_Ensure();                                                         \
        fmi2Status status_ = finish(c, function, (ok) ? Py_None : NULL);                                       \
        PyGILState_Release(gil_);                                                                            \
        status_;                                                                                             \
    })

fmi2Status fmi2GetFMUstate(fmi2Component component, fmi2FMUstate *s) {
    Instance *c = component;
    if (!allowed(c, "fmi2GetFMUstate", ANY_MODE)) return fmi2Error;
    if (!s) return refuse(c, "fmi2GetFMUstate: NULL state pointer");
    return WITH_GIL("fmi2GetFMUstate", save_state(&c->py, s, c->mode, c->time));
}

fmi2Status fmi2SetFMUstate(fmi2Component component, fmi2FMUstate s) {
    Instance *c = component;
    SavedState *saved = s;
    if (!allowed(c, "fmi2SetFMUstate", ANY_MODE)) return fmi2Error;
    if (!saved) return refuse(c, "fmi2SetFMUstate: NULL state");
    fmi2Status status = WITH_GIL("fmi2SetFMUstate", restore_state(&c->py, saved));
    if (status == fmi2OK) c->mode = saved->mode, c->time = saved->time;
    return status;
}

fmi2Status fmi2FreeFMUstate(fmi2Component component, fmi2FMUstate *s) {
    Instance *c = component;
    if (!allowed(c, "fmi2FreeFMUstate", ANY_MODE)) return fmi2Error;
    if (!s || !*s) return fmi2OK;
    PyGILState_STATE gil = PyGILState_Ensure();
    free_state(s);
    PyGILState_Release(gil);
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component component, fmi2FMUstate s, size_t *size) {
    Instance *c = component;
    if (!allowed(c, "fmi2SerializedFMUstateSize", ANY_MODE)) return fmi2Error;
    if (!s || !size) return refuse(c, "fmi2SerializedFMUstateSize: NULL state or size");
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *bytes = serialized_state(&c->py, s);
    if (bytes) *size = (size_t)PyBytes_Size(bytes);
    fmi2Status status = finish(c, "fmi2SerializedFMUstateSize", bytes);
    Py_XDECREF(bytes);
    PyGILState_Release(gil);
    return status;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component component, fmi2FMUstate s, fmi2Byte out[], size_t size) {
    Instance *c = component;
    if (!allowed(c, "fmi2SerializeFMUstate", ANY_MODE)) return fmi2Error;
    if (!s || !out) return refuse(c, "fmi2SerializeFMUstate: NULL state or buffer");
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *bytes = serialized_state(&c->py, s);
    fmi2Status status = finish(c, "fmi2SerializeFMUstate", bytes);
    if (bytes && (size_t)PyBytes_Size(bytes) > size) status = refuse(c, "fmi2SerializeFMUstate: the buffer is too small");
    else if (bytes) memcpy(out, PyBytes_AsString(bytes), (size_t)PyBytes_Size(bytes));
    Py_XDECREF(bytes);
    PyGILState_Release(gil);
    return status;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component component, const fmi2Byte data[], size_t size, fmi2FMUstate *s) {
    Instance *c = component;
    if (!allowed(c, "fmi2DeSerializeFMUstate", ANY_MODE)) return fmi2Error;
    if (!s) return refuse(c, "fmi2DeSerializeFMUstate: NULL state pointer");
    return WITH_GIL("fmi2DeSerializeFMUstate", deserialize_state(&c->py, (const char *)data, size, s, ANY_MODE));
}

#define UNSUPPORTED(ret, name, params, args)                                                                 \
    ret name params {                                                                                        \
        if (c) emit(c, fmi2Error, "logStatusError", #name " is not supported by this FMU");                  \
        return fmi2Error;                                                                                    \
    }
FMI2_UNSUPPORTED(UNSUPPORTED)
