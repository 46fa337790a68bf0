/*
 * FMI 2.0 co-simulation over a pythonfmu slave class (an Fmi2Slave subclass), loaded by
 * fmi2_loader.c once it has found a CPython (3.10 or newer) for it.
 *
 * Replaces pythonfmu 0.7's Linux binary, which drops every log message (the reason of an error
 * included), turns every Python exception into fmi2Fatal, and cannot be loaded by a C host.
 * Here a Python exception is fmi2Error with the exception's text as the log message, the slave's
 * own messages reach the host's logger, and a call in the wrong state gets fmi2Error and a message
 * (the state machine of the FMI 2.0 standard, section 4.2.4, as in the Reference FMUs). The work
 * is done in slave_bridge.h, shared with the FMI 3.0 wrapper; this file maps the FMI 2.0 calls.
 */
#include "fmi2Functions.h"
#include "fmi2_functions.h"
#include "slave_bridge.h"

static const char *const METHODS[N_METHODS] = {
    [SETUP] = "setup_experiment", [ENTER] = "enter_initialization_mode", [EXIT] = "exit_initialization_mode",
    [TERMINATE] = "terminate", [DO_STEP] = "do_step", [GET_STATE] = "_get_fmu_state",
    [SET_STATE] = "_set_fmu_state", [TO_BYTES] = "_fmu_state_to_bytes", [FROM_BYTES] = "_fmu_state_from_bytes",
    [GET_F64] = "get_real", [SET_F64] = "set_real", [GET_I32] = "get_integer", [SET_I32] = "set_integer",
    [GET_BOOL] = "get_boolean", [SET_BOOL] = "set_boolean", [GET_STR] = "get_string", [SET_STR] = "set_string",
    [READER] = "real_reader", [WRITER] = "real_writer"};

/* The modes of slave_bridge.h in the standard's words, by bit. */
static const char *const MODE_NAMES[] = {
    "instantiated", "in initialization mode", "in step-complete state",
    "in step-failed state (its last step was discarded)", "terminated",
    "in error state (after an fmi2Error; fmi2Reset or fmi2SetFMUstate recover it)"};

typedef struct {
    Slave py; /* first: an Instance is a Slave to slave_bridge.h */
    fmi2CallbackFunctions cb;
} Instance;

static void emit(Slave *s, int status, const char *category, const char *text) {
    Instance *c = (Instance *)s;
    if (c->cb.logger && (status != fmi2OK || s->logging_on))
        c->cb.logger(c->cb.componentEnvironment, s->name ? s->name : "", (fmi2Status)status, category, "%s", text);
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
    c->py = (Slave){.names = METHODS, .mode_names = MODE_NAMES, .emit = emit};
    if (type != fmi2CoSimulation) {
        emit(&c->py, fmi2Error, "logStatusError", "fmi2Instantiate: this FMU supports co-simulation only");
    } else if (open_instance(&c->py, "fmi2Instantiate", name, location, visible, logging_on)) {
        return c;
    }
    free_slave_memory(&c->py);
    free(c);
    return NULL;
}

FMI2_Export void fmi2FreeInstance(fmi2Component c) { free_instance(c); }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean on, size_t n, const fmi2String cats[]) {
    (void)n, (void)cats;
    return set_logging(c, "fmi2SetDebugLogging", on);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean tolerance_defined, fmi2Real tolerance, fmi2Real start,
                               fmi2Boolean stop_defined, fmi2Real stop) {
    Slave *s = c;
    if (!allowed(s, "fmi2SetupExperiment", INSTANTIATED)) return fmi2Error;
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject *args = Py_BuildValue("(dNN)", start, stop_defined ? PyFloat_FromDouble(stop) : Py_NewRef(Py_None),
                                   tolerance_defined ? PyFloat_FromDouble(tolerance) : Py_NewRef(Py_None));
    PyObject *result = args ? call_method(s, SETUP, args) : NULL;
    fmi2Status status = finish(s, "fmi2SetupExperiment", result != NULL);
    Py_XDECREF(args);
    Py_XDECREF(result);
    PyGILState_Release(gil);
    if (status == fmi2OK) s->time = start;
    return status;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    return simple_call(c, "fmi2EnterInitializationMode", INSTANTIATED, ENTER, INITIALIZATION);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    return simple_call(c, "fmi2ExitInitializationMode", INITIALIZATION, EXIT, STEPPING);
}

