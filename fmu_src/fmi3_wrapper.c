/*
 * FMI 3.0 co-simulation over a pythonfmu3 slave class (an Fmi3Slave subclass), loaded by
 * fmi3_loader.c once it has found a CPython (3.10 or newer) for it. The counterpart of
 * fmi2_wrapper.c: errors carry the Python exception's text, the slave's messages reach the host,
 * and a call in the wrong state gets fmi3Error and a message (FMI 3.0 section 4.2, co-simulation
 * without event mode). The work is done in slave_bridge.h; this file maps the FMI 3.0 calls.
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
    [GET_BOOL] = "get_boolean", [SET_BOOL] = "set_boolean", [GET_STR] = "get_string", [SET_STR] = "set_string",
    [READER] = "real_reader", [WRITER] = "real_writer"};

/* The modes of slave_bridge.h in the standard's words, by bit. */
static const char *const MODE_NAMES[] = {
    "instantiated", "in initialization mode", "in step mode", "in step mode after a discarded step", "terminated",
    "in error state (after an fmi3Error; fmi3Reset or fmi3SetFMUState recover it)"};

typedef struct {
    Slave py; /* first: an Instance is a Slave to slave_bridge.h */
    fmi3InstanceEnvironment environment;
    fmi3LogMessageCallback log_message;
} Instance;

static void emit(Slave *s, int status, const char *category, const char *text) {
    Instance *c = (Instance *)s;
    if (c->log_message && (status != fmi3OK || s->logging_on))
        c->log_message(c->environment, (fmi3Status)status, category, text);
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
    c->py = (Slave){.names = METHODS, .mode_names = MODE_NAMES, .emit = emit};
    if (event_mode_used) {
        emit(&c->py, fmi3Error, "logStatusError", "fmi3InstantiateCoSimulation: this FMU has no event mode");
    } else if (open_instance(&c->py, "fmi3InstantiateCoSimulation", name, resource_path, visible, logging_on)) {
        return c;
    }
    free_slave_memory(&c->py);
    free(c);
    return NULL;
}

FMI3_Export void fmi3FreeInstance(fmi3Instance c) { free_instance(c); }

fmi3Status fmi3SetDebugLogging(fmi3Instance c, fmi3Boolean on, size_t n, const fmi3String cats[]) {
    (void)n, (void)cats;
    return set_logging(c, "fmi3SetDebugLogging", on);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance c, fmi3Boolean tolerance_defined, fmi3Float64 tolerance,
                                       fmi3Float64 start, fmi3Boolean stop_defined, fmi3Float64 stop) {
    (void)tolerance_defined, (void)tolerance, (void)stop_defined, (void)stop;
    Slave *s = c;
    if (!allowed(s, "fmi3EnterInitializationMode", INSTANTIATED)) return fmi3Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *args = Py_BuildValue("(d)", start); /* pythonfmu3's setup_experiment(start_time) */
    PyObject *setup = args ? call_method(s, SETUP, args) : NULL;
    PyObject *result = setup ? call_method(s, ENTER, NULL) : NULL;
    fmi3Status status = finish(s, "fmi3EnterInitializationMode", result != NULL);
    Py_XDECREF(args);
    Py_XDECREF(setup);
    Py_XDECREF(result);
    PyGILState_Release(gil);
    if (status == fmi3OK) s->mode = INITIALIZATION, s->time = start;
    return status;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance c) {
    return simple_call(c, "fmi3ExitInitializationMode", INITIALIZATION, EXIT, STEPPING);
}

fmi3Status fmi3Terminate(fmi3Instance c) {
    return simple_call(c, "fmi3Terminate", STEPPING | STEP_DISCARDED, TERMINATE, TERMINATED);
}

fmi3Status fmi3Reset(fmi3Instance c) { return reset(c, "fmi3Reset"); }

