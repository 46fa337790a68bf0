/*
 * FMI 3.0 co-simulation over a pythonfmu3 slave class (an Fmi3Slave subclass), loaded by
 * fmi3_loader.c once it has found a CPython (3.10 or newer) for it. The counterpart of
 * fmi2_wrapper.c: errors carry the Python exception's text, the slave's messages reach the host,
 * and a call in the wrong state gets fmi3Error and a message (FMI 3.0 section 4.2, co-simulation
 * without event mode).
 */
#include "fmi3Functions.h"
#include "fmi3_functions.h"
#include "slave_bridge.h"

static const char *const METHODS[N_METHODS] = {
    [SETUP] = "setup_experiment", [ENTER] = "enter_initialization_mode", [EXIT] = "exit_initialization_mode",
    [TERMINATE] = "terminate", [DO_STEP] = "do_step", [GET_STATE] = "_get_fmu_state",
    [SET_STATE] = "_set_fmu_state", [TO_BYTES] = "_fmu_state_to_bytes", [FROM_BYTES] = "_fmu_state_from_bytes",
    [GET_F64] = "get_float64", [SET_F64] = "set_float64", [GET_I32] = "get_int32", [SET_I32] = "set_int32",
    [GET_I64] = "get_int64", [SET_I64] = "set_int64", [GET_U64] = "get_uint64", [SET_U64] = "set_uint64",
    [GET_BOOL] = "get_boolean", [SET_BOOL] = "set_boolean", [GET_STR] = "get_string", [SET_STR] = "set_string"};

typedef enum {
    INSTANTIATED = 1 << 0,
    INITIALIZATION = 1 << 1,
    STEP_MODE = 1 << 2,
    STEP_DISCARDED = 1 << 3, /* the last step was discarded */
    TERMINATED = 1 << 4,
    ERROR = 1 << 5,
} Mode;
#define ANY_MODE (INSTANTIATED | INITIALIZATION | STEP_MODE | STEP_DISCARDED | TERMINATED | ERROR)
#define GETTABLE (INITIALIZATION | STEP_MODE | STEP_DISCARDED | TERMINATED | ERROR)
#define SETTABLE (INSTANTIATED | INITIALIZATION | STEP_MODE)

typedef struct {
    Slave py;
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback log_message;
    int logging_on;
    Mode mode;
    double time; /* the last successful communication point */
} Instance;

static void emit(void *owner, int status, const char *category, const char *text) {
    Instance *c = owner;
    if (c->log_message && (status != fmi3OK || c->logging_on))
        c->log_message(c->environment, (fmi3Status)status, category, text);
}

static const char *mode_name(Mode mode) {
    switch (mode) {
    case INSTANTIATED: return "instantiated";
    case INITIALIZATION: return "in initialization mode";
    case STEP_MODE: return "in step mode";
    case STEP_DISCARDED: return "in step mode after a discarded step";
    case TERMINATED: return "terminated";
    default: return "in error state (after an fmi3Error; fmi3Reset or fmi3SetFMUState recover it)";
    }
}

static int allowed(Instance *c, const char *function, int modes) {
    if (!c) return 0;
    if (c->mode & modes) return 1;
    char text[256];
    snprintf(text, sizeof text, "%s must not be called when the instance is %s", function, mode_name(c->mode));
    emit(c, fmi3Error, "logStatusError", text);
    return 0;
}

/* Refuse a call with bad arguments: fmi3Error and the reason, the mode unchanged. */
static fmi3Status refuse(Instance *c, const char *text) {
    emit(c, fmi3Error, "logStatusError", text);
    return fmi3Error;
}

static fmi3Status finish(Instance *c, const char *function, PyObject *result) {
    if (result) return flush_log(&c->py), fmi3OK;
    log_failure(&c->py, function);
    c->mode = ERROR;
    return fmi3Error;
}

static fmi3Status simple_call(fmi3Instance instance, const char *function, int modes, int method, Mode next) {
    Instance *c = instance;
    if (!allowed(c, function, modes)) return fmi3Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *result = call_method(&c->py, method, NULL);
    fmi3Status status = finish(c, function, result);
    Py_XDECREF(result);
    PyGILState_Release(gil);
    if (status == fmi3OK) c->mode = next;
    return status;
}