fmi2Status fmi2Terminate(fmi2Component c) {
    return simple_call(c, "fmi2Terminate", STEPPING | STEP_DISCARDED, TERMINATE, TERMINATED);
}

fmi2Status fmi2Reset(fmi2Component c) { return reset(c, "fmi2Reset"); }

#define GETTER(Name, method, ctype, convert)                                                                 \
    fmi2Status Name(fmi2Component c, const fmi2ValueReference vr[], size_t n, ctype v[]) {                   \
        return GET_VALUES(c, #Name, method, vr, n, v, convert);                                              \
    }
GETTER(fmi2GetReal, GET_F64, fmi2Real, v[i] = PyFloat_AsDouble(x))
GETTER(fmi2GetInteger, GET_I32, fmi2Integer, v[i] = (fmi2Integer)PyLong_AsLong(x))
GETTER(fmi2GetBoolean, GET_BOOL, fmi2Boolean, v[i] = PyObject_IsTrue(x) > 0)
GETTER(fmi2GetString, GET_STR, fmi2String, v[i] = keep_string(s, x, i))

#define SETTER(Name, method, ctype, make)                                                                    \
    fmi2Status Name(fmi2Component c, const fmi2ValueReference vr[], size_t n, const ctype v[]) {             \
        return SET_VALUES(c, #Name, method, vr, n, v, make);                                                 \
    }
SETTER(fmi2SetReal, SET_F64, fmi2Real, PyFloat_FromDouble(v[i]))
SETTER(fmi2SetInteger, SET_I32, fmi2Integer, PyLong_FromLong(v[i]))
SETTER(fmi2SetBoolean, SET_BOOL, fmi2Boolean, PyBool_FromLong(v[i]))
SETTER(fmi2SetString, SET_STR, fmi2String, PyUnicode_FromString(v[i] ? v[i] : ""))

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real t, fmi2Real h, fmi2Boolean no_prior) {
    (void)no_prior;
    return do_step(c, "fmi2DoStep", t, h);
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real *v) {
    Slave *s = c;
    if (!allowed(s, "fmi2GetRealStatus", STEPPING | STEP_DISCARDED | TERMINATED)) return fmi2Error;
    if (kind != fmi2LastSuccessfulTime || !v)
        return refuse(s, "fmi2GetRealStatus", "only fmi2LastSuccessfulTime is known");
    *v = s->time;
    return fmi2OK;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Boolean *v) {
    Slave *s = c;
    if (!allowed(s, "fmi2GetBooleanStatus", STEPPING | STEP_DISCARDED | TERMINATED)) return fmi2Error;
    if (kind != fmi2Terminated || !v) return refuse(s, "fmi2GetBooleanStatus", "only fmi2Terminated is known");
    *v = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *s) { return get_fmu_state(c, "fmi2GetFMUstate", s); }
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate s) { return set_fmu_state(c, "fmi2SetFMUstate", s); }
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *s) { return free_fmu_state(c, "fmi2FreeFMUstate", s); }

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate s, size_t *size) {
    return serialize_fmu_state(c, "fmi2SerializedFMUstateSize", s, NULL, size);
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate s, fmi2Byte out[], size_t size) {
    return out ? serialize_fmu_state(c, "fmi2SerializeFMUstate", s, out, &size)
               : refuse(c, "fmi2SerializeFMUstate", "NULL buffer");
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte data[], size_t size, fmi2FMUstate *s) {
    return deserialize_fmu_state(c, "fmi2DeSerializeFMUstate", data, size, s);
}

#define UNSUPPORTED(ret, name, params, args)                                                                 \
    ret name params {                                                                                        \
        return c ? refuse(c, #name, "not supported by this FMU") : fmi2Error;                                \
    }
FMI2_UNSUPPORTED(UNSUPPORTED)