/* Scalars only: nValues must equal nValueReferences. */
#define GETTER(Type, method, convert)                                                                        \
    fmi3Status fmi3Get##Type(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, fmi3##Type v[],      \
                             size_t n) {                                                                     \
        if (n != nvr) return refuse(c, "fmi3Get" #Type, "arrays are not supported (nValues != nValueReferences)"); \
        return GET_VALUES(c, "fmi3Get" #Type, method, vr, n, v, convert);                                    \
    }
GETTER(Float64, GET_F64, v[i] = PyFloat_AsDouble(x))
GETTER(Int32, GET_I32, v[i] = (fmi3Int32)PyLong_AsLong(x))
GETTER(Int64, GET_I64, v[i] = PyLong_AsLongLong(x))
GETTER(UInt64, GET_U64, v[i] = PyLong_AsUnsignedLongLong(x))
GETTER(Boolean, GET_BOOL, v[i] = PyObject_IsTrue(x) > 0)
GETTER(String, GET_STR, v[i] = keep_string(s, x, i))

#define SETTER(Type, method, make)                                                                           \
    fmi3Status fmi3Set##Type(fmi3Instance c, const fmi3ValueReference vr[], size_t nvr, const fmi3##Type v[], \
                             size_t n) {                                                                     \
        if (n != nvr) return refuse(c, "fmi3Set" #Type, "arrays are not supported (nValues != nValueReferences)"); \
        return SET_VALUES(c, "fmi3Set" #Type, method, vr, n, v, make);                                       \
    }
SETTER(Float64, SET_F64, PyFloat_FromDouble(v[i]))
SETTER(Int32, SET_I32, PyLong_FromLong(v[i]))
SETTER(Int64, SET_I64, PyLong_FromLongLong(v[i]))
SETTER(UInt64, SET_U64, PyLong_FromUnsignedLongLong(v[i]))
SETTER(Boolean, SET_BOOL, PyBool_FromLong(v[i]))
SETTER(String, SET_STR, PyUnicode_FromString(v[i] ? v[i] : ""))

fmi3Status fmi3DoStep(fmi3Instance c, fmi3Float64 t, fmi3Float64 h, fmi3Boolean no_prior, fmi3Boolean *event_needed,
                      fmi3Boolean *terminate, fmi3Boolean *early_return, fmi3Float64 *last_time) {
    (void)no_prior;
    if (!event_needed || !terminate || !early_return || !last_time)
        return refuse(c, "fmi3DoStep", "NULL output pointer");
    fmi3Status status = do_step(c, "fmi3DoStep", t, h);
    *event_needed = *terminate = *early_return = fmi3False;
    *last_time = c ? ((Slave *)c)->time : t;
    return status;
}

fmi3Status fmi3GetFMUState(fmi3Instance c, fmi3FMUState *s) { return get_fmu_state(c, "fmi3GetFMUState", s); }
fmi3Status fmi3SetFMUState(fmi3Instance c, fmi3FMUState s) { return set_fmu_state(c, "fmi3SetFMUState", s); }
fmi3Status fmi3FreeFMUState(fmi3Instance c, fmi3FMUState *s) { return free_fmu_state(c, "fmi3FreeFMUState", s); }

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance c, fmi3FMUState s, size_t *size) {
    return serialize_fmu_state(c, "fmi3SerializedFMUStateSize", s, NULL, size);
}

fmi3Status fmi3SerializeFMUState(fmi3Instance c, fmi3FMUState s, fmi3Byte out[], size_t size) {
    return out ? serialize_fmu_state(c, "fmi3SerializeFMUState", s, (char *)out, &size)
               : refuse(c, "fmi3SerializeFMUState", "NULL buffer");
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance c, const fmi3Byte data[], size_t size, fmi3FMUState *s) {
    return deserialize_fmu_state(c, "fmi3DeserializeFMUState", (const char *)data, size, s);
}

#define UNSUPPORTED(ret, name, params, args)                                                                 \
    ret name params {                                                                                        \
        return c ? refuse(c, #name, "not supported by this FMU") : fmi3Error;                                \
    }
FMI3_UNSUPPORTED(UNSUPPORTED)