FMI3_Export const char *fmi3GetVersion(void) { return fmi3Version; }

FMI3_Export fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String name, fmi3String token, fmi3String resource_path, fmi3Boolean visible, fmi3Boolean logging_on,
    fmi3Boolean event_mode_used, fmi3Boolean early_return_allowed, const fmi3ValueReference required[],
    size_t n_required, fmi3InstanceEnvironment environment, fmi3LogMessageCallback log_message,
    fmi3IntermediateUpdateCallback intermediate_update) {
    (void)token, (void)early_return_allowed, (void)required, (void)n_required, (void)intermediate_update;
    if (!name) return NULL;
    Instance *c = calloc(1, sizeof *c);
    if (!c) return NULL;
    c->environment = environment;
    c->log_message = log_message;
    c->logging_on = logging_on;
    c->mode = INSTANTIATED;
    c->py.names = METHODS;
    c->py.emit = emit;
    c->py.owner = c;
    if (event_mode_used) {
        emit(c, fmi3Error, "logStatusError", "fmi3InstantiateCoSimulation: this FMU has no event mode");
    } else if (open_slave(&c->py, "fmi3InstantiateCoSimulation", name, resource_path, visible)) {
        return c;
    }
    free_slave_memory(&c->py);
    free(c);
    return NULL;
}

FMI3_Export void fmi3FreeInstance(fmi3Instance instance) {
    Instance *c = instance;
    if (!c) return;
    PyGILState_STATE gil = PyGILState_Ensure();
    release_slave(&c->py);
    PyGILState_Release(gil);
    free_slave_memory(&c->py);
    free(c);
}

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean on, size_t n, const fmi3String cats[]) {
    (void)n, (void)cats;
    Instance *c = instance;
    if (!allowed(c, "fmi3SetDebugLogging", ANY_MODE)) return fmi3Error;
    c->logging_on = on;
    return fmi3OK;
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean tolerance_defined, fmi3Float64 tolerance,
                                       fmi3Float64 start, fmi3Boolean stop_defined, fmi3Float64 stop) {
    (void)tolerance_defined, (void)tolerance, (void)stop_defined, (void)stop;
    Instance *c = instance;
    if (!allowed(c, "fmi3EnterInitializationMode", INSTANTIATED)) return fmi3Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *args = Py_BuildValue("(d)", start); /* pythonfmu3's setup_experiment(start_time) */
    PyObject *setup = args ? call_method(&c->py, SETUP, args) : NULL;
    PyObject *result = setup ? call_method(&c->py, ENTER, NULL) : NULL;
    fmi3Status status = finish(c, "fmi3EnterInitializationMode", result);
    Py_XDECREF(args);
    Py_XDECREF(setup);
    Py_XDECREF(result);
    PyGILState_Release(gil);
    if (status == fmi3OK) c->mode = INITIALIZATION, c->time = start;
    return status;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance c) {
    return simple_call(c, "fmi3ExitInitializationMode", INITIALIZATION, EXIT, STEP_MODE);
}

fmi3Status fmi3Terminate(fmi3Instance c) {
    return simple_call(c, "fmi3Terminate", STEP_MODE | STEP_DISCARDED, TERMINATE, TERMINATED);
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    Instance *c = instance;
    if (!allowed(c, "fmi3Reset", ANY_MODE)) return fmi3Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    fmi3Status status = new_slave(&c->py, 0) ? fmi3OK : (python_error(&c->py, "fmi3Reset"), fmi3Error);
    PyGILState_Release(gil);
    c->mode = status == fmi3OK ? INSTANTIATED : ERROR;
    return status;
}

/* fmi3Get<Type>: slave.get_<type>(value references), each of the n values converted by `convert`. */
#define GETTER(Type, method, convert)                                                                        \
    fmi3Status fmi3Get##Type(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,               \
                             fmi3##Type v[], size_t n) {                                                     \
        Instance *c = instance;                                                                              \
        if (!allowed(c, "fmi3Get" #Type, GETTABLE)) return fmi3Error;                                        \
        if (nvr == 0) return fmi3OK;                                                                         \
        if (!vr || !v || n != nvr)                                                                           \
            return refuse(c, "fmi3Get" #Type ": NULL arrays or arrays of arrays");                                                            \
        PyGILState_STATE gil = PyGILState_Ensure();                                                          \
        PyObject *values = get_values(&c->py, method, vr, n);                                                \
        for (size_t i = 0; values && i < n; i++) {                                                           \
            PyObject *x = item(values, i);                                                                   \
            convert;                                                                                         \
            if (PyErr_Occurred()) Py_CLEAR(values);                                                          \
        }                                                                                                    \
        fmi3Status status = finish(c, "fmi3Get" #Type, values);                                              \
        Py_XDECREF(values);                                                                                  \
        PyGILState_Release(gil);                                                                             \
        return status;                                                                                       \
    }

GETTER(Float64, GET_F64, v[i] = PyFloat_AsDouble(x))
GETTER(Int32, GET_I32, v[i] = (fmi3Int32)PyLong_AsLong(x))
GETTER(Int64, GET_I64, v[i] = PyLong_AsLongLong(x))
GETTER(UInt64, GET_U64, v[i] = PyLong_AsUnsignedLongLong(x))
GETTER(Boolean, GET_BOOL, v[i] = PyObject_IsTrue(x) > 0)
GETTER(String, GET_STR, v[i] = keep_string(&c->py, x, i))

#define SETTER(Type, method, make)                                                                           \
    fmi3Status fmi3Set##Type(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,               \
                             const fmi3##Type v[], size_t n) {                                               \
        Instance *c = instance;                                                                              \
        if (!allowed(c, "fmi3Set" #Type, SETTABLE)) return fmi3Error;                                        \
        if (nvr == 0) return fmi3OK;                                                                         \
        if (!vr || !v || n != nvr)                                                                           \
            return refuse(c, "fmi3Set" #Type ": NULL arrays or arrays of arrays");                                                            \
        PyGILState_STATE gil = PyGILState_Ensure();                                                          \
        int ok = set_values(&c->py, method, vr, n, LIST_OF(n, make));                                        \
        fmi3Status status = finish(c, "fmi3Set" #Type, ok ? Py_None : NULL);                                 \
        PyGILState_Release(gil);                                                                             \
        return status;                                                                                       \
    }

SETTER(Float64, SET_F64, PyFloat_FromDouble(v[i]))
SETTER(Int32, SET_I32, PyLong_FromLong(v[i]))
SETTER(Int64, SET_I64, PyLong_FromLongLong(v[i]))
SETTER(UInt64, SET_U64, PyLong_FromUnsignedLongLong(v[i]))
SETTER(Boolean, SET_BOOL, PyBool_FromLong(v[i]))
SETTER(String, SET_STR, PyUnicode_FromString(v[i] ? v[i] : ""))

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 t, fmi3Float64 h, fmi3Boolean no_prior,
                      fmi3Boolean *event_needed, fmi3Boolean *terminate, fmi3Boolean *early_return,
                      fmi3Float64 *last_time) {
    (void)no_prior;
    Instance *c = instance;
    if (!allowed(c, "fmi3DoStep", STEP_MODE)) return fmi3Error;
    if (!event_needed || !terminate || !early_return || !last_time)
        return refuse(c, "fmi3DoStep: NULL output pointer");
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *args = Py_BuildValue("(dd)", t, h);
    PyObject *result = args ? call_method(&c->py, DO_STEP, args) : NULL;
    int done = result ? PyObject_IsTrue(result) : -1;
    Py_XDECREF(args);
    Py_XDECREF(result);
    fmi3Status status = finish(c, "fmi3DoStep", done >= 0 ? Py_None : NULL);
    PyGILState_Release(gil);
    if (status == fmi3OK && done) c->time = t + h;
    else if (status == fmi3OK) c->mode = STEP_DISCARDED, status = fmi3Discard;
    *event_needed = *terminate = *early_return = fmi3False;
    *last_time = c->time;
    return status;
}

/* FMU states hold the slave's state object with the instance's mode and time (slave_bridge.h). */
#define WITH_GIL(function, ok)                                                                               \
    ({                                                                                                       \
        PyGILState_STATE gil_ = PyGILState_Ensure();                                                         \
        fmi3Status status_ = finish(c, function, (ok) ? Py_None : NULL);                                       \
        PyGILState_Release(gil_);                                                                            \
        status_;                                                                                             \
    })

fmi3Status fmi3GetFMUState(fmi3Instance component, fmi3FMUState *s) {
    Instance *c = component;
    if (!allowed(c, "fmi3GetFMUState", ANY_MODE)) return fmi3Error;
    if (!s) return refuse(c, "fmi3GetFMUState: NULL state pointer");
    return WITH_GIL("fmi3GetFMUState", save_state(&c->py, s, c->mode, c->time));
}

fmi3Status fmi3SetFMUState(fmi3Instance component, fmi3FMUState s) {
    Instance *c = component;
    SavedState *saved = s;
    if (!allowed(c, "fmi3SetFMUState", ANY_MODE)) return fmi3Error;
    if (!saved) return refuse(c, "fmi3SetFMUState: NULL state");
    fmi3Status status = WITH_GIL("fmi3SetFMUState", restore_state(&c->py, saved));
    if (status == fmi3OK) c->mode = saved->mode, c->time = saved->time;
    return status;
}

fmi3Status fmi3FreeFMUState(fmi3Instance component, fmi3FMUState *s) {
    Instance *c = component;
    if (!allowed(c, "fmi3FreeFMUState", ANY_MODE)) return fmi3Error;
    if (!s || !*s) return fmi3OK;
    PyGILState_STATE gil = PyGILState_Ensure();
    free_state(s);
    PyGILState_Release(gil);
    return fmi3OK;
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance component, fmi3FMUState s, size_t *size) {
    Instance *c = component;
    if (!allowed(c, "fmi3SerializedFMUStateSize", ANY_MODE)) return fmi3Error;
    if (!s || !size) return refuse(c, "fmi3SerializedFMUStateSize: NULL state or size");
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *bytes = serialized_state(&c->py, s);
    if (bytes) *size = (size_t)PyBytes_Size(bytes);
    fmi3Status status = finish(c, "fmi3SerializedFMUStateSize", bytes);
    Py_XDECREF(bytes);
    PyGILState_Release(gil);
    return status;
}

fmi3Status fmi3SerializeFMUState(fmi3Instance component, fmi3FMUState s, fmi3Byte out[], size_t size) {
    Instance *c = component;
    if (!allowed(c, "fmi3SerializeFMUState", ANY_MODE)) return fmi3Error;
    if (!s || !out) return refuse(c, "fmi3SerializeFMUState: NULL state or buffer");
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *bytes = serialized_state(&c->py, s);
    fmi3Status status = finish(c, "fmi3SerializeFMUState", bytes);
    if (bytes && (size_t)PyBytes_Size(bytes) > size) status = refuse(c, "fmi3SerializeFMUState: the buffer is too small");
    else if (bytes) memcpy(out, PyBytes_AsString(bytes), (size_t)PyBytes_Size(bytes));
    Py_XDECREF(bytes);
    PyGILState_Release(gil);
    return status;
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance component, const fmi3Byte data[], size_t size, fmi3FMUState *s) {
    Instance *c = component;
    if (!allowed(c, "fmi3DeserializeFMUState", ANY_MODE)) return fmi3Error;
    if (!s) return refuse(c, "fmi3DeserializeFMUState: NULL state pointer");
    return WITH_GIL("fmi3DeserializeFMUState", deserialize_state(&c->py, (const char *)data, size, s, ANY_MODE));
}

#define UNSUPPORTED(ret, name, params, args)                                                                 \
    ret name params {                                                                                        \
        if (c) emit(c, fmi3Error, "logStatusError", #name " is not supported by this FMU");                  \
        return fmi3Error;                                                                                    \
    }
FMI3_UNSUPPORTED(UNSUPPORTED)
